// `plan`, `cook-job`, `jobs` and `assemble` as a farm runs them, one process per step: the pack is
// byte-identical to `cook`; a job run again is a no-op; a missing, corrupted or stale result is
// named and nothing is written; after an edit only the jobs it changes have no result.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cooker/gltf_files.h"
#include "cooker/tool_runner.h"

namespace lightpatch::test {
namespace {

const std::vector<std::string> kFast = {"--quality", "draft", "--lightmap-size", "48", "--quiet"};

std::vector<std::string> cat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

ToolRun ok(const std::vector<std::string>& args) {
  const ToolRun r = run_tool(args);
  EXPECT_EQ(r.code, 0) << describe(args, r);
  return r;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);)
    if (!l.empty()) out.push_back(l);
  return out;
}

// The small room with a second semi-dynamic lamp (at `lamp2`): three light groups.
void write_room(const std::string& path, glm::vec3 lamp2 = {1.2f, 1.4f, -1.0f}) {
  scenegen::SceneBuilder b = small_room();
  b.add_light_node("lamp2",
                   {.name = "lamp2", .type = scenegen::LightType::kPoint, .intensity = 3.0f}, lamp2,
                   {0, -1, 0}, /*semi_dynamic=*/true, 0.05f);
  b.write(path);
}

// Folder entries below `dir`, recursively, with their sizes (what a failed step must not touch).
std::vector<std::string> tree(const std::string& dir) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    out.push_back(e.path().string() +
                  (e.is_regular_file() ? " " + std::to_string(e.file_size()) : ""));
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Jobs of the room (bounce light on): names[0] the gather rays, then the static lights, lamp and
// lamp2.
TEST(FarmCli, JobsInSeparateProcessesGiveTheCooksBytes) {
  ScratchDir dir;
  write_room(dir.file("room.glb"));
  ok(cat({"cook", dir.file("room.glb"), "-o", dir.file("cook.lpk")}, kFast));
  const std::string jobs = dir.file("jobs");
  const ToolRun plan = ok(cat({"plan", dir.file("room.glb"), "-o", jobs}, kFast));
  const std::vector<std::string> names = lines(plan.out);
  ASSERT_EQ(names.size(), 4u) << plan.out;
  EXPECT_EQ(names[0].rfind("gather-", 0), 0u);
  EXPECT_EQ(names[1].rfind("g000-", 0), 0u);
  EXPECT_EQ(lines(ok({"jobs", jobs}).out), names);
  EXPECT_EQ(lines(ok({"jobs", jobs, "--pending"}).out), names);

  // A light group before the gather job (it traces the rays itself), on one thread; then the
  // rest in one process, the gather job among them.
  ok({"cook-job", jobs, names[2], "--threads", "1", "--quiet"});
  EXPECT_EQ(lines(ok({"jobs", jobs, "--pending"}).out),
            (std::vector<std::string>{names[0], names[1], names[3]}));
  ok({"cook-job", jobs, names[3], names[0], names[1], "--quiet"});
  EXPECT_TRUE(lines(ok({"jobs", jobs, "--pending"}).out).empty());
  ok({"assemble", jobs, "-o", dir.file("farm.lpk"), "--quiet"});
  EXPECT_TRUE(read_bytes(dir.file("farm.lpk")) == read_bytes(dir.file("cook.lpk")))
      << "the assembled pack differs from cook's";

  // A light group after the gather job loads its rays instead of tracing them.
  std::filesystem::remove(jobs + "/results/" + names[3] + ".lpg");
  ok({"cook-job", jobs, names[3], "--quiet", "--report", dir.file("job.json")});
  const nlohmann::json report = nlohmann::json::parse(read_bytes(dir.file("job.json")));
  EXPECT_TRUE(report["stages"].contains("bake.gather_load")) << report["stages"].dump();
  EXPECT_FALSE(report["stages"].contains("bake.gather_rays")) << report["stages"].dump();
  ok({"assemble", jobs, "-o", dir.file("farm2.lpk"), "--quiet"});
  EXPECT_TRUE(read_bytes(dir.file("farm2.lpk")) == read_bytes(dir.file("cook.lpk")));

  // Run again: nothing to do, nothing rewritten.
  const std::string result = jobs + "/results/" + names[1] + ".lpg";
  const auto before = std::filesystem::last_write_time(result);
  const ToolRun again = ok({"cook-job", jobs, names[1]});
  EXPECT_NE(again.err.find("nothing to do"), std::string::npos) << again.err;
  EXPECT_EQ(std::filesystem::last_write_time(result), before);
}

// A moving light's panes are made where the jobs are assembled, from the gather rays the gather
// job wrote (which texels bounce light and which are buried): the same panes and bytes as cook.
TEST(FarmCli, AMovingLightsPanesFromTheGatherJobGiveTheCooksBytes) {
  ScratchDir dir;
  two_rooms_lantern().write(dir.file("rooms.glb"));
  ok(cat({"cook", dir.file("rooms.glb"), "-o", dir.file("cook.lpk")}, kFast));
  const std::string jobs = dir.file("jobs");
  const std::vector<std::string> names =
      lines(ok(cat({"plan", dir.file("rooms.glb"), "-o", jobs}, kFast)).out);
  ASSERT_GE(names.size(), 2u);
  EXPECT_EQ(names[0].rfind("gather-", 0), 0u);
  std::vector<std::string> run = {"cook-job", jobs};
  run.insert(run.end(), names.begin(), names.end());
  run.push_back("--quiet");
  ok(run);
  ok({"assemble", jobs, "-o", dir.file("farm.lpk"), "--quiet"});
  EXPECT_TRUE(read_bytes(dir.file("farm.lpk")) == read_bytes(dir.file("cook.lpk")))
      << "the assembled pack differs from cook's";
}

