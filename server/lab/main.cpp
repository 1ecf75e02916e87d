// haptic-lab: runs hapticd scenes in lockstep time, in-process, with the server's own loop code,
// and writes what happened:
//   haptic-lab run --scene S.json --duration D --out trace.csv   (S.json: a hapticd configuration)
//   haptic-lab transparency [--device C.json | --mass … --damping …] [--stiffness … --w1 …]
//                           --csv sweep.csv --markdown report.md
//   haptic-lab zwidth [--device C.json | --mass … --damping …] [--period … --law … --delay …]
//                     --csv grid.csv --markdown report.md
//   haptic-lab study [--short] [--case …] [--scheme …] [--steps …] --out DIR   (docs/numerics.md)
// Exit status: 0 done; 2 bad input (a message on standard error names it, before any work);
// 3 a run that went non-finite; CLI11's own codes (> 100) for malformed command lines.

#include <CLI/CLI.hpp>
#include <haptic/version.hpp>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "config/server_config.hpp"
#include <google/protobuf/util/json_util.h>

#include "lab/device_model.hpp"
#include "lab/identify.hpp"
#include "lab/lab_run.hpp"
#include "lab/progress_bar.hpp"
#include "lab/study_command.hpp"
#include "lab/transparency.hpp"
#include "lab/zwidth.hpp"

namespace {

/// A subcommand: its parser, and what runs it once parsed (returns the exit status; may throw
/// std::exception for bad input, which main reports with exit status 2). Adding a subcommand is
/// one line in main: `commands.push_back(add_<name>(cli));` (or from_functions below).
struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

/// A subcommand that comes as a pair of functions, `CLI::App* add(CLI::App&, Options&)` and
/// `int run(const Options&)`: `commands.push_back(from_functions<Options>(cli, add, run));`.
template <typename Options, typename Add, typename Run>
Subcommand from_functions(CLI::App& cli, Add add, Run run) {
  auto options = std::make_shared<Options>();
  CLI::App* app = add(cli, *options);
  return {app, [options, run] { return run(*options); }};
}

/// Writes a study's CSV (when asked) and its markdown report (to a file, or standard output),
/// followed by `appendix` (markdown).
template <typename Params, typename Report>
void write_reports(const Params& params, const Report& report, const std::string& csv_path,
                   const std::string& markdown_path, const std::string& appendix) {
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
  std::ostream& out = markdown_path.empty() ? std::cout : md;
  haptic::lab::write_markdown(params, report, out);
  if (!appendix.empty()) out << '\n' << appendix;
}

/// `--device CONFIG.json`, the alternative to giving the model's mass and damping by hand.
struct DeviceOption {
  std::string path;
  CLI::Option* device = nullptr;
  CLI::Option* mass = nullptr;
  CLI::Option* damping = nullptr;
  CLI::Option* period = nullptr;

  /// Adds --device, --mass, --damping and --period to `app`.
  void add(CLI::App* app, double& mass_kg, double& damping_n_s_m, double& period_s) {
    device = app->add_option("--device", path,
                             "take the device model (apparent mass, damping) and the loop rate from "
                             "this hapticd configuration (JSON); excludes --mass and --damping")
                 ->check(CLI::ExistingFile);
    mass = app->add_option("--mass", mass_kg, "device mass, kg (default 0.01)");
    damping = app->add_option("--damping", damping_n_s_m, "device damping, N*s/m (default 0.022)");
    period = app->add_option("--period", period_s,
                             "sample period T, s (default 0.001, or 1/loop_rate_hz with --device)");
  }

