// The metrics endpoint's text: Prometheus' exposition format (0.0.4), checked line by line, and
// every figure of GetStats in it under its conventional name.
#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "net/prometheus_text.hpp"

namespace haptic::net {
namespace {

/// name -> samples (labels -> value), and each family's TYPE; fails the test on any line the
/// format does not allow, a sample before its family's TYPE, or a family described twice.
struct Parsed {
  std::map<std::string, std::string> types;
  std::map<std::string, std::map<std::string, double>> samples;
};

Parsed parse(const std::string& text) {
  static const std::regex help(R"(# HELP ([a-zA-Z_:][a-zA-Z0-9_:]*) .+)");
  static const std::regex type(R"(# TYPE ([a-zA-Z_:][a-zA-Z0-9_:]*) (counter|gauge|summary|histogram|untyped))");
  static const std::regex sample(
      R"(([a-zA-Z_:][a-zA-Z0-9_:]*)(\{((?:[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\]|\\.)*",?)*)\})? (\S+))");
  Parsed parsed;
  std::set<std::string> helped;
  std::istringstream lines(text);
  std::string line;
  std::smatch match;
  while (std::getline(lines, line)) {
    if (std::regex_match(line, match, help)) {
      EXPECT_TRUE(helped.insert(match[1]).second) << "HELP twice: " << line;
    } else if (std::regex_match(line, match, type)) {
      EXPECT_TRUE(parsed.types.emplace(match[1], match[2]).second) << "TYPE twice: " << line;
    } else if (std::regex_match(line, match, sample)) {
      const std::string name = match[1];
      EXPECT_TRUE(parsed.types.count(name)) << "sample before its TYPE: " << line;
      std::size_t used = 0;
      const double value = std::stod(match[4].str(), &used);
      EXPECT_EQ(used, match[4].length()) << line;
      EXPECT_TRUE(parsed.samples[name].emplace(match[3], value).second) << "sample twice: " << line;
    } else {
      ADD_FAILURE() << "not a line of the format: '" << line << "'";
    }
  }
  return parsed;
}

