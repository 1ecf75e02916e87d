// hapticd's configuration: protobuf JSON, defaults, and errors that name the field.
#include <gtest/gtest.h>

#include <fstream>

#include "config/devices.hpp"
#include "config/federation_options.hpp"
#include "config/server_config.hpp"
#include "parse_error.hpp"

namespace haptic::config {
namespace {

TEST(Config, DefaultsAreTheDocumentedOnes) {
  const v1::ServerConfig config = default_config();
  EXPECT_EQ(config.grpc_address(), "127.0.0.1:50051");  // loopback unless asked otherwise
  EXPECT_EQ(config.udp_address(), "127.0.0.1");
  EXPECT_EQ(config.udp_port(), 50052u);
  EXPECT_EQ(config.loop_rate_hz(), 1000.0);
  EXPECT_EQ(config.time_mode(), v1::REAL_TIME);
  EXPECT_EQ(config.lease_timeout_ms(), 1000u);
  EXPECT_EQ(config.removal_ramp_ms(), 50u);
  EXPECT_EQ(config.simulated_point_mass().mass(), 0.01);      // Eom et al.
  EXPECT_EQ(config.simulated_point_mass().damping(), 0.022);  // Eom et al.
  EXPECT_TRUE(config.real_time().use_fifo());
  EXPECT_EQ(validate(config), "");
}

// The real-time defaults: a spin that fits every rate (200 µs, or 80 % of a shorter period), the
// State sender on the loop's CPU just below the loop's priority, and the loop's CPU left for the
// server to choose when it starts (runtime/loop_cpu.hpp).
TEST(Config, RealTimeDefaultsFitTheRateAndPutTheSenderJustBelowTheLoop) {
  EXPECT_EQ(default_config().real_time().spin_us(), 200u);
  EXPECT_EQ(parse_config(R"({"loop_rate_hz": 4000})", "x").real_time().spin_us(), 200u);
  EXPECT_EQ(parse_config(R"({"loop_rate_hz": 10000})", "x").real_time().spin_us(), 80u);  // valid at 10 kHz
  EXPECT_EQ(parse_config(R"({"real_time": {"spin_us": 30}})", "x").real_time().spin_us(), 30u);
  const v1::ServerConfig config = default_config();
  EXPECT_FALSE(config.real_time().has_cpu());
  EXPECT_EQ(config.real_time().sender_cpu(), kSenderOnLoopCpu);
  EXPECT_EQ(config.real_time().sender_priority(), config.real_time().fifo_priority() - 1);
  EXPECT_EQ(parse_config(R"({"real_time": {"use_fifo": false}})", "x").real_time().sender_priority(), 0);
  EXPECT_NE(error_of(R"({"real_time": {"sender_priority": 80}})").find("real_time.sender_priority"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"real_time": {"sender_cpu": -3}})").find("real_time.sender_cpu"),
            std::string::npos);
}

TEST(Config, ExplicitZeroIsKeptWhereZeroMeansSomething) {
  const v1::ServerConfig config =
      parse_config(R"({"udp_port": 0, "status_period_s": 0, "real_time": {"use_fifo": false}})", "x");
  EXPECT_EQ(config.udp_port(), 0u);        // pick a free port
  EXPECT_EQ(config.status_period_s(), 0u); // no status line
  EXPECT_FALSE(config.real_time().use_fifo());
}

TEST(Config, TheShippedConfigurationFileParses) {
  EXPECT_NO_THROW(load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/hapticd.json"));
  EXPECT_NO_THROW(load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/docker/hapticd-container.json"));
  EXPECT_TRUE(load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/dc_motor_000.json")
                  .has_simulated_dc_motor());
  EXPECT_TRUE(load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/five_bar_003.json")
                  .has_simulated_five_bar());
  EXPECT_TRUE(load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/joystick_004.json")
                  .has_simulated_joystick());
  EXPECT_TRUE(load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/parallel_dob_001.json")
                  .has_simulated_parallel_dob());
}

// A zero written out is a value, not "the default": a rate or a sub-step count of 0 is refused.
TEST(Config, AnExplicitZeroRateOrSubstepCountIsRefusedNotTakenForTheDefault) {
  EXPECT_NE(error_of(R"({"loop_rate_hz": 0})").find("loop_rate_hz: must be in [100, 10000], got 0"),
            std::string::npos)
      << error_of(R"({"loop_rate_hz": 0})");
  for (const char* device : {"simulated_point_mass", "simulated_dc_motor", "simulated_five_bar",
                             "simulated_joystick", "simulated_parallel_dob"}) {
    const std::string error = error_of(std::string("{\"") + device + "\": {\"substeps\": 0}}");
    EXPECT_NE(error.find(std::string(device) + ".substeps: must be 1 to 10000 (absent: 10), got 0"),
              std::string::npos)
        << error;
    const std::string too_many = error_of(std::string("{\"") + device + "\": {\"substeps\": 10001}}");
    EXPECT_NE(too_many.find(std::string(device) + ".substeps: must be 1 to 10000"), std::string::npos)
        << too_many;
  }
  // Absent, they take their defaults.
  const v1::ServerConfig config = parse_config("{}", "x");
  EXPECT_EQ(config.loop_rate_hz(), 1000.0);
  EXPECT_EQ(config.simulated_point_mass().substeps(), 10u);
  EXPECT_EQ(validate(config), "");
}

// One session, and one host's sessions, hold at most half of each server-wide budget unless told
// otherwise; a share above its whole is refused naming both; the handshake deadline is bounded.
TEST(Config, TheSharesOfTheBudgetsDefaultToHalfAndNeverExceedTheWhole) {
  const v1::ServerConfig config = default_config();
  EXPECT_EQ(config.max_scene_triangles_per_session(), 100'000u);
  EXPECT_EQ(config.max_scene_triangles_per_peer(), 100'000u);
  EXPECT_EQ(config.max_scene_bytes_per_session(), 32ull << 20);
  EXPECT_EQ(config.max_scene_bytes_per_peer(), 32ull << 20);
  EXPECT_EQ(config.max_event_streams_per_peer(), 16u);
  EXPECT_EQ(config.handshake_timeout_ms(), 5000u);
  EXPECT_NE(error_of(R"({"max_scene_triangles": 10, "max_scene_triangles_per_peer": 11})")
                .find("max_scene_triangles_per_peer: must be at most max_scene_triangles (10), got 11"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"max_event_streams": 8, "max_event_streams_per_peer": 9})")
                .find("max_event_streams_per_peer: must be at most max_event_streams (8), got 9"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"handshake_timeout_ms": 50})").find("handshake_timeout_ms: must be 100 to 60000, got 50"),
            std::string::npos);
}

TEST(Config, ADriversCallThreadRunsAtTheLoopsPriorityOnlyWhereTheLoopIsRealTimeWithFifo) {
  // The loop waits on a driver port's call thread every tick, so it asks for what the loop asks
  // for: real_time.fifo_priority in real time with use_fifo (the default, 80), and normal
  // scheduling in lockstep or with FIFO turned off.
  const auto priority = [](const std::string& json) {
    v1::ServerConfig config = config::parse_config(json, "test");
    config::fill_defaults(config);
    return config::driver_thread_priority(config);
  };
  EXPECT_EQ(priority("{}"), 80);
  EXPECT_EQ(priority(R"({"real_time": {"fifo_priority": 50}})"), 50);
  EXPECT_EQ(priority(R"({"real_time": {"use_fifo": false}})"), 0);
  EXPECT_EQ(priority(R"({"time_mode": "LOCKSTEP"})"), 0);
}

TEST(Config, BadValuesAreRejectedNamingTheField) {
  EXPECT_NE(error_of(R"({"loop_rate_hz": 20000})").find("loop_rate_hz"), std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_point_mass": {"coulomb": -0.1}})").find("simulated_point_mass.coulomb"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_point_mass": {"coulomb": 100}})").find("simulated_point_mass.coulomb"),
            std::string::npos);  // above the default max_force
  EXPECT_NE(error_of(R"({"simulated_point_mass": {"actuator_lag": 0.5}})").find("simulated_point_mass.actuator_lag"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_point_mass": {"mass": -1}})").find("simulated_point_mass.mass"),
            std::string::npos);
  // A simulated sensor's noise and step: finite, >= 0 and at most 10 mm.
  EXPECT_NE(error_of(R"({"simulated_point_mass": {"sensor": {"noise_m": -1e-6}}})")
                .find("simulated_point_mass.sensor.noise_m: must be finite and in [0, 0.01] m"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_point_mass": {"sensor": {"quantization_m": 0.5}}})")
                .find("simulated_point_mass.sensor.quantization_m"),
            std::string::npos);
  EXPECT_EQ(error_of(R"({"simulated_point_mass": {"sensor": {"noise_m": 1e-6, "quantization_m": 1e-6}}})"), "");
  // A simulated device's encoders: one value or one per joint, each finite in [0, 0.1].
  EXPECT_NE(error_of(R"({"simulated_joystick": {"encoders": {"quantization": [1e-4, 1e-4]}}})")
                .find("simulated_joystick.encoders.quantization: give one value for every joint or one per joint (3), got 2"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_parallel_dob": {"encoders": {"noise": [1e-5, -1e-5]}}})")
                .find("simulated_parallel_dob.encoders.noise[1]: must be finite and in [0, 0.1]"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_dc_motor": {"encoders": {"quantization": [0.5]}}})")
                .find("simulated_dc_motor.encoders.quantization[0]"),
            std::string::npos);
  EXPECT_EQ(error_of(R"({"simulated_joystick": {"encoders": {"quantization": [3.835e-4, 3.835e-4, 1e-3], "noise": [1e-5]}}})"), "");
  // The five-bar's counts are its own: noise only.
  EXPECT_NE(error_of(R"({"simulated_five_bar": {"encoders": {"quantization": [1e-4]}}})")
                .find("simulated_five_bar.encoders.quantization: must be empty"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_five_bar": {"encoders": {"noise": [1e-5], "tachometers": true}}})")
                .find("simulated_five_bar.encoders.tachometers: must be false"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_five_bar": {"encoders": {"noise": [1e-5, 1e-5]}}})")
                .find("simulated_five_bar.encoders.noise: give one value for every joint or one per joint (3)"),
            std::string::npos);
  EXPECT_EQ(error_of(R"({"simulated_five_bar": {"encoders": {"noise": [5e-5], "seed": 3}}})"), "");
  // A driver port's measured profile: each axis's mass > 0, damping >= 0, the delay in [0, 0.1] s.
  const std::string driver = R"({"driver": {"library": "x.so", "profile": )";
  EXPECT_NE(error_of(driver + R"({"apparent_mass": {"x": 0.1, "y": 0, "z": 0.1}}}})")
                .find("driver.profile.apparent_mass.y: must be finite and in (0, 1000] kg"),
            std::string::npos);
  EXPECT_NE(error_of(driver + R"({"apparent_mass": {"x": 0.1, "y": 0.1, "z": 0.1}, "apparent_damping": {"z": -1}}}})")
                .find("driver.profile.apparent_damping.z"),
            std::string::npos);
  EXPECT_NE(error_of(driver + R"({"apparent_mass": {"x": 0.1, "y": 0.1, "z": 0.1}, "actuator_lag_s": -0.001}}})")
                .find("driver.profile.actuator_lag_s: must be finite and in [0, 0.1] s"),
            std::string::npos);
  EXPECT_NE(error_of(driver + R"({"apparent_mass": {"x": 0.1, "y": 0.1, "z": 0.1}, "delay_s": 0.5}}})")
                .find("driver.profile.delay_s: must be finite and in [0, 0.1] s"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_point_mass": {"initial_position": {"z": 5}}})")
                .find("simulated_point_mass.initial_position"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"real_time": {"spin_us": 5000}})").find("real_time.spin_us"), std::string::npos);
  EXPECT_NE(error_of(R"({"session_force_budget": -1})").find("session_force_budget"), std::string::npos);
  EXPECT_NE(error_of(R"({"passivity": {"max_damping": "NaN"}})").find("passivity.max_damping"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"initial_scene": {"objects": [{"sphere": {"radius": 0.01}}]}})")
                .find("initial_scene.objects[0].impedance"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"initial_operator": {"mode": "APPLY_FORCE", "force": {"x": "NaN"}}})")
                .find("initial_operator.force.x"),
            std::string::npos);
  for (const char* bad : {"127.0.0.1", "127.0.0.1:", "127.0.0.1:http", "127.0.0.1:70000", ":9464",
                          "::1:9464"}) {
    const std::string error = error_of(std::string(R"({"metrics_address": ")") + bad + "\"}");
    EXPECT_NE(error.find("metrics_address: must be HOST:PORT or [IPv6]:PORT (port 0 to 65535; 0 "
                         "picks one), got '" + std::string(bad) + "'"),
              std::string::npos)
        << error;
  }
  for (const char* good : {"127.0.0.1:9464", "localhost:0", "[::1]:9464"}) {
    EXPECT_EQ(validate(parse_config(std::string(R"({"metrics_address": ")") + good + "\"}", "x")), "")
        << good;
  }
}

