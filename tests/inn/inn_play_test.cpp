// The inn game's scripted scenario, end to end on the reduced inn: generate (--scale small,
// --draco), cook at draft quality, play headless (EGL surfaceless), then check the run's own
// records: every scripted change landed within its latency bound (cross-checked against the
// planner's per-frame counters in frames.csv), frames kept to the budget rule, lighting a light
// brightened the light map around it (snuffing darkened it), and the carried item, lit by the
// light probes, darkened when the candle beside it was snuffed and hardly changed for a candle in
// the other room. The lantern (a moving light) is taken and carried through the door: every move
// lands within its bound, and its bounce light as the pack recomposes it at two poses agrees with
// bake-state of the same states.
#include <algorithm>
#include <cmath>
#include <cstdio>
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

// A PFM image's values (3 channels), in file order (both images compared come from one writer).
std::vector<float> read_pfm(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  std::string magic;
  int w = 0, h = 0;
  double scale = 0;
  f >> magic >> w >> h >> scale;
  f.get();
  std::vector<float> v(f && magic == "PF" && w > 0 && h > 0 ? size_t(w) * size_t(h) * 3 : 0);
  f.read(reinterpret_cast<char*>(v.data()), std::streamsize(v.size() * sizeof(float)));
  if (!f) v.clear();
  return v;
}

struct BounceError {
  double relative_rmse = 0, bias = 0, median_ratio = 0;
  size_t texels = 0;
};

