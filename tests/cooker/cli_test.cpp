// The `lightpatch` tool as a user runs it (DESIGN.md, Command line): the verbs succeed on a small
// valid scene and write their outputs; on bad input they exit non-zero with a message on stderr,
// leave an existing output file byte for byte as it was and leave no temporary file behind.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gltf_files.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/pack_format.h"
#include "tool_runner.h"

namespace lightpatch::test {
namespace {

// Runs a command that must fail: non-zero exit, a message on stderr containing `word`, `output`
// (if not empty) byte for byte as before, and the folder holding exactly what it held before.
void expect_failure(const ScratchDir& dir, const std::vector<std::string>& args,
                    const std::string& word, const std::string& output) {
  const std::vector<std::string> before = dir.entries();
  const std::vector<std::uint8_t> old =
      output.empty() ? std::vector<std::uint8_t>() : read_bytes(output);
  const ToolRun r = run_tool(args);
  const std::string what = describe(args, r);
  EXPECT_NE(r.code, 0) << what;
  EXPECT_LT(r.code, 128) << "killed by a signal: " << what;
  EXPECT_FALSE(r.err.empty()) << what;
  EXPECT_NE(r.err.find(word), std::string::npos) << "'" << word << "' not in stderr: " << what;
  if (!output.empty()) {
    ASSERT_TRUE(std::filesystem::exists(output)) << what;
    EXPECT_TRUE(read_bytes(output) == old) << output << " changed: " << what;
  }
  EXPECT_EQ(dir.entries(), before) << "files left behind or removed: " << what;
}

void write_precious(const std::string& path) {
  write_text(path, "precious bytes, keep me\n");
}

TEST(Cli, CookInfoVerifyRecomposeAndBakeStateOnASmallScene) {
  ScratchDir dir;
  small_room().write(dir.file("room.glb"));
  expect_success(cat({"cook", dir.file("room.glb"), "-o", dir.file("room.lpk"), "--report",
                      dir.file("report.json")},
                     kFast));
  ASSERT_TRUE(std::filesystem::exists(dir.file("room.lpk")));
  const nlohmann::json report = nlohmann::json::parse(read_bytes(dir.file("report.json")));
  EXPECT_EQ(report["scene"]["objects"], 1);
  EXPECT_EQ(report["scene"]["semi_dynamic_lights"], 1);

  const ToolRun verify = expect_success({"verify", dir.file("room.lpk")});
  EXPECT_NE(verify.out.find("OK"), std::string::npos) << verify.out;
  const ToolRun info = expect_success({"info", dir.file("room.lpk")});
  EXPECT_NE(info.out.find("lamp"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("crate"), std::string::npos) << info.out;
  const ToolRun info_json = expect_success({"info", dir.file("room.lpk"), "--json"});
  const nlohmann::json j = nlohmann::json::parse(info_json.out);
  EXPECT_EQ(j["lightmap"]["width"], 32);
  EXPECT_EQ(j["objects"][0], "crate");
  // Patches by level add up to all of them, and what they take in the atlases (magnified
  // patches less than their destination) is what the waste figure counts.
  const nlohmann::json& pt = j["patches"];
  ASSERT_EQ(pt["by_level"].size(), 4u);
  uint64_t levels = 0;
  for (const auto& n : pt["by_level"]) levels += n.get<uint64_t>();
  EXPECT_EQ(levels, pt["total"].get<uint64_t>());
  EXPECT_EQ(pt["magnified"].get<uint64_t>(), levels - pt["by_level"][0].get<uint64_t>());
  EXPECT_EQ(pt["atlas_channel_texels"], j["atlas_patch_bytes"]);
  EXPECT_LE(pt["atlas_channel_texels"].get<uint64_t>(), pt["channel_texels"].get<uint64_t>());
  EXPECT_NE(info.out.find("magnified"), std::string::npos) << info.out;

  expect_success(
      {"recompose", dir.file("room.lpk"), "--backend", "cpu", "-o", dir.file("authored.pfm")});
  const cooker::FloatImage authored = cooker::read_pfm(dir.file("authored.pfm"));
  EXPECT_EQ(authored.width, 32);
  EXPECT_EQ(authored.height, 32);
  EXPECT_EQ(authored.channels, 3);
  double sum = 0;
  for (float v : authored.data) {
    ASSERT_TRUE(std::isfinite(v));
    sum += v;
  }
  EXPECT_GT(sum, 0.0);

  write_text(dir.file("dark.json"),
             R"({"lights": {"lamp": {"on": false}}, "objects": {"crate": {"visible": false}}})");
  write_text(dir.file("states.jsonl"),
             "{\"lights\": {\"lamp\": {\"intensity\": 2.0}}}\n\n"
             "{\"objects\": {\"crate\": {\"visible\": false}}}\n");
  expect_success({"recompose", dir.file("room.lpk"), "--state", dir.file("dark.json"), "-o",
                  dir.file("dark.pfm")});
  expect_success({"recompose", dir.file("room.lpk"), "--states", dir.file("states.jsonl"), "-o",
                  dir.file("states.pfm")});
  // bake-state: the same layout as the cook, so the same map size.
  expect_success(cat({"bake-state", dir.file("room.glb"), "--state", dir.file("dark.json"), "-o",
                      dir.file("dark_ref.pfm")},
                     kFast));
  const cooker::FloatImage dark = cooker::read_pfm(dir.file("dark.pfm"));
  const cooker::FloatImage dark_ref = cooker::read_pfm(dir.file("dark_ref.pfm"));
  EXPECT_EQ(dark_ref.width, dark.width);
  EXPECT_EQ(dark_ref.height, dark.height);
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"authored.pfm", "dark.json", "dark.pfm",
                                                     "dark_ref.pfm", "report.json", "room.glb",
                                                     "room.lpk", "states.jsonl", "states.pfm"}));
}

