// Scene state files: DESIGN.md's format and clear errors.
#include <gtest/gtest.h>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/state_spec.h"

namespace lightpatch::cooker {
namespace {

TEST(StateSpec, ParsesTheDesignExample) {
  const StateSpec s = parse_state_json(
      R"({"lights": {"candle_3": {"on": true, "color": [1.0, 0.8, 0.6], "intensity": 4.0}},
          "objects": {"spell_book": {"visible": false}}})",
      "state");
  ASSERT_EQ(s.lights.count("candle_3"), 1u);
  const LightOverride& o = s.lights.at("candle_3");
  EXPECT_TRUE(o.has_on && o.on && o.has_color && o.has_intensity);
  EXPECT_FLOAT_EQ(o.color[1], 0.8f);
  EXPECT_FLOAT_EQ(o.intensity, 4.0f);
  EXPECT_EQ(s.objects.at("spell_book"), false);
  const StateSpec empty = parse_state_json("{}", "state");
  EXPECT_TRUE(empty.lights.empty() && empty.objects.empty());
}

void expect_error(const std::string& text, const std::string& fragment) {
  try {
    parse_state_json(text, "s.json");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const CookError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
        << "message '" << e.what() << "' lacks '" << fragment << "'";
  }
}

TEST(StateSpec, RejectsBadInputWithClearErrors) {
  expect_error("{", "invalid JSON");
  expect_error("[]", "must be a JSON object");
  expect_error(R"({"lamps": {}})", "unknown key \"lamps\"");
  expect_error(R"({"lights": []})", "\"lights\" must be an object");
  expect_error(R"({"lights": {"a": {"color": [1, 2]}}})", "lights.a.color");
  expect_error(R"({"lights": {"a": {"color": [1, -2, 0]}}})", "non-negative");
  expect_error(R"({"lights": {"a": {"color": [1, "x", 0]}}})", "must be a number");
  expect_error(R"({"lights": {"a": {"intensity": -1}}})", "non-negative");
  expect_error(R"({"lights": {"a": {"intensity": NaN}}})", "invalid JSON");
  expect_error(R"({"lights": {"a": {"on": 1}}})", "true or false");
  expect_error(R"({"lights": {"a": {"brightness": 1}}})", "unknown key");
  expect_error(R"({"objects": {"b": {"visible": "no"}}})", "true or false");
  expect_error(R"({"objects": {"b": true}})", "must be an object");
}

}  // namespace
}  // namespace lightpatch::cooker