TEST(Config, TheViewersAddressIsCheckedAndWithTokensKeptOnLoopback) {
  const std::string bad = error_of(R"({"viewer_address": "127.0.0.1"})");
  EXPECT_NE(bad.find("viewer_address: must be HOST:PORT or [IPv6]:PORT (port 0 to 65535; 0 picks one), "
                     "got '127.0.0.1'"),
            std::string::npos)
      << bad;
  const std::string tokens =
      R"("security": {"tokens": [{"name": "v", "token": "observer-token-0123456789", "role": "OBSERVER"}]})";
  EXPECT_EQ(validate(parse_config(R"({"viewer_address": "127.0.0.1:8080", )" + tokens + "}", "x")), "");
  // Plain HTTP off loopback would carry the tokens in clear.
  const std::string remote = error_of(R"({"viewer_address": "0.0.0.0:8080", )" + tokens + "}");
  EXPECT_NE(remote.find("viewer_address: '0.0.0.0:8080' is not a loopback address, and the viewer speaks "
                        "plain HTTP, so the bearer tokens its page sends would cross the network in clear"),
            std::string::npos)
      << remote;
  EXPECT_EQ(validate(parse_config(
                R"({"viewer_address": "0.0.0.0:8080", "insecure_remote_access": true, )" + tokens + "}", "x")),
            "");
  // Without tokens there is nothing to leak but what it shows: served (with a warning at start).
  EXPECT_EQ(validate(parse_config(R"({"viewer_address": "0.0.0.0:8080"})", "x")), "");
}

