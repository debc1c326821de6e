#include "gltf_scene.h"

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#include <tiny_gltf.h>

#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

namespace lightpatch::inn {

struct GltfScene::Model {
  tinygltf::Model gltf;
};

namespace {

constexpr const char* kDraco = "KHR_draco_mesh_compression";
constexpr const char* kLights = "KHR_lights_punctual";

std::runtime_error error(const std::string& path, const std::string& what) {
  return std::runtime_error(path + ": " + what);
}

// The game never samples textures; accept images without decoding them.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int,
                const unsigned char*, int, void*) {
  return true;
}

bool extras_flag(const tinygltf::Value& extras, const char* key) {
  return extras.IsObject() && extras.Has(key) && extras.Get(key).IsBool() &&
         extras.Get(key).Get<bool>();
}

glm::mat4 local_matrix(const tinygltf::Node& n) {
  glm::mat4 m(1.0f);
  if (n.matrix.size() == 16) {
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        m[c][r] = static_cast<float>(n.matrix[static_cast<size_t>(c * 4 + r)]);
    return m;
  }
  if (n.translation.size() == 3) {
    m = glm::translate(
        m, glm::vec3(static_cast<float>(n.translation[0]), static_cast<float>(n.translation[1]),
                     static_cast<float>(n.translation[2])));
  }
  if (n.rotation.size() == 4) {
    const glm::quat q(static_cast<float>(n.rotation[3]), static_cast<float>(n.rotation[0]),
                      static_cast<float>(n.rotation[1]), static_cast<float>(n.rotation[2]));
    const float len = glm::length(q);
    if (len > 0.0f && std::isfinite(len)) m = m * glm::mat4_cast(q / len);
  }
  if (n.scale.size() == 3) {
    m = glm::scale(m, glm::vec3(static_cast<float>(n.scale[0]), static_cast<float>(n.scale[1]),
                                static_cast<float>(n.scale[2])));
  }
  return m;
}

// Float components of a plain accessor (float or normalized/unnormalized integers).
std::vector<float> read_accessor(const tinygltf::Model& model, int index, int comps,
                                 const std::string& label) {
  if (index < 0 || static_cast<size_t>(index) >= model.accessors.size())
    throw std::runtime_error(label + ": missing accessor " + std::to_string(index));
  const tinygltf::Accessor& acc = model.accessors[static_cast<size_t>(index)];
  const int have = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(acc.type));
  if (have != comps)
    throw std::runtime_error(label + ": accessor has " + std::to_string(have) + " components");
  std::vector<float> out(acc.count * static_cast<size_t>(comps), 0.0f);
  if (acc.bufferView < 0) return out;  // all zeros (glTF 3.6.2.3)
  if (static_cast<size_t>(acc.bufferView) >= model.bufferViews.size())
    throw std::runtime_error(label + ": missing bufferView");
  const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(acc.bufferView)];
  if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model.buffers.size())
    throw std::runtime_error(label + ": missing buffer");
  const std::vector<unsigned char>& data = model.buffers[static_cast<size_t>(view.buffer)].data;
  const int csize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
  if (csize <= 0) throw std::runtime_error(label + ": bad component type");
  const size_t elem = static_cast<size_t>(csize) * static_cast<size_t>(comps);
  const size_t stride = view.byteStride ? view.byteStride : elem;
  const size_t start = view.byteOffset + acc.byteOffset;
  if (acc.count > 0 &&
      (start + stride * (acc.count - 1) + elem > view.byteOffset + view.byteLength ||
       view.byteOffset + view.byteLength > data.size()))
    throw std::runtime_error(label + ": accessor reads past its bufferView");
  for (size_t i = 0; i < acc.count; ++i) {
    const unsigned char* p = data.data() + start + i * stride;
    for (int c = 0; c < comps; ++c) {
      const unsigned char* q = p + c * csize;
      float v = 0.0f;
      switch (acc.componentType) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
          std::memcpy(&v, q, 4);
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
          v = q[0] / (acc.normalized ? 255.0f : 1.0f);
          break;
        case TINYGLTF_COMPONENT_TYPE_BYTE:
          v = static_cast<float>(static_cast<int8_t>(q[0])) / (acc.normalized ? 127.0f : 1.0f);
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
          uint16_t s;
          std::memcpy(&s, q, 2);
          v = s / (acc.normalized ? 65535.0f : 1.0f);
          break;
        }
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
          int16_t s;
          std::memcpy(&s, q, 2);
          v = static_cast<float>(s) / (acc.normalized ? 32767.0f : 1.0f);
          break;
        }
        default:
          throw std::runtime_error(label + ": unsupported component type");
      }
      out[i * static_cast<size_t>(comps) + static_cast<size_t>(c)] = v;
    }
  }
  return out;
}

