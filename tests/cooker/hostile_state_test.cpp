// Hostile state files (issue 15): nesting that crashed the error message's dump(), numbers past
// a double, keys and values meant to flood stderr. Each gets a CookError naming the file.
#include <gtest/gtest.h>

#include <string>

#include "gltf_files.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/state_spec.h"

namespace lightpatch::test {
namespace {

std::string state_error(const std::string& text) {
  try {
    cooker::parse_state_json(text, "hostile.json");
    ADD_FAILURE() << "accepted: " << text.substr(0, 200);
  } catch (const cooker::CookError& e) {
    return e.what();
  }
  return {};
}

TEST(HostileState, DeepNestingIsRefusedBeforeParsing) {
  // 100,000 levels (200 kB): SIGSEGV in the error message's dump() before.
  const std::string deep = "{\"lights\": {\"a\": {\"color\": " + std::string(100000, '[') +
                           std::string(100000, ']') + "}}}";
  const std::string m = state_error(deep);
  EXPECT_NE(m.find("hostile.json: invalid state: JSON nested deeper than 256 levels"),
            std::string::npos)
      << m;
  // A shallow file is still parsed in full.
  EXPECT_EQ(cooker::parse_state_json("{\"lights\": {\"a\": {\"color\": [1, 2, 3]}}}", "ok.json")
                .lights.at("a")
                .color[2],
            3.0f);
}

TEST(HostileState, ANumberPastADoubleNamesTheFile) {
  ScratchDir dir;
  const std::string path = dir.file("overflow.json");
  write_text(path, "{\"lights\": {\"a\": {\"intensity\": 1e400}}}");
  try {
    cooker::load_state_file(path);
    ADD_FAILURE() << "1e400 accepted";
  } catch (const cooker::CookError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(path + ": invalid JSON", 0), 0u) << m;
    EXPECT_NE(m.find("1e400"), std::string::npos) << m;
  }
}

TEST(HostileState, LongKeysAndValuesAreCutInMessages) {
  const std::string key(1'000'000, 'k');
  const std::string long_key = state_error("{\"lights\": {\"" + key + "\": {\"on\": 2}}}");
  EXPECT_LT(long_key.size(), 400u) << long_key.substr(0, 400);
  EXPECT_NE(long_key.find("... (1000000 bytes)"), std::string::npos) << long_key;

  std::string array = "[0";
  for (int i = 0; i < 200000; ++i) array += ",0";
  const std::string long_value = state_error("{\"lights\": {\"a\": {\"on\": " + array + "]}}}");
  EXPECT_LT(long_value.size(), 400u) << long_value.substr(0, 400);
  EXPECT_NE(long_value.find("on must be true or false, got [0,0,0"), std::string::npos)
      << long_value;

  const std::string escape = state_error("{\"objects\": {\"box\\u001b[2J\": {\"shown\": true}}}");
  EXPECT_EQ(escape.find('\x1b'), std::string::npos) << escape;
  EXPECT_NE(escape.find("objects.box\\x1B[2J.shown: unknown key"), std::string::npos) << escape;
}

}  // namespace
}  // namespace lightpatch::test
