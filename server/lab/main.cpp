// haptic-lab: runs hapticd scenes in lockstep time, in-process, with the server's own loop code,
// and writes what happened:
//   haptic-lab run --scene S.json --duration D --out trace.csv   (S.json: a hapticd configuration)
//   haptic-lab transparency [--mass … --stiffness … --w1 …] --csv sweep.csv --markdown report.md

#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "app/config.hpp"
#include "lab/lab_run.hpp"
#include "lab/transparency.hpp"

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
  CLI::App* transparency = cli.add_subcommand(
      "transparency", "001's controller design for a device model: J(B_c), ||L||inf(B_c), the optimum");
  haptic::engine::WallDesignParams design;
  std::string csv_path, markdown_path;
  transparency->add_option("--mass", design.mass, "device mass, kg (default 0.01)");
  transparency->add_option("--damping", design.damping, "device damping, N*s/m (default 0.022)");
  transparency->add_option("--stiffness", design.wall_stiffness, "wall stiffness K, N/m (default 1000)");
  transparency->add_option("--wall-damping", design.wall_damping, "wall damping B, N*s/m (default 1)");
  transparency->add_option("--period", design.sample_period, "sample period T, s (default 0.001)");
  transparency->add_option("--w1", design.weight_cutoff, "transparency weight cut-off, rad/s (default 100)");
  transparency->add_option("--alpha", design.mass_uncertainty, "mass uncertainty (default 0.5)");
  transparency->add_option("--beta", design.damping_uncertainty, "damping uncertainty (default 0.5)");
  transparency->add_option("--csv", csv_path, "write the sweep as CSV here");
  transparency->add_option("--markdown", markdown_path, "write the report here; default: standard output");
  CLI11_PARSE(cli, argc, argv);

  if (*transparency) {
    try {
      const haptic::lab::TransparencyReport report = haptic::lab::transparency_study(design);
      if (!csv_path.empty()) {
        std::ofstream csv(csv_path);
        if (!csv) throw std::invalid_argument(csv_path + ": cannot write");
        haptic::lab::write_csv(report, csv);
      }
      std::ofstream md;
      if (!markdown_path.empty()) {
        md.open(markdown_path);
        if (!md) throw std::invalid_argument(markdown_path + ": cannot write");
      }
      haptic::lab::write_markdown(design, report, markdown_path.empty() ? std::cout : md);
      return 0;
    } catch (const std::exception& error) {
      std::cerr << "haptic-lab: " << error.what() << "\n";
      return 2;
    }
  }

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