TEST(Config, TheHttpFacesAddressAndOriginsAreCheckedAndItIsExposedAsGrpcIs) {
  EXPECT_EQ(validate(parse_config(R"({"http_address": "127.0.0.1:0"})", "x")), "");
  const std::string bad = error_of(R"({"http_address": "127.0.0.1"})");
  EXPECT_NE(bad.find("http_address: must be HOST:PORT or [IPv6]:PORT"), std::string::npos) << bad;
  // Off loopback as grpc_address: with TLS and tokens (HTTPS), or with insecure_remote_access.
  const std::string tokens_only = R"("security": {"tokens": [{"name": "v", "token": "observer-token-0123456789", "role": "OBSERVER"}]})";
  const std::string remote = error_of(R"({"http_address": "0.0.0.0:8081", )" + tokens_only + "}");
  EXPECT_NE(remote.find("http_address: '0.0.0.0:8081' is not a loopback address, and security has tokens but no TLS"),
            std::string::npos)
      << remote;
  EXPECT_EQ(validate(parse_config(R"({"http_address": "0.0.0.0:8081", "insecure_remote_access": true})", "x")), "");
  for (const char* good : {"http://lab.example", "https://lab.example:8443", "http://127.0.0.1:8080",
                           "http://[::1]:8080"}) {
    EXPECT_EQ(validate(parse_config(std::string(R"({"http_allowed_origins": [")") + good + "\"]}", "x")), "")
        << good;
  }
  for (const char* wrong : {"lab.example", "ftp://lab.example", "http://lab.example/", "http://lab.example:99999",
                            "*", "http://", "https://lab.example:8443/path", "http://user@lab.example"}) {
    const std::string error = error_of(std::string(R"({"http_allowed_origins": ["ok.example", ")") + wrong + "\"]}");
    EXPECT_NE(error.find("http_allowed_origins[0]: 'ok.example' has no scheme"), std::string::npos) << error;
    const std::string second =
        error_of(std::string(R"({"http_allowed_origins": ["http://ok.example", ")") + wrong + "\"]}");
    EXPECT_NE(second.find("http_allowed_origins[1]: '" + std::string(wrong) + "'"), std::string::npos) << second;
  }
}

TEST(Config, NonLoopbackAddressesAreRefusedUnlessInsecureRemoteAccessIsAccepted) {
  // Without TLS or tokens, a non-loopback bind would let anyone on the network command forces.
  EXPECT_EQ(error_of(R"({"grpc_address": "0.0.0.0:50051"})").rfind("test.json: grpc_address: '0.0.0.0:50051' is not a loopback address", 0), 0u)
      << error_of(R"({"grpc_address": "0.0.0.0:50051"})");
  EXPECT_NE(error_of(R"({"grpc_address": "[::]:0"})").find("grpc_address: '[::]:0'"), std::string::npos);
  EXPECT_NE(error_of(R"({"udp_address": "0.0.0.0"})").find("udp_address: '0.0.0.0' is not a loopback"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"grpc_address": "0.0.0.0:50051"})").find("--insecure"), std::string::npos);
  // Loopback in any spelling is accepted; so is anything once remote access is accepted.
  EXPECT_EQ(error_of(R"({"grpc_address": "127.0.0.1:0", "udp_address": "127.0.0.2"})"), "");
  EXPECT_EQ(error_of(R"({"grpc_address": "[::1]:0", "udp_address": "::1"})"), "");
  EXPECT_EQ(error_of(R"({"grpc_address": "localhost:0", "udp_address": "localhost"})"), "");
  EXPECT_EQ(error_of(R"({"grpc_address": "0.0.0.0:50051", "udp_address": "0.0.0.0",
                         "insecure_remote_access": true})"),
            "");
}

TEST(Config, BindAddressesSplitIntoHostAndLoopbackIsRecognised) {
  EXPECT_EQ(host_of_address("127.0.0.1:50051"), "127.0.0.1");
  EXPECT_EQ(host_of_address("[::1]:50051"), "::1");
  EXPECT_EQ(host_of_address("::1"), "::1");
  EXPECT_EQ(host_of_address("localhost:1"), "localhost");
  EXPECT_TRUE(is_loopback_host("127.0.0.1"));
  EXPECT_TRUE(is_loopback_host("127.255.0.9"));
  EXPECT_TRUE(is_loopback_host("::1"));
  EXPECT_TRUE(is_loopback_host("::ffff:127.0.0.1"));
  EXPECT_FALSE(is_loopback_host("0.0.0.0"));
  EXPECT_FALSE(is_loopback_host("::"));
  EXPECT_FALSE(is_loopback_host(""));
  EXPECT_FALSE(is_loopback_host("10.0.0.1"));
  EXPECT_FALSE(is_loopback_host("no-such-host.invalid"));
}

TEST(Config, ImpossibleDeviceParametersAreRejectedNamingThem) {
  EXPECT_NE(error_of(R"({"simulated_dc_motor": {"r": 1.5}})").find("simulated_dc_motor.r:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_dc_motor": {"eta": 0}})").find("simulated_dc_motor.eta:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_dc_motor": {"link_mass": -0.2}})").find("simulated_dc_motor.link_mass:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_dc_motor": {"gravity": "NaN"}})").find("simulated_dc_motor.gravity:"),
            std::string::npos);
  EXPECT_EQ(error_of(R"({"simulated_dc_motor": {"with_inductance": true, "gravity": 0}})"), "");
  EXPECT_NE(error_of(R"({"simulated_dc_motor": {"integrator": "rk45"}})")
                .find("simulated_dc_motor.integrator: unknown integrator \"rk45\""),
            std::string::npos);
}