TEST(PrometheusText, EveryFigureIsThereUnderItsConventionalName) {
  v1::Stats stats;
  stats.set_ticks(12345);
  stats.set_achieved_rate_hz(999.5);
  stats.set_lateness_p50_us(3);
  stats.set_lateness_p99_us(40);
  stats.set_lateness_p999_us(900);
  stats.set_lateness_max_us(2500);
  stats.set_window_s(10);
  stats.set_overruns(2);
  stats.set_sessions(2);
  stats.set_datagrams_sent(777);
  stats.set_force_faults(1);
  stats.set_send_delay_p50_us(12);
  v1::ClientStats& a = *stats.add_clients();
  a.set_session_id(0x1234);
  a.set_client_name("viewer \"left\"\\1\nx");  // every character the format escapes
  a.set_datagrams_sent(700);
  a.set_states_received(690);
  a.set_states_lost(10);
  a.set_heartbeats(50);
  a.set_last_heartbeat_age_s(0.05);
  a.set_round_trip_samples(50);
  a.set_round_trip_p50_us(150);
  a.set_round_trip_p99_us(400);
  a.set_round_trip_p999_us(800);
  v1::ClientStats& b = *stats.add_clients();
  b.set_session_id(0xabcdef);
  b.set_client_name("observer");
  b.set_last_heartbeat_age_s(-1);

  const std::string text = prometheus_text(stats);
  const Parsed parsed = parse(text);
  // Conventions: the prefix everywhere, counters and only counters end in _total.
  for (const auto& [name, type] : parsed.types) {
    EXPECT_EQ(name.rfind("hapticd_", 0), 0u) << name;
    EXPECT_EQ(type == "counter", name.size() > 6 && name.substr(name.size() - 6) == "_total") << name;
    // Quantiles are a summary's samples, and a summary's are quantiles.
    bool has_quantiles = false;
    if (const auto family = parsed.samples.find(name); family != parsed.samples.end()) {
      for (const auto& [labels, sample] : family->second) {
        has_quantiles = has_quantiles || labels.find("quantile=") != std::string::npos;
      }
    }
    EXPECT_EQ(type == "summary", has_quantiles) << name << " is typed " << type;
  }
  for (const char* name : {"hapticd_loop_lateness_seconds", "hapticd_send_delay_seconds",
                           "hapticd_client_round_trip_seconds"}) {
    EXPECT_EQ(parsed.types.at(name), "summary") << name;
  }
  const auto value = [&](const std::string& name, const std::string& labels = {}) {
    const auto family = parsed.samples.find(name);
    if (family == parsed.samples.end()) {
      ADD_FAILURE() << "no " << name;
      return -1.0;
    }
    const auto found = family->second.find(labels);
    if (found == family->second.end()) {
      ADD_FAILURE() << "no " << name << "{" << labels << "}";
      return -1.0;
    }
    return found->second;
  };
  EXPECT_EQ(value("hapticd_loop_ticks_total"), 12345.0);
  EXPECT_EQ(value("hapticd_loop_rate_hertz"), 999.5);
  EXPECT_EQ(value("hapticd_loop_overruns_total"), 2.0);
  EXPECT_DOUBLE_EQ(value("hapticd_loop_lateness_seconds", R"(quantile="0.5")"), 3e-6);  // µs -> s
  EXPECT_DOUBLE_EQ(value("hapticd_loop_lateness_seconds", R"(quantile="0.99")"), 40e-6);
  EXPECT_DOUBLE_EQ(value("hapticd_loop_lateness_seconds", R"(quantile="0.999")"), 900e-6);
  EXPECT_DOUBLE_EQ(value("hapticd_loop_lateness_max_seconds"), 2.5e-3);
  EXPECT_EQ(value("hapticd_stats_window_seconds"), 10.0);
  EXPECT_DOUBLE_EQ(value("hapticd_send_delay_seconds", R"(quantile="0.5")"), 12e-6);
  EXPECT_EQ(value("hapticd_sessions"), 2.0);
  EXPECT_EQ(value("hapticd_udp_datagrams_sent_total"), 777.0);
  EXPECT_EQ(value("hapticd_force_faults_total"), 1.0);

  const std::string a_labels = R"(session="0000000000001234",client="viewer \"left\"\\1\nx")";
  const std::string b_labels = R"(session="0000000000abcdef",client="observer")";
  EXPECT_EQ(value("hapticd_client_datagrams_sent_total", a_labels), 700.0);
  EXPECT_EQ(value("hapticd_client_states_received_total", a_labels), 690.0);
  EXPECT_EQ(value("hapticd_client_states_lost_total", a_labels), 10.0);
  EXPECT_EQ(value("hapticd_client_heartbeats_total", a_labels), 50.0);
  EXPECT_EQ(value("hapticd_client_last_heartbeat_age_seconds", a_labels), 0.05);
  EXPECT_EQ(value("hapticd_client_last_heartbeat_age_seconds", b_labels), -1.0);
  EXPECT_DOUBLE_EQ(value("hapticd_client_round_trip_seconds", a_labels + R"(,quantile="0.99")"), 400e-6);
  // A client with no round trip measured has no round-trip series (not a misleading zero).
  EXPECT_EQ(parsed.samples.at("hapticd_client_round_trip_seconds").size(), 3u);
}

/// `name`{`labels`} in `parsed`; fails the test (and gives -1) when it is not there.
double value_of(const Parsed& parsed, const std::string& name, const std::string& labels = {}) {
  const auto family = parsed.samples.find(name);
  if (family == parsed.samples.end()) {
    ADD_FAILURE() << "no " << name;
    return -1.0;
  }
  const auto found = family->second.find(labels);
  if (found == family->second.end()) {
    ADD_FAILURE() << "no " << name << "{" << labels << "}";
    return -1.0;
  }
  return found->second;
}

