#include "lightpatch/scenegen/scene_builder.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <utility>

#include <nlohmann/json.hpp>

#include "draco_encode.h"

namespace lightpatch::scenegen {
namespace {

using Json = nlohmann::ordered_json;

constexpr int kFloat = 5126;
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;
constexpr float kHalfPi = 1.57079632679489662f;

bool finite(glm::vec3 v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

Json vec_json(const float* v, int n) {
  Json a = Json::array();
  for (int i = 0; i < n; ++i) a.push_back(static_cast<double>(v[i]));
  return a;
}

// Appends raw bytes to the binary buffer at a 4-byte aligned offset; returns the offset.
std::size_t append_aligned(std::vector<std::uint8_t>& bin, const void* data, std::size_t size) {
  while (bin.size() % 4 != 0) bin.push_back(0);
  const std::size_t offset = bin.size();
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  bin.insert(bin.end(), bytes, bytes + size);
  return offset;
}

bool use_uint16(const Primitive& p) {
  switch (p.index_type) {
    case IndexType::kUint16:
      return true;
    case IndexType::kUint32:
      return false;
    case IndexType::kAuto:
      break;
  }
  // 65535 is the primitive-restart value, which glTF forbids in index data.
  return p.geometry.vertex_count() <= 65535;
}

std::string base64(const std::vector<std::uint8_t>& data) {
  static constexpr char kTable[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((data.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < data.size(); i += 3) {
    const std::uint32_t v =
        (std::uint32_t{data[i]} << 16) | (std::uint32_t{data[i + 1]} << 8) | data[i + 2];
    out += kTable[(v >> 18) & 63];
    out += kTable[(v >> 12) & 63];
    out += kTable[(v >> 6) & 63];
    out += kTable[v & 63];
  }
  if (i < data.size()) {
    std::uint32_t v = std::uint32_t{data[i]} << 16;
    if (i + 1 < data.size()) v |= std::uint32_t{data[i + 1]} << 8;
    out += kTable[(v >> 18) & 63];
    out += kTable[(v >> 12) & 63];
    out += i + 1 < data.size() ? kTable[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

void write_file(const std::filesystem::path& path, const void* data, std::size_t size) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error("cannot open " + path.string() + " for writing");
  f.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  f.close();
  if (!f) throw std::runtime_error("cannot write " + path.string());
}

// Writes into a temporary file beside `path`, then renames it over `path`.
void write_atomically(const std::filesystem::path& path, const void* data, std::size_t size) {
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  try {
    write_file(tmp, data, size);
    std::filesystem::rename(tmp, path);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
}

}  // namespace

glm::quat rotation_towards(glm::vec3 direction) {
  const float len = glm::length(direction);
  if (!(len > 0.0f) || !std::isfinite(len))
    throw std::invalid_argument("rotation_towards: zero direction");
  const glm::vec3 d = direction / len;
  const glm::vec3 from(0.0f, 0.0f, -1.0f);
  const float c = glm::dot(from, d);
  if (c < -0.999999f) return glm::quat(0.0f, 0.0f, 1.0f, 0.0f);  // 180° about +Y
  const glm::vec3 axis = glm::cross(from, d);
  // Half-angle construction: q = (1 + c, axis) normalized.
  return glm::normalize(glm::quat(1.0f + c, axis.x, axis.y, axis.z));
}

int SceneBuilder::add_material(Material material) {
  auto in01 = [](float v) { return v >= 0.0f && v <= 1.0f; };
  const glm::vec4& c = material.base_color;
  if (!in01(c.r) || !in01(c.g) || !in01(c.b) || !in01(c.a)) {
    throw std::invalid_argument("material '" + material.name + "': base colour outside [0, 1]");
  }
  const glm::vec3& e = material.emissive;
  if (!in01(e.r) || !in01(e.g) || !in01(e.b)) {
    throw std::invalid_argument("material '" + material.name + "': emissive outside [0, 1]");
  }
  if (!in01(material.metallic) || !in01(material.roughness)) {
    throw std::invalid_argument("material '" + material.name +
                                "': metallic/roughness outside [0, 1]");
  }
  if (!(material.emissive_strength >= 0.0f) || !std::isfinite(material.emissive_strength)) {
    throw std::invalid_argument("material '" + material.name + "': bad emissive strength");
  }
  materials_.push_back(std::move(material));
  return static_cast<int>(materials_.size()) - 1;
}

int SceneBuilder::add_mesh(std::string name, std::vector<Primitive> primitives) {
  if (primitives.empty()) throw std::invalid_argument("mesh '" + name + "' has no primitives");
  for (const Primitive& p : primitives) {
    try {
      p.geometry.check();
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("mesh '" + name + "': " + e.what());
    }
    if (p.geometry.empty())
      throw std::invalid_argument("mesh '" + name + "' has an empty primitive");
    if (p.material < -1 || p.material >= static_cast<int>(materials_.size())) {
      throw std::invalid_argument("mesh '" + name + "': unknown material");
    }
    if (p.index_type == IndexType::kUint16 && p.geometry.vertex_count() > 65535) {
      throw std::invalid_argument("mesh '" + name + "': too many vertices for 16-bit indices");
    }
  }
  meshes_.push_back({std::move(name), std::move(primitives)});
  return static_cast<int>(meshes_.size()) - 1;
}

int SceneBuilder::add_mesh(std::string name, Geometry geometry, int material,
                           IndexType index_type) {
  std::vector<Primitive> primitives;
  primitives.push_back({std::move(geometry), material, index_type});
  return add_mesh(std::move(name), std::move(primitives));
}

int SceneBuilder::add_light(Light light) {
  const std::string what = "light '" + light.name + "': ";
  if (!finite(light.color) || light.color.r < 0.0f || light.color.g < 0.0f ||
      light.color.b < 0.0f) {
    throw std::invalid_argument(what + "bad colour");
  }
  if (!(light.intensity >= 0.0f) || !std::isfinite(light.intensity))
    throw std::invalid_argument(what + "bad intensity");
  if (!(light.range >= 0.0f) || !std::isfinite(light.range))
    throw std::invalid_argument(what + "bad range");
  if (light.type == LightType::kSpot &&
      !(light.inner_cone_angle >= 0.0f && light.inner_cone_angle < light.outer_cone_angle &&
        light.outer_cone_angle <= kHalfPi)) {
    throw std::invalid_argument(what + "need 0 <= inner cone < outer cone <= pi/2");
  }
  lights_.push_back(std::move(light));
  return static_cast<int>(lights_.size()) - 1;
}

int SceneBuilder::add_node(Node node) {
  if (node.mesh < -1 || node.mesh >= static_cast<int>(meshes_.size())) {
    throw std::invalid_argument("node '" + node.name + "': unknown mesh");
  }
  if (node.light < -1 || node.light >= static_cast<int>(lights_.size())) {
    throw std::invalid_argument("node '" + node.name + "': unknown light");
  }
  if (!finite(node.translation) || !finite(node.scale) || !(std::isfinite(node.rotation.w)) ||
      !finite(glm::vec3(node.rotation.x, node.rotation.y, node.rotation.z)) ||
      !(glm::length(node.rotation) > 0.0f)) {
    throw std::invalid_argument("node '" + node.name + "': bad transform");
  }
  if (!(node.light_radius >= 0.0f) || !std::isfinite(node.light_radius)) {
    throw std::invalid_argument("node '" + node.name + "': bad light radius");
  }
  nodes_.push_back(std::move(node));
  return static_cast<int>(nodes_.size()) - 1;
}

void SceneBuilder::add_child(int parent, int child) {
  const int n = static_cast<int>(nodes_.size());
  if (parent < 0 || parent >= n || child < 0 || child >= n || parent == child) {
    throw std::invalid_argument("add_child: bad node index");
  }
  nodes_[static_cast<std::size_t>(parent)].children.push_back(child);
}

int SceneBuilder::add_mesh_node(std::string name, Geometry geometry, int material,
                                glm::vec3 translation, bool semi_dynamic) {
  const int mesh = add_mesh(name, std::move(geometry), material);
  Node node;
  node.name = std::move(name);
  node.translation = translation;
  node.mesh = mesh;
  node.semi_dynamic = semi_dynamic;
  return add_node(std::move(node));
}

int SceneBuilder::add_light_node(std::string name, const Light& light, glm::vec3 position,
                                 glm::vec3 direction, bool semi_dynamic, float light_radius) {
  Light l = light;
  l.name = name;
  const int index = add_light(std::move(l));
  Node node;
  node.name = std::move(name);
  node.translation = position;
  if (light.type != LightType::kPoint) node.rotation = rotation_towards(direction);
  node.light = index;
  node.semi_dynamic = semi_dynamic;
  node.light_radius = light_radius;
  return add_node(std::move(node));
}

std::size_t SceneBuilder::triangle_count() const {
  std::size_t total = 0;
  for (const Node& n : nodes_) {
    if (n.mesh < 0) continue;
    for (const Primitive& p : meshes_[static_cast<std::size_t>(n.mesh)].primitives)
      total += p.geometry.triangle_count();
  }
  return total;
}

void SceneBuilder::check_graph() const {
  const std::size_t n = nodes_.size();
  std::vector<int> parent(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    for (int c : nodes_[i].children) {
      if (c < 0 || static_cast<std::size_t>(c) >= n || static_cast<std::size_t>(c) == i) {
        throw std::invalid_argument("node '" + nodes_[i].name + "': bad child index");
      }
      if (parent[static_cast<std::size_t>(c)] != -1) {
        throw std::invalid_argument("node '" + nodes_[static_cast<std::size_t>(c)].name +
                                    "' has two parents");
      }
      parent[static_cast<std::size_t>(c)] = static_cast<int>(i);
    }
  }
  // Every node must be reachable from a root; otherwise the parent links form a cycle.
  std::vector<char> seen(n, 0);
  std::vector<int> stack;
  for (std::size_t i = 0; i < n; ++i) {
    if (parent[i] == -1) stack.push_back(static_cast<int>(i));
  }
  while (!stack.empty()) {
    const auto i = static_cast<std::size_t>(stack.back());
    stack.pop_back();
    seen[i] = 1;
    for (int c : nodes_[i].children) stack.push_back(c);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!seen[i]) throw std::invalid_argument("node '" + nodes_[i].name + "' is part of a cycle");
  }
}

namespace {

// Builds the glTF document; binary data goes to `bin` (4-byte aligned, padded to 4).
Json build_document(const std::vector<Material>& materials, const auto& meshes,
                    const std::vector<Light>& lights, const std::vector<Node>& nodes,
                    const WriteOptions& options, std::vector<std::uint8_t>& bin) {
  Json doc;
  doc["asset"] = {{"generator", "lightpatch scenegen"}, {"version", "2.0"}};
  bool emissive_strength_used = false;

  std::vector<int> roots;
  {
    std::vector<char> is_child(nodes.size(), 0);
    for (const Node& n : nodes) {
      for (int c : n.children) is_child[static_cast<std::size_t>(c)] = 1;
    }
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if (!is_child[i]) roots.push_back(static_cast<int>(i));
    }
  }
  doc["scene"] = 0;
  doc["scenes"] = Json::array({Json{{"nodes", roots}}});

  Json jnodes = Json::array();
  for (const Node& n : nodes) {
    Json j;
    j["name"] = n.name;
    if (n.matrix) {
      Json m = Json::array();
      for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) m.push_back(static_cast<double>((*n.matrix)[c][r]));
      }
      j["matrix"] = m;
    } else {
      const glm::quat q = glm::normalize(n.rotation);
      if (q != glm::quat(1.0f, 0.0f, 0.0f, 0.0f)) {
        j["rotation"] = {static_cast<double>(q.x), static_cast<double>(q.y),
                         static_cast<double>(q.z), static_cast<double>(q.w)};
      }
      if (n.scale != glm::vec3(1.0f)) j["scale"] = vec_json(&n.scale.x, 3);
      if (n.translation != glm::vec3(0.0f)) j["translation"] = vec_json(&n.translation.x, 3);
    }
    if (n.mesh >= 0) j["mesh"] = n.mesh;
    if (!n.children.empty()) j["children"] = n.children;
    if (n.light >= 0) j["extensions"]["KHR_lights_punctual"]["light"] = n.light;
    if (n.semi_dynamic || n.light_radius > 0.0f || !n.cast_shadows || n.moving) {
      Json extras = Json::object();
      if (n.semi_dynamic) extras["semiDynamic"] = true;
      if (n.moving) extras["moving"] = true;
      if (n.light_radius > 0.0f) extras["lightRadius"] = static_cast<double>(n.light_radius);
      if (!n.cast_shadows) extras["castShadows"] = false;
      j["extras"] = extras;
    }
    jnodes.push_back(j);
  }
  if (!jnodes.empty()) doc["nodes"] = jnodes;

  Json jmaterials = Json::array();
  for (const Material& m : materials) {
    Json j;
    j["name"] = m.name;
    j["pbrMetallicRoughness"] = {{"baseColorFactor", vec_json(&m.base_color.x, 4)},
                                 {"metallicFactor", static_cast<double>(m.metallic)},
                                 {"roughnessFactor", static_cast<double>(m.roughness)}};
    if (m.emissive != glm::vec3(0.0f)) {
      j["emissiveFactor"] = vec_json(&m.emissive.x, 3);
      if (m.emissive_strength != 1.0f) {
        j["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] =
            static_cast<double>(m.emissive_strength);
        emissive_strength_used = true;
      }
    }
    if (m.double_sided) j["doubleSided"] = true;
    jmaterials.push_back(j);
  }
  if (!jmaterials.empty()) doc["materials"] = jmaterials;

  Json accessors = Json::array();
  Json views = Json::array();
  auto add_view = [&](const void* data, std::size_t size, int target) {
    const std::size_t offset = append_aligned(bin, data, size);
    Json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}};
    if (target != 0) v["target"] = target;
    views.push_back(v);
    return static_cast<int>(views.size()) - 1;
  };
  auto add_accessor = [&](int view, int component_type, std::size_t count, const char* type) {
    Json a;
    if (view >= 0) a["bufferView"] = view;
    a["componentType"] = component_type;
    a["count"] = count;
    a["type"] = type;
    accessors.push_back(a);
    return static_cast<int>(accessors.size()) - 1;
  };

  const DracoSettings draco_settings{options.draco_position_bits, options.draco_normal_bits,
                                     options.draco_texcoord_bits, options.draco_speed};
  Json jmeshes = Json::array();
  for (const auto& mesh : meshes) {
    Json jprims = Json::array();
    for (const Primitive& p : mesh.primitives) {
      // glTF requires TEXCOORD_n to be numbered from 0 without gaps: a light-map-only primitive
      // also carries its UVs as TEXCOORD_0.
      Geometry with_uv0;
      const bool fill_uv0 = p.geometry.uv0.empty() && !p.geometry.uv1.empty();
      if (fill_uv0) {
        with_uv0 = p.geometry;
        with_uv0.uv0 = with_uv0.uv1;
      }
      const Geometry& g = fill_uv0 ? with_uv0 : p.geometry;
      std::vector<glm::vec3> normals = g.normals;
      for (glm::vec3& n : normals) n = glm::vec3(glm::normalize(glm::dvec3(n)));
      const glm::vec3 lo = g.bounds_min();
      const glm::vec3 hi = g.bounds_max();
      Json prim;
      Json attributes;
      bool small_indices = use_uint16(p);
      if (options.draco) {
        Geometry normalized = g;
        normalized.normals = normals;
        const DracoPrimitive d = encode_draco(normalized, draco_settings);
        if (d.point_count > 65535) small_indices = false;
        const int view = add_view(d.bytes.data(), d.bytes.size(), 0);
        const int pos = add_accessor(-1, kFloat, d.point_count, "VEC3");
        accessors[static_cast<std::size_t>(pos)]["min"] = vec_json(&lo.x, 3);
        accessors[static_cast<std::size_t>(pos)]["max"] = vec_json(&hi.x, 3);
        attributes["POSITION"] = pos;
        attributes["NORMAL"] = add_accessor(-1, kFloat, d.point_count, "VEC3");
        if (!g.uv0.empty())
          attributes["TEXCOORD_0"] = add_accessor(-1, kFloat, d.point_count, "VEC2");
        if (!g.uv1.empty())
          attributes["TEXCOORD_1"] = add_accessor(-1, kFloat, d.point_count, "VEC2");
        prim["attributes"] = attributes;
        prim["indices"] = add_accessor(-1, small_indices ? kUnsignedShort : kUnsignedInt,
                                       d.face_count * 3, "SCALAR");
        Json ext_attributes;
        for (const char* semantic : {"POSITION", "NORMAL", "TEXCOORD_0", "TEXCOORD_1"}) {
          const auto it = d.attribute_ids.find(semantic);
          if (it != d.attribute_ids.end()) ext_attributes[semantic] = it->second;
        }
        prim["extensions"]["KHR_draco_mesh_compression"] = {{"bufferView", view},
                                                            {"attributes", ext_attributes}};
      } else {
        const std::size_t n = g.vertex_count();
        const int pos = add_accessor(
            add_view(g.positions.data(), n * sizeof(glm::vec3), kArrayBuffer), kFloat, n, "VEC3");
        accessors[static_cast<std::size_t>(pos)]["min"] = vec_json(&lo.x, 3);
        accessors[static_cast<std::size_t>(pos)]["max"] = vec_json(&hi.x, 3);
        attributes["POSITION"] = pos;
        attributes["NORMAL"] = add_accessor(
            add_view(normals.data(), n * sizeof(glm::vec3), kArrayBuffer), kFloat, n, "VEC3");
        if (!g.uv0.empty()) {
          attributes["TEXCOORD_0"] = add_accessor(
              add_view(g.uv0.data(), n * sizeof(glm::vec2), kArrayBuffer), kFloat, n, "VEC2");
        }
        if (!g.uv1.empty()) {
          attributes["TEXCOORD_1"] = add_accessor(
              add_view(g.uv1.data(), n * sizeof(glm::vec2), kArrayBuffer), kFloat, n, "VEC2");
        }
        prim["attributes"] = attributes;
        int view;
        if (small_indices) {
          std::vector<std::uint16_t> idx(g.indices.begin(), g.indices.end());
          view = add_view(idx.data(), idx.size() * sizeof(std::uint16_t), kElementArrayBuffer);
        } else {
          view = add_view(g.indices.data(), g.indices.size() * sizeof(std::uint32_t),
                          kElementArrayBuffer);
        }
        prim["indices"] = add_accessor(view, small_indices ? kUnsignedShort : kUnsignedInt,
                                       g.indices.size(), "SCALAR");
      }
      if (p.material >= 0) prim["material"] = p.material;
      jprims.push_back(prim);
    }
    jmeshes.push_back({{"name", mesh.name}, {"primitives", jprims}});
  }
  while (bin.size() % 4 != 0) bin.push_back(0);
  if (!jmeshes.empty()) {
    doc["meshes"] = jmeshes;
    doc["accessors"] = accessors;
    doc["bufferViews"] = views;
    doc["buffers"] = Json::array({Json{{"byteLength", bin.size()}}});
  }

  if (!lights.empty()) {
    Json jlights = Json::array();
    for (const Light& l : lights) {
      Json j;
      if (!l.name.empty()) j["name"] = l.name;
      j["color"] = vec_json(&l.color.x, 3);
      j["intensity"] = static_cast<double>(l.intensity);
      switch (l.type) {
        case LightType::kPoint:
          j["type"] = "point";
          break;
        case LightType::kSpot:
          j["type"] = "spot";
          j["spot"] = {{"innerConeAngle", static_cast<double>(l.inner_cone_angle)},
                       {"outerConeAngle", static_cast<double>(l.outer_cone_angle)}};
          break;
        case LightType::kDirectional:
          j["type"] = "directional";
          break;
      }
      if (l.type != LightType::kDirectional && l.range > 0.0f)
        j["range"] = static_cast<double>(l.range);
      jlights.push_back(j);
    }
    doc["extensions"]["KHR_lights_punctual"]["lights"] = jlights;
  }

  std::vector<std::string> used;
  if (options.draco && !meshes.empty()) used.emplace_back("KHR_draco_mesh_compression");
  if (!lights.empty()) used.emplace_back("KHR_lights_punctual");
  if (emissive_strength_used) used.emplace_back("KHR_materials_emissive_strength");
  if (!used.empty()) doc["extensionsUsed"] = used;
  if (options.draco && !meshes.empty()) doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  return doc;
}

}  // namespace

std::vector<std::uint8_t> SceneBuilder::to_glb(const WriteOptions& options) const {
  check_graph();
  std::vector<std::uint8_t> bin;
  const Json doc = build_document(materials_, meshes_, lights_, nodes_, options, bin);
  std::string json = doc.dump();
  while (json.size() % 4 != 0) json += ' ';
  const std::size_t total = 12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin.size());
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error("scene too large for .glb");
  std::vector<std::uint8_t> out;
  out.reserve(total);
  auto put32 = [&](std::uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  };
  put32(0x46546C67u);  // "glTF"
  put32(2);
  put32(static_cast<std::uint32_t>(total));
  put32(static_cast<std::uint32_t>(json.size()));
  put32(0x4E4F534Au);  // "JSON"
  out.insert(out.end(), json.begin(), json.end());
  if (!bin.empty()) {
    put32(static_cast<std::uint32_t>(bin.size()));
    put32(0x004E4942u);  // "BIN\0"
    out.insert(out.end(), bin.begin(), bin.end());
  }
  return out;
}

std::string SceneBuilder::to_gltf(const WriteOptions& options, const std::string& bin_uri,
                                  std::vector<std::uint8_t>* bin) const {
  check_graph();
  std::vector<std::uint8_t> data;
  Json doc = build_document(materials_, meshes_, lights_, nodes_, options, data);
  if (!data.empty()) {
    if (options.storage == BufferStorage::kEmbedded) {
      doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(data);
    } else {
      if (bin == nullptr)
        throw std::invalid_argument("to_gltf: external storage needs a bin output");
      doc["buffers"][0]["uri"] = bin_uri;
      *bin = std::move(data);
    }
  }
  return doc.dump(1);
}

void SceneBuilder::write(const std::string& path, const WriteOptions& options) const {
  const std::filesystem::path p(path);
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".glb") {
    const std::vector<std::uint8_t> glb = to_glb(options);
    write_atomically(p, glb.data(), glb.size());
  } else if (ext == ".gltf") {
    std::filesystem::path bin_path = p;
    bin_path.replace_extension(".bin");
    std::vector<std::uint8_t> bin;
    const std::string text = to_gltf(options, bin_path.filename().string(), &bin);
    if (!bin.empty()) write_atomically(bin_path, bin.data(), bin.size());
    write_atomically(p, text.data(), text.size());
  } else {
    throw std::invalid_argument("write: '" + path + "' must end in .glb or .gltf");
  }
}

}  // namespace lightpatch::scenegen