TEST(Config, TheDocumentsDevicesAreCheckedNamingTheField) {
  EXPECT_NE(error_of(R"({"simulated_dc_motor": {}, "simulated_joystick": {}})")
                .find("at most one device"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_five_bar": {"velocity": "kalman"}})")
                .find("simulated_five_bar.velocity:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_five_bar": {"inertias": "guessed"}})")
                .find("simulated_five_bar.inertias:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_five_bar": {"substeps": 100000}})")
                .find("simulated_five_bar.substeps:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_joystick": {"max_force": -1}})").find("simulated_joystick.max_force:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_joystick": {"initial_shaft_length": 2}})")
                .find("simulated_joystick.initial_shaft_length:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_joystick": {"rearm_after_s": "NaN"}})")
                .find("simulated_joystick.rearm_after_s:"),
            std::string::npos);
  // Q's cut-off must lie below the Nyquist rate of the loop.
  EXPECT_NE(error_of(R"({"simulated_parallel_dob": {"cutoff_hz": 600}})")
                .find("simulated_parallel_dob.cutoff_hz:"),
            std::string::npos);
  EXPECT_EQ(error_of(R"({"loop_rate_hz": 2000, "simulated_parallel_dob": {"cutoff_hz": 600}})"), "");
  EXPECT_NE(error_of(R"({"simulated_parallel_dob": {"nominal_mass": -0.01}})")
                .find("simulated_parallel_dob.nominal_mass:"),
            std::string::npos);
  EXPECT_EQ(error_of(R"({"simulated_five_bar": {"velocity": "estimator", "coriolis": false}})"), "");
}

