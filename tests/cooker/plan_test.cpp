// The effect plan (DESIGN.md, "Only what the scene calls for") against everything forced on
// (--no-plan): the plan skips the pairs, bounce and colour the scene does not call for, the
// forced cook keeps them, both packs recompose the same states within the quantization of the
// maps in play, and `cook --measure-plan` reports what the plan saved.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gltf_files.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/cooker/tracer.h"
#include "test_scenes.h"
#include "tool_runner.h"

namespace lightpatch::test {
namespace {

using cooker::BakedMaps;
using cooker::BakeOptions;
using cooker::Report;

// An open floor (no walls: most of its bounce leaves the scene), a crate under a semi-dynamic lamp
// whose range is 4 m, and a second crate 10 m away, outside the lamp's reach.
scenegen::SceneBuilder open_floor() {
  using namespace scenegen;
  SceneBuilder b;
  const int grey = b.add_material({.name = "grey", .base_color = {0.6f, 0.6f, 0.6f, 1.0f}});
  const int wood = b.add_material({.name = "wood", .base_color = {0.5f, 0.3f, 0.2f, 1.0f}});
  b.add_mesh_node("floor", make_plane(4.0f, 4.0f, 2, 2), grey);
  b.add_mesh_node("crate", make_box({-0.25f, 0.0f, -0.25f}, {0.25f, 0.5f, 0.25f}), wood,
                  {-0.5f, 0.0f, 0.3f}, /*semi_dynamic=*/true);
  b.add_mesh_node("far_crate", make_box({-0.25f, 0.0f, -0.25f}, {0.25f, 0.5f, 0.25f}), wood,
                  {7.0f, 0.0f, 7.0f}, /*semi_dynamic=*/true);
  b.add_light_node("lamp",
                   {.name = "lamp", .color = {1.0f, 0.9f, 0.8f}, .intensity = 6.0f, .range = 4.0f},
                   {-0.3f, 1.6f, 0.2f}, {0, -1, 0}, /*semi_dynamic=*/true);
  return b;
}

const std::vector<std::string> kFast = {"--quality",     "draft", "--lightmap-size", "64",
                                        "--gather-rays", "32",    "--quiet"};

std::vector<std::string> cat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

void expect_success(const std::vector<std::string>& args) {
  const ToolRun r = run_tool(args);
  ASSERT_EQ(r.code, 0) << describe(args, r);
}

// The report's decision of `kind` (bake_plan.h) about `light` and `object` ("" for none).
const nlohmann::json* find_decision(const nlohmann::json& report, const std::string& kind,
                                    const std::string& light, const std::string& object = "") {
  for (const nlohmann::json& d : report["decisions"]) {
    if (d["kind"] == kind && d.value("light", "") == light && d.value("object", "") == object)
      return &d;
  }
  return nullptr;
}

// An open plane receives no bounce: its light leaves the scene. The plan turns
// the lamp's indirect light off, so it culls the pair of a box below the floor, out of the lamp's
// reach; forced, the bounce is gathered (and is below half an output step everywhere) and the
// pair traced and kept.
TEST(Plan, OpenPlaneGetsNoBounceAndItsFarPairIsCulled) {
  cooker::Scene scene;
  add_quad(scene, {-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, "floor");
  add_object_box(scene, {-0.5f, -8.0f, -0.5f}, {0.5f, -7.0f, 0.5f}, "cellar_box");
  cooker::Light lamp = point_light("lamp", {0, 2, 0}, 5.0f, true);
  lamp.range = 4.0f;
  scene.lights = {lamp};
  finish(scene);
  const cooker::TexelSet texels = grid_texels(32, 32, {-4, 0, -4}, {8, 0, 0}, {0, 0, 8}, {0, 1, 0});
  auto tracer = cooker::make_embree_tracer(scene);
  cooker::Progress progress(true);
  BakeOptions o;
  o.quality = cooker::Quality::kDraft;
  o.gather_rays = 32;
  Report planned_report, forced_report;
  const BakedMaps planned =
      cooker::bake_maps(scene, bare_layout(32, 32), texels, *tracer, o, progress, planned_report);
  o.plan_effects = false;
  const BakedMaps forced =
      cooker::bake_maps(scene, bare_layout(32, 32), texels, *tracer, o, progress, forced_report);
  const nlohmann::json& pr = planned_report.root();
  const nlohmann::json& fr = forced_report.root();
  const nlohmann::json* ind = find_decision(pr, "group_bounce", "lamp");
  ASSERT_NE(ind, nullptr);
  EXPECT_FALSE((*ind)["taken"].get<bool>());
  EXPECT_LT((*ind)["value"].get<double>(), (*ind)["bound"].get<double>()) << (*ind)["reason"];
  ASSERT_NE(find_decision(fr, "group_bounce", "lamp"), nullptr);
  EXPECT_TRUE((*find_decision(fr, "group_bounce", "lamp"))["taken"].get<bool>());
  const nlohmann::json* pair = find_decision(pr, "pair", "lamp", "cellar_box");
  ASSERT_NE(pair, nullptr);
  EXPECT_FALSE((*pair)["taken"].get<bool>());
  EXPECT_EQ((*pair)["stage"], "plan") << "culled before tracing: " << (*pair)["reason"];
  EXPECT_TRUE(planned.shadows.empty());
  ASSERT_EQ(forced.shadows.size(), 1u);
  EXPECT_EQ(fr["pairs_skipped"].get<int>(), 0);
  ASSERT_EQ(planned.contribution.size(), 1u);
  ASSERT_EQ(forced.contribution.size(), 1u);
  EXPECT_EQ(planned.contribution[0].channels, 1);
  EXPECT_EQ(forced.contribution[0].channels, 3);
  // What the forced bounce adds, and the shadow the box casts, stay below half an output step at
  // the authored exposure (lamp intensity 5).
  const float half_step = 0.5f * planned.output_step / 5.0f;
  float worst = 0.0f, peak = 0.0f;
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      for (int c = 0; c < 3; ++c) {
        const float a = planned.contribution[0].at(x, y, 0);
        const float b = forced.contribution[0].at(x, y, c) - forced.shadows[0].map.at(x, y, c);
        worst = std::max(worst, std::fabs(a - b));
        peak = std::max(peak, a);
      }
    }
  }
  EXPECT_GT(peak, 20.0f * half_step);
  EXPECT_LE(worst, half_step);
}

nlohmann::json load(const std::string& path) {
  return nlohmann::json::parse(read_bytes(path));
}

// Direct light only: the far crate is outside the lamp's reach, culled before tracing; forced, its
// pair is traced and kept.
TEST(Plan, ForcedDirectCookTracesThePairThePlanCulls) {
  ScratchDir dir;
  open_floor().write(dir.file("floor.glb"));
  const std::string scene = dir.file("floor.glb");
  const std::vector<std::string> direct = cat(kFast, {"--no-indirect"});
  expect_success(
      cat({"cook", scene, "-o", dir.file("planned.lpk"), "--report", dir.file("planned.json")},
          direct));
  expect_success(cat({"cook", scene, "-o", dir.file("forced.lpk"), "--no-plan", "--report",
                      dir.file("forced.json")},
                     direct));
  const nlohmann::json planned = load(dir.file("planned.json"));
  const nlohmann::json forced = load(dir.file("forced.json"));
  const nlohmann::json* far_planned = find_decision(planned, "pair", "lamp", "far_crate");
  const nlohmann::json* far_forced = find_decision(forced, "pair", "lamp", "far_crate");
  ASSERT_NE(far_planned, nullptr);
  ASSERT_NE(far_forced, nullptr);
  EXPECT_FALSE((*far_planned)["taken"].get<bool>());
  EXPECT_EQ((*far_planned)["stage"], "plan") << (*far_planned)["reason"];
  EXPECT_TRUE((*far_forced)["taken"].get<bool>());
  EXPECT_TRUE((*far_forced)["forced"].get<bool>());
  // Culled, the pair costs no ray; forced, the pass also asks which objects each ray crosses.
  EXPECT_GE(forced["bake"]["rays"].get<double>(), planned["bake"]["rays"].get<double>());
  EXPECT_GE(forced["pack"]["groups"].get<int>(), planned["pack"]["groups"].get<int>());
  for (const char* state : {R"({})", R"({"objects": {"far_crate": {"visible": false}}})"}) {
    SCOPED_TRACE(state);
    write_text(dir.file("state.json"), state);
    expect_success({"recompose", dir.file("planned.lpk"), "--state", dir.file("state.json"), "-o",
                    dir.file("p.pfm")});
    expect_success({"recompose", dir.file("forced.lpk"), "--state", dir.file("state.json"), "-o",
                    dir.file("f.pfm")});
    // The far crate blocks none of the lamp's light: the same maps, the same bytes of light map.
    EXPECT_EQ(cooker::read_pfm(dir.file("p.pfm")).data, cooker::read_pfm(dir.file("f.pfm")).data);
  }
}

TEST(Plan, ForcedCookKeepsWhatThePlanSkipsAndRecomposesTheSameStates) {
  ScratchDir dir;
  open_floor().write(dir.file("floor.glb"));
  const std::string scene = dir.file("floor.glb");
  expect_success(cat({"cook", scene, "-o", dir.file("planned.lpk"), "--report",
                      dir.file("planned.json"), "--write-gltf", dir.file("planned.glb")},
                     kFast));
  expect_success(cat({"cook", scene, "-o", dir.file("forced.lpk"), "--no-plan", "--report",
                      dir.file("forced.json")},
                     kFast));
  const nlohmann::json planned = load(dir.file("planned.json"));
  const nlohmann::json forced = load(dir.file("forced.json"));
  EXPECT_EQ(planned["bake"]["plan_effects"], true);
  EXPECT_EQ(forced["bake"]["plan_effects"], false);
  // bake-state takes --no-plan too (every object's bounce) and bakes the same layout.
  expect_success(cat({"bake-state", scene, "--no-plan", "-o", dir.file("state.pfm"), "--report",
                      dir.file("state.json")},
                     kFast));
  EXPECT_EQ(load(dir.file("state.json"))["bake"]["plan_effects"], false);
  EXPECT_EQ(cooker::read_pfm(dir.file("state.pfm")).width, 64);

  // The far crate: out of the lamp's direct reach, it may still change the lamp's bounce light;
  // the plan drops its pair (for its peak, or its bounce change's first bounce); forced, the pair
  // is kept.
  const nlohmann::json* far_planned = find_decision(planned, "pair", "lamp", "far_crate");
  const nlohmann::json* far_forced = find_decision(forced, "pair", "lamp", "far_crate");
  ASSERT_NE(far_planned, nullptr);
  ASSERT_NE(far_forced, nullptr);
  EXPECT_FALSE((*far_planned)["taken"].get<bool>());
  EXPECT_FALSE((*far_planned)["reason"].get<std::string>().empty());
  EXPECT_TRUE((*far_forced)["taken"].get<bool>());
  EXPECT_TRUE((*far_forced)["forced"].get<bool>());
  EXPECT_LT(planned["pairs_kept"].get<int>(), forced["pairs_kept"].get<int>());
  EXPECT_EQ(forced["pairs_skipped"].get<int>(), 0);

  // Indirect light: forcing keeps the lamp's bounce light with every object's change to it; the
  // plan decides from the bounce light's peak.
  const nlohmann::json* ind_forced = find_decision(forced, "group_bounce", "lamp");
  ASSERT_NE(ind_forced, nullptr);
  EXPECT_TRUE((*ind_forced)["taken"].get<bool>());
  const nlohmann::json* ind_planned = find_decision(planned, "group_bounce", "lamp");
  ASSERT_NE(ind_planned, nullptr);
  EXPECT_FALSE((*ind_planned)["reason"].get<std::string>().empty());
  const nlohmann::json* bounce_far = find_decision(forced, "object_bounce", "lamp", "far_crate");
  ASSERT_NE(bounce_far, nullptr);
  EXPECT_TRUE((*bounce_far)["taken"].get<bool>());
  // A point light has no size: nothing to force.
  const nlohmann::json* soft = find_decision(forced, "soft_shadows", "lamp");
  ASSERT_NE(soft, nullptr);
  EXPECT_FALSE((*soft)["taken"].get<bool>());
  EXPECT_FALSE((*soft)["forced"].get<bool>());
  // Colour: forced keeps every 3-channel patch at 3 channels.
  EXPECT_EQ(forced["pack"]["colour"]["patches_1_channel_from_3"], 0);
  EXPECT_GE(forced["pack"]["patches"].get<int>(), planned["pack"]["patches"].get<int>());
  EXPECT_GE(forced["pack"]["groups"].get<int>(), planned["pack"]["groups"].get<int>());

  // Both packs recompose every state of the crates alike: each map in play may differ by its
  // significance threshold (half an output step at the authored exposure, below which the plan
  // drops maps and the pack drops texels) and its 8-bit quantization (up to a step), so one
  // output step per map in play per pack.
  const float step = planned["bake"]["output_step"].get<float>();
  ASSERT_GT(step, 0.0f);
  // The texels a mesh reads: the bilinear taps of every triangle's light-map box (the cooked
  // glTF's TEXCOORD_1). A pack that cuts a patch along its charts drops the rest (the
  // dilation's fill, a border's outer ring: Layout.BilinearReadsOfEveryTriangleStayInsideItsChart
  // LessTheOuterBorderRings), and the two packs need not cut the same patches.
  const int side = 64;  // kFast's --lightmap-size
  std::vector<uint8_t> reads(size_t(side) * side, 0);
  const cooker::Scene cooked = cooker::import_gltf(dir.file("planned.glb"));
  for (const cooker::MeshInstance& m : cooked.meshes) {
    ASSERT_EQ(m.uv1.size(), m.positions.size());
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      glm::vec2 lo(1e30f), hi(-1e30f);
      for (size_t k = 0; k < 3; ++k) {
        lo = glm::min(lo, m.uv1[m.indices[t + k]] * float(side));
        hi = glm::max(hi, m.uv1[m.indices[t + k]] * float(side));
      }
      const int x0 = std::max(0, int(std::floor(lo.x - 0.5f)));
      const int x1 = std::min(side - 1, int(std::floor(hi.x - 0.5f)) + 1);
      const int y0 = std::max(0, int(std::floor(lo.y - 0.5f)));
      const int y1 = std::min(side - 1, int(std::floor(hi.y - 0.5f)) + 1);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) reads[size_t(y) * side + size_t(x)] = 1;
    }
  }
  const std::vector<std::pair<std::string, int>> states = {
      {R"({})", 4},
      {R"({"objects": {"crate": {"visible": false}}})", 3},
      {R"({"objects": {"far_crate": {"visible": false}}})", 3},
      {R"({"lights": {"lamp": {"intensity": 2.0, "color": [0.2, 1.0, 0.5]}}})", 4},
  };
  for (size_t i = 0; i < states.size(); ++i) {
    SCOPED_TRACE(states[i].first);
    const std::string state = dir.file("state" + std::to_string(i) + ".json");
    write_text(state, states[i].first);
    expect_success(
        {"recompose", dir.file("planned.lpk"), "--state", state, "-o", dir.file("p.pfm")});
    expect_success(
        {"recompose", dir.file("forced.lpk"), "--state", state, "-o", dir.file("f.pfm")});
    const cooker::FloatImage p = cooker::read_pfm(dir.file("p.pfm"));
    const cooker::FloatImage f = cooker::read_pfm(dir.file("f.pfm"));
    ASSERT_EQ(p.data.size(), f.data.size());
    // The lamp's state scales its maps: the light's factor over its authored one.
    const float scale = i == 3 ? 2.0f * 1.0f / 6.0f : 1.0f;
    const float tolerance = 2.0f * float(states[i].second) * step * std::max(1.0f, scale);
    ASSERT_EQ(p.data.size(), reads.size() * 3);
    float worst = 0.0f, peak = 0.0f;
    for (size_t k = 0; k < p.data.size(); ++k) {
      if (!reads[k / 3]) continue;
      worst = std::max(worst, std::fabs(p.data[k] - f.data[k]));
      peak = std::max(peak, f.data[k]);
    }
    EXPECT_GT(peak, 10.0f * step);  // the states are lit: the comparison measures something
    EXPECT_LE(worst, tolerance) << "output step " << step;
    std::printf("planned vs forced, state %zu: max difference %.3g (%.2f output steps)\n", i, worst,
                worst / step);
  }
}