std::vector<float> read_draco_positions(const tinygltf::Model& model, const tinygltf::Value& ext,
                                        const std::string& label) {
  if (!ext.IsObject() || !ext.Has("bufferView") || !ext.Get("bufferView").IsInt() ||
      !ext.Has("attributes"))
    throw std::runtime_error(label + ": malformed " + kDraco);
  const int bv = ext.Get("bufferView").GetNumberAsInt();
  if (bv < 0 || static_cast<size_t>(bv) >= model.bufferViews.size())
    throw std::runtime_error(label + ": missing Draco bufferView");
  const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(bv)];
  if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model.buffers.size() ||
      view.byteOffset + view.byteLength >
          model.buffers[static_cast<size_t>(view.buffer)].data.size())
    throw std::runtime_error(label + ": Draco bufferView outside its buffer");
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(
                  model.buffers[static_cast<size_t>(view.buffer)].data.data() + view.byteOffset),
              view.byteLength);
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok() || !decoded.value())
    throw std::runtime_error(label + ": Draco decoding failed");
  const std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
  const tinygltf::Value& attrs = ext.Get("attributes");
  if (!attrs.IsObject() || !attrs.Has("POSITION") || !attrs.Get("POSITION").IsInt())
    throw std::runtime_error(label + ": Draco data has no POSITION");
  const draco::PointAttribute* a =
      mesh->GetAttributeByUniqueId(static_cast<uint32_t>(attrs.Get("POSITION").GetNumberAsInt()));
  if (!a || a->num_components() != 3)
    throw std::runtime_error(label + ": Draco POSITION missing or not 3D");
  std::vector<float> out(static_cast<size_t>(mesh->num_points()) * 3);
  for (draco::PointIndex i(0); i < mesh->num_points(); ++i) {
    if (!a->ConvertValue<float>(a->mapped_index(i), 3,
                                out.data() + static_cast<size_t>(i.value()) * 3))
      throw std::runtime_error(label + ": Draco POSITION could not be converted");
  }
  return out;
}

uint32_t read_u32(const std::vector<unsigned char>& b, size_t at) {
  uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

void write_u32(std::vector<unsigned char>& b, size_t at, uint32_t v) {
  std::memcpy(b.data() + at, &v, 4);
}

// tinygltf 2.7.0 (Debian 12) rejects a primitive whose `indices` accessor has no bufferView, which
// is how every KHR_draco_mesh_compression primitive is written (the connectivity is in the Draco
// stream). The cooker works around it the same way (draco_indices_patch in cooker/src/import.cpp):
// `indices` is
// removed from Draco primitives before tinygltf parses the JSON. False when nothing changed.
bool strip_draco_indices(const std::string& text, std::string* out) {
  nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object() || !j.contains("meshes") || !j["meshes"].is_array())
    return false;
  bool changed = false;
  for (auto& mesh : j["meshes"]) {
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
      continue;
    for (auto& prim : mesh["primitives"]) {
      if (prim.is_object() && prim.contains("indices") && prim.contains("extensions") &&
          prim["extensions"].is_object() && prim["extensions"].contains(kDraco)) {
        prim.erase("indices");
        changed = true;
      }
    }
  }
  if (changed) *out = j.dump();
  return changed;
}