TEST(Config, TheSixDofPointMassTakesItsRotationsDefaultsAndNamesABadValue) {
  const v1::ServerConfig six = load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/six_dof.json");
  ASSERT_TRUE(six.simulated_point_mass().has_rotation());
  EXPECT_EQ(six.simulated_point_mass().rotation().inertia(), 1e-4);
  EXPECT_EQ(six.initial_scene().fields_size(), 2);
  const v1::ServerConfig defaults = parse_config(R"({"simulated_point_mass": {"rotation": {}}})", "x");
  EXPECT_EQ(defaults.simulated_point_mass().rotation().inertia(), 1e-4);
  EXPECT_EQ(defaults.simulated_point_mass().rotation().damping(), 5e-4);
  EXPECT_EQ(defaults.simulated_point_mass().rotation().max_torque(), 0.2);
  EXPECT_EQ(parse_config(R"({"simulated_point_mass": {"rotation": {"damping": 0}}})", "x")
                .simulated_point_mass().rotation().damping(),
            0.0);  // zero damping is a choice, not a default
  EXPECT_NE(error_of(R"({"simulated_point_mass": {"rotation": {"inertia": -1}}})")
                .find("simulated_point_mass.rotation.inertia:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"simulated_point_mass": {"rotation": {"initial_orientation": {"w": 2}}}})")
                .find("simulated_point_mass.rotation.initial_orientation: must be a unit quaternion"),
            std::string::npos);
}