TEST(Plan, MeasurePlanReportsTimesBytesAndCountsOfBothRuns) {
  ScratchDir dir;
  open_floor().write(dir.file("floor.glb"));
  const std::vector<std::string> args =
      cat({"cook", dir.file("floor.glb"), "-o", dir.file("floor.lpk"), "--measure-plan", "--report",
           dir.file("report.json")},
          {"--quality", "draft", "--lightmap-size", "64", "--gather-rays", "32"});
  const ToolRun r = run_tool(args);
  ASSERT_EQ(r.code, 0) << describe(args, r);
  EXPECT_NE(r.err.find("plan: saved"), std::string::npos) << r.err;
  const nlohmann::json report = load(dir.file("report.json"));
  ASSERT_TRUE(report.contains("plan")) << report.dump(2);
  const nlohmann::json& plan = report["plan"];
  for (const char* run : {"planned", "forced"}) {
    SCOPED_TRACE(run);
    const nlohmann::json& j = plan[run];
    for (const char* key : {"seconds", "rays", "pack_bytes", "atlas_bytes", "patches", "groups"}) {
      ASSERT_TRUE(j[key].is_number()) << key;
      const double v = j[key].get<double>();
      EXPECT_TRUE(std::isfinite(v) && v >= 0.0) << key << " = " << v;
    }
    for (const auto& [stage, seconds] : j["stage_seconds"].items()) {
      const double v = seconds.get<double>();
      EXPECT_TRUE(std::isfinite(v) && v >= 0.0) << stage << " = " << v;
    }
    EXPECT_TRUE(j["stage_seconds"].contains("bake"));
    EXPECT_TRUE(j["stage_seconds"].contains("pack"));
  }
  // The planned run is timed again after the forced one; it gives the pack written.
  EXPECT_EQ(plan["planned_pack_identical"], true);
  EXPECT_EQ(plan["planned"]["pack_bytes"].get<double>(),
            double(read_bytes(dir.file("floor.lpk")).size()));
  EXPECT_GE(plan["forced"]["patches"].get<double>(), plan["planned"]["patches"].get<double>());
  EXPECT_GE(plan["forced"]["groups"].get<double>(), plan["planned"]["groups"].get<double>());
  EXPECT_GE(plan["forced"]["rays"].get<double>(), plan["planned"]["rays"].get<double>());
  EXPECT_EQ(
      plan["saved"]["pack_bytes"].get<double>(),
      plan["forced"]["pack_bytes"].get<double>() - plan["planned"]["pack_bytes"].get<double>());
  for (const char* category : {"pairs", "overlap_corrections", "indirect_groups", "object_bounce",
                               "static_shadows", "colour"}) {
    SCOPED_TRACE(category);
    const nlohmann::json& c = plan["categories"][category];
    for (const char* run : {"planned", "forced"}) {
      EXPECT_GE(c[run]["taken"].get<double>(), 0.0);
      EXPECT_GE(c[run]["skipped"].get<double>(), 0.0);
    }
  }
  const nlohmann::json& pairs = plan["categories"]["pairs"];
  EXPECT_GT(pairs["planned"]["skipped"].get<int>(), 0);
  EXPECT_EQ(pairs["forced"]["skipped"].get<int>(), 0);
  EXPECT_GT(pairs["forced"]["taken"].get<int>(), pairs["planned"]["taken"].get<int>());
  EXPECT_EQ(plan["categories"]["object_bounce"]["forced"]["skipped"].get<int>(), 0);
  EXPECT_EQ(plan["categories"]["colour"]["forced"]["skipped"].get<double>(), 0.0);
  ASSERT_FALSE(plan["groups"].empty());
  for (const nlohmann::json& g : plan["groups"]) {
    EXPECT_GE(g["planned_s"].get<double>(), 0.0);
    EXPECT_GT(g["forced_s"].get<double>(), 0.0);
  }
  // Every decision has a reason; a saved time only where one was measured, and finite.
  int with_time = 0;
  for (const nlohmann::json& d : report["decisions"]) {
    EXPECT_FALSE(d["reason"].get<std::string>().empty()) << d.dump();
    if (d.contains("time_saved_s")) {
      ++with_time;
      EXPECT_FALSE(d["taken"].get<bool>()) << d.dump();
      EXPECT_TRUE(std::isfinite(d["time_saved_s"].get<double>())) << d.dump();
    }
  }
  EXPECT_EQ(with_time, plan["decisions_timed"].get<int>());
  // --measure-plan compares with --no-plan: both at once is refused.
  const ToolRun both = run_tool({"cook", dir.file("floor.glb"), "-o", dir.file("x.lpk"),
                                 "--measure-plan", "--no-plan", "--quiet"});
  EXPECT_EQ(both.code, 2) << both.err;
  EXPECT_NE(both.err.find("--measure-plan"), std::string::npos) << both.err;
}

}  // namespace
}  // namespace lightpatch::test
