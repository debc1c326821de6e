// Hostile glTF input: each broken file, made by editing a valid scenegen scene, gets a CookError
// whose message names the problem (never a crash, never a scene).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "gltf_files.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/unwrap.h"

namespace lightpatch::test {
namespace {

namespace sg = scenegen;

// Imports `path` and checks that it fails with a CookError containing every one of `words`.
void expect_import_error(const std::string& path, const std::vector<std::string>& words) {
  try {
    const cooker::Scene s = cooker::import_gltf(path);
    ADD_FAILURE() << path << " imported without error (" << s.meshes.size() << " meshes)";
  } catch (const cooker::CookError& e) {
    const std::string m = e.what();
    for (const std::string& w : words)
      EXPECT_NE(m.find(w), std::string::npos) << "'" << w << "' not in: " << m;
  }
}

// Accessor index of `semantic` ("POSITION", ...; "indices") of the first primitive of mesh `mesh`.
int accessor_of(const GltfParts& p, int mesh, const std::string& semantic) {
  const auto& prim = p.json["meshes"][static_cast<size_t>(mesh)]["primitives"][0];
  return semantic == "indices" ? prim["indices"].get<int>()
                               : prim["attributes"][semantic].get<int>();
}

nlohmann::ordered_json& node_named(GltfParts& p, const std::string& name) {
  for (auto& n : p.json["nodes"])
    if (n["name"] == name) return n;
  throw std::runtime_error("test: no node " + name);
}

// small_room() meshes in order: 0 floor, 1 pillar, 2 crate.
struct Case {
  const char* name;
  std::function<void(GltfParts&)> edit;
  std::vector<std::string> words;
};

TEST(ImportErrors, EachBrokenSceneNamesItsProblem) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<Case> cases = {
      {"nan_position",
       [&](GltfParts& p) { set_float(p, accessor_of(p, 0, "POSITION"), 2, 1, nan); },
       {"'floor'", "POSITION 2", "NaN or infinite"}},
      {"inf_position",
       [&](GltfParts& p) { set_float(p, accessor_of(p, 2, "POSITION"), 0, 0, -inf); },
       {"'crate'", "POSITION 0", "NaN or infinite"}},
      {"nan_normal",
       [&](GltfParts& p) { set_float(p, accessor_of(p, 1, "NORMAL"), 5, 2, nan); },
       {"'pillar'", "NORMAL 5", "NaN or infinite"}},
      {"inf_normal",
       [&](GltfParts& p) { set_float(p, accessor_of(p, 0, "NORMAL"), 0, 1, inf); },
       {"NORMAL 0", "NaN or infinite"}},
      {"index_past_vertex_count",
       [&](GltfParts& p) { set_index(p, accessor_of(p, 2, "indices"), 4, 999); },
       {"'crate'", "index 4 = 999", "past the vertex count"}},
      {"accessor_reads_past_view",
       [&](GltfParts& p) { p.json["accessors"][accessor_of(p, 0, "POSITION")]["count"] = 100000; },
       {"POSITION", "past the end"}},
      {"view_past_buffer",
       [&](GltfParts& p) { p.json["bufferViews"][0]["byteOffset"] = 1 << 20; },
       {"bufferView 0", "past the end"}},
      {"missing_buffer_view",
       [&](GltfParts& p) { p.json["accessors"][accessor_of(p, 1, "NORMAL")]["bufferView"] = 77; },
       {"bufferView"}},
      {"missing_buffer", [&](GltfParts& p) { p.json["bufferViews"][3]["buffer"] = 5; }, {"buffer"}},
      {"no_buffers",
       [&](GltfParts& p) {
         p.json.erase("buffers");
         p.bin.clear();
       },
       {"buffer"}},
      {"zero_area_only",
       [&](GltfParts& p) {
         const int pos = accessor_of(p, 2, "POSITION");
         const size_t n = p.json["accessors"][pos]["count"];
         for (size_t v = 0; v < n; ++v)  // every vertex of the crate on one line
           for (int c = 0; c < 3; ++c) set_float(p, pos, v, c, c == 0 ? 0.1f * float(v) : 0.0f);
       },
       {"'crate'", "zero-area"}},
      {"unsupported_required_extension",
       [&](GltfParts& p) {
         p.json["extensionsUsed"].push_back("EXT_made_up");
         p.json["extensionsRequired"] = {"EXT_made_up"};
       },
       {"unsupported extension", "EXT_made_up"}},
      {"duplicate_object_names",
       [&](GltfParts& p) {
         node_named(p, "pillar")["extras"] = {{"semiDynamic", true}};
         node_named(p, "pillar")["name"] = "crate";
       },
       {"semi-dynamic", "share the name 'crate'"}},
      {"duplicate_light_names",
       [&](GltfParts& p) {
         node_named(p, "spot")["extras"] = {{"semiDynamic", true}};
         node_named(p, "spot")["name"] = "lamp";
       },
       {"semi-dynamic light", "share the name 'lamp'"}},
      {"unnamed_object",
       [&](GltfParts& p) { node_named(p, "crate").erase("name"); },
       {"semi-dynamic mesh node", "has no name"}},
      {"unnamed_light",
       [&](GltfParts& p) { node_named(p, "lamp")["name"] = ""; },
       {"semi-dynamic light node", "has no name"}},
      {"node_cycle",
       [&](GltfParts& p) {
         node_named(p, "floor")["children"] = {1};
         node_named(p, "pillar")["children"] = {0};
       },
       {"reached twice"}},
      {"missing_light",
       [&](GltfParts& p) {
         node_named(p, "lamp")["extensions"]["KHR_lights_punctual"]["light"] = 9;
       },
       {"'lamp'", "missing light 9"}},
      {"spot_cones_reversed",
       [&](GltfParts& p) {
         auto& spot = p.json["extensions"]["KHR_lights_punctual"]["lights"][1]["spot"];
         spot["innerConeAngle"] = 0.7;
         spot["outerConeAngle"] = 0.6;
       },
       {"'spot'", "cone"}},
      {"negative_intensity",
       [&](GltfParts& p) {
         p.json["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = -2.0;
       },
       {"'lamp'", "intensity"}},
      {"negative_light_radius",
       [&](GltfParts& p) { node_named(p, "lamp")["extras"]["lightRadius"] = -1.0; },
       {"lightRadius"}},
      {"nan_translation",
       [&](GltfParts& p) {
         node_named(p, "pillar")["translation"] = {1.0, 1e39, 0.0};
       },
       {"'pillar'", "non-finite transform"}},
      {"position_is_vec2",
       [&](GltfParts& p) { p.json["accessors"][accessor_of(p, 0, "POSITION")]["type"] = "VEC2"; },
       {"POSITION", "components"}},
      {"sparse_position",
       [&](GltfParts& p) {
         p.json["accessors"][accessor_of(p, 0, "POSITION")]["sparse"] = {
             {"count", 1},
             {"indices", {{"bufferView", 2}, {"componentType", 5123}}},
             {"values", {{"bufferView", 0}}}};
       },
       {"sparse"}},
      {"absurd_count_without_data",  // found by fuzz_gltf_import: std::bad_alloc, no message
       [&](GltfParts& p) {
         auto& acc = p.json["accessors"][accessor_of(p, 0, "POSITION")];
         acc.erase("bufferView");
         acc["count"] = 4000000000u;
       },
       {"4000000048 vertices", "mesh 0 'floor'", "--max-vertices"}},
      {"no_triangles_at_all",
       [&](GltfParts& p) {
         for (auto& n : p.json["nodes"]) n.erase("mesh");
       },
       {"no triangles"}},
  };
  ScratchDir dir;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    GltfParts parts = parts_of(small_room());
    c.edit(parts);
    const std::string path = write_glb(dir, c.name, parts);
    std::vector<std::string> words = c.words;
    words.push_back(path);  // every message names the file
    expect_import_error(path, words);
  }
}

TEST(ImportErrors, UnreadableAndEmptyFiles) {
  ScratchDir dir;
  expect_import_error(dir.file("absent.glb"), {"absent.glb", "No such file"});
  expect_import_error(dir.path().string(), {"directory"});
  write_text(dir.file("empty.gltf"), "");
  expect_import_error(dir.file("empty.gltf"), {"empty.gltf", "empty"});
}

TEST(ImportErrors, TruncatedGlbAtEveryLengthIsAnError) {
  ScratchDir dir;
  const std::vector<std::uint8_t> glb = small_room().to_glb();
  const std::string path = dir.file("cut.glb");
  size_t checked = 0;
  for (size_t cut = 0; cut < glb.size(); cut += (cut < 24 || cut + 16 > glb.size()) ? 1 : 41) {
    SCOPED_TRACE("cut at " + std::to_string(cut) + " of " + std::to_string(glb.size()));
    write_bytes(path, std::vector<std::uint8_t>(glb.begin(), glb.begin() + static_cast<long>(cut)));
    if (cut == 0)
      expect_import_error(path, {"empty"});
    else if (cut < 4)
      expect_import_error(path, {"invalid glTF"});  // not even the magic
    else
      expect_import_error(path, {"invalid glTF binary", "truncated"});
    ++checked;
  }
  EXPECT_GT(checked, 50u);
  // A BIN chunk that claims the 8 bytes of its own header as data (tinygltf 2.7 reads past the end
  // of such a file).
  GltfParts parts = parts_of(small_room());
  std::vector<std::uint8_t> bad = join_glb(parts);
  const size_t bin_header = 20 + (parts.json.dump().size() + 3) / 4 * 4;
  const std::uint32_t claimed = static_cast<std::uint32_t>(bad.size() - bin_header);
  std::memcpy(bad.data() + bin_header, &claimed, 4);
  write_bytes(path, bad);
  expect_import_error(path, {"BIN chunk", "truncated"});
}

TEST(ImportErrors, InvalidJson) {
  ScratchDir dir;
  GltfParts parts = parts_of(small_room());
  const std::string text = parts.json.dump(1);
  write_text(dir.file("half.gltf"), text.substr(0, text.size() / 2));
  expect_import_error(dir.file("half.gltf"), {"half.gltf", "invalid glTF"});
  write_text(dir.file("garbage.gltf"), "{\"asset\": {\"version\": \"2.0\"}, nodes: [}");
  expect_import_error(dir.file("garbage.gltf"), {"invalid glTF"});
  write_text(dir.file("array.gltf"), "[1, 2, 3]");
  expect_import_error(dir.file("array.gltf"), {"invalid glTF"});
  // Broken JSON inside a .glb container.
  std::vector<std::uint8_t> glb = join_glb(parts);
  glb[20] = '[';
  write_bytes(dir.file("json.glb"), glb);
  expect_import_error(dir.file("json.glb"), {"json.glb", "invalid glTF binary"});
}

// Found by fuzz_gltf_import: tinygltf parses extras recursively and overflowed the stack.
TEST(ImportErrors, DeeplyNestedJsonIsRefusedNotACrash) {
  ScratchDir dir;
  const std::string deep(100000, '[');
  write_text(dir.file("deep.gltf"),
             "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"extras\": " + deep +
                 std::string(100000, ']') + "}]}");
  expect_import_error(dir.file("deep.gltf"), {"deep.gltf", "nested deeper"});
  GltfParts parts = parts_of(small_room());
  nlohmann::ordered_json v = 1;
  for (int i = 0; i < 300; ++i) v = nlohmann::ordered_json{{"k", v}};
  parts.json["nodes"][0]["extras"] = v;
  expect_import_error(write_glb(dir, "deep", parts), {"deep.glb", "nested deeper"});
  // Brackets inside strings do not count, and ordinary nesting passes.
  GltfParts fine = parts_of(small_room());
  fine.json["nodes"][0]["extras"] = {{"note", std::string(1000, '[')}};
  EXPECT_EQ(cooker::import_gltf(write_glb(dir, "fine", fine)).objects.size(), 1u);
}

TEST(ImportErrors, MissingBinFileIsNamed) {
  ScratchDir dir;
  small_room().write(dir.file("room.gltf"));
  std::filesystem::remove(dir.file("room.bin"));
  expect_import_error(dir.file("room.gltf"), {"room.gltf", "room.bin"});
  // A .bin shorter than the buffer's byteLength.
  small_room().write(dir.file("short.gltf"));
  std::vector<std::uint8_t> bin = read_bytes(dir.file("short.bin"));
  bin.resize(bin.size() / 2);
  write_bytes(dir.file("short.bin"), bin);
  expect_import_error(dir.file("short.gltf"), {"short.gltf"});
}

TEST(ImportErrors, CorruptDracoData) {
  ScratchDir dir;
  GltfParts parts = parts_of(small_room(), {.draco = true});
  const size_t view = parts.json["meshes"][0]["primitives"][0]["extensions"]
                                ["KHR_draco_mesh_compression"]["bufferView"];
  const size_t at = parts.json["bufferViews"][view]["byteOffset"];
  const size_t len = parts.json["bufferViews"][view]["byteLength"];
  for (size_t i = at; i < at + len; ++i) parts.bin[i] = static_cast<std::uint8_t>(0xA5 ^ i);
  expect_import_error(write_glb(dir, "draco", parts), {"'floor'", "Draco"});

  GltfParts missing = parts_of(small_room(), {.draco = true});
  missing.json["meshes"][1]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
              ["bufferView"] = 40;
  expect_import_error(write_glb(dir, "draco_view", missing), {"'pillar'", "bufferView 40"});
}

TEST(ImportErrors, Texcoord1OutsideTheUnitSquare) {
  ScratchDir dir;
  sg::SceneBuilder b;
  sg::Geometry g = sg::make_quad({0, 0, 0}, {1, 0, 0}, {1, 0, -1}, {0, 0, -1});
  g.uv1 = {{0.0f, 0.0f}, {1.0f, 0.0f}, {0.0f, 1.0f}, {1.0f, 1.25f}};
  b.add_mesh_node("tile", g, -1);
  b.write(dir.file("outside.glb"));
  expect_import_error(dir.file("outside.glb"), {"'tile'", "TEXCOORD_1 3", "outside [0,1]"});

  GltfParts parts = parts_of(b);
  set_float(parts, accessor_of(parts, 0, "TEXCOORD_1"), 3, 1,
            std::numeric_limits<float>::quiet_NaN());
  expect_import_error(write_glb(dir, "nan_uv1", parts), {"TEXCOORD_1 3", "outside [0,1]"});
}

// build_layout() must reject overlapping light-map UVs and name the mesh.
void expect_layout_error(const std::string& path, const std::vector<std::string>& words) {
  const cooker::Scene s = cooker::import_gltf(path);
  try {
    const cooker::Layout l = cooker::build_layout(s, {.lightmap_size = 64});
    ADD_FAILURE() << "layout built (" << l.width << "x" << l.height << ")";
  } catch (const cooker::CookError& e) {
    for (const std::string& w : words)
      EXPECT_NE(std::string(e.what()).find(w), std::string::npos)
          << "'" << w << "' not in: " << e.what();
  }
}

TEST(ImportErrors, OverlappingTexcoord1InOneNodeNamesTheMesh) {
  ScratchDir dir;
  // Two primitives of one node (one mesh, two materials) whose light-map UVs share area. (Two
  // nodes may overlap: each node's UVs are its own, placed by scale and offset.)
  {
    sg::SceneBuilder b;
    sg::Geometry a = sg::make_quad({0, 0, 0}, {1, 0, 0}, {1, 0, -1}, {0, 0, -1});
    a.uv1 = {{0.0f, 0.0f}, {0.6f, 0.0f}, {0.0f, 0.6f}, {0.6f, 0.6f}};
    sg::Geometry c = sg::make_quad({2, 0, 0}, {3, 0, 0}, {3, 0, -1}, {2, 0, -1});
    c.uv1 = {{0.4f, 0.4f}, {1.0f, 0.4f}, {0.4f, 1.0f}, {1.0f, 1.0f}};
    b.add_node({.name = "table", .mesh = b.add_mesh("table", {{a, -1}, {c, -1}})});
    b.write(dir.file("two.glb"));
    expect_layout_error(dir.file("two.glb"), {"TEXCOORD_1", "'table' (primitive 1)",
                                              "'table' (primitive 0)", "overlap"});
  }
  // One mesh folded onto itself, on an unnamed node: the message still says which one.
  {
    sg::Geometry a = sg::make_quad({0, 0, 0}, {1, 0, 0}, {1, 0, -1}, {0, 0, -1}, 2, 1);
    // Vertices: bottom row p0, mid, p1; top row p3, mid, p2. Both halves map onto the same square.
    a.uv1 = {{0.1f, 0.1f}, {0.5f, 0.1f}, {0.1f, 0.1f}, {0.1f, 0.5f}, {0.5f, 0.5f}, {0.1f, 0.5f}};
    sg::SceneBuilder c;
    sg::Geometry ok = sg::make_quad({0, 1, 0}, {1, 1, 0}, {1, 1, -1}, {0, 1, -1});
    ok.uv1 = {{0.6f, 0.6f}, {0.9f, 0.6f}, {0.6f, 0.9f}, {0.9f, 0.9f}};
    c.add_mesh_node("ok", ok, -1);
    c.add_node({.name = "", .mesh = c.add_mesh("folded", a, -1)});
    c.write(dir.file("folded.glb"));
    expect_layout_error(dir.file("folded.glb"), {"TEXCOORD_1", "node 1", "its own triangles"});
  }
}

}  // namespace
}  // namespace lightpatch::test