TEST(Config, AFederationThatWouldLeaveItsDomainInTheClearOrNeverReachItsPeersIsWarnedOf) {
  const auto warnings_of = [](const char* json) {
    return federation_warnings(parse_config(json, "x").federation());
  };
  // allow_insecure on a LAN address: accepted, and said.
  const std::vector<std::string> clear =
      warnings_of(R"({"federation": {"site": "a", "interface": "192.168.10.11", "allow_insecure": true}})");
  ASSERT_EQ(clear.size(), 1u);
  EXPECT_NE(clear[0].find("federation: interface \"192.168.10.11\" without DDS Security (allow_insecure)"),
            std::string::npos)
      << clear[0];
  // The default interface "lo" with a peer on the LAN: that peer is never reached.
  const std::vector<std::string> unreachable =
      warnings_of(R"({"federation": {"site": "a", "peers": ["127.0.0.1", "192.168.10.12", "bench-b"]}})");
  ASSERT_EQ(unreachable.size(), 2u);
  EXPECT_NE(unreachable[0].find("peer \"192.168.10.12\" is not on this host, but the interface is \"lo\""),
            std::string::npos)
      << unreachable[0];
  EXPECT_NE(unreachable[1].find("peer \"bench-b\""), std::string::npos) << unreachable[1];
  // Nothing to say on loopback with peers on this host, or with none.
  EXPECT_TRUE(warnings_of(R"({"federation": {"site": "a", "peers": ["127.0.0.1"]}})").empty());
  EXPECT_TRUE(warnings_of(R"({"federation": {"site": "a"}})").empty());
}

