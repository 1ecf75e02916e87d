// The vendor drivers' params reader (driver/vendors/common/driver_params.hpp): JSON as JSON says
// it (the hand-written reader before it ended a value at the first ']' or '}' and dropped escapes),
// every unknown key and every value of the wrong kind refused naming the key.

#include <gtest/gtest.h>

#include <string>

#include "common/driver_params.hpp"

namespace haptic::vendor {
namespace {

std::string refusal(const std::string& json) {
  try {
    const DriverParams params(json, {"library", "index", "gain", "offset", "calibrate"});
    (void)params.number("index");
    (void)params.number("gain");
    (void)params.text("library");
    (void)params.triple("offset");
    (void)params.boolean("calibrate");
  } catch (const ParamsError& error) {
    return error.what();
  }
  return "(taken)";
}

TEST(DriverParams, StringsKeepTheirEscapesAndBracketsAndValuesReadAsJson) {
  const DriverParams params(R"({"library": "/opt/dhd [v3]/lib\u00e9\n", "index": 2, "gain": -1.5e-3,
                                "offset": [1, -2.5, 3e2], "calibrate": true})",
                            {"library", "index", "gain", "offset", "calibrate"});
  EXPECT_EQ(params.text("library"), std::string("/opt/dhd [v3]/lib\xc3\xa9\n"));
  EXPECT_EQ(params.number("index"), 2.0);
  EXPECT_EQ(params.number("gain"), -1.5e-3);
  EXPECT_EQ(params.triple("offset"), (std::array<double, 3>{1.0, -2.5, 300.0}));
  EXPECT_EQ(params.boolean("calibrate"), true);
  EXPECT_FALSE(params.has("missing"));
  EXPECT_EQ(params.number("missing"), std::nullopt);
}

TEST(DriverParams, EachWrongKindOrUnknownKeyIsRefusedNamingIt) {
  EXPECT_EQ(refusal(R"({"index": "2"})"), "params.index: expected a number");
  EXPECT_EQ(refusal(R"({"calibrate": 1})"), "params.calibrate: expected true or false");
  EXPECT_EQ(refusal(R"({"library": ["a"]})"), "params.library: expected a string");
  EXPECT_EQ(refusal(R"({"offset": [[1, 2], 3]})"), "params.offset: expected [x, y, z] (three numbers)");
  EXPECT_EQ(refusal(R"({"offset": [1, 2]})"), "params.offset: expected [x, y, z] (three numbers)");
  EXPECT_EQ(refusal(R"({"indx": 1})"),
            "params.indx: not an option of this driver (it takes library, index, gain, offset, calibrate)");
  EXPECT_EQ(refusal(R"([1, 2])"), "params: expected a JSON object");
  EXPECT_EQ(refusal(R"({"index": 1,)").rfind("params: not valid JSON", 0), 0u);
  EXPECT_EQ(refusal(R"({"index": 1, "offset": [0, 0, 1], "calibrate": false})"), "(taken)");
}

}  // namespace
}  // namespace haptic::vendor
