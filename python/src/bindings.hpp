#pragma once
// The parts of the hapticd Python module, each binding one header's worth of the SDK.

#include <pybind11/pybind11.h>

namespace haptic::python {

/// Specs, operator inputs and the server's reports (haptic/types.hpp).
void bind_value_types(pybind11::module_& m);
/// The exceptions (haptic/error.hpp), one Python class per C++ one under hapticd.Error.
void bind_errors(pybind11::module_& m);
/// Client, its handles and the scene's free functions (haptic/client.hpp, haptic/motion.hpp).
void bind_client(pybind11::module_& m);
/// Recorder and Client.record (haptic/recorder.hpp); after bind_client.
void bind_recorder(pybind11::module_& m);

}  // namespace haptic::python