TEST(Config, TheFederationSectionTakesItsDefaultsAndNamesABadField) {
  const v1::ServerConfig config = parse_config(R"({"federation": {"site": "bench-a.lab", "ros2": {}}})", "x");
  EXPECT_EQ(config.federation().interface(), "lo");
  EXPECT_EQ(config.federation().ros2().ros_namespace(), "/hapticd/bench_a_lab");
  EXPECT_EQ(config.federation().ros2().rate_hz(), 100.0);
  EXPECT_EQ(config.federation().ros2().frame_id(), "hapticd_world");
  EXPECT_EQ(config.federation().peer_credit().max_power_w(), 1.0);  // federation::CreditCap's
  EXPECT_EQ(config.federation().peer_credit().burst_j(), 0.1);
  EXPECT_EQ(relay_options(parse_config(R"({"federation": {"site": "a", "peer_credit": {"max_power_w": 0.25}}})", "x")
                              .federation(),
                          1000.0)
                .credit.max_power_W,
            0.25);
  EXPECT_NE(error_of(R"({"federation": {"site": "a", "peer_credit": {"burst_j": 0}}})")
                .find("federation.peer_credit.burst_j: must be > 0 and at most 100, got 0"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"federation": {}})").find("federation.site: must be 1 to 64 characters"), std::string::npos);
  // A site's name is its DDS partition: a pattern would speak for other sites.
  for (const char* site : {"bench-*", "bench?", "[ab]", "-lead", "bench a"}) {
    EXPECT_NE(error_of(std::string(R"({"federation": {"site": ")") + site + "\"}}")
                  .find("federation.site: letters, digits, '.', '_' and '-' only"),
              std::string::npos)
        << site;
  }
  EXPECT_NE(error_of(R"({"federation": {"site": "a", "domain_id": 500}})")
                .find("federation.domain_id: must be 0 to 232, got 500"),
            std::string::npos);
  // Off this host only with DDS Security or the explicit flag, and the message says both.
  const std::string leaves = error_of(R"({"federation": {"site": "a", "interface": "eth0"}})");
  EXPECT_NE(leaves.find("federation.interface: \"eth0\" leaves this host without DDS Security"), std::string::npos)
      << leaves;
  EXPECT_NE(leaves.find("set federation.security"), std::string::npos) << leaves;
  EXPECT_NE(leaves.find("federation.allow_insecure: true"), std::string::npos) << leaves;
  EXPECT_EQ(parse_config(R"({"federation": {"site": "a", "interface": "eth0", "allow_insecure": true}})", "x")
                .federation().interface(),
            "eth0");
  // An address or name that only looks like loopback leaves this host too; loopback's own stay.
  for (const char* away : {"10.0.127.1", "127.example.com", "0.0.0.0"}) {
    EXPECT_NE(error_of(std::string(R"({"federation": {"site": "a", "interface": ")") + away + R"("}})")
                  .find("leaves this host without DDS Security"),
              std::string::npos)
        << away;
  }
  for (const char* here : {"lo", "127.0.0.1", "::1", "::ffff:127.0.0.1"}) {
    EXPECT_EQ(parse_config(std::string(R"({"federation": {"site": "a", "interface": ")") + here + R"("}})", "x")
                  .federation().interface(),
              here);
  }
  EXPECT_NE(error_of(R"({"federation": {"site": "a", "ros2": {"rate_hz": 5000}}})")
                .find("federation.ros2.rate_hz: must be 1 to 1000 and at most the loop rate"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"federation": {"site": "a", "ros2": {"ros_namespace": "no-slash"}}})")
                .find("federation.ros2.ros_namespace:"),
            std::string::npos);
}

TEST(Config, AFederationsRos2WrenchInputIsOffUnlessSetAndTakesItsDefaults) {
  const v1::ServerConfig off = parse_config(R"({"federation": {"site": "a", "ros2": {}}})", "x");
  EXPECT_FALSE(off.federation().ros2().has_wrench_input());
  EXPECT_EQ(relay_options(off.federation(), 1000.0).ros2->wrench_topic, "");
  const v1::ServerConfig on = parse_config(R"({"federation": {"site": "a", "ros2": {"wrench_input": {}}}})", "x");
  const v1::Ros2WrenchInputConfig& input = on.federation().ros2().wrench_input();
  EXPECT_EQ(input.topic(), "wrench_command");
  EXPECT_EQ(input.force_scale(), 1.0);
  EXPECT_EQ(input.stale_s(), 0.2);
  EXPECT_EQ(relay_options(on.federation(), 1000.0).ros2->wrench_topic, "wrench_command");
  const runtime::RobotWrenchParams params = robot_wrench_params(on.federation());
  EXPECT_EQ(params.force_scale, 1.0);
  EXPECT_EQ(params.stale_s, 0.2);
  const auto refused = [](const std::string& input_json, const std::string& message) {
    const std::string error = error_of(R"({"federation": {"site": "a", "ros2": {"wrench_input": )" + input_json + "}}}");
    EXPECT_NE(error.find(message), std::string::npos) << error;
  };
  refused(R"({"force_scale": 20})", "federation.ros2.wrench_input.force_scale: must be 0 to 10, got 20");
  refused(R"({"force_scale": -1})", "federation.ros2.wrench_input.force_scale: must be 0 to 10");
  refused(R"({"stale_s": 0})", "federation.ros2.wrench_input.stale_s: must be 0.01 to 5, got 0");
  refused(R"({"topic": "wrench"})", "federation.ros2.wrench_input.topic: \"wrench\" is one hapticd publishes");
  refused(R"({"topic": "/abs"})", "federation.ros2.wrench_input.topic: must be names");
}

/// A federation section on eth0 with DDS Security, every file `file` but the governance.
std::string secure_federation(const std::string& file, const std::string& governance, const std::string& extra = "") {
  return R"({"federation": {"site": "a", "interface": "eth0", )" + extra + R"("security": {"identity_ca": ")" + file +
         R"(", "identity_certificate": ")" + file + R"(", "identity_private_key": ")" + file +
         R"(", "permissions_ca": ")" + file + R"(", "governance": ")" + governance + R"(", "permissions": ")" +
         file + R"("}}})";
}

TEST(Config, FederationSecurityLetsTheFederationLeaveThisHostAndEachOfItsFilesIsChecked) {
  // Any readable file passes the load's checks; what is in it is Cyclone's to judge (the
  // federation's tests give it real ones).
  const std::string file = std::string(HAPTIC_SOURCE_DIR) + "/scripts/federation-certs";
  const v1::ServerConfig config = parse_config(secure_federation(file, file), "x");
  EXPECT_EQ(config.federation().security().governance(), file);
  const federation::RelayOptions relay = relay_options(config.federation(), 1000.0);
  ASSERT_TRUE(relay.domain.security.has_value());
  EXPECT_EQ(relay.domain.security->identity_certificate, file);
  EXPECT_EQ(relay.domain.security->governance, file);
  EXPECT_FALSE(relay_options(parse_config(R"({"federation": {"site": "a"}})", "x").federation(), 1000.0)
                   .domain.security.has_value());

  // Each message names the field and says what is wrong with it.
  const auto refused = [](const std::string& json, const std::string& message) {
    const std::string error = error_of(json);
    EXPECT_NE(error.find(message), std::string::npos) << error;
  };
  refused(secure_federation(file, "/x/gov.p7s"), "federation.security.governance: cannot read /x/gov.p7s");
  refused(secure_federation(file, "gov.p7s"),
          "federation.security.governance: must be an absolute path of letters, digits and / . _ - +");
  refused(secure_federation(file, "/x/gov.p7s</Governance>"), "federation.security.governance: must be an absolute path");
  refused(secure_federation(file, ""), "federation.security.governance: required with security");
  refused(secure_federation("/x/ca.pem", file), "federation.security.identity_ca: cannot read /x/ca.pem");
  refused(secure_federation(file, file, R"("domain_id": 231, )"), "federation.domain_id: must be 0 to 230 with security");
  refused(R"({"federation": {"site": "a", "security": {}}})", "federation.security.identity_ca: required");
}

