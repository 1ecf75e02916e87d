// hapticctl's views of GetStats without a server: the status with and without a federation, and
// the federation's block (its counts, one line per coupling with its books in mJ).
#include <gtest/gtest.h>

#include <string>

#include "views.hpp"

namespace hapticctl {
namespace {

haptic::FederationStats two_couplings() {
  haptic::FederationStats f;
  f.samples_published = 5000;
  f.samples_failed = 1;
  f.items_published = 2;
  f.items_applied = 3;
  f.items_refused = 4;
  f.wrenches_accepted = 60;
  f.wrenches_refused = 7;
  haptic::CouplingStats tool;
  tool.kind = haptic::CouplingStats::Kind::kTool;
  tool.port = 1;
  tool.remote = 0xa1b2c3d4e5f60718ull;
  tool.injected_j = 0.25;
  tool.given_j = 0.125;
  tool.sent_j = 0.0625;
  tool.received_j = 0.5;
  tool.reservoir_j = 0.5625;
  haptic::CouplingStats mass;
  mass.kind = haptic::CouplingStats::Kind::kMass;
  mass.remote = 0x2a;
  mass.mass = 0xffffffff00000007ull;
  mass.injected_j = 1.5e-6;
  mass.reservoir_j = 1.5e-6;
  f.couplings = {tool, mass};
  return f;
}

TEST(HapticctlViews, TheFederationBlockHasItsCountsAndEachCouplingsBooksInMillijoules) {
  EXPECT_EQ(federation_view(two_couplings()),
            "federation  5000 samples published, 1 failed; items 2 published, 3 applied, 4 refused; "
            "wrenches 60 accepted, 7 refused\n"
            "  tool port 1 with tool a1b2c3d4e5f60718: injected 250.000 mJ, given 125.000 mJ, "
            "sent 62.500 mJ, received 500.000 mJ, held 562.500 mJ\n"
            "  mass ffffffff00000007 with site 000000000000002a: injected 0.002 mJ, given 0.000 mJ, "
            "sent 0.000 mJ, received 0.000 mJ, held 0.002 mJ\n");
  EXPECT_EQ(federation_view(haptic::FederationStats{}),
            "federation  0 samples published, 0 failed; items 0 published, 0 applied, 0 refused; "
            "wrenches 0 accepted, 0 refused\n"
            "  no coupling across the network\n");
  haptic::FederationStats lied_to;
  lied_to.samples_refused = 12;
  lied_to.energy_refused_j = 0.5;
  lied_to.sites_cut_off = 1;
  EXPECT_NE(federation_view(lied_to).find("  from other sites: 12 samples refused, 500.000 mJ claimed and not "
                                          "credited, 1 sites cut off\n"),
            std::string::npos)
      << federation_view(lied_to);
}

TEST(HapticctlViews, TheStatusShowsAFederationOnlyWhenTheServerHasOne) {
  haptic::Stats stats;
  stats.ticks = 10;
  const std::string alone = status_view(stats);
  EXPECT_EQ(alone.rfind("loop      10 ticks", 0), 0u) << alone;
  EXPECT_EQ(alone.find("federation"), std::string::npos) << alone;

  stats.federation = two_couplings();
  const std::string federated = status_view(stats);
  EXPECT_EQ(federated.rfind(alone, 0), 0u) << federated;  // the same lines first
  EXPECT_EQ(federated.substr(alone.size()), federation_view(*stats.federation)) << federated;
}

}  // namespace
}  // namespace hapticctl