TEST(Cli, CookingTwiceGivesByteIdenticalPacks) {
  ScratchDir dir;
  small_room(0.05f).write(dir.file("room.gltf"));
  expect_success(cat({"cook", dir.file("room.gltf"), "-o", dir.file("a.lpk")}, kFast));
  expect_success(cat({"cook", dir.file("room.gltf"), "-o", dir.file("b.lpk")}, kFast));
  const std::vector<std::uint8_t> a = read_bytes(dir.file("a.lpk"));
  EXPECT_GT(a.size(), sizeof(pack::Header));
  EXPECT_TRUE(a == read_bytes(dir.file("b.lpk"))) << "two cooks of the same scene differ";
}

TEST(Cli, BadScenesAndOptionsLeaveTheOutputUntouched) {
  ScratchDir dir;
  small_room().write(dir.file("room.glb"));
  GltfParts nan_parts = parts_of(small_room());
  set_float(nan_parts, 0, 1, 1, std::nanf(""));
  write_glb(dir, "nan", nan_parts);
  write_text(dir.file("broken.gltf"), "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [");
  const std::string out = dir.file("out.lpk");
  const std::string map = dir.file("out.pfm");
  write_precious(out);
  write_precious(map);
  const std::string scene = dir.file("room.glb");

  for (const std::string verb : {"cook", "bake-state"}) {
    SCOPED_TRACE(verb);
    const std::string o = verb == "cook" ? out : map;
    expect_failure(dir, cat({verb, dir.file("broken.gltf"), "-o", o}, kFast), "invalid glTF", o);
    expect_failure(dir, cat({verb, dir.file("nan.glb"), "-o", o}, kFast), "NaN", o);
    expect_failure(dir, cat({verb, dir.file("absent.glb"), "-o", o}, kFast), "absent.glb", o);
    expect_failure(dir, {verb, scene, "-o", o, "--lightmap-size", "abc"}, "--lightmap-size", o);
    expect_failure(dir, {verb, scene, "-o", o, "--lightmap-size", "3"}, "--lightmap-size", o);
    expect_failure(dir, {verb, scene, "-o", o, "--texels-per-unit", "-1"}, "--texels-per-unit", o);
    expect_failure(dir, {verb, scene, "-o", o, "--texels-per-unit", "nan"}, "--texels-per-unit", o);
    expect_failure(dir, {verb, scene, "-o", o, "--quality", "ultra"}, "ultra", o);
    expect_failure(dir, {verb, scene, "-o", o, "--frobnicate"}, "--frobnicate", o);
    expect_failure(dir, {verb, scene, "-o", o, "--lightmap-size"}, "--lightmap-size", o);
    expect_failure(dir, {verb, "-o", o}, "SCENE", o);
    expect_failure(dir, cat({verb, scene}, kFast), "-o", o);
    expect_failure(dir, cat({verb, scene, "-o", dir.file("no/such/dir/x")}, kFast), "no/such/dir",
                   "");
    expect_failure(dir, cat({verb, scene, "-o", dir.path().string()}, kFast), "directory", "");
  }
}