TEST(PrometheusText, AFederationsCountersAndEachCouplingsBooks) {
  v1::Stats stats;
  v1::FederationStats& federation = *stats.mutable_federation();
  federation.set_samples_published(5000);
  federation.set_samples_failed(1);
  federation.set_items_published(2);
  federation.set_items_applied(3);
  federation.set_items_refused(4);
  federation.set_wrenches_accepted(60);
  federation.set_wrenches_refused(7);
  federation.set_samples_refused(8);
  federation.set_energy_refused_j(0.25);
  federation.set_sites_cut_off(1);
  v1::CouplingStats& tool = *federation.add_couplings();
  tool.set_kind(v1::CouplingStats::TOOL);
  tool.set_port(1);
  tool.set_remote(0xa1b2c3d4e5f60718ull);
  tool.set_injected_j(0.25);
  tool.set_given_j(0.125);
  tool.set_sent_j(0.0625);
  tool.set_received_j(0.5);
  tool.set_reservoir_j(0.5625);  // 0.25 − 0.125 + 0.5 − 0.0625
  v1::CouplingStats& mass = *federation.add_couplings();
  mass.set_kind(v1::CouplingStats::MASS);
  mass.set_remote(0x2a);
  mass.set_mass(0xffffffff00000007ull);
  mass.set_injected_j(1.5);
  mass.set_reservoir_j(1.5);

  const Parsed parsed = parse(prometheus_text(stats));
  for (const auto& [name, type] : parsed.types) {
    EXPECT_EQ(type == "counter", name.size() > 6 && name.substr(name.size() - 6) == "_total") << name;
  }
  EXPECT_EQ(value_of(parsed, "hapticd_federation_samples_published_total"), 5000.0);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_samples_failed_total"), 1.0);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_items_published_total"), 2.0);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_items_applied_total"), 3.0);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_items_refused_total"), 4.0);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_wrenches_accepted_total"), 60.0);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_wrenches_refused_total"), 7.0);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_samples_refused_total"), 8.0);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_energy_refused_joules_total"), 0.25);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_sites_cut_off_total"), 1.0);

  const std::string energy = "hapticd_federation_coupling_energy_joules_total";
  const std::string tool_labels = R"(kind="tool",port="1",remote="a1b2c3d4e5f60718")";
  EXPECT_EQ(value_of(parsed, energy, tool_labels + R"(,book="injected")"), 0.25);
  EXPECT_EQ(value_of(parsed, energy, tool_labels + R"(,book="given")"), 0.125);
  EXPECT_EQ(value_of(parsed, energy, tool_labels + R"(,book="sent")"), 0.0625);
  EXPECT_EQ(value_of(parsed, energy, tool_labels + R"(,book="received")"), 0.5);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_coupling_reservoir_joules", tool_labels), 0.5625);
  const std::string mass_labels = R"(kind="mass",remote="000000000000002a",mass="ffffffff00000007")";
  EXPECT_EQ(value_of(parsed, energy, mass_labels + R"(,book="injected")"), 1.5);
  EXPECT_EQ(value_of(parsed, energy, mass_labels + R"(,book="given")"), 0.0);
  EXPECT_EQ(value_of(parsed, "hapticd_federation_coupling_reservoir_joules", mass_labels), 1.5);
  EXPECT_EQ(parsed.samples.at(energy).size(), 8u);  // four books of each coupling
  EXPECT_EQ(parsed.types.at("hapticd_federation_coupling_reservoir_joules"), "gauge");
}

TEST(PrometheusText, NoFederationNoFederationFamilies) {
  v1::Stats stats;
  stats.set_ticks(1);
  const std::string text = prometheus_text(stats);
  EXPECT_EQ(text.find("federation"), std::string::npos) << text;

  // A federation with no coupling yet: its counters, and the books' families with no sample.
  stats.mutable_federation();
  const Parsed parsed = parse(prometheus_text(stats));
  EXPECT_EQ(value_of(parsed, "hapticd_federation_samples_published_total"), 0.0);
  EXPECT_EQ(parsed.samples.count("hapticd_federation_coupling_energy_joules_total"), 0u);
  EXPECT_EQ(parsed.types.at("hapticd_federation_coupling_energy_joules_total"), "counter");
}

TEST(PrometheusText, LabelValuesAreEscaped) {
  EXPECT_EQ(escape_label_value(R"(a"b\c)" "\n"), R"(a\"b\\c\n)");
  EXPECT_EQ(escape_label_value("plain name-1"), "plain name-1");
}

}  // namespace
}  // namespace haptic::net