bool load_file(tinygltf::TinyGLTF& loader, tinygltf::Model* model, std::string* err,
               std::string* warn, const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    *err = "cannot open file for reading";
    return false;
  }
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(f)),
                                   std::istreambuf_iterator<char>());
  const std::string base_dir = std::filesystem::path(path).parent_path().string();
  if (bytes.size() < 4 || std::memcmp(bytes.data(), "glTF", 4) != 0) {
    std::string text(bytes.begin(), bytes.end()), fixed;
    if (strip_draco_indices(text, &fixed)) text = std::move(fixed);
    return loader.LoadASCIIFromString(model, err, warn, text.c_str(),
                                      static_cast<unsigned>(text.size()), base_dir);
  }
  // GLB: header (magic, version, length), the JSON chunk (length, type, text), then BIN.
  if (bytes.size() >= 20 && read_u32(bytes, 16) == 0x4E4F534Au) {
    const uint64_t json_length = read_u32(bytes, 12);
    std::string fixed;
    if (20 + json_length <= bytes.size() &&
        strip_draco_indices(
            std::string(bytes.begin() + 20,
                        bytes.begin() + static_cast<std::ptrdiff_t>(20 + json_length)),
            &fixed)) {
      while (fixed.size() % 4) fixed.push_back(' ');  // chunks stay 4-byte aligned
      std::vector<unsigned char> out(bytes.begin(), bytes.begin() + 20);
      out.insert(out.end(), fixed.begin(), fixed.end());
      out.insert(out.end(), bytes.begin() + static_cast<std::ptrdiff_t>(20 + json_length),
                 bytes.end());
      write_u32(out, 8, static_cast<uint32_t>(out.size()));
      write_u32(out, 12, static_cast<uint32_t>(fixed.size()));
      bytes = std::move(out);
    }
  }
  return loader.LoadBinaryFromMemory(model, err, warn, bytes.data(),
                                     static_cast<unsigned>(bytes.size()), base_dir);
}

}  // namespace

GltfScene::GltfScene(const std::string& path) : model_(std::make_unique<Model>()), path_(path) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  std::string err, warn;
  const bool ok = load_file(loader, &model_->gltf, &err, &warn, path);
  if (!ok) throw error(path, err.empty() ? "cannot read glTF" : err);
  const tinygltf::Model& m = model_->gltf;

  for (const tinygltf::Material& mat : m.materials) {
    GltfMaterial g;
    const std::vector<double>& bc = mat.pbrMetallicRoughness.baseColorFactor;
    if (bc.size() >= 3)
      g.albedo = glm::vec3(static_cast<float>(bc[0]), static_cast<float>(bc[1]),
                           static_cast<float>(bc[2]));
    float strength = 1.0f;
    const auto es = mat.extensions.find("KHR_materials_emissive_strength");
    if (es != mat.extensions.end() && es->second.IsObject() && es->second.Has("emissiveStrength"))
      strength = static_cast<float>(es->second.Get("emissiveStrength").GetNumberAsDouble());
    if (mat.emissiveFactor.size() == 3) {
      g.emissive = strength * glm::vec3(static_cast<float>(mat.emissiveFactor[0]),
                                        static_cast<float>(mat.emissiveFactor[1]),
                                        static_cast<float>(mat.emissiveFactor[2]));
    }
    g.double_sided = mat.doubleSided;
    materials_.push_back(g);
  }

  nodes_.resize(m.nodes.size());
  for (size_t i = 0; i < m.nodes.size(); ++i) {
    nodes_[i].name = m.nodes[i].name;
    nodes_[i].mesh = m.nodes[i].mesh;
    nodes_[i].semi_dynamic = extras_flag(m.nodes[i].extras, "semiDynamic");
  }
  // World transforms from the default scene's roots (iterative: no recursion on file data).
  const int scene = m.defaultScene >= 0 ? m.defaultScene : 0;
  if (static_cast<size_t>(scene) >= m.scenes.size()) throw error(path, "no scene");
  std::vector<std::pair<int, glm::mat4>> stack;
  for (int root : m.scenes[static_cast<size_t>(scene)].nodes)
    stack.emplace_back(root, glm::mat4(1.0f));
  while (!stack.empty()) {
    const auto [node, parent] = stack.back();
    stack.pop_back();
    if (node < 0 || static_cast<size_t>(node) >= m.nodes.size())
      throw error(path, "reference to missing node " + std::to_string(node));
    GltfNode& n = nodes_[static_cast<size_t>(node)];
    if (n.in_scene) throw error(path, "node " + std::to_string(node) + " is reached twice");
    n.in_scene = true;
    n.world = parent * local_matrix(m.nodes[static_cast<size_t>(node)]);
    for (int child : m.nodes[static_cast<size_t>(node)].children)
      stack.emplace_back(child, n.world);
    const auto ext = m.nodes[static_cast<size_t>(node)].extensions.find(kLights);
    if (ext != m.nodes[static_cast<size_t>(node)].extensions.end()) {
      GltfLight l;
      l.name = n.name;
      l.node = node;
      l.position = glm::vec3(n.world * glm::vec4(0, 0, 0, 1));
      const glm::vec3 d = glm::mat3(n.world) * glm::vec3(0, 0, -1);
      if (glm::length(d) > 0.0f) l.direction = glm::normalize(d);
      l.semi_dynamic = n.semi_dynamic;
      lights_.push_back(l);
    }
  }
}

