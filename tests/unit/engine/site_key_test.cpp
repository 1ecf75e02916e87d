// engine::SiteKey and the keys made from it (engine/core/site_key.hpp): the same at every site,
// never 0, distinct where their inputs are.
#include <gtest/gtest.h>

#include "engine/core/site_key.hpp"

namespace haptic::engine {
namespace {

TEST(SiteKey, IsTheFnv1aOfTheSitesName) {
  EXPECT_EQ(fnv1a(""), kFnvOffsetBasis);
  EXPECT_EQ(fnv1a("a"), 0xaf63dc4c8601ec8cull);  // FNV-1a 64's published test vector
  EXPECT_EQ(site_key("lab-a").value, fnv1a("lab-a"));
  EXPECT_TRUE(site_key(""));  // never "none", whatever the name
}

TEST(SiteKey, ToolKeysDifferByPortAndBySite) {
  EXPECT_NE(tool_key("lab-a", 0), tool_key("lab-a", 1));
  EXPECT_NE(tool_key("lab-a", 0), tool_key("lab-b", 0));
  EXPECT_NE(tool_key("lab-a", 0), site_key("lab-a").value);
  EXPECT_NE(tool_key("lab-a", 256), tool_key("lab-a", 1));  // every byte of the port counts
  static_assert(tool_key("lab-a", 0) != 0);
}

TEST(SiteKey, SharedMassKeysDifferByOriginAndId) {
  EXPECT_NE(shared_mass_key(site_key("lab-a"), 1), shared_mass_key(site_key("lab-a"), 2));
  EXPECT_NE(shared_mass_key(site_key("lab-a"), 1), shared_mass_key(site_key("lab-b"), 1));
  EXPECT_NE(shared_mass_key(SiteKey{}, 0), 0u);
}

}  // namespace
}  // namespace haptic::engine