TEST(Cli, EveryVerbDocumentsItsOptions) {
  const ToolRun top = expect_success({"--help"});
  for (const char* verb :
       {"cook", "bake-state", "info", "verify", "recompose", "bench", "accuracy"}) {
    SCOPED_TRACE(verb);
    EXPECT_NE(top.out.find(std::string("lightpatch ") + verb), std::string::npos) << top.out;
    const ToolRun help = expect_success({verb, "--help"});
    EXPECT_NE(help.out.find("usage: lightpatch"), std::string::npos) << help.out;
  }
  const ToolRun cook = expect_success({"cook", "--help"});
  for (const char* option :
       {"--lightmap-size",   "--texels-per-unit", "--quality",    "--no-indirect",
        "--area-samples",    "--texel-samples",   "--seed",       "--integrator",
        "--gather-rays",     "--indirect-scale",  "--denoise",    "--contact-texels",
        "--threads",         "--report",          "--quiet",      "--no-plan",
        "--measure-plan",    "--panes",           "--pane-level", "--max-patch-level",
        "--level-tolerance", "--bounce-tolerance"}) {
    EXPECT_NE(cook.out.find(option), std::string::npos) << option << " undocumented:\n" << cook.out;
  }
  const ToolRun bake_state = expect_success({"bake-state", "--help"});
  for (const char* option :
       {"--state", "--integrator", "--samples", "--target-noise", "--std-error", "--quality"}) {
    EXPECT_NE(bake_state.out.find(option), std::string::npos) << option << " undocumented:\n"
                                                              << bake_state.out;
  }
}

// bake-state --integrator reference: the map and its standard error beside it, same layout as
// the cook's integrator, its noise in the report; bad combinations refused, nothing written.
TEST(Cli, BakeStateReferenceWritesTheMapAndItsStandardError) {
  ScratchDir dir;
  small_room(0.1f).write(dir.file("room.glb"));
  const std::string scene = dir.file("room.glb");
  const std::vector<std::string> small = {"--lightmap-size", "32", "--quiet"};
  expect_success(
      cat({"bake-state", scene, "-o", dir.file("cook.pfm"), "--quality", "draft"}, small));
  expect_success(cat({"bake-state", scene, "-o", dir.file("ref.pfm"), "--integrator", "reference",
                      "--samples", "8", "--report", dir.file("ref.json")},
                     small));
  expect_success(cat({"bake-state", scene, "-o", dir.file("ref2.pfm"), "--integrator", "reference",
                      "--samples", "8", "--std-error", dir.file("noise.pfm")},
                     small));
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"cook.pfm", "noise.pfm", "ref.json", "ref.pfm",
                                                     "ref.stderr.pfm", "ref2.pfm", "room.glb"}));
  const cooker::FloatImage cook = cooker::read_pfm(dir.file("cook.pfm"));
  const cooker::FloatImage ref = cooker::read_pfm(dir.file("ref.pfm"));
  const cooker::FloatImage err = cooker::read_pfm(dir.file("ref.stderr.pfm"));
  EXPECT_EQ(ref.width, cook.width);
  EXPECT_EQ(ref.height, cook.height);
  EXPECT_EQ(err.width, ref.width);
  EXPECT_EQ(err.channels, 3);
  EXPECT_TRUE(read_bytes(dir.file("ref.pfm")) == read_bytes(dir.file("ref2.pfm")));
  EXPECT_TRUE(read_bytes(dir.file("ref.stderr.pfm")) == read_bytes(dir.file("noise.pfm")));
  double lit = 0.0, noisy = 0.0;
  for (size_t i = 0; i < ref.data.size(); ++i) {
    ASSERT_TRUE(std::isfinite(ref.data[i]) && std::isfinite(err.data[i]));
    ASSERT_GE(err.data[i], 0.0f);
    lit += ref.data[i];
    noisy += err.data[i];
  }
  EXPECT_GT(lit, 0.0);
  EXPECT_GT(noisy, 0.0);  // the room has bounce light: 8 samples cannot be exact
  const nlohmann::json report = nlohmann::json::parse(read_bytes(dir.file("ref.json")));
  ASSERT_TRUE(report.contains("reference")) << report.dump();
  EXPECT_EQ(report["reference"]["samples"], 8);
  EXPECT_GT(report["reference"]["rays"].get<double>(), 0.0);
  EXPECT_GT(report["reference"]["mean_rel_std_error"].get<double>(), 0.0);
  EXPECT_GT(report["reference"]["rel_rmse_noise"].get<double>(), 0.0);

  const std::string map = dir.file("ref.pfm");
  expect_failure(dir, cat({"bake-state", scene, "-o", map, "--integrator", "photon"}, small),
                 "--integrator", map);
  expect_failure(dir, cat({"bake-state", scene, "-o", map, "--samples", "8"}, small), "--samples",
                 map);
  expect_failure(
      dir,
      cat({"bake-state", scene, "-o", map, "--integrator", "reference", "--samples", "1"}, small),
      "--samples", map);
  expect_failure(
      dir,
      cat({"bake-state", scene, "-o", map, "--integrator", "reference", "--std-error", map}, small),
      "--std-error", map);
}

