#pragma once
// The hapticd client SDK.
#include "haptic/client.hpp"
#include "haptic/error.hpp"
#include "haptic/motion.hpp"
#include "haptic/types.hpp"
