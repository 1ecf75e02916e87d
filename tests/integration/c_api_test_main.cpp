// Starts a lockstep hapticd and runs the C99 program of c_api_test.c against it.

#include <gtest/gtest.h>

#include "integration/c_api_test.h"
#include "integration/recording_files.hpp"
#include "integration/server_process.hpp"

TEST(CApi, CProgramHoldsAWallPushAndSeesRefusalsNamingTheField) {
  haptic::test::ServerProcess server{haptic::test::lockstep_config()};
  EXPECT_EQ(c_api_test_run(server.address().c_str()), 0);
}

// A C program records a session to CSV and HDF5 through the C API while its state callback keeps
// what it saw; both files hold every sample the callback saw, every field the same.
TEST(CApi, TheRecorderWritesEverySampleTheCProgramsCallbackSaw) {
  haptic::test::ServerProcess server{haptic::test::lockstep_config()};
  const haptic::test::TempDir dir;
  ASSERT_EQ(c_api_record_run(server.address().c_str(), dir.path().c_str()), 0);
  const auto seen = haptic::test::csv_rows(haptic::test::read_csv(dir.file("seen.csv")));
  const auto csv = haptic::test::csv_rows(haptic::test::read_csv(dir.file("session.csv")));
  const auto hdf5 = haptic::test::h5_file_rows(dir.file("session.h5"));
  EXPECT_EQ(csv.size(), hdf5.size());
  EXPECT_GE(csv.size(), seen.size());
  haptic::test::expect_rows_match(csv, seen, "CSV");
  haptic::test::expect_rows_match(hdf5, seen, "HDF5");
  const auto events = haptic::test::read_csv(dir.file("session.events.csv"));
  ASSERT_FALSE(events.rows.empty());
  EXPECT_EQ(events.rows[0][events.column("kind_name")], "watch_started");
}