TEST(Cli, BakeOptionsReachTheBakeAndItsReport) {
  ScratchDir dir;
  small_room().write(dir.file("room.glb"));
  const std::string scene = dir.file("room.glb");
  expect_success(cat({"cook", scene, "-o", dir.file("direct.lpk"), "--no-indirect", "--report",
                      dir.file("direct.json")},
                     kFast));
  EXPECT_EQ(nlohmann::json::parse(read_bytes(dir.file("direct.json")))["indirect"]["enabled"],
            false);
  expect_success(
      cat({"cook", scene, "-o", dir.file("a.lpk"), "--gather-rays", "48", "--indirect-scale", "2",
           "--denoise", "1", "--seed", "7", "--threads", "1", "--report", dir.file("a.json")},
          kFast));
  const nlohmann::json a = nlohmann::json::parse(read_bytes(dir.file("a.json")));
  EXPECT_EQ(a["indirect"]["enabled"], true);
  EXPECT_EQ(a["indirect"]["integrator"], "gather");
  EXPECT_EQ(a["indirect"]["rays_per_coarse_texel"], 48);
  EXPECT_EQ(a["indirect"]["level"], 2);
  EXPECT_EQ(a["indirect"]["denoise_passes"], 1);
  // One thread or all cores: the same pack.
  expect_success(cat({"cook", scene, "-o", dir.file("b.lpk"), "--gather-rays", "48",
                      "--indirect-scale", "2", "--denoise", "1", "--seed", "7"},
                     kFast));
  EXPECT_TRUE(read_bytes(dir.file("a.lpk")) == read_bytes(dir.file("b.lpk")));
  // Another seed: other rays, another pack.
  expect_success(cat({"cook", scene, "-o", dir.file("c.lpk"), "--gather-rays", "48",
                      "--indirect-scale", "2", "--denoise", "1", "--seed", "8"},
                     kFast));
  EXPECT_FALSE(read_bytes(dir.file("a.lpk")) == read_bytes(dir.file("c.lpk")));
  expect_failure(dir, cat({"cook", scene, "-o", dir.file("x.lpk"), "--indirect-scale", "3"}, kFast),
                 "--indirect-scale", "");
  expect_failure(dir, cat({"cook", scene, "-o", dir.file("x.lpk"), "--pane-level", "4"}, kFast),
                 "--pane-level takes an integer in [0, 3]", "");
  expect_failure(dir,
                 cat({"cook", scene, "-o", dir.file("x.lpk"), "--max-patch-level", "4"}, kFast),
                 "--max-patch-level takes an integer in [0, 3]", "");
  expect_failure(dir,
                 cat({"cook", scene, "-o", dir.file("x.lpk"), "--level-tolerance", "0"}, kFast),
                 "--level-tolerance takes a number in", "");
  // A scale asked for is kept or refused, never lowered (auto lowers it to fit).
  expect_failure(dir,
                 {"cook", scene, "-o", dir.file("x.lpk"), "--quality", "draft", "--lightmap-size",
                  "36", "--indirect-scale", "8"},
                 "not a multiple of the indirect scale 8", "");
  expect_failure(dir, cat({"cook", scene, "-o", dir.file("x.lpk"), "--integrator", "vpl"}, kFast),
                 "integrator", "");
  const std::string out = dir.file("out.lpk");
  write_precious(out);
  expect_failure(dir, {"cook", scene, "-o", out, "--gather-rays", "0"}, "--gather-rays", out);
  expect_failure(dir, {"cook", scene, "-o", out, "--threads", "many"}, "--threads", out);
  expect_failure(dir, {"cook", scene, "-o", out, "--seed", "-3"}, "--seed", out);
}

