#include "gltf_files.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wall"
#pragma clang diagnostic ignored "-Wextra"
#elif defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#endif
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image_write.h>
#if defined(__clang__)
#pragma clang diagnostic pop
#elif defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace lightpatch::test {

namespace fs = std::filesystem;

ScratchDir::ScratchDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = "lp_cooker_";
  if (info != nullptr) name += std::string(info->test_suite_name()) + "_" + info->name();
  name += "_" + std::to_string(::getpid());
  std::replace(name.begin(), name.end(), '/', '_');
  path_ = fs::temp_directory_path() / name;
  fs::remove_all(path_);
  fs::create_directories(path_);
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

std::vector<std::string> ScratchDir::entries() const {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(path_)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::uint8_t> read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("test: cannot read " + path);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!f) throw std::runtime_error("test: cannot write " + path);
}

void write_text(const std::string& path, const std::string& text) {
  write_bytes(path, std::vector<std::uint8_t>(text.begin(), text.end()));
}

namespace {

std::uint32_t get_u32(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

}  // namespace

GltfParts split_glb(const std::vector<std::uint8_t>& b) {
  if (b.size() < 20 || get_u32(b, 0) != 0x46546C67u) throw std::runtime_error("test: not a .glb");
  const std::uint32_t json_len = get_u32(b, 12);
  GltfParts parts;
  parts.json = nlohmann::ordered_json::parse(b.begin() + 20, b.begin() + 20 + json_len);
  const std::size_t bin_at = 20u + json_len;
  if (bin_at + 8 <= b.size()) {
    parts.bin.assign(b.begin() + static_cast<std::ptrdiff_t>(bin_at + 8), b.end());
  }
  return parts;
}

std::vector<std::uint8_t> join_glb(const GltfParts& parts) {
  std::string json = parts.json.dump();
  while (json.size() % 4 != 0) json += ' ';
  std::vector<std::uint8_t> bin = parts.bin;
  while (bin.size() % 4 != 0) bin.push_back(0);
  std::vector<std::uint8_t> out;
  put_u32(out, 0x46546C67u);
  put_u32(out, 2);
  put_u32(out,
          static_cast<std::uint32_t>(12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin.size())));
  put_u32(out, static_cast<std::uint32_t>(json.size()));
  put_u32(out, 0x4E4F534Au);
  out.insert(out.end(), json.begin(), json.end());
  if (!bin.empty()) {
    put_u32(out, static_cast<std::uint32_t>(bin.size()));
    put_u32(out, 0x004E4942u);
    out.insert(out.end(), bin.begin(), bin.end());
  }
  return out;
}

GltfParts parts_of(const scenegen::SceneBuilder& builder, const scenegen::WriteOptions& options) {
  return split_glb(builder.to_glb(options));
}

std::string write_gltf(const ScratchDir& dir, const std::string& stem, GltfParts parts) {
  if (parts.json.contains("buffers") && !parts.json["buffers"].empty()) {
    parts.json["buffers"][0]["uri"] = stem + ".bin";
    write_bytes(dir.file(stem + ".bin"), parts.bin);
  }
  const std::string path = dir.file(stem + ".gltf");
  write_text(path, parts.json.dump(1));
  return path;
}

std::string write_glb(const ScratchDir& dir, const std::string& stem, const GltfParts& parts) {
  const std::string path = dir.file(stem + ".glb");
  write_bytes(path, join_glb(parts));
  return path;
}

std::size_t float_offset(const GltfParts& parts, int accessor, std::size_t element, int component) {
  const auto& acc = parts.json.at("accessors").at(static_cast<std::size_t>(accessor));
  const auto& view = parts.json.at("bufferViews").at(acc.at("bufferView").get<std::size_t>());
  const std::size_t comps = acc.at("type") == "SCALAR" ? 1
                            : acc.at("type") == "VEC2" ? 2
                            : acc.at("type") == "VEC3" ? 3
                                                       : 4;
  const std::size_t size = acc.at("componentType") == 5126   ? 4
                           : acc.at("componentType") == 5123 ? 2
                                                             : 4;
  const std::size_t stride = view.value("byteStride", comps * size);
  return view.value("byteOffset", std::size_t{0}) + acc.value("byteOffset", std::size_t{0}) +
         element * stride + static_cast<std::size_t>(component) * size;
}

void set_float(GltfParts& parts, int accessor, std::size_t element, int component, float value) {
  std::memcpy(parts.bin.data() + float_offset(parts, accessor, element, component), &value, 4);
}

float get_float(const GltfParts& parts, int accessor, std::size_t element, int component) {
  float v = 0;
  std::memcpy(&v, parts.bin.data() + float_offset(parts, accessor, element, component), 4);
  return v;
}

void set_index(GltfParts& parts, int accessor, std::size_t element, std::uint32_t value) {
  const std::size_t at = float_offset(parts, accessor, element, 0);
  const int type = parts.json["accessors"][static_cast<std::size_t>(accessor)]["componentType"];
  if (type == 5123) {
    const auto v = static_cast<std::uint16_t>(value);
    std::memcpy(parts.bin.data() + at, &v, 2);
  } else {
    std::memcpy(parts.bin.data() + at, &value, 4);
  }
}