GltfScene::~GltfScene() = default;

int GltfScene::primitive_count(int node) const {
  if (node < 0 || static_cast<size_t>(node) >= nodes_.size()) return 0;
  const int mesh = nodes_[static_cast<size_t>(node)].mesh;
  if (mesh < 0 || static_cast<size_t>(mesh) >= model_->gltf.meshes.size()) return 0;
  return static_cast<int>(model_->gltf.meshes[static_cast<size_t>(mesh)].primitives.size());
}

int GltfScene::primitive_material(int node, int primitive) const {
  if (primitive < 0 || primitive >= primitive_count(node)) return -1;
  const int mesh = nodes_[static_cast<size_t>(node)].mesh;
  const int mat = model_->gltf.meshes[static_cast<size_t>(mesh)]
                      .primitives[static_cast<size_t>(primitive)]
                      .material;
  return mat >= 0 && static_cast<size_t>(mat) < materials_.size() ? mat : -1;
}

std::vector<glm::vec3> GltfScene::world_positions(int node, int primitive) const {
  if (primitive < 0 || primitive >= primitive_count(node))
    throw error(path_,
                "node " + std::to_string(node) + " has no primitive " + std::to_string(primitive));
  const tinygltf::Model& m = model_->gltf;
  const GltfNode& n = nodes_[static_cast<size_t>(node)];
  const tinygltf::Primitive& prim =
      m.meshes[static_cast<size_t>(n.mesh)].primitives[static_cast<size_t>(primitive)];
  const std::string label = path_ + ": node " + std::to_string(node) + " '" + n.name +
                            "' primitive " + std::to_string(primitive);
  std::vector<float> raw;
  const auto draco = prim.extensions.find(kDraco);
  if (draco != prim.extensions.end()) {
    raw = read_draco_positions(m, draco->second, label);
  } else {
    const auto pos = prim.attributes.find("POSITION");
    if (pos == prim.attributes.end()) throw std::runtime_error(label + ": no POSITION");
    raw = read_accessor(m, pos->second, 3, label + " POSITION");
  }
  std::vector<glm::vec3> out(raw.size() / 3);
  for (size_t i = 0; i < out.size(); ++i) {
    out[i] = glm::vec3(n.world * glm::vec4(raw[3 * i], raw[3 * i + 1], raw[3 * i + 2], 1.0f));
  }
  return out;
}

}  // namespace lightpatch::inn
