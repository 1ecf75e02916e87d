// The C# binding under Mono (Debian's mono-runtime, the runtime Unity's scripting grew from)
// against a real lockstep hapticd: the binding's own checks, the Unity package's component (with a
// stand-in for UnityEngine), and touch_wall in C# printing exactly what the C++ one prints, each
// against a fresh server.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "integration/recording_files.hpp"
#include "integration/run_program.hpp"
#include "integration/server_process.hpp"
#include "integration/touch_wall_output.hpp"

namespace haptic::test {
namespace {

Outcome mono(const std::string& program, const std::vector<std::string>& args) {
  std::vector<std::string> words = {"--debug", program};
  words.insert(words.end(), args.begin(), args.end());
#ifdef MONO_PRELOAD
  // A sanitizer build: the instrumented libhaptic_c needs their runtime loaded first.
  words.insert(words.begin(), {MONO_PRELOAD, "ASAN_OPTIONS=detect_leaks=0:halt_on_error=1", MONO_BINARY});
  return run_program("/usr/bin/env", words);
#else
  return run_program(MONO_BINARY, words);
#endif
}

TEST(CSharp, TheBindingRegistersEveryKindHoldsAPushRefusesNamingTheFieldAndCallsBackOnItsThreads) {
  ServerProcess server(lockstep_config());
  const TempDir dir;
  const Outcome outcome = mono(CSHARP_TESTS, {server.address(), dir.path()});
  EXPECT_EQ(outcome.exit_code, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("all C# checks passed"), std::string::npos) << outcome.output;
  // Its recorders' files hold every sample its callback saw (written to seen.csv), every field the same.
  const auto seen = csv_rows(read_csv(dir.file("seen.csv")));
  const auto csv = csv_rows(read_csv(dir.file("session.csv")));
  const auto hdf5 = h5_file_rows(dir.file("session.h5"));
  EXPECT_EQ(csv.size(), hdf5.size());
  expect_rows_match(csv, seen, "CSV from C#");
  expect_rows_match(hdf5, seen, "HDF5 from C#");
}

TEST(CSharp, TheUnityComponentMovesItsTransformWithTheTool) {
  ServerProcess server(lockstep_config());
  const Outcome outcome = mono(UNITY_COMPONENT_TEST, {server.address()});
  EXPECT_EQ(outcome.exit_code, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("the Unity component's checks passed"), std::string::npos) << outcome.output;
}

TEST(CSharp, TouchWallPrintsExactlyWhatTheCppOnePrints) {
  expect_prints_what_cpp_prints(
      [](const std::vector<std::string>& args) { return run_program(TOUCH_WALL_BINARY, args); },
      [](const std::vector<std::string>& args) { return mono(CSHARP_TOUCH_WALL, args); });
}

}  // namespace
}  // namespace haptic::test