std::string base64(const std::vector<std::uint8_t>& data) {
  static constexpr char kTable[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < data.size(); i += 3) {
    const std::uint32_t b0 = data[i];
    const std::uint32_t b1 = i + 1 < data.size() ? data[i + 1] : 0;
    const std::uint32_t b2 = i + 2 < data.size() ? data[i + 2] : 0;
    const std::uint32_t v = (b0 << 16) | (b1 << 8) | b2;
    out += kTable[(v >> 18) & 63];
    out += kTable[(v >> 12) & 63];
    out += i + 1 < data.size() ? kTable[(v >> 6) & 63] : '=';
    out += i + 2 < data.size() ? kTable[v & 63] : '=';
  }
  return out;
}

namespace {

// The small room from its three meshes: a grey floor and pillar, a semi-dynamic wooden crate, a
// semi-dynamic point lamp (of `lamp_radius` metres) and a static spot.
scenegen::SceneBuilder room_of(const scenegen::Geometry& floor, const scenegen::Geometry& pillar,
                               const scenegen::Geometry& crate, float lamp_radius) {
  using namespace scenegen;
  SceneBuilder b;
  const int grey = b.add_material({.name = "grey", .base_color = {0.6f, 0.6f, 0.6f, 1.0f}});
  const int wood = b.add_material({.name = "wood", .base_color = {0.5f, 0.3f, 0.2f, 1.0f}});
  b.add_mesh_node("floor", floor, grey);
  b.add_mesh_node("pillar", pillar, grey, {1.2f, 0.0f, 1.2f});
  b.add_mesh_node("crate", crate, wood, {-0.5f, 0.0f, 0.3f}, /*semi_dynamic=*/true);
  b.add_light_node(
      "lamp",
      {.name = "lamp", .type = LightType::kPoint, .color = {1.0f, 0.9f, 0.8f}, .intensity = 6.0f},
      {-0.3f, 1.6f, 0.2f}, {0, -1, 0}, /*semi_dynamic=*/true, lamp_radius);
  b.add_light_node("spot",
                   {.name = "spot",
                    .type = LightType::kSpot,
                    .intensity = 10.0f,
                    .inner_cone_angle = 0.3f,
                    .outer_cone_angle = 0.6f},
                   {1.0f, 2.5f, -1.0f}, {-0.2f, -1.0f, 0.3f});
  return b;
}

// Gives each 4-vertex face of `g` (make_box / make_plane with one subdivision: vertices in the
// order (0,0) (1,0) (0,1) (1,1) of the face) a cell of a 4 x 4 grid, starting at cell `*next`.
void grid_uv1(scenegen::Geometry& g, int* next) {
  constexpr float kCell = 0.25f, kMargin = 0.02f;
  const glm::vec2 corner[4] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  g.uv1.resize(g.positions.size());
  for (size_t v = 0; v < g.positions.size(); ++v) {
    const int cell = *next + static_cast<int>(v / 4);
    const glm::vec2 origin(kCell * float(cell % 4), kCell * float(cell / 4));
    g.uv1[v] = origin + glm::vec2(kMargin) + corner[v % 4] * (kCell - 2 * kMargin);
  }
  *next += static_cast<int>(g.positions.size() / 4);
  g.uv0 = g.uv1;  // glTF wants TEXCOORD_0 wherever there is a TEXCOORD_1 (the validator checks)
}

}  // namespace

scenegen::SceneBuilder small_room(float lamp_radius) {
  using namespace scenegen;
  return room_of(make_plane(4.0f, 4.0f, 2, 2), make_box({-0.2f, 0.0f, -0.2f}, {0.2f, 1.0f, 0.2f}),
                 make_box({-0.25f, 0.0f, -0.25f}, {0.25f, 0.5f, 0.25f}), lamp_radius);
}

scenegen::SceneBuilder small_room_with_uv1() {
  using namespace scenegen;
  int next = 0;
  Geometry floor = make_plane(4.0f, 4.0f);
  Geometry pillar = make_box({-0.2f, 0.0f, -0.2f}, {0.2f, 1.0f, 0.2f});
  Geometry crate = make_box({-0.25f, 0.0f, -0.25f}, {0.25f, 0.5f, 0.25f});
  grid_uv1(floor, &next);
  grid_uv1(pillar, &next);
  grid_uv1(crate, &next);
  return room_of(floor, pillar, crate, 0.0f);
}

namespace {
// The closed 4 x 2.5 x 4 m plaster room of the bounce-light test scenes; returns its wood material.
int plaster_room(scenegen::SceneBuilder& b) {
  using namespace scenegen;
  const int plaster = b.add_material({.name = "plaster", .base_color = {0.7f, 0.7f, 0.7f, 1.0f}});
  const int wood = b.add_material({.name = "wood", .base_color = {0.55f, 0.38f, 0.22f, 1.0f}});
  b.add_mesh_node("room", make_box({-2.0f, 0.0f, -2.0f}, {2.0f, 2.5f, 2.0f}, Facing::kInward),
                  plaster);
  return wood;
}
}  // namespace

