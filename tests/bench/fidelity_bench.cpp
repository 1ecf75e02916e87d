// Model fidelity against run time for every simulated device: each integrator and sub-step count,
// and each model term a configuration may drop (000's inductance, 003's Coriolis terms, 003's
// flexible mode), run the same 1 s scenario (the simulated hand pushing with a 2 Hz sine, no scene
// force) and report the largest tool-position error against a reference (RK4, 200 sub-steps per
// 1 ms tick, every term on) next to the CPU time per simulated millisecond. Error and time come
// from the same run, so the ratios between rows are what to read on a noisy machine.
//
// The flexible five-bar is its own entry, "003 five-bar, flexible": its reference is the flexible
// model, and its position is the physical (deflected) tip the hand holds, since the device's
// reading is the rigid tip of the joints and would hide the deflection; its "rigid" row is the
// error of dropping the mode.
//
// Usage: fidelity_bench [--csv FILE]   (the CSV has one row per configuration)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "runtime/dc_motor_model.hpp"
#include "runtime/device_port.hpp"
#include "runtime/five_bar_model.hpp"
#include "runtime/joystick_model.hpp"
#include "runtime/parallel_dob_model.hpp"
#include "runtime/simulated_dc_motor_device.hpp"
#include "runtime/simulated_dob_device.hpp"
#include "runtime/simulated_five_bar_device.hpp"
#include "runtime/simulated_joystick_device.hpp"

using namespace haptic;

namespace {

constexpr double kT = 1e-3;   // tick, s
constexpr int kTicks = 1000;  // 1 s
constexpr const char* kFlexibleFiveBar = "003 five-bar, flexible";

struct Variant {
  std::string device;
  std::string model;  // the model-term choice ("full", "no inductance", …)
  engine::IntegrationSettings integration;
};

engine::HandInput sine_push(engine::Vec3 amplitude) {
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kApplyForce;
  hand.force = amplitude;
  hand.profile.shape = engine::ForceProfile::Shape::kSine;
  hand.profile.frequency_hz = 2.0;
  return hand;
}

/// Builds the device a variant describes, with the scenario's hand already set.
/// A device with its model, driven at its tool point.
struct Modelled {
  std::unique_ptr<runtime::SimulatedDevice> device;
  std::unique_ptr<runtime::DeviceModel> model;
  std::unique_ptr<runtime::DevicePort> port;
};

Modelled modelled(std::unique_ptr<runtime::SimulatedDevice> device,
                  std::unique_ptr<runtime::DeviceModel> model) {
  auto port = std::make_unique<runtime::DevicePort>(*device, *model);
  return {std::move(device), std::move(model), std::move(port)};
}

Modelled make(const Variant& v) {
  if (v.device == "000 DC motor") {
    auto d = std::make_unique<runtime::SimulatedDcMotorDevice>(
        engine::DcMotorParams{},
        v.model == "no inductance" ? engine::DcMotorModel::kWithoutInductance
                                   : engine::DcMotorModel::kWithInductance,
        0.5, 5.0, v.integration);
    d->set_hand(sine_push({0.0, 0.5, 0.0}));
    return modelled(std::move(d), std::make_unique<runtime::DcMotorModel>(engine::DcMotorParams{}, true));
  }
  if (v.device == "003 five-bar" || v.device == kFlexibleFiveBar) {
    runtime::SimulatedFiveBarOptions options;
    options.plant.integration = v.integration;
    options.plant.coriolis = v.model != "no Coriolis";
    options.plant.flexible_mode = v.model == "flexible";
    options.quantized = false;  // compare the plant, not the encoders
    auto d = std::make_unique<runtime::SimulatedFiveBarDevice>(engine::FiveBarParams{},
                                                               engine::FiveBarState{}, options);
    d->set_hand(sine_push({2.0, 2.0, 2.0}));
    return modelled(std::move(d), std::make_unique<runtime::FiveBarModel>(engine::FiveBarParams{},
                                                                          options.velocity_cutoff));
  }
  if (v.device == "004 joystick") {
    runtime::SimulatedJoystickConfig config;
    config.integration = v.integration;
    auto d = std::make_unique<runtime::SimulatedJoystickDevice>(config);
    d->set_hand(sine_push({3.0, 3.0, 0.0}));
    return modelled(std::move(d), std::make_unique<runtime::JoystickModel>(config.model()));
  }
  engine::Parallel2DofParams params;
  params.integration = v.integration;
  auto d = std::make_unique<runtime::SimulatedDobDevice>(params, engine::Vec3{0.0, 0.25, 0.0}, 10.0);
  d->set_hand(sine_push({0.02, 0.02, 0.0}));
  return modelled(std::move(d), std::make_unique<runtime::ParallelDobModel>(
                                    params, engine::DisturbanceObserverParams{}, engine::Vec3{0.0, 0.25, 0.0}));
}

struct Run {
  std::vector<engine::Vec3> positions;
  double seconds = 0.0;  // CPU-ish wall time of the best of three runs
};

Run simulate(const Variant& v) {
  Run best;
  for (int repetition = 0; repetition < 3; ++repetition) {
    Modelled device = make(v);
    // The flexible entry compares the physical tip (see the header).
    const auto* five_bar = v.device == kFlexibleFiveBar
                               ? static_cast<const runtime::SimulatedFiveBarDevice*>(device.device.get())
                               : nullptr;
    Run run;
    run.positions.reserve(kTicks);
    runtime::ToolReading reading;
    engine::Vec3 p_WT, v_WT;
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; k < kTicks; ++k) {
      device.port->write(runtime::ToolCommand{}, kT);
      device.port->read(reading);
      if (five_bar != nullptr) {
        five_bar->plant().physical_tip_state(p_WT, v_WT);
        run.positions.push_back(p_WT);
      } else {
        run.positions.push_back(reading.p_WT);
      }
    }
    run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (repetition == 0 || run.seconds < best.seconds) best = std::move(run);
  }
  return best;
}

