// Hostile glTF (issue 15): offsets near 2^64, image data outside its buffer, images and scenes
// that declare more than the documented limits, files outside the scene's folder, transforms
// that overflow, cycles, names meant to flood or drive the terminal. Each gets a CookError that
// names the problem (and, for a limit, the option that raises it), under ASan+UBSan as well; the
// big inputs are generated here, small files that declare big things.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "gltf_files.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/import.h"

namespace lightpatch::test {
namespace {

namespace sg = scenegen;
namespace fs = std::filesystem;
using cooker::ImportLimits;

// The CookError of importing `path`, or a test failure when it imports.
std::string import_error(const std::string& path, const ImportLimits& limits = {}) {
  try {
    const cooker::Scene s = cooker::import_gltf(path, limits);
    ADD_FAILURE() << path << " imported without error (" << s.meshes.size() << " meshes)";
  } catch (const cooker::CookError& e) {
    return e.what();
  }
  return {};
}

void expect_words(const std::string& message, const std::vector<std::string>& words) {
  for (const std::string& w : words)
    EXPECT_NE(message.find(w), std::string::npos) << "'" << w << "' not in: " << message;
}

// A PNG of its signature, header and end chunk only: what a decoder reads before it allocates.
// stb_image does not check chunk CRCs, so they are left zero.
std::vector<std::uint8_t> png_header(std::uint32_t width, std::uint32_t height) {
  std::vector<std::uint8_t> b = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  auto be32 = [&](std::uint32_t v) {
    for (int i = 3; i >= 0; --i) b.push_back(std::uint8_t(v >> (8 * i)));
  };
  be32(13);
  b.insert(b.end(), {'I', 'H', 'D', 'R'});
  be32(width);
  be32(height);
  // 8-bit grey (stb_image refuses RGB this large itself), deflate, no filter, no interlace.
  b.insert(b.end(), {8, 0, 0, 0, 0});
  be32(0);
  be32(0);
  b.insert(b.end(), {'I', 'E', 'N', 'D'});
  be32(0);
  return b;
}

std::vector<std::uint8_t> png_2x2() {
  return png(2, 2, {255, 0, 0, 0, 255, 0, 0, 0, 255, 9, 9, 9});
}

// The small room with image `i` used as material 0's base colour (or `slot`), from `image`.
void add_texture(GltfParts& p, const nlohmann::ordered_json& image,
                 const std::string& slot = "baseColorTexture") {
  const size_t i = p.json["images"].size();
  p.json["images"].push_back(image);
  p.json["textures"].push_back({{"source", i}});
  if (slot == "baseColorTexture")
    p.json["materials"][0]["pbrMetallicRoughness"][slot] = {{"index", i}};
  else
    p.json["materials"][0][slot] = {{"index", i}};
}

nlohmann::ordered_json data_uri_image(const std::vector<std::uint8_t>& bytes) {
  return {{"uri", "data:image/png;base64," + base64(bytes)}};
}

// An image in a bufferView of buffer 0 at `offset`, `length` bytes.
nlohmann::ordered_json buffer_view_image(GltfParts& p, std::uint64_t offset, std::uint64_t length) {
  p.json["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}});
  return {{"bufferView", p.json["bufferViews"].size() - 1}, {"mimeType", "image/png"}};
}

constexpr std::uint64_t kNear2To64 = 18446744073709551600ull;

TEST(HostileImport, ImageDataOutsideItsBufferIsRefusedBeforeDecoding) {
  ScratchDir dir;
  // 2^40: tinygltf's image loader read from there (SIGSEGV); past the end by 12 kB: a heap
  // overflow in the decoder; near 2^64: the pointer wraps.
  const std::uint64_t offsets[] = {std::uint64_t(1) << 40, 0, kNear2To64};
  for (const std::uint64_t offset : offsets) {
    GltfParts p = parts_of(small_room());
    const std::uint64_t length = offset == 0 ? p.bin.size() + 12000 : 100;
    add_texture(p, buffer_view_image(p, offset, length));
    const std::string m = import_error(write_glb(dir, "image_view", p));
    expect_words(m, {"image 0: bufferView", "extends past the end of buffer 0"});
  }
}

TEST(HostileImport, OffsetsNear2To64DoNotWrapAround) {
  ScratchDir dir;
  {
    GltfParts p = parts_of(small_room());
    const int position = p.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"];
    p.json["accessors"][position]["byteOffset"] = kNear2To64;
    expect_words(import_error(write_glb(dir, "accessor", p)),
                 {"POSITION accessor", "reads past the end of its bufferView"});
  }
  {
    GltfParts p = parts_of(small_room());
    p.json["bufferViews"][0]["byteOffset"] = kNear2To64;
    expect_words(import_error(write_glb(dir, "view", p)),
                 {"bufferView 0", "extends past the end of buffer 0"});
  }
  {
    sg::WriteOptions draco;
    draco.draco = true;
    GltfParts p = parts_of(small_room(), draco);
    const int view = p.json["meshes"][0]["primitives"][0]["extensions"]
                           ["KHR_draco_mesh_compression"]["bufferView"];
    p.json["bufferViews"][view]["byteOffset"] = kNear2To64;
    expect_words(import_error(write_glb(dir, "draco", p)),
                 {"KHR_draco_mesh_compression", "extends past the end of its buffer"});
  }
}

TEST(HostileImport, ImageSizeIsCheckedFromItsHeaderAgainstTheLimit) {
  ScratchDir dir;
  for (const std::uint32_t side : {16000u, 23170u}) {
    GltfParts p = parts_of(small_room());
    add_texture(p, data_uri_image(png_header(side, side)));
    const std::string s = std::to_string(side);
    expect_words(import_error(write_gltf(dir, "big_png", p)),
                 {"image 0", s + "x" + s, "over the limit of 33554432 texture pixels",
                  "--max-texture-pixels N raises it"});
  }
  // The budget is summed over the base-colour images: two 2x2 images need 8 pixels.
  GltfParts p = parts_of(small_room());
  add_texture(p, data_uri_image(png_2x2()));
  p.json["materials"].push_back(p.json["materials"][0]);
  p.json["materials"][1]["pbrMetallicRoughness"]["baseColorTexture"]["index"] = 1;
  p.json["images"].push_back(data_uri_image(png_2x2()));
  p.json["textures"].push_back({{"source", 1}});
  const std::string path = write_gltf(dir, "two_images", p);
  ImportLimits seven;
  seven.max_texture_pixels = 7;
  expect_words(import_error(path, seven), {"image 1", "2x2", "limit of 7 texture pixels"});
  ImportLimits eight;
  eight.max_texture_pixels = 8;
  EXPECT_EQ(cooker::import_gltf(path, eight).textures.size(), 2u);
}

TEST(HostileImport, ImagesNoMaterialSamplesAreNeverDecoded) {
  ScratchDir dir;
  const std::vector<std::uint8_t> garbage(64, 0xAB);
  GltfParts p = parts_of(small_room());
  add_texture(p, data_uri_image(png_header(60000, 60000)), "normalTexture");
  add_texture(p, data_uri_image(garbage), "occlusionTexture");
  const cooker::Scene s = cooker::import_gltf(write_gltf(dir, "normal_map", p));
  EXPECT_TRUE(s.textures.empty());
  // The same garbage as a base colour is decoded, and refused.
  GltfParts q = parts_of(small_room());
  add_texture(q, data_uri_image(garbage));
  expect_words(import_error(write_gltf(dir, "garbage", q)), {"Unknown image format"});
}

TEST(HostileImport, SceneSizeIsCountedBeforeAnythingIsRead) {
  ScratchDir dir;
  // One 20,000-triangle mesh instanced by 500 nodes: 10 M triangles in a file of 0.6 MB.
  sg::SceneBuilder b;
  const int grid = b.add_mesh("grid", sg::make_plane(1, 1, 100, 100), -1);
  for (int i = 0; i < 500; ++i)
    b.add_node({.name = "tile" + std::to_string(i),
                .translation = {float(i % 25), 0.0f, float(i / 25)},
                .mesh = grid});
  const std::string path = dir.file("instanced.glb");
  b.write(path);
  ASSERT_EQ(b.triangle_count(), 10'000'000u);
  expect_words(import_error(path),
               {"10000000 triangles", "mesh 0 'grid', 10000000 in 500 node(s)",
                "over the limit of 4000000 triangles", "--max-triangles N raises it"});
  ImportLimits low;
  low.max_vertices = 1000;
  low.max_triangles = 100'000'000;
  expect_words(import_error(path, low),
               {"5100500 vertices", "limit of 1000 vertices", "--max-vertices N raises it"});
}

// 200 primitives each reading a 2^24-element accessor without a bufferView (all zeros): 10 kB
// of JSON that asked for minutes of work.
GltfParts with_zero_primitives(int mode) {
  GltfParts p = parts_of(small_room());
  const size_t accessor = p.json["accessors"].size();
  p.json["accessors"].push_back({{"componentType", 5126}, {"count", 1 << 24}, {"type", "VEC3"}});
  nlohmann::ordered_json primitives = nlohmann::ordered_json::array();
  for (int i = 0; i < 200; ++i)
    primitives.push_back({{"attributes", {{"POSITION", accessor}}}, {"mode", mode}});
  p.json["meshes"].push_back({{"name", "dust"}, {"primitives", primitives}});
  p.json["nodes"].push_back({{"name", "dust"}, {"mesh", p.json["meshes"].size() - 1}});
  p.json["scenes"][0]["nodes"].push_back(p.json["nodes"].size() - 1);
  return p;
}

TEST(HostileImport, HugeAccessorsWithoutDataAreBoundedUpFront) {
  ScratchDir dir;
  // Points are skipped before their accessors are read.
  const cooker::Scene points =
      cooker::import_gltf(write_glb(dir, "points", with_zero_primitives(0)));
  size_t skipped = 0;
  for (const std::string& note : points.notes)
    skipped += note.find("points/lines") != std::string::npos;
  EXPECT_EQ(skipped, 200u);
  // As triangles they are 1.1 G triangles of 3.4 G vertices: refused before one is read.
  const std::string path = write_glb(dir, "triangles", with_zero_primitives(4));
  expect_words(import_error(path), {"1118481032 triangles", "mesh 3 'dust', 1118481000 in 1 node",
                                    "--max-triangles N raises it"});
  ImportLimits many_triangles;
  many_triangles.max_triangles = uint64_t(1) << 40;
  expect_words(
      import_error(path, many_triangles),
      {"3355443257 vertices", "mesh 3 'dust', 3355443200 in 1 node", "--max-vertices N raises it"});
}

TEST(HostileImport, BuffersAndImagesComeFromTheScenesFolderOnly) {
  ScratchDir dir;
  fs::create_directories(dir.path() / "scene");
  GltfParts p = parts_of(small_room());
  write_bytes(dir.file("outside.bin"), p.bin);
  p.json["buffers"][0]["uri"] = "../outside.bin";
  p.json.erase("images");
  const std::string scene = dir.file("scene/room.gltf");
  write_text(scene, p.json.dump());
  expect_words(import_error(scene),
               {"outside.bin", "is outside the scene's folder", "--uri-root DIR"});
  ImportLimits allowed;
  allowed.uri_roots = {dir.path().string()};
  EXPECT_FALSE(cooker::import_gltf(scene, allowed).meshes.empty());

  // A link inside the folder to a file outside it is outside.
  fs::create_symlink("../outside.bin", dir.path() / "scene" / "link.bin");
  p.json["buffers"][0]["uri"] = "link.bin";
  write_text(scene, p.json.dump());
  expect_words(import_error(scene), {"link.bin", "is outside the scene's folder"});

  // An image outside is refused too (tinygltf alone only warns and goes on).
  write_bytes(dir.file("scene/room.bin"), p.bin);
  write_bytes(dir.file("albedo.png"), png_2x2());
  p.json["buffers"][0]["uri"] = "room.bin";
  add_texture(p, {{"uri", "../albedo.png"}});
  write_text(scene, p.json.dump());
  expect_words(import_error(scene), {"albedo.png", "is outside the scene's folder"});
  EXPECT_EQ(cooker::import_gltf(scene, allowed).textures.size(), 1u);
}

TEST(HostileImport, TransformsThatOverflowSayWhatIsWrong) {
  ScratchDir dir;
  struct Case {
    float parent, child;
    std::vector<std::string> words;
  };
  const Case cases[] = {
      {1e30f, 1.0f, {"node 0 'floor'", "beyond +-1000000 m", "scale or translation"}},
      {1e20f, 1e20f, {"'floor'", "world transform overflows"}},
      {1e-30f, 1.0f, {"only zero-area triangles", "world scale is 1e-30"}},
  };
  for (const Case& c : cases) {
    GltfParts p = parts_of(small_room());
    p.json["nodes"][0]["scale"] = {c.child, c.child, c.child};
    p.json["nodes"].push_back(
        {{"name", "world"}, {"scale", {c.parent, c.parent, c.parent}}, {"children", {0}}});
    auto& roots = p.json["scenes"][0]["nodes"];
    for (size_t i = 0; i < roots.size(); ++i)
      if (roots[i] == 0) roots[i] = p.json["nodes"].size() - 1;
    expect_words(import_error(write_glb(dir, "scaled", p)), c.words);
  }
}

TEST(HostileImport, ANodeCycleWithoutASceneIsNamed) {
  ScratchDir dir;
  GltfParts p = parts_of(small_room());
  p.json.erase("scenes");
  p.json.erase("scene");
  // Every node is someone's child: no root at all.
  const size_t n = p.json["nodes"].size();
  for (size_t i = 0; i < n; ++i) p.json["nodes"][i]["children"] = {(i + 1) % n};
  expect_words(import_error(write_glb(dir, "cycle", p)), {"node 0 'floor'", "cycle"});
}

TEST(HostileImport, NamesInMessagesAreCutAndEscaped) {
  ScratchDir dir;
  GltfParts p = parts_of(small_room());
  p.json["nodes"][0]["name"] = std::string(10'000'000, 'n');
  p.json["nodes"][0]["scale"] = {1e30, 1e30, 1e30};
  const std::string flood = import_error(write_glb(dir, "long_name", p));
  EXPECT_LT(flood.size(), 1000u) << flood.substr(0, 300);
  expect_words(flood, {"... (10000000 bytes)", "beyond +-1000000 m"});

  p.json["nodes"][0]["name"] = "lamp\x1b[2J\nrm -rf \xe2\x80\xae";
  const std::string escaped = import_error(write_glb(dir, "escape_name", p));
  EXPECT_EQ(escaped.find('\x1b'), std::string::npos) << escaped;
  EXPECT_EQ(escaped.find('\n'), std::string::npos) << escaped;
  expect_words(escaped, {"'lamp\\x1B[2J\\nrm -rf \\u202E'"});
}

}  // namespace
}  // namespace lightpatch::test