TEST(Cli, BadStateFilesLeaveTheOutputUntouched) {
  ScratchDir dir;
  small_room().write(dir.file("room.glb"));
  const std::string scene = dir.file("room.glb");
  const std::string map = dir.file("out.pfm");
  write_precious(map);
  const std::vector<std::pair<std::string, std::string>> states = {
      {R"({"lights": {"candle_9": {"on": false}}})", "candle_9"},
      {R"({"objects": {"spell_book": {"visible": false}}})", "spell_book"},
      {R"({"lights": {"spot": {"on": false}}})", "spot"},  // static: cannot be switched
      {R"({"lights": {"lamp": {"on": false}})", "invalid JSON"},
      {R"({"lights": {"lamp": {"intensity": -1}}})", "intensity"},
      {R"({"lights": {"lamp": {"color": [1, 2]}}})", "color"},
      {R"({"objects": {"crate": {"visible": "no"}}})", "visible"},
      {R"({"light": {}})", "unknown key"},
      {"", "invalid JSON"},
  };
  for (size_t i = 0; i < states.size(); ++i) {
    SCOPED_TRACE(states[i].first);
    const std::string state = dir.file("state" + std::to_string(i) + ".json");
    write_text(state, states[i].first);
    expect_failure(dir, cat({"bake-state", scene, "--state", state, "-o", map}, kFast),
                   states[i].second, map);
  }
  expect_failure(dir,
                 cat({"bake-state", scene, "--state", dir.file("absent.json"), "-o", map}, kFast),
                 "absent.json", map);
}

TEST(Cli, DamagedPacksAndBadRecomposeInputsAreRejected) {
  ScratchDir dir;
  small_room().write(dir.file("room.glb"));
  expect_success(cat({"cook", dir.file("room.glb"), "-o", dir.file("room.lpk")}, kFast));
  const std::vector<std::uint8_t> pack = read_bytes(dir.file("room.lpk"));
  ASSERT_GT(pack.size(), 256u);
  const std::string map = dir.file("out.pfm");
  write_precious(map);

  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> damaged;
  damaged.push_back({"empty.lpk", {}});
  damaged.push_back(
      {"half.lpk", {pack.begin(), pack.begin() + static_cast<long>(pack.size() / 2)}});
  damaged.push_back({"short.lpk", {pack.begin(), pack.end() - 1}});
  damaged.push_back({"header.lpk", {pack.begin(), pack.begin() + 16}});
  std::vector<std::uint8_t> magic = pack;
  magic[0] ^= 0xFF;
  damaged.push_back({"magic.lpk", magic});
  std::vector<std::uint8_t> table = pack;
  table[sizeof(pack::Header) + 5] ^= 0x5A;  // inside the section index: the checksum fails
  damaged.push_back({"table.lpk", table});
  std::vector<std::uint8_t> longer = pack;
  longer.push_back(0);
  damaged.push_back({"longer.lpk", longer});
  for (const auto& [name, bytes] : damaged) {
    SCOPED_TRACE(name);
    write_bytes(dir.file(name), bytes);
    expect_failure(dir, {"recompose", dir.file(name), "--backend", "cpu", "-o", map}, name, map);
    expect_failure(dir, {"verify", dir.file(name)}, name, "");
    expect_failure(dir, {"info", dir.file(name)}, name, "");
  }
  expect_failure(dir, {"recompose", dir.file("absent.lpk"), "-o", map}, "absent.lpk", map);

  const std::string room = dir.file("room.lpk");
  write_text(dir.file("unknown.json"), R"({"objects": {"spell_book": {"visible": false}}})");
  expect_failure(dir, {"recompose", room, "--state", dir.file("unknown.json"), "-o", map},
                 "spell_book", map);
  write_text(dir.file("bad.jsonl"), "{\"lights\": {}}\n{not json}\n");
  expect_failure(dir, {"recompose", room, "--states", dir.file("bad.jsonl"), "-o", map},
                 "bad.jsonl:2", map);
  expect_failure(dir, {"recompose", room, "--backend", "vulkan", "-o", map}, "vulkan", map);
  expect_failure(dir, {"recompose", room}, "-o", map);
  expect_failure(dir,
                 {"recompose", room, "--state", dir.file("unknown.json"), "--states",
                  dir.file("bad.jsonl"), "-o", map},
                 "--state", map);
  expect_failure(dir, {"info"}, "PACK", "");
  expect_failure(dir, {"frobnicate"}, "unknown verb", "");
}

}  // namespace
}  // namespace lightpatch::test