scenegen::SceneBuilder thin_panel_room() {
  using namespace scenegen;
  SceneBuilder b;
  const int wood = plaster_room(b);
  b.add_mesh_node("panel", make_box({1.93f, 0.0f, -0.6f}, {1.95f, 1.3f, 0.6f}), wood, {},
                  /*semi_dynamic=*/true);
  b.add_light_node(
      "lamp",
      {.name = "lamp", .type = LightType::kPoint, .color = {1.0f, 0.85f, 0.7f}, .intensity = 8.0f},
      {0.9f, 1.6f, 1.1f}, {0, -1, 0}, /*semi_dynamic=*/true, /*light_radius=*/0.05f);
  b.add_light_node("spot",
                   {.name = "spot",
                    .type = LightType::kSpot,
                    .intensity = 60.0f,
                    .inner_cone_angle = 0.3f,
                    .outer_cone_angle = 0.45f},
                   {0.0f, 2.45f, 0.0f}, {0.0f, -1.0f, 0.0f});
  return b;
}

scenegen::SceneBuilder two_rooms_lantern() {
  using namespace scenegen;
  SceneBuilder b;
  const int plaster = b.add_material({.name = "plaster", .base_color = {0.7f, 0.7f, 0.7f, 1.0f}});
  const int red = b.add_material({.name = "rug", .base_color = {0.6f, 0.15f, 0.1f, 1.0f}});
  // Slabs of 10 cm, each its own node (a level is walls and floors of a few big boxes): the floor
  // and ceiling under both rooms, the outer walls, and the partition with a doorway.
  const float h = 2.5f;
  auto slab = [&](const std::string& name, glm::vec3 lo, glm::vec3 hi) {
    b.add_mesh_node(name, make_box(lo, hi), plaster);
  };
  slab("floor", {-4.1f, -0.1f, -2.1f}, {4.1f, 0.0f, 2.1f});
  slab("ceiling", {-4.1f, h, -2.1f}, {4.1f, h + 0.1f, 2.1f});
  slab("wall_north", {-4.1f, 0.0f, -2.1f}, {4.1f, h, -2.0f});
  slab("wall_south", {-4.1f, 0.0f, 2.0f}, {4.1f, h, 2.1f});
  slab("wall_west", {-4.1f, 0.0f, -2.0f}, {-4.0f, h, 2.0f});
  slab("wall_east", {4.0f, 0.0f, -2.0f}, {4.1f, h, 2.0f});
  slab("partition", {-0.1f, 0.0f, -2.0f}, {0.1f, h, 1.0f});
  slab("lintel", {-0.1f, 2.0f, 1.0f}, {0.1f, h, 2.0f});
  b.add_mesh_node("rug", make_box({-3.0f, 0.0f, -1.5f}, {-1.0f, 0.02f, 0.5f}), red);
  b.add_light_node("lamp_b", {.name = "lamp_b", .type = LightType::kPoint, .intensity = 6.0f},
                   {2.0f, 2.0f, 0.0f}, {0, -1, 0}, /*semi_dynamic=*/false,
                   /*light_radius=*/0.05f);
  const int lantern = b.add_light_node("lantern",
                                       {.name = "lantern",
                                        .type = LightType::kPoint,
                                        .color = {1.0f, 0.8f, 0.55f},
                                        .intensity = 3.0f},
                                       {-2.0f, 1.2f, -1.0f}, {0, -1, 0}, /*semi_dynamic=*/false,
                                       /*light_radius=*/0.04f);
  b.node(lantern).moving = true;
  return b;
}

scenegen::SceneBuilder low_slab_room() {
  using namespace scenegen;
  SceneBuilder b;
  const int wood = plaster_room(b);
  b.add_mesh_node("slab", make_box({-0.3f, 0.015f, -0.3f}, {0.3f, 0.05f, 0.3f}), wood);
  b.add_light_node("candle",
                   {.name = "candle",
                    .type = LightType::kPoint,
                    .color = {1.0f, 0.8f, 0.55f},
                    .intensity = 2.0f},
                   {0.42f, 0.08f, 0.0f}, {0, -1, 0}, /*semi_dynamic=*/true, /*light_radius=*/0.01f);
  return b;
}

std::vector<std::uint8_t> png(int w, int h, const std::vector<std::uint8_t>& rgb) {
  std::vector<std::uint8_t> out;
  stbi_write_png_to_func(
      [](void* ctx, void* data, int size) {
        auto* v = static_cast<std::vector<std::uint8_t>*>(ctx);
        v->insert(v->end(), static_cast<std::uint8_t*>(data),
                  static_cast<std::uint8_t*>(data) + size);
      },
      &out, w, h, 3, rgb.data(), w * 3);
  return out;
}

}  // namespace lightpatch::test