TEST(Config, ExtraDevicesAreCheckedLikePortZerosNamingTheirIndex) {
  // Defaults fill an extra point mass like port 0's; any device may be an extra one.
  const v1::ServerConfig config = parse_config(
      R"({"extra_devices": [{"simulated_point_mass": {"initial_position": {"y": 0.02}}},
                            {"simulated_joystick": {}}]})", "x");
  ASSERT_EQ(config.extra_devices_size(), 2);
  EXPECT_EQ(config.extra_devices(0).simulated_point_mass().mass(), 0.01);
  EXPECT_EQ(config.extra_devices(0).simulated_point_mass().max_force(), 20.0);
  EXPECT_TRUE(config.extra_devices(1).has_simulated_joystick());
  EXPECT_TRUE(load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/multi_user.json")
                  .extra_devices(0).has_simulated_point_mass());

  const std::string bad_mass = error_of(
      R"({"extra_devices": [{"simulated_point_mass": {}}, {"simulated_point_mass": {"mass": -1}}]})");
  EXPECT_NE(bad_mass.find("extra_devices[1].simulated_point_mass.mass:"), std::string::npos) << bad_mass;
  EXPECT_NE(error_of(R"({"extra_devices": [{"simulated_point_mass": {"initial_position": {"z": 5}}}]})")
                .find("extra_devices[0].simulated_point_mass.initial_position:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"extra_devices": [{"simulated_five_bar": {"velocity": "kalman"}}]})")
                .find("extra_devices[0].simulated_five_bar.velocity:"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"extra_devices": [{"simulated_parallel_dob": {"cutoff_hz": 600}}]})")
                .find("extra_devices[0].simulated_parallel_dob.cutoff_hz:"),
            std::string::npos);
  const std::string empty = error_of(R"({"extra_devices": [{}]})");
  EXPECT_NE(empty.find("extra_devices[0].device: must set one of"), std::string::npos) << empty;
  std::string eight = R"({"extra_devices": [)";
  for (int i = 0; i < 8; ++i) eight += std::string(i ? "," : "") + R"({"simulated_point_mass": {}})";
  eight += "]}";
  EXPECT_NE(error_of(eight).find("extra_devices: at most 7"), std::string::npos) << error_of(eight);
}

TEST(SceneFile, TheShippedSceneLoadsAndBadOnesNameTheFileAndTheElement) {
  const v1::Scene scene =
      load_scene_file(std::string(HAPTIC_SOURCE_DIR) + "/config/scenes/wall_sphere_spring.json");
  EXPECT_EQ(scene.objects_size(), 2);
  EXPECT_EQ(scene.fields_size(), 1);
  EXPECT_TRUE(scene.objects(1).has_sphere());

  const std::string path = ::testing::TempDir() + "/bad_scene.json";
  const auto error_for = [&](const std::string& json) {
    {
      std::ofstream out(path);
      out << json;
    }
    try {
      load_scene_file(path);
    } catch (const ConfigError& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  EXPECT_EQ(error_for(R"({"objects": [{"impedance": {"stiffness": 100}, "sphere": {"radius": -1}}]})")
                .rfind(path + ": objects[0].sphere.radius", 0),
            0u);
  EXPECT_NE(error_for(R"({"objects": [{"colour": 3}]})").find("not a valid Scene"), std::string::npos);
  EXPECT_NE(error_for(R"({"fields": [{"spring_to_point": {"stiffness": "NaN"}}]})")
                .find("fields[0].spring_to_point.stiffness"),
            std::string::npos);
  EXPECT_EQ(error_for(R"({"objects": []})"), "");
}

TEST(Config, MalformedJsonAndUnknownFieldsAreErrorsNamingTheSource) {
  EXPECT_NE(error_of("{").find("test.json"), std::string::npos);
  const std::string unknown = error_of(R"({"loop_rate": 1000})");
  EXPECT_NE(unknown.find("test.json"), std::string::npos);
  EXPECT_NE(unknown.find("loop_rate"), std::string::npos);
  EXPECT_THROW(load_config_file("/nonexistent/hapticd.json"), ConfigError);
}

}  // namespace
}  // namespace haptic::config
