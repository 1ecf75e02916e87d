// Starts a lockstep hapticd and runs the C99 program of c_api_test.c against it.

#include <gtest/gtest.h>

#include "integration/c_api_test.h"
#include "integration/server_process.hpp"

TEST(CApi, CProgramHoldsAWallPushAndSeesRefusalsNamingTheField) {
  haptic::test::ServerProcess server{haptic::test::lockstep_config()};
  EXPECT_EQ(c_api_test_run(server.address().c_str()), 0);
}