// (rec_on - rec_off) against (bake_on - bake_off), per texel mean of the channels, over the texels
// whose bake-state bounce light is at least 1 % of its 99th percentile.
BounceError bounce_error(const std::vector<float>& rec_on, const std::vector<float>& rec_off,
                         const std::vector<float>& bake_on, const std::vector<float>& bake_off) {
  const size_t n = rec_on.size() / 3;
  std::vector<double> r(n), b(n);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      r[i] += (rec_on[i * 3 + c] - rec_off[i * 3 + c]) / 3.0;
      b[i] += (bake_on[i * 3 + c] - bake_off[i * 3 + c]) / 3.0;
    }
  }
  std::vector<double> sorted = b;
  std::sort(sorted.begin(), sorted.end());
  const double floor = 0.01 * sorted[size_t(0.99 * double(n - 1))];
  double se = 0, sb2 = 0, sr = 0, sb = 0;
  std::vector<double> ratio;
  BounceError e;
  for (size_t i = 0; i < n; ++i) {
    if (!(b[i] > floor)) continue;
    ++e.texels;
    se += (r[i] - b[i]) * (r[i] - b[i]);
    sb2 += b[i] * b[i];
    sr += r[i];
    sb += b[i];
    ratio.push_back(r[i] / b[i]);
  }
  if (e.texels == 0) return e;
  e.relative_rmse = std::sqrt(se / sb2);
  e.bias = (sr - sb) / sb;
  std::nth_element(ratio.begin(), ratio.begin() + ptrdiff_t(ratio.size() / 2), ratio.end());
  e.median_ratio = ratio[ratio.size() / 2];
  return e;
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

  // The camera draws only the chunks and objects its view meets (view_culling.h), and the
  // lantern's shadow only the cube faces the camera may look up: counted in triangles, the same
  // on every run. Measured on this scenario: 2,718 of the small inn's 5,624 triangles a frame on
  // average (0.48), all of them before the culling.
  const uint64_t world = summary["triangles"]["world"].get<uint64_t>();
  ASSERT_GT(world, 0u);
  uint64_t walk_shadow = 0;
  for (const Row& f : frames) {
    EXPECT_LE(u64(f, "scene_triangles"), world) << "frame " << f.at("frame");
    if (f.at("step").rfind("lantern_walk_", 0) == 0) walk_shadow += u64(f, "shadow_triangles");
  }
  EXPECT_GT(walk_shadow, 0u);  // the carried lantern's shadow follows it
  EXPECT_LT(summary["triangles"]["scene_per_frame_mean"].get<double>(), 0.75 * double(world));
  std::printf("triangles a frame: %.0f of the world's %llu; the lantern's faces %.0f a redraw\n",
              summary["triangles"]["scene_per_frame_mean"].get<double>(),
              static_cast<unsigned long long>(world),
              summary["triangles"]["shadow_per_redraw_mean"].get<double>());

  // Budget rule (planner.h): at most `budget` texels a frame, except a single oversize step
  // (the clear of a map larger than the budget, or one patch) alone in its frame.
  for (const Row& f : frames) {
    EXPECT_TRUE(u64(f, "texels") <= budget || u64(f, "draws") <= 1) << "frame " << f.at("frame");
  }

  std::set<std::string> lit;
  std::map<std::string, int> held_checks;
  std::vector<std::string> moves;  // the lantern walk's state files
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
    if (s.at("action") == "start" || s.at("action") == "carry") continue;
    if (s.at("action") == "move") {
      // The lantern's panes follow over several frames (runtime.h, "Moving lights"); nothing else
      // changes during the walk, so nothing is pending once it landed.
      EXPECT_EQ(u64(frames[u64(s, "landed_frame") - 1], "pending_changes"), 0u);
      // Carried at a walk: one pose a frame, the step's last one counted in its latency.
      EXPECT_EQ(u64(s, "glide_frames") + 1, scenario["steps"][i - 1]["frames"].get<uint64_t>());
      EXPECT_TRUE(std::filesystem::exists(out / s.at("state")));
      moves.push_back(s.at("state"));
      continue;
    }
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

  // The lantern walk, at its first pose (in the dining room) and its third (in the doorway): the
  // lantern's bounce light as the pack recomposes it (lantern on less lantern off) against
  // bake-state of the same two states (the cook's draft preset). Measured at the default 64 panes,
  // level 1: 22.7 % relative RMSE, bias -2.6 %, median ratio 0.97 (dining room); 25.0 %, -3.4 %,
  // 0.96 (doorway); 35.1 %, -10.1 %, 1.14 and 33.1 %, -10.7 %, 0.91 before the panes kept to
  // texels whose light bounces and were split by how unevenly a light lights them: issue 16's
  // 10 % is not met (docs/moving_lights.md). Panes left at the lantern's hook (the recomposition
  // of the hook's pose against the same bake-state) gave 51.9 %, -45.1 % and 79.5 %, -33.2 %,
  // median 0.72 (32 panes): each pose outside a bound below.
  ASSERT_EQ(moves.size(), 5u);
  for (const size_t k : {size_t(0), size_t(2)}) {
    SCOPED_TRACE(moves[k]);
    const std::filesystem::path on = out / moves[k], off = dir / ("off_" + moves[k]);
    nlohmann::json state = nlohmann::json::parse(test::slurp(on));
    state["lights"]["lantern"]["on"] = false;
    std::ofstream(off) << state.dump();
    std::vector<float> maps[4];
    int i = 0;
    for (const std::filesystem::path& st : {on, off}) {
      const std::filesystem::path rec = dir / "rec.pfm", bake = dir / "bake.pfm";
      ASSERT_EQ(run("\"" + tool + "\" recompose \"" + pack.string() + "\" --state \"" +
                        st.string() + "\" -o \"" + rec.string() + "\"",
                    dir / "recompose.log"),
                0)
          << test::slurp(dir / "recompose.log");
      ASSERT_EQ(
          run("\"" + tool + "\" bake-state \"" + scene.string() + "\" --quality draft --state \"" +
                  st.string() + "\" -o \"" + bake.string() + "\" --quiet",
              dir / "bake.log"),
          0)
          << test::slurp(dir / "bake.log");
      maps[i] = read_pfm(rec);
      maps[i + 2] = read_pfm(bake);
      ++i;
    }
    for (const auto& m : maps) ASSERT_EQ(m.size(), maps[0].size());
    ASSERT_FALSE(maps[0].empty());
    const BounceError e = bounce_error(maps[0], maps[1], maps[2], maps[3]);
    EXPECT_GT(e.texels, maps[0].size() / 3 / 4);  // the bounce light reaches much of the inn
    EXPECT_LT(e.relative_rmse, 0.32);
    EXPECT_LT(std::fabs(e.bias), 0.35);
    EXPECT_GT(e.median_ratio, 0.75);
    EXPECT_LT(e.median_ratio, 1.35);
    std::printf(
        "%s: lantern bounce light against bake-state: %.1f %% relative RMSE, bias %+.1f %%, "
        "median ratio %.3f over %zu texels\n",
        moves[k].c_str(), 100.0 * e.relative_rmse, 100.0 * e.bias, e.median_ratio, e.texels);
  }
}

}  // namespace
}  // namespace lightpatch::inn