TEST(FarmCli, AssembleNamesMissingAndCorruptedResultsAndWritesNothing) {
  ScratchDir dir;
  write_room(dir.file("room.glb"));
  const std::string jobs = dir.file("jobs");
  const std::vector<std::string> names =
      lines(ok(cat({"plan", dir.file("room.glb"), "-o", jobs}, kFast)).out);
  ASSERT_EQ(names.size(), 4u);
  ok({"cook-job", jobs, names[0], names[1], names[2], "--quiet"});
  // names[2]'s result, cut short; names[3] never ran.
  const std::string cut = jobs + "/results/" + names[2] + ".lpg";
  std::vector<uint8_t> bytes = read_bytes(cut);
  bytes.resize(bytes.size() / 2);
  write_bytes(cut, bytes);
  const std::vector<std::string> before = tree(dir.path().string());
  const std::vector<std::string> args = {"assemble", jobs, "-o", dir.file("out.lpk")};
  const ToolRun r = run_tool(args);
  EXPECT_EQ(r.code, 1) << describe(args, r);
  EXPECT_NE(r.err.find(names[2]), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(names[3] + " (lamp2): missing"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(names[1]), std::string::npos) << r.err;
  EXPECT_EQ(tree(dir.path().string()), before) << "assemble wrote or removed files";
  // `jobs --pending` lists both; cook-job replaces the corrupted one.
  EXPECT_EQ(lines(ok({"jobs", jobs, "--pending"}).out),
            (std::vector<std::string>{names[2], names[3]}));
  ok({"cook-job", jobs, names[2], names[3], "--quiet"});
  ok({"assemble", jobs, "-o", dir.file("out.lpk"), "--quiet"});
}

TEST(FarmCli, AnEditRerunsOnlyTheJobsItChangesAndStaleJobsAreRefused) {
  ScratchDir dir;
  write_room(dir.file("room.glb"));
  const std::string jobs = dir.file("jobs");
  const std::vector<std::string> first =
      lines(ok(cat({"plan", dir.file("room.glb"), "-o", jobs}, kFast)).out);
  ASSERT_EQ(first.size(), 4u);
  ok(cat({"cook-job", jobs}, {first[0], first[1], first[2], first[3], "--quiet"}));

  // Move lamp2 after planning: its old job no longer matches the scene.
  write_room(dir.file("room.glb"), {1.1f, 1.4f, -0.9f});
  std::filesystem::remove(jobs + "/results/" + first[3] + ".lpg");
  const std::vector<std::string> before = tree(dir.path().string());
  const std::vector<std::string> stale = {"cook-job", jobs, first[3]};
  const ToolRun r = run_tool(stale);
  EXPECT_EQ(r.code, 1) << describe(stale, r);
  EXPECT_NE(r.err.find("plan again"), std::string::npos) << r.err;
  EXPECT_EQ(tree(dir.path().string()), before) << "a stale job wrote or removed files";

  // Plan again: lamp2's group has a new name; the gather rays and the other groups keep theirs
  // and their results.
  const std::vector<std::string> second =
      lines(ok(cat({"plan", dir.file("room.glb"), "-o", jobs}, kFast)).out);
  ASSERT_EQ(second.size(), 4u);
  EXPECT_EQ(second[0], first[0]);
  EXPECT_EQ(second[1], first[1]);
  EXPECT_EQ(second[2], first[2]);
  EXPECT_NE(second[3], first[3]);
  EXPECT_EQ(lines(ok({"jobs", jobs, "--pending"}).out), (std::vector<std::string>{second[3]}));
  ok({"cook-job", jobs, second[3], "--quiet"});
  ok({"assemble", jobs, "-o", dir.file("farm.lpk"), "--quiet"});
  ok(cat({"cook", dir.file("room.glb"), "-o", dir.file("cook.lpk")}, kFast));
  EXPECT_TRUE(read_bytes(dir.file("farm.lpk")) == read_bytes(dir.file("cook.lpk")));
}

TEST(FarmCli, JobNamesThatAreNotNamesAreRefused) {
  ScratchDir dir;
  write_room(dir.file("room.glb"));
  const std::string jobs = dir.file("jobs");
  ok(cat({"plan", dir.file("room.glb"), "-o", jobs}, kFast));
  for (const std::string& bad : {std::string("../../etc/passwd"), std::string("g000-xyz"),
                                 std::string("g000-0123456789abcdef0123456789abcdef")}) {
    const std::vector<std::string> args = {"cook-job", jobs, bad};
    const ToolRun r = run_tool(args);
    EXPECT_EQ(r.code, 1) << describe(args, r);
    EXPECT_FALSE(r.err.empty());
  }
  const std::vector<std::string> no_dir = {"assemble", dir.file("nowhere"), "-o",
                                           dir.file("x.lpk")};
  EXPECT_EQ(run_tool(no_dir).code, 1);
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.lpk")));
}

}  // namespace
}  // namespace lightpatch::test
