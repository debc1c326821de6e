// The inn game's scripted scenario, end to end on the reduced inn: generate (--scale small,
// --draco), cook at draft quality, play headless (EGL surfaceless), then check the run's own
// records: every scripted change landed within its latency bound (cross-checked against the
// planner's per-frame counters in frames.csv), frames kept to the budget rule, lighting a light
// brightened the light map around it (snuffing darkened it), and the carried item, lit by the
// light probes, darkened when the candle beside it was snuffed and hardly changed for a candle in
// the other room.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gltf_test_util.h"

namespace lightpatch::inn {
namespace {

using Row = std::map<std::string, std::string>;

std::vector<Row> read_csv(const std::filesystem::path& path) {
  std::ifstream f(path);
  std::vector<Row> rows;
  std::string line;
  std::vector<std::string> header;
  auto split = [](const std::string& l) {
    std::vector<std::string> cells;
    std::stringstream ss(l);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (!l.empty() && l.back() == ',') cells.emplace_back();
    return cells;
  };
  if (!std::getline(f, line)) return rows;
  header = split(line);
  while (std::getline(f, line)) {
    const std::vector<std::string> cells = split(line);
    Row r;
    for (size_t i = 0; i < header.size(); ++i) r[header[i]] = i < cells.size() ? cells[i] : "";
    rows.push_back(r);
  }
  return rows;
}

int run(const std::string& command, const std::filesystem::path& log) {
  const int rc = std::system((command + " > \"" + log.string() + "\" 2>&1").c_str());
  return rc == -1 ? -1 : WEXITSTATUS(rc);
}

uint64_t u64(const Row& r, const char* key) {
  return std::stoull(r.at(key));
}
double num(const Row& r, const char* key) {
  return std::stod(r.at(key));
}

TEST(InnPlay, ScriptedScenarioLandsWithinBoundsAndLightsBrighten) {
  const std::filesystem::path dir = test::scratch_dir();
  const std::string inn = LIGHTPATCH_INN_BIN, tool = LIGHTPATCH_TOOL_BIN;
  const std::filesystem::path scene = dir / "inn.glb", pack = dir / "inn.lpk", out = dir / "run";
  ASSERT_EQ(run("\"" + inn + "\" generate --scale small --draco -o \"" + scene.string() + "\"",
                dir / "generate.log"),
            0)
      << test::slurp(dir / "generate.log");
  ASSERT_EQ(run("\"" + tool + "\" cook \"" + scene.string() + "\" -o \"" + pack.string() +
                    "\" --quality draft --quiet",
                dir / "cook.log"),
            0)
      << test::slurp(dir / "cook.log");
  const int rc =
      run("\"" + inn + "\" play --headless --script default --size 320x180 --scene \"" +
              scene.string() + "\" --pack \"" + pack.string() + "\" --out \"" + out.string() + "\"",
          dir / "play.log");
  EXPECT_EQ(rc, 0) << test::slurp(dir / "play.log");

  const nlohmann::json scenario = nlohmann::json::parse(test::slurp(dir / "inn.scenario.json"));
  const nlohmann::json summary = nlohmann::json::parse(test::slurp(out / "summary.json"));
  EXPECT_EQ(summary["failures"].get<int>(), 0);
  const uint64_t budget = summary["budget_texels"].get<uint64_t>();
  const std::vector<Row> steps = read_csv(out / "steps.csv");
  const std::vector<Row> frames = read_csv(out / "frames.csv");
  ASSERT_EQ(steps.size(), scenario["steps"].size() + 1);  // + the initial build
  ASSERT_FALSE(frames.empty());

  // Budget rule (planner.h): at most `budget` texels a frame, except a single oversize step
  // (the clear of a map larger than the budget, or one patch) alone in its frame.
  for (const Row& f : frames) {
    EXPECT_TRUE(u64(f, "texels") <= budget || u64(f, "draws") <= 1) << "frame " << f.at("frame");
  }

  std::set<std::string> lit;
  std::map<std::string, int> held_checks;
  for (size_t i = 0; i < steps.size(); ++i) {
    const Row& s = steps[i];
    SCOPED_TRACE("step " + s.at("step"));
    EXPECT_EQ(s.at("landed"), "1");
    EXPECT_EQ(s.at("error"), "");
    const uint64_t latency = u64(s, "latency_frames"), bound = u64(s, "bound_frames");
    EXPECT_LE(latency, bound);
    if (i > 0) {
      EXPECT_EQ(s.at("step"), scenario["steps"][i - 1]["name"].get<std::string>());
      EXPECT_TRUE(std::filesystem::exists(out / s.at("screenshot")));
    }
    if (s.at("action") == "start") continue;
    // The run's latency agrees with the planner's counters frame by frame: pending from the frame
    // the change was made until it landed, and landed with the same latency.
    const uint64_t applied = u64(s, "applied_frame"), landed = u64(s, "landed_frame");
    ASSERT_GE(landed, applied);
    ASSERT_LE(landed, frames.size());
    for (uint64_t f = applied; f < landed; ++f) {
      const Row& fr = frames[f - 1];
      EXPECT_GE(u64(fr, "pending_changes"), 1u) << "frame " << f;
      EXPECT_GE(u64(fr, "oldest_pending_frames"), f - applied + 1) << "frame " << f;
    }
    const Row& at = frames[landed - 1];
    EXPECT_GE(u64(at, "completed_changes"), 1u);
    EXPECT_EQ(u64(at, "max_latency_frames"), latency);
    if (s.at("action") != "light") continue;
    // The light map around a lit light is brighter than when it was out.
    const nlohmann::json& step = scenario["steps"][i - 1];
    const bool on = step["state"]["lights"][s.at("node")]["on"].get<bool>();
    const double before = num(s, "meter_before"), after = num(s, "meter_after");
    EXPECT_GE(before, 0.0);
    EXPECT_GE(after, 0.0);
    const double brighter = on ? after : before, darker = on ? before : after;
    EXPECT_GT(brighter, 2.0 * darker + 0.05) << "before " << before << ", after " << after;
    if (on) lit.insert(s.at("node"));

    // The carried item (the first ingredient) held beside a candle: its light from the probes
    // (luminance facing the nearest flame, and the mean over directions), for the unflickered
    // state, so before and after differ by the step's change alone.
    if (!step.contains("held_item")) continue;
    const std::string what = step["held_item"].get<std::string>();
    ++held_checks[what];
    EXPECT_EQ(s.at("item"), scenario["items"][0].get<std::string>());
    for (const char* which : {"facing", "mean"}) {
      SCOPED_TRACE(which);
      const double b = num(s, ("item_" + std::string(which) + "_before").c_str());
      const double a = num(s, ("item_" + std::string(which) + "_after").c_str());
      // Other lights (the room's torch) still light it: never black.
      EXPECT_GT(std::min(a, b), 0.0);
      if (what == "near_light_off") {
        EXPECT_LT(a, 0.5 * b);
      } else if (what == "near_light_on") {
        EXPECT_GT(a, 2.0 * b);
      } else {
        // A candle in the other room reaches the item only by a little bounce light through the
        // door (the small inn's draft cook: 0.7 % of it).
        EXPECT_EQ(what, "other_room_light");
        EXPECT_LE(std::fabs(a - b), 0.02 * b);
      }
    }
  }
  EXPECT_EQ(lit.size(), scenario["semi_dynamic_lights"].size());
  EXPECT_EQ(held_checks["near_light_off"], 1);
  EXPECT_EQ(held_checks["near_light_on"], 1);
  EXPECT_EQ(held_checks["other_room_light"], 2);
}

}  // namespace
}  // namespace lightpatch::inn
