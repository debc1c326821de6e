// The `lightpatch` tool against hostile files and commands (issue 15), run as a user runs it: an
// output that is an input or another output, outputs and inputs that are not regular files,
// inputs over the size limit, leftovers of killed runs, packs the runtime cannot recompose,
// names that would drive the terminal. Each gets exit status 1 and a message naming the problem
// (for a limit: the limit and the option that raises it); nothing is overwritten or left behind.
// Also: every limit is documented in --help and the README.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gltf_files.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/pack_format.h"
#include "pack_bytes.h"
#include "tool_runner.h"

namespace lightpatch::test {
namespace {

namespace fs = std::filesystem;

// The command exits 1 with every one of `words` on stderr, and the folder and `kept` (if not
// empty) are byte for byte as before.
ToolRun expect_refusal(const ScratchDir& dir, const std::vector<std::string>& args,
                       const std::vector<std::string>& words, const std::string& kept = "") {
  const std::vector<std::string> before = dir.entries();
  const std::vector<std::uint8_t> old =
      kept.empty() ? std::vector<std::uint8_t>() : read_bytes(kept);
  const ToolRun r = run_tool(args);
  const std::string what = describe(args, r);
  EXPECT_EQ(r.code, 1) << what;
  for (const std::string& w : words)
    EXPECT_NE(r.err.find(w), std::string::npos) << "'" << w << "' not in stderr: " << what;
  if (!kept.empty()) {
    EXPECT_TRUE(read_bytes(kept) == old) << kept << " changed: " << what;
  }
  EXPECT_EQ(dir.entries(), before) << "files left behind or removed: " << what;
  return r;
}

// A scene, a state and a pack cooked from them, in a scratch folder.
struct Cooked {
  ScratchDir dir;
  std::string scene = dir.file("room.glb"), state = dir.file("state.json"),
              pack = dir.file("room.lpk");
  Cooked() {
    small_room().write(scene);
    write_text(state, R"({"lights": {"lamp": {"on": false}}})");
    expect_success(cat({"cook", scene, "-o", pack}, kFast));
  }
};

// Writes `bytes` edited by `edit` (checksum fixed) as `name` in `dir`; returns its path.
template <typename Edit>
std::string edited_pack(const ScratchDir& dir, const std::string& source, const std::string& name,
                        Edit edit) {
  const std::vector<std::uint8_t> bytes = read_bytes(source);
  Aligned a(bytes, bytes.size());
  edit(a.data());
  fix_checksum(a.data(), a.size);
  const std::string path = dir.file(name);
  write_bytes(path, std::vector<std::uint8_t>(a.data(), a.data() + a.size));
  return path;
}

template <typename T>
T* section_record(std::uint8_t* d, std::uint32_t type, std::uint32_t index) {
  pack::Header h;
  std::memcpy(&h, d, sizeof(h));
  for (std::uint32_t i = 0; i < h.section_count; ++i) {
    pack::SectionEntry e;
    std::memcpy(&e, d + sizeof(h) + i * sizeof(e), sizeof(e));
    if (e.type == type) return reinterpret_cast<T*>(d + e.offset) + index;
  }
  return nullptr;
}

TEST(HostileTool, AnOutputThatIsAnInputOrAnotherOutputIsRefused) {
  Cooked c;
  const std::string& s = c.scene;
  const std::string map = c.dir.file("map.pfm");
  fs::create_hard_link(s, c.dir.file("alias.glb"));
  auto fast = [](const std::vector<std::string>& args) { return cat(args, kFast); };
  struct Case {
    std::vector<std::string> args;
    std::string kept, word;
  };
  const std::vector<Case> cases = {
      {fast({"cook", s, "-o", s}), s, "it is the input"},
      {fast({"bake-state", s, "-o", s}), s, "it is the input"},
      {fast({"bake-state", s, "--state", c.state, "-o", c.state}), c.state, "it is the input"},
      {fast({"cook", s, "-o", c.pack, "--report", c.pack}), c.pack, "it is also the output"},
      {fast({"cook", s, "-o", map, "--report", s}), s, "it is the input"},
      {fast({"cook", s, "-o", c.dir.file("alias.glb")}), s, "it is the input"},
      {{"recompose", c.pack, "-o", c.pack}, c.pack, "it is the input"},
      {{"recompose", c.pack, "--state", c.state, "-o", c.state}, c.state, "it is the input"},
  };
  for (const Case& k : cases) expect_refusal(c.dir, k.args, {"refusing to write", k.word}, k.kept);
}

TEST(HostileTool, OutputsAndInputsThatAreNotRegularFilesAreRefused) {
  Cooked c;
  const std::string fifo = c.dir.file("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string map = c.dir.file("map.pfm");
  expect_refusal(c.dir, cat({"cook", c.scene, "-o", fifo}, kFast), {"it exists and is a FIFO"});
  expect_refusal(c.dir, cat({"cook", c.scene, "-o", "/dev/null"}, kFast),
                 {"'/dev/null': it exists and is a character device"});
  expect_refusal(c.dir, {"recompose", c.pack, "-o", "/dev/null"}, {"character device"});
  struct stat st {};
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  // Inputs: refused at once (a FIFO without a writer would block a plain open).
  expect_refusal(c.dir, cat({"cook", "/dev/zero", "-o", c.dir.file("z.lpk")}, kFast),
                 {"'/dev/zero': it is a character device, not a regular file"});
  expect_refusal(c.dir, cat({"bake-state", c.scene, "--state", fifo, "-o", map}, kFast),
                 {"it is a FIFO, not a regular file"});
  expect_refusal(c.dir, {"recompose", c.pack, "--states", "/dev/urandom", "-o", map},
                 {"'/dev/urandom': it is a character device"});
  expect_refusal(c.dir, {"verify", fifo}, {"not a regular file"});
}

TEST(HostileTool, InputsOverTheSizeLimitAreRefusedNamingTheOption) {
  Cooked c;
  const std::string big = c.dir.file("big.json");
  write_text(big, "{\"lights\": {}}" + std::string((3 << 20) / 2, ' '));  // 1.5 MiB
  const std::string map = c.dir.file("map.pfm");
  expect_refusal(
      c.dir, {"recompose", c.pack, "--state", big, "--max-input-mb", "1", "-o", map},
      {"over the input size limit of 1048576 bytes (1 MiB; --max-input-mb N raises it)"});
  const ToolRun zero = run_tool({"verify", c.pack, "--max-input-mb", "0"});
  EXPECT_EQ(zero.code, 2) << zero.err;  // a usage error
  EXPECT_NE(zero.err.find("--max-input-mb takes an integer in [1, "), std::string::npos)
      << zero.err;
  expect_success({"recompose", c.pack, "--state", big, "--max-input-mb", "2", "-o", map});
}

TEST(HostileTool, ALeftoverOfAKilledRunIsRemovedByTheNextRun) {
  Cooked c;
  const pid_t pid = ::fork();  // a pid no process has once reaped
  if (pid == 0) ::_exit(0);
  int status = 0;
  ::waitpid(pid, &status, 0);
  const std::string leftover = c.pack + cooker::kTemporaryMarker + std::to_string(pid) + "-q1W2e3";
  write_text(leftover, "a pack cut short by SIGKILL");
  expect_success(cat({"cook", c.scene, "-o", c.pack}, kFast));
  EXPECT_FALSE(fs::exists(leftover));
  EXPECT_EQ(c.dir.entries(), (std::vector<std::string>{"room.glb", "room.lpk", "state.json"}));
}

TEST(HostileTool, VerifyRefusesWhatTheRuntimeCannotRecompose) {
  Cooked c;
  const std::string huge_scale = edited_pack(c.dir, c.pack, "scale.lpk", [](std::uint8_t* d) {
    section_record<pack::PatchRecord>(d, pack::kSectionPatches, 0)->scale = 1e38f;
  });
  const std::string huge_map = edited_pack(c.dir, c.pack, "map.lpk", [](std::uint8_t* d) {
    auto* h = reinterpret_cast<pack::Header*>(d);
    h->lightmap_width = h->lightmap_height = pack::kMaxLightmapSize;
  });
  const std::string wide_map = edited_pack(c.dir, c.pack, "wide.lpk", [](std::uint8_t* d) {
    auto* h = reinterpret_cast<pack::Header*>(d);
    h->lightmap_width = 4097;
    h->lightmap_height = 4096;
  });
  const std::string not_utf8 = edited_pack(c.dir, c.pack, "utf8.lpk", [](std::uint8_t* d) {
    const auto* l = section_record<pack::LightRecord>(d, pack::kSectionLights, 0);
    section_record<std::uint8_t>(d, pack::kSectionStrings, 0)[l->name_offset] = 0xFF;
  });
  const std::string out = c.dir.file("out.pfm");
  for (const std::string verb : {"verify", "info", "recompose"}) {
    SCOPED_TRACE(verb);
    auto args = [&](const std::string& pack) {
      return verb == "recompose" ? std::vector<std::string>{verb, pack, "-o", out}
                                 : std::vector<std::string>{verb, pack};
    };
    expect_refusal(c.dir, args(huge_scale),
                   {"out of range: the authored light map could reach 1e+38, beyond the 1e+36 "
                    "the runtime opens (no option raises it"});
    expect_refusal(c.dir, args(huge_map),
                   {"light map 16384x16384 is 268435456 texels, over the limit of 16777216",
                    "(--max-lightmap-texels N raises it)"});
    expect_refusal(c.dir, args(not_utf8), {"corrupt: light 0: name is not valid UTF-8"});
  }
  expect_refusal(c.dir, {"info", not_utf8, "--json"}, {"not valid UTF-8"});
  // One texel column over the default, then accepted with the limit raised.
  expect_refusal(c.dir, {"verify", wide_map}, {"(--max-lightmap-texels N raises it)"});
  expect_success({"verify", wide_map, "--max-lightmap-texels", "16781312"});
}

TEST(HostileTool, ACookTheRuntimeWouldRefuseIsNotWritten) {
  ScratchDir dir;
  GltfParts p = parts_of(small_room());
  p.json["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = 1e37;  // the lamp
  const std::string scene = write_glb(dir, "bright", p);
  expect_refusal(dir, cat({"cook", scene, "-o", dir.file("bright.lpk")}, kFast),
                 {"the cooked pack is one the runtime refuses: out of range",
                  "beyond the 1e+36 the runtime opens"});
}

TEST(HostileTool, InfoPrintsNamesEscaped) {
  ScratchDir dir;
  GltfParts p = parts_of(small_room());
  const std::string name = "lamp\x1b[2J\n\xe2\x80\xae";
  for (auto& n : p.json["nodes"])
    if (n["name"] == "lamp") n["name"] = name;
  const std::string scene = write_glb(dir, "room", p);
  const std::string pack = dir.file("room.lpk");
  expect_success(cat({"cook", scene, "-o", pack}, kFast));
  const ToolRun info = expect_success({"info", pack});
  EXPECT_EQ(info.out.find('\x1b'), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("  lamp\\x1B[2J\\n\\u202E  colour"), std::string::npos) << info.out;
  const ToolRun json = expect_success({"info", pack, "--json"});
  EXPECT_EQ(json.out.find('\x1b'), std::string::npos);  // JSON escapes control characters
  EXPECT_EQ(nlohmann::json::parse(json.out)["lights"][0]["name"], name);
}

TEST(HostileTool, SceneLimitRefusalsNameTheOptionThatRaisesThem) {
  ScratchDir dir;
  small_room().write(dir.file("room.glb"));
  const std::string out = dir.file("room.lpk");
  expect_refusal(dir,
                 cat({"cook", dir.file("room.glb"), "-o", out, "--max-triangles", "10"}, kFast),
                 {"over the limit of 10 triangles (--max-triangles N raises it)"});
  expect_refusal(
      dir,
      cat({"bake-state", dir.file("room.glb"), "-o", dir.file("m.pfm"), "--max-vertices", "10"},
          kFast),
      {"over the limit of 10 vertices (--max-vertices N raises it)"});
  // A buffer outside the scene's folder, and what allows it.
  fs::create_directories(dir.path() / "scene");
  GltfParts p = parts_of(small_room());
  write_bytes(dir.file("shared.bin"), p.bin);
  p.json["buffers"][0]["uri"] = "../shared.bin";
  write_text(dir.file("scene/room.gltf"), p.json.dump());
  expect_refusal(dir, cat({"cook", dir.file("scene/room.gltf"), "-o", out}, kFast),
                 {"is outside the scene's folder", "--uri-root DIR allows files under DIR"});
  expect_success(cat(
      {"cook", dir.file("scene/room.gltf"), "-o", out, "--uri-root", dir.path().string()}, kFast));
}

std::string readme() {
  std::ifstream f(LIGHTPATCH_README);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

TEST(HostileTool, EveryLimitIsDocumentedInHelpAndReadme) {
  const std::vector<std::string> scene_limits = {
      "--max-triangles N",      "4000000",  "--max-vertices N", "12000000",
      "--max-texture-pixels N", "33554432", "--uri-root DIR"};
  const std::vector<std::string> pack_limits = {"--max-lightmap-texels N", "16777216", "1e36"};
  const std::vector<std::string> input_limit = {"--max-input-mb N", "1024"};
  for (const std::string verb :
       {"cook", "bake-state", "accuracy", "info", "verify", "recompose", "bench", "preview"}) {
    SCOPED_TRACE(verb);
    const ToolRun help = expect_success({verb, "--help"});
    const bool imports = verb == "cook" || verb == "bake-state" || verb == "accuracy";
    for (const std::string& w : cat(imports ? scene_limits : pack_limits, input_limit))
      EXPECT_NE(help.out.find(w), std::string::npos) << "'" << w << "' not in: " << help.out;
  }
  const std::string text = readme();
  const size_t section = text.find("## Limits");
  ASSERT_NE(section, std::string::npos) << "README has no Limits section";
  for (const std::string& w : cat(cat(scene_limits, pack_limits), input_limit))
    EXPECT_NE(text.find(w.substr(0, w.find(' ')), section), std::string::npos)
        << "'" << w << "' not in the README's Limits section";
}

}  // namespace
}  // namespace lightpatch::test