  /// With --device: the model, its mass, damping and (unless --period was given) period copied
  /// into the parameters (haptic::lab::apply_device_arguments).
  std::optional<haptic::lab::DeviceModel> apply(double& mass_kg, double& damping_n_s_m, double& period_s) const {
    return haptic::lab::apply_device_arguments({device->count() > 0 ? path : std::string(), mass->count() > 0,
                                                damping->count() > 0, period->count() > 0},
                                               mass_kg, damping_n_s_m, period_s);
  }
};

Subcommand add_run(CLI::App& cli) {
  struct Options {
    std::string scene_path, out_path;
    double duration_s = 1.0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* app = cli.add_subcommand("run", "run one scene and write a per-tick trace (CSV)");
  app->add_option("--scene", o->scene_path, "hapticd configuration (JSON haptic.v1.ServerConfig)")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--duration", o->duration_s, "simulated time, s (default 1)");
  app->add_option("--out", o->out_path, "trace file (CSV); default: standard output");
  return {app, [o] {
            const haptic::v1::ServerConfig config = haptic::config::load_config_file(o->scene_path);
            std::ofstream file;
            if (!o->out_path.empty()) {
              file.open(o->out_path);
              if (!file) throw std::invalid_argument(o->out_path + ": cannot write");
            }
            std::ostream& trace = o->out_path.empty() ? std::cout : file;
            // A bar for runs that take a while (over 1,000,000 ticks: ≳ 10 s with the trace).
            haptic::lab::ProgressBar bar("haptic-lab run", true);
            const haptic::lab::RunSummary summary = haptic::lab::run_scene(
                config, o->duration_s, trace, [&bar](std::uint64_t tick, std::uint64_t ticks) {
                  if (ticks > 1000000) bar.update(tick, ticks);
                });
            std::cerr << "haptic-lab: " << summary.ticks << " ticks; energy to the device "
                      << summary.energy_to_device << " J, from it " << summary.energy_from_device << " J; "
                      << summary.fault_ticks << " fault ticks; "
                      << (summary.finite ? "finite" : "NOT FINITE") << "\n";
            return summary.finite ? 0 : 3;
          }};
}

/// The hold model named on the command line. Throws std::invalid_argument otherwise.
haptic::engine::HoldModel hold_model_from_name(const std::string& name) {
  for (const haptic::engine::HoldModel hold : haptic::engine::kHoldModels) {
    if (name == haptic::engine::hold_model_name(hold)) return hold;
  }
  throw std::invalid_argument("--hold: must be second-order, delay, pade or exact, got \"" + name + "\"");
}

Subcommand add_transparency(CLI::App& cli) {
  struct Options {
    haptic::engine::WallDesignParams design;
    DeviceOption device;
    std::string hold = "second-order", csv_path, markdown_path;
  };
  auto o = std::make_shared<Options>();
  CLI::App* app = cli.add_subcommand(
      "transparency", "001's controller design for a device model: J(B_c), ||L||inf(B_c), the optimum");
  o->device.add(app, o->design.mass, o->design.damping, o->design.sample_period);
  app->add_option("--stiffness", o->design.wall_stiffness, "wall stiffness K, N/m (default 1000)");
  app->add_option("--wall-damping", o->design.wall_damping, "wall damping B, N*s/m (default 1)");
  app->add_option("--w1", o->design.weight_cutoff, "transparency weight cut-off, rad/s (default 100)");
  app->add_option("--alpha", o->design.mass_uncertainty, "mass uncertainty (default 0.5)");
  app->add_option("--beta", o->design.damping_uncertainty, "damping uncertainty (default 0.5)");
  app->add_option("--hold", o->hold,
                  "the hold's model for the sweep: second-order (default), delay, pade or exact; "
                  "the report gives every model's verdict");
  app->add_option("--csv", o->csv_path, "write the sweep as CSV here");
  app->add_option("--markdown", o->markdown_path, "write the report here; default: standard output");
  return {app, [o] {
            o->design.hold = hold_model_from_name(o->hold);
            const auto model = o->device.apply(o->design.mass, o->design.damping, o->design.sample_period);
            write_reports(o->design, haptic::lab::transparency_study(o->design), o->csv_path,
                          o->markdown_path, model ? haptic::lab::describe(*model) : std::string());
            return 0;
          }};
}

/// The wall discretization named on the command line. Throws std::invalid_argument otherwise.
haptic::engine::ImpedanceDiscretization discretization_from_name(const std::string& law) {
  if (law == "backward_difference") return haptic::engine::ImpedanceDiscretization::kBackwardDifference;
  if (law == "exact_zoh") return haptic::engine::ImpedanceDiscretization::kExactZoh;
  if (law == "tustin") return haptic::engine::ImpedanceDiscretization::kTustin;
  throw std::invalid_argument("--law: must be backward_difference, exact_zoh or tustin, got \"" + law + "\"");
}

Subcommand add_zwidth(CLI::App& cli) {
  struct Options {
    haptic::lab::ZWidthParams z;
    DeviceOption device;
    std::string law = "backward_difference", csv_path, markdown_path;
  };
  auto o = std::make_shared<Options>();
  CLI::App* app = cli.add_subcommand(
      "zwidth", "the (K, B) region a device model renders: Colgate's bound, eigenvalues, simulation");
  o->device.add(app, o->z.mass, o->z.damping, o->z.period);
  app->add_option("--law", o->law, "backward_difference (default), exact_zoh or tustin");
  app->add_option("--delay", o->z.delay_ticks, "extra ticks of delay (default 0)");
  app->add_option("--hand-mass", o->z.hand_mass, "operator's hand mass, kg (default 0)");
  app->add_option("--hand-stiffness", o->z.hand_stiffness, "hand stiffness, N/m (default 0)");
  app->add_option("--hand-damping", o->z.hand_damping, "hand damping, N*s/m (default 0)");
  app->add_option("--k-min", o->z.k_min, "grid: least stiffness, N/m (default 1)");
  app->add_option("--k-max", o->z.k_max, "grid: greatest stiffness, N/m (default 1e5)");
  app->add_option("--k-points", o->z.k_points, "grid: stiffnesses, log-spaced (default 16)");
  app->add_option("--b-max", o->z.b_max, "grid: greatest damping, N*s/m (default 10)");
  app->add_option("--b-points", o->z.b_points, "grid: dampings, 0 then log-spaced (default 12)");
  app->add_option("--csv", o->csv_path, "write the grid as CSV here");
  app->add_option("--markdown", o->markdown_path, "write the report here; default: standard output");
  return {app, [o] {
            o->z.discretization = discretization_from_name(o->law);
            const auto model = o->device.apply(o->z.mass, o->z.damping, o->z.period);
            write_reports(o->z, haptic::lab::zwidth(o->z), o->csv_path, o->markdown_path,
                          model ? haptic::lab::describe(*model) : std::string());
            return 0;
          }};
}

Subcommand add_identify(CLI::App& cli) {
  struct Options {
    haptic::lab::IdentifyParams p;
    std::string device_path, axis = "x", fit = "harmonics", csv_path, markdown_path;
    std::vector<double> zwidth_dampings, centering;
    std::string sweep_csv, profile_path;
    std::vector<std::size_t> sweep_periods{4, 8, 16, 32};
    std::vector<double> sweep_amplitudes;
  };
  auto o = std::make_shared<Options>();
  CLI::App* app = cli.add_subcommand(
      "identify", "a device axis's mass, damping, friction, delay, noise and quantization, from a multisine it plays "
                  "(docs/identification.md)");
  app->add_option("--device", o->device_path, "hapticd configuration (JSON) whose device is identified")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--port", o->p.port, "device port (default 0)");
  app->add_option("--axis", o->axis, "x (default), y or z, of W");
  app->add_flag("--along-motion", o->p.along_motion,
                "excite along the direction the tool moves when pushed along --axis (a device whose tool moves "
                "on a curve, 000's DC motor)");
  app->add_flag("--real-time", o->p.device_time.real_time,
                "pace the ticks at the loop's rate on the monotonic clock, for hardware behind a driver (the "
                "default runs them as fast as they compute: simulated devices and stand-ins that step per command)");
  app->add_option("--amplitude", o->p.signal.amplitude_n, "the force's peak, N (default 1)");
  app->add_option("--lag", o->p.max_lag_s,
                  "also fit a first-order lag between the command and the force, up to this many s (a motor's "
                  "or an amplifier's time constant; default 0: none)");
  app->add_option("--fit", o->fit,
                  "harmonics (default): at the excited harmonics; moving: in time, over the stretches where the "
                  "axis moved, for a device that friction holds still through part of each period");
  app->add_option("--centering", o->centering,
                  "K,B: a spring (N/m) and damper (N*s/m) about the start added to the excitation, for a device "
                  "that stick and slip walks away (default none)")
      ->delimiter(',')
      ->expected(2);
  app->add_option("--f-min", o->p.signal.f_min_hz, "lowest excited frequency, Hz (default 2)");
  app->add_option("--f-max", o->p.signal.f_max_hz, "highest, Hz (default 40)");
  app->add_option("--harmonics", o->p.signal.max_harmonics, "excited harmonics, log-spaced (default 24)");
  app->add_option("--period-ticks", o->p.signal.samples_per_period, "the multisine's period in ticks (default 2048)");
  app->add_option("--periods", o->p.signal.periods, "periods fitted, >= 4 (default 8)");
  app->add_option("--settle-periods", o->p.signal.settle_periods, "periods left out after the ramp (default 1)");
  app->add_option("--ramp", o->p.signal.ramp_s, "ramp in and out, s (default 0.5)");
  app->add_option("--box", o->p.limits.box_half_width_m,
                  "the tool may go this far from its start along each axis, m, or it stops (default 0.05)");
  app->add_option("--max-speed", o->p.limits.max_speed_m_s, "or faster than this, m/s (default 0.5)");
  app->add_option("--csv", o->csv_path, "write the frequency response (measured and model) as CSV here");
  app->add_option("--markdown", o->markdown_path, "write the report here; default: standard output");
  app->add_option("--zwidth", o->zwidth_dampings,
                  "also the Z-width at these wall dampings, N*s/m (comma-separated): predicted from the identified "
                  "model against walls of increasing stiffness run on the device itself")
      ->delimiter(',');
  app->add_option("--profile-out", o->profile_path,
                  "instead of one run: identify along x, y and z and write the port's profile (JSON) here, for "
                  "a driver port's configuration (driver.profile)");
  app->add_option("--sweep-csv", o->sweep_csv,
                  "instead of one run: identify at every pair of --sweep-periods and --sweep-amplitudes and write "
                  "each run's errors against the device's model and its intervals here (docs/numerics.md)");
  app->add_option("--sweep-periods", o->sweep_periods, "periods fitted (default 4,8,16,32)")->delimiter(',');
  app->add_option("--sweep-amplitudes", o->sweep_amplitudes, "peaks, N (default: --amplitude alone)")->delimiter(',');
  return {app, [o] {
            if (o->axis != "x" && o->axis != "y" && o->axis != "z") {
              throw std::invalid_argument("--axis: must be x, y or z, got \"" + o->axis + "\"");
            }
            o->p.axis = o->axis == "x" ? 0 : o->axis == "y" ? 1 : 2;
            if (o->fit != "harmonics" && o->fit != "moving") {
              throw std::invalid_argument("--fit: must be harmonics or moving, got \"" + o->fit + "\"");
            }
            if (o->centering.size() == 2) o->p.centering = {o->centering[0], o->centering[1]};
            o->p.fit_method =
                o->fit == "moving" ? haptic::engine::FitMethod::kMovingStretches : haptic::engine::FitMethod::kHarmonics;
            const haptic::v1::ServerConfig config = haptic::config::load_config_file(o->device_path);
            if (!o->profile_path.empty()) {
              const haptic::v1::DeviceProfile profile = haptic::lab::identify_profile(config, o->p, o->device_path);
              google::protobuf::util::JsonPrintOptions json;
              json.add_whitespace = true;
              json.preserve_proto_field_names = true;
              json.always_print_primitive_fields = true;
              std::string text;
              if (!google::protobuf::util::MessageToJsonString(profile, &text, json).ok()) {
                throw std::invalid_argument("profile: cannot be written as JSON");
              }
              std::ofstream out(o->profile_path);
              if (!out) throw std::invalid_argument(o->profile_path + ": cannot write");
              out << text << "\n";
              std::cerr << "haptic-lab identify: the profile (driver.profile) written to " << o->profile_path << "\n";
              return 0;
            }
            if (!o->sweep_csv.empty()) {
              if (o->sweep_amplitudes.empty()) o->sweep_amplitudes.push_back(o->p.signal.amplitude_n);
              haptic::lab::ProgressBar bar("haptic-lab identify --sweep", true);
              const auto rows = haptic::lab::identify_sweep(
                  config, o->p, o->sweep_periods, o->sweep_amplitudes, o->device_path,
                  [&bar](std::size_t done, std::size_t total) { bar.update(done, total); });
              std::ofstream csv(o->sweep_csv);
              if (!csv) throw std::invalid_argument(o->sweep_csv + ": cannot write");
              csv << haptic::lab::identify_sweep_csv(rows);
              std::cerr << "haptic-lab identify: " << rows.size() << " runs written to " << o->sweep_csv << "\n";
              return 0;
            }
            const haptic::lab::IdentifyResult result = haptic::lab::identify(config, o->p, o->device_path);
            if (!o->csv_path.empty()) {
              std::ofstream csv(o->csv_path);
              if (!csv) throw std::invalid_argument(o->csv_path + ": cannot write");
              csv << haptic::lab::identify_response_csv(result);
            }
            std::string report = haptic::lab::identify_report(result, o->p, o->device_path);
            if (!o->zwidth_dampings.empty()) {
              haptic::lab::ProgressBar bar("haptic-lab identify --zwidth", true);
              report += haptic::lab::zwidth_report(
                  haptic::lab::check_zwidth(config, o->p, result, o->zwidth_dampings,
                                            [&bar](std::size_t done, std::size_t total) { bar.update(done, total); }));
            }
            if (o->markdown_path.empty()) {
              std::cout << report;
            } else {
              std::ofstream md(o->markdown_path);
              if (!md) throw std::invalid_argument(o->markdown_path + ": cannot write");
              md << report;
            }
            return 0;
          }};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"haptic-lab: runs hapticd scenes in lockstep time and reports on them"};
  cli.require_subcommand(1);
  cli.set_version_flag("--version", std::string("haptic-lab ") + HAPTIC_VERSION +
                                        " (the engine and devices of hapticd " HAPTIC_VERSION ")");
  std::vector<Subcommand> commands;
  commands.push_back(add_run(cli));
  commands.push_back(add_transparency(cli));
  commands.push_back(add_zwidth(cli));
  commands.push_back(add_identify(cli));
  commands.push_back(from_functions<haptic::lab::StudyCommandOptions>(cli, haptic::lab::add_study_command,
                                                                     haptic::lab::run_study_command));
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // --help is 0; any mistake on the command line (a missing file among them) is 2, as a refused
    // parameter is below, whatever number CLI11 gives its kind of error.
    return cli.exit(error) == 0 ? 0 : 2;
  }

  for (const Subcommand& command : commands) {
    if (!*command.app) continue;
    try {
      return command.run();
    } catch (const std::exception& error) {
      std::cerr << "haptic-lab " << command.app->get_name() << ": " << error.what() << "\n";
      return 2;
    }
  }
  return 2;  // unreachable: require_subcommand(1)
}
