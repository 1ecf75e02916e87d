// haptic-lab: runs hapticd scenes in lockstep time, in-process, with the server's own loop code,
// and writes what happened. Today: `haptic-lab run --scene S.json --duration D --out trace.csv`,
// S.json a hapticd configuration (device ports, operator, objects, fields, rate, integrators).

#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "app/config.hpp"
#include "lab/lab_run.hpp"

int main(int argc, char** argv) {
  CLI::App cli{"haptic-lab: runs hapticd scenes in lockstep time and reports on them"};
  cli.require_subcommand(1);
  CLI::App* run = cli.add_subcommand("run", "run one scene and write a per-tick trace (CSV)");
  std::string scene_path, out_path;
  double duration_s = 1.0;
  run->add_option("--scene", scene_path, "hapticd configuration (JSON haptic.v1.ServerConfig)")
      ->required()
      ->check(CLI::ExistingFile);
  run->add_option("--duration", duration_s, "simulated time, s (default 1)");
  run->add_option("--out", out_path, "trace file (CSV); default: standard output");
  CLI11_PARSE(cli, argc, argv);

  try {
    const haptic::v1::ServerConfig config = haptic::app::load_config_file(scene_path);
    std::ofstream file;
    if (!out_path.empty()) {
      file.open(out_path);
      if (!file) throw std::invalid_argument(out_path + ": cannot write");
    }
    std::ostream& trace = out_path.empty() ? std::cout : file;
    const haptic::lab::RunSummary summary = haptic::lab::run_scene(config, duration_s, trace);
    std::cerr << "haptic-lab: " << summary.ticks << " ticks; energy to the device "
              << summary.energy_to_device << " J, from it " << summary.energy_from_device << " J; "
              << summary.fault_ticks << " fault ticks; " << (summary.finite ? "finite" : "NOT FINITE")
              << "\n";
    return summary.finite ? 0 : 3;
  } catch (const std::exception& error) {
    std::cerr << "haptic-lab: " << error.what() << "\n";
    return 2;
  }
}