double max_error(const Run& run, const Run& reference) {
  double worst = 0.0;
  for (std::size_t k = 0; k < run.positions.size(); ++k) {
    const double e = engine::norm(run.positions[k] - reference.positions[k]);
    worst = std::isfinite(e) ? std::max(worst, e) : INFINITY;
  }
  return worst;
}

}  // namespace

int main(int argc, char** argv) {
  std::string csv_path;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--csv" && i + 1 < argc) csv_path = argv[++i];
  }
  struct Device {
    std::string name;
    std::vector<std::string> models;  // the first is the reference's
  };
  const std::vector<Device> devices = {{"000 DC motor", {"full", "no inductance"}},
                                       {"003 five-bar", {"full", "no Coriolis"}},
                                       {kFlexibleFiveBar, {"flexible", "rigid"}},
                                       {"004 joystick", {"full"}},
                                       {"001 parallel DOB", {"full"}}};
  const engine::Integrator methods[] = {engine::Integrator::kExplicitEuler,
                                        engine::Integrator::kSemiImplicitEuler, engine::Integrator::kRk4,
                                        engine::Integrator::kImplicitEuler, engine::Integrator::kTrapezoidal};
  const std::uint32_t substeps[] = {1, 2, 5, 10, 20};

  std::ofstream csv;
  if (!csv_path.empty()) {
    csv.open(csv_path);
    csv << "device,model,integrator,substeps,max_error_m,us_per_simulated_ms\n";
  }
  std::printf("%-22s %-14s %-20s %8s %14s %12s\n", "device", "model", "integrator", "substeps",
              "max error [m]", "µs per ms");
  std::size_t total = 0;
  for (const Device& device : devices) total += device.models.size() * std::size(methods) * std::size(substeps);
  std::size_t done = 0;
  for (const Device& device : devices) {
    const Run reference = simulate({device.name, device.models.front(), {engine::Integrator::kRk4, 200}});
    for (const std::string& model : device.models) {
      for (const engine::Integrator method : methods) {
        for (const std::uint32_t n : substeps) {
          const Variant v{device.name, model, {method, n}};
          const Run run = simulate(v);
          const double error = max_error(run, reference);
          const double us_per_ms = run.seconds * 1e6 / kTicks;
          std::printf("%-22s %-14s %-20s %8u %14.3g %12.2f\n", device.name.c_str(), model.c_str(),
                      std::string(engine::integrator_name(method)).c_str(), n, error, us_per_ms);
          if (csv.is_open()) {
            csv << device.name << ',' << model << ',' << engine::integrator_name(method) << ',' << n
                << ',' << error << ',' << us_per_ms << '\n';
          }
          ++done;
          std::fprintf(stderr, "\r[%3zu%%]", 100 * done / total);
        }
      }
    }
  }
  std::fprintf(stderr, "\n");
  return 0;
}
