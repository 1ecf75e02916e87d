// haptic-lab: runs hapticd scenes in lockstep time, in-process, with the server's own loop code,
// and writes what happened:
//   haptic-lab run --scene S.json --duration D --out trace.csv   (S.json: a hapticd configuration)
//   haptic-lab transparency [--mass … --stiffness … --w1 …] --csv sweep.csv --markdown report.md
//   haptic-lab zwidth [--mass … --period … --law … --delay …] --csv grid.csv --markdown report.md

#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

#include "app/config.hpp"
#include "lab/lab_run.hpp"
#include "lab/transparency.hpp"
#include "lab/zwidth.hpp"

namespace {

/// Writes a study's CSV (when asked) and its markdown report (to a file, or standard output).
template <typename Params, typename Report>
void write_reports(const Params& params, const Report& report, const std::string& csv_path,
                   const std::string& markdown_path) {
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
  haptic::lab::write_markdown(params, report, markdown_path.empty() ? std::cout : md);
}

}  // namespace

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
  CLI::App* zwidth = cli.add_subcommand(
      "zwidth", "the (K, B) region a device model renders: Colgate's bound, eigenvalues, simulation");
  haptic::lab::ZWidthParams z;
  std::string law = "backward_difference", z_csv, z_markdown;
  zwidth->add_option("--mass", z.mass, "device mass, kg (default 0.01)");
  zwidth->add_option("--damping", z.damping, "device damping, N*s/m (default 0.022)");
  zwidth->add_option("--period", z.period, "sample period, s (default 0.001)");
  zwidth->add_option("--law", law, "backward_difference (default), exact_zoh or tustin");
  zwidth->add_option("--delay", z.delay_ticks, "extra ticks of delay (default 0)");
  zwidth->add_option("--hand-mass", z.hand_mass, "operator's hand mass, kg (default 0)");
  zwidth->add_option("--hand-stiffness", z.hand_stiffness, "hand stiffness, N/m (default 0)");
  zwidth->add_option("--hand-damping", z.hand_damping, "hand damping, N*s/m (default 0)");
  zwidth->add_option("--csv", z_csv, "write the grid as CSV here");
  zwidth->add_option("--markdown", z_markdown, "write the report here; default: standard output");
  CLI11_PARSE(cli, argc, argv);

  if (*zwidth) {
    try {
      if (law == "backward_difference") {
        z.discretization = haptic::engine::ImpedanceDiscretization::kBackwardDifference;
      } else if (law == "exact_zoh") {
        z.discretization = haptic::engine::ImpedanceDiscretization::kExactZoh;
      } else if (law == "tustin") {
        z.discretization = haptic::engine::ImpedanceDiscretization::kTustin;
      } else {
        throw std::invalid_argument("law: must be backward_difference, exact_zoh or tustin, got \"" + law + "\"");
      }
      write_reports(z, haptic::lab::zwidth(z), z_csv, z_markdown);
      return 0;
    } catch (const std::exception& error) {
      std::cerr << "haptic-lab: " << error.what() << "\n";
      return 2;
    }
  }

  if (*transparency) {
    try {
      write_reports(design, haptic::lab::transparency_study(design), csv_path, markdown_path);
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
