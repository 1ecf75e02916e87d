// haptic-driver-kit: checks a device driver library against what hapticd needs of it (driver_kit),
// as a vendor or a lab writing one runs it: `haptic-driver-kit my_driver.so --params '{...}'`.
// Exit status 0 when every check passes, 1 when one fails, 2 for a bad command line.
#include <CLI/CLI.hpp>
#include <haptic/version.hpp>

#include <iostream>

#include "driver_kit.hpp"

int main(int argc, char** argv) {
  CLI::App cli{"haptic-driver-kit: checks a hapticd device driver (a shared library built against "
               "<haptic/driver.h>). It commands forces: run it on hardware that is free to move."};
  cli.set_version_flag("--version", std::string("haptic-driver-kit ") + HAPTIC_VERSION);
  haptic::driver_kit::KitOptions options;
  std::string model = "cartesian";
  cli.add_option("library", options.library, "the driver's shared library")->required()->check(CLI::ExistingFile);
  cli.add_option("--params", options.params_json, "JSON its create() gets (driver.params)")->capture_default_str();
  cli.add_option("--model", model, "cartesian, or anything else to skip the Cartesian checks")
      ->capture_default_str();
  std::uint32_t call_timeout_ms = 20;
  cli.add_option("--call-timeout-ms", call_timeout_ms,
                 "longest a read or write may take before it is a hang (hapticd's call_timeout_ms); "
                 "raise it on a loaded host without real-time scheduling")
      ->capture_default_str()
      ->check(CLI::Range(1u, 10000u));
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return cli.exit(error) == 0 ? 0 : 2;
  }
  options.cartesian = model == "cartesian";
  options.call_timeout_s = call_timeout_ms * 1e-3;
  std::cout << "haptic-driver-kit: " << options.library << " with params " << options.params_json << "\n";
  const auto results = haptic::driver_kit::run_kit(options, std::cout);
  int passed = 0, failed = 0;
  for (const auto& result : results) {
    if (result.skipped) {
      std::cout << "SKIP  " << result.name << " (" << result.detail << ")\n";
    } else if (result.passed) {
      ++passed;
      std::cout << "PASS  " << result.name << "\n";
    } else {
      ++failed;
      std::cout << "FAIL  " << result.name << ": " << result.detail << "\n";
    }
  }
  std::cout << passed << " passed, " << failed << " failed\n";
  return failed == 0 ? 0 : 1;
}
