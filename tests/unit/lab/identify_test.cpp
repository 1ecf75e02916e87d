// haptic-lab identify on the devices themselves, in lockstep: the point mass's mass and damping
// come back as its configuration gives them, with the hold's half tick as its delay; a run that
// carries the tool out of its box is stopped and refused saying how to change it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <initializer_list>
#include <string>

#include "config/server_config.hpp"
#include "engine/scene/impedance.hpp"
#include "lab/device_zwidth.hpp"
#include "lab/identify.hpp"

namespace haptic::lab {
namespace {

IdentifyParams light_excitation(double amplitude_n) {
  IdentifyParams p;
  p.axis = 0;
  p.signal.amplitude_n = amplitude_n;
  p.signal.periods = 6;
  return p;
}

TEST(LabIdentify, ThePointMassIsItsConfiguredMassAndDampingWithTheHoldsHalfTick) {
  // Eom et al.'s device: 10 g, 0.022 N·s/m, at 1 kHz (the configuration's defaults).
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP"})", "test");
  const IdentifyParams params = light_excitation(0.02);
  const IdentifyResult result = identify(config, params, "test");
  ASSERT_TRUE(result.model_mass && result.model_damping) << result.model_method;
  EXPECT_EQ(result.model_method, "description");
  EXPECT_NEAR(result.fit.mass.value, 0.01, 0.01 * 0.01);
  EXPECT_NEAR(result.fit.damping.value, 0.022, 0.05 * 0.022);
  EXPECT_NEAR(result.fit.delay.value, 0.5e-3, 0.1e-3);
  EXPECT_NEAR(result.fit.coulomb.value, 0.0, 1e-4);
  EXPECT_LT(result.fit.relative_residual, 0.01);
  const std::string report = identify_report(result, params, "test");
  EXPECT_NE(report.find("| mass (kg) |"), std::string::npos) << report;
  const std::string csv = identify_response_csv(result);
  EXPECT_EQ(csv.rfind("frequency_hz,measured_m_per_n", 0), 0u);
  std::printf("%s", report.c_str());
}

TEST(LabIdentify, AnExcitationThatCarriesTheToolOutOfItsBoxIsStoppedAndRefusedSayingWhatToChange) {
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP"})", "test");
  const auto refusal = [&](const IdentifyParams& params) {
    try {
      identify(config, params, "test");
    } catch (const std::invalid_argument& error) {
      return std::string(error.what());
    }
    return std::string("not refused");
  };
  // 2 N on 10 g: faster than 0.5 m/s within a quarter second.
  std::string what = refusal(light_excitation(2.0));
  EXPECT_NE(what.find("the excitation stopped at tick"), std::string::npos) << what;
  EXPECT_NE(what.find("faster than"), std::string::npos) << what;
  EXPECT_NE(what.find("lower the amplitude"), std::string::npos) << what;
  // Allowed any speed, it leaves its ±50 mm box instead.
  IdentifyParams fast = light_excitation(2.0);
  fast.limits.max_speed_m_s = 100.0;
  what = refusal(fast);
  EXPECT_NE(what.find("left its box of ±50"), std::string::npos) << what;
  IdentifyParams bad = light_excitation(0.02);
  bad.axis = 3;
  EXPECT_THROW(identify(config, bad, "test"), std::invalid_argument);
  bad = light_excitation(0.02);
  bad.port = 4;
  EXPECT_THROW(identify(config, bad, "test"), std::invalid_argument);
}

/// The Z-width the identified model predicts (the sampled wall's analysis with the identified
/// mass, damping and delay beyond the hold) against the device's own, walls of increasing K run on
/// it in lockstep along the identified direction, at three dampings: within 10 %. Returns the
/// largest error (a fraction).
double predicted_against_measured(const v1::ServerConfig& config, const IdentifyParams& params,
                                  std::initializer_list<double> dampings) {
  const IdentifyResult id = identify(config, params, "test");
  const engine::MassDamperDevice model{id.fit.mass.value, id.fit.damping.value};
  // The delay beyond the hold's half tick, in ticks, fractional (the analysis interpolates).
  const double delay_ticks = std::max(0.0, (id.fit.delay.value - id.period_s / 2.0) / id.period_s);
  DeviceWallParams wall;
  wall.direction = id.direction;
  double worst = 0.0;
  for (const double damping : dampings) {
    const double predicted = engine::sampled_wall_margin({100.0, damping, 0.0}, engine::ImpedanceDiscretization::kBackwardDifference,
                                                         model, id.period_s, delay_ticks)
                                 .max_stable_stiffness;
    // From a guess off by a factor 3, so the bracket is found, not given.
    const double measured = device_zwidth_boundary(config, wall, damping, 3.0 * predicted);
    std::printf("  B %.2f N·s/m: K_max predicted %.1f N/m, measured on the device %.1f N/m (%+.1f %%)", damping,
                predicted, measured, 100.0 * (predicted - measured) / measured);
    if (id.model_mass && id.model_damping) {
      // What the device's own description would have predicted, for comparison.
      const double described = engine::sampled_wall_margin({100.0, damping, 0.0},
                                                           engine::ImpedanceDiscretization::kBackwardDifference,
                                                           {*id.model_mass, *id.model_damping}, id.period_s, 0)
                                   .max_stable_stiffness;
      std::printf("; from the description's figures %.1f N/m (%+.1f %%)", described, 100.0 * (described - measured) / measured);
    }
    std::printf("\n");
    EXPECT_NEAR(predicted, measured, 0.10 * measured) << "B = " << damping;
    worst = std::max(worst, std::abs(predicted - measured) / measured);
  }
  return worst;
}

TEST(LabIdentify, TheIdentifiedModelPredictsThePointMasssOwnZWidthWithin10Percent) {
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP"})", "test");
  EXPECT_LT(predicted_against_measured(config, light_excitation(0.02), {0.0, 0.1, 0.3}), 0.01);
}

TEST(LabIdentify, TheDcMotorAlongItsLinksTangentIsWhatItsLoopSeesAndPredictsItsZWidth) {
  // 000's DC motor, its gearbox and link: the tool moves on a circle, so it is excited along the
  // motion a push along y gives (the link's tangent).
  const v1::ServerConfig config =
      config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/dc_motor_000.json");
  IdentifyParams params = light_excitation(0.2);
  params.axis = 1;
  params.along_motion = true;
  const IdentifyResult id = identify(config, params, "test");
  EXPECT_NEAR(std::abs(id.direction.y), 0.8765, 1e-3);
  predicted_against_measured(config, params, {1.0, 5.0, 20.0});
}

}  // namespace
}  // namespace haptic::lab
