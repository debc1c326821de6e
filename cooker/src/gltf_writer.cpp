// `cook --write-gltf`: the source file's JSON edited in place (baked primitives replaced, every
// buffer and image moved into one binary chunk) and written as .glb (glTF 2.0 §4.4).
#include "lightpatch/cooker/gltf_writer.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/io.h"

namespace lightpatch::cooker {

namespace {

using Json = nlohmann::ordered_json;

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;
constexpr uint32_t kChunkBin = 0x004E4942;
constexpr int kFloat = 5126, kUint32 = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr const char* kDraco = "KHR_draco_mesh_compression";

uint32_t u32(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

// RFC 4648 base64 (data: URIs); throws on a character outside the alphabet.
std::vector<uint8_t> base64_decode(const std::string& s, const std::string& what) {
  std::vector<uint8_t> out;
  uint32_t acc = 0;
  int bits = 0;
  for (char c : s) {
    int v;
    if (c >= 'A' && c <= 'Z')
      v = c - 'A';
    else if (c >= 'a' && c <= 'z')
      v = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      v = c - '0' + 52;
    else if (c == '+')
      v = 62;
    else if (c == '/')
      v = 63;
    else if (c == '=')
      break;
    else
      throw CookError(what + ": invalid base64 in a data URI");
    acc = (acc << 6) | uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(uint8_t(acc >> bits));
    }
  }
  return out;
}

// A URI relative to the scene's folder (percent-decoded) or a data: URI, as bytes.
std::vector<uint8_t> read_uri(const std::string& uri, const std::string& base_dir,
                              const std::string& what) {
  if (uri.rfind("data:", 0) == 0) {
    const size_t comma = uri.find(',');
    if (comma == std::string::npos || uri.find(";base64") > comma)
      throw CookError(what + ": a data URI that is not base64");
    return base64_decode(uri.substr(comma + 1), what);
  }
  std::string path;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size()) {
      path += char(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      path += uri[i];
    }
  }
  return read_file(base_dir + path);
}

class Bin {
 public:
  // Appends bytes (4-byte aligned) as a new bufferView of buffer 0; returns its index.
  int view(Json& gltf, const void* data, size_t size, int target) {
    while (bytes_.size() % 4 != 0) bytes_.push_back(0);
    const size_t at = bytes_.size();
    bytes_.insert(bytes_.end(), static_cast<const uint8_t*>(data),
                  static_cast<const uint8_t*>(data) + size);
    Json v = {{"buffer", 0}, {"byteOffset", at}, {"byteLength", size}};
    if (target) v["target"] = target;
    gltf["bufferViews"].push_back(v);
    return int(gltf["bufferViews"].size()) - 1;
  }
  // A float or uint32 accessor over a new bufferView; returns its index.
  template <typename T>
  int accessor(Json& gltf, const std::vector<T>& data, int components, int component_type,
               const char* type, int target) {
    const int v = view(gltf, data.data(), data.size() * sizeof(T), target);
    gltf["accessors"].push_back({{"bufferView", v},
                                 {"componentType", component_type},
                                 {"count", data.size() / size_t(components)},
                                 {"type", type}});
    return int(gltf["accessors"].size()) - 1;
  }
  size_t append(const std::vector<uint8_t>& data) {
    while (bytes_.size() % 4 != 0) bytes_.push_back(0);
    const size_t at = bytes_.size();
    bytes_.insert(bytes_.end(), data.begin(), data.end());
    return at;
  }
  std::vector<uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

// One baked primitive in its node's local space, as accessors; returns the primitive's JSON.
Json baked_primitive(Json gltf_primitive, const MeshInstance& m, const MeshLayout& ml, Json& gltf,
                     Bin& bin) {
  const glm::mat4 to_local = glm::inverse(m.world);
  const glm::mat3 normal_to_local = glm::transpose(glm::mat3(m.world));
  std::vector<float> pos, nrm, uv0, uv1;
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (size_t v = 0; v < ml.uv.size(); ++v) {
    const uint32_t s = ml.source_vertex[v];
    const glm::vec3 p = glm::vec3(to_local * glm::vec4(m.positions[s], 1.0f));
    glm::vec3 n = normal_to_local * m.normals[s];
    const float len = glm::length(n);
    n = len > 0.0f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
    pos.insert(pos.end(), {p.x, p.y, p.z});
    nrm.insert(nrm.end(), {n.x, n.y, n.z});
    if (!m.uv0.empty()) uv0.insert(uv0.end(), {m.uv0[s].x, m.uv0[s].y});
    uv1.insert(uv1.end(), {ml.uv[v].x, ml.uv[v].y});
  }
  // The importer turned a mirrored node's triangles around to keep them front-facing in world
  // space; in the node's own space they face as the file had them.
  std::vector<uint32_t> idx = ml.indices;
  if (glm::determinant(glm::mat3(m.world)) < 0.0f)
    for (size_t t = 0; t + 2 < idx.size(); t += 3) std::swap(idx[t + 1], idx[t + 2]);
  Json attributes = Json::object();
  attributes["POSITION"] = bin.accessor(gltf, pos, 3, kFloat, "VEC3", kArrayBuffer);
  gltf["accessors"].back()["min"] = {lo.x, lo.y, lo.z};
  gltf["accessors"].back()["max"] = {hi.x, hi.y, hi.z};
  attributes["NORMAL"] = bin.accessor(gltf, nrm, 3, kFloat, "VEC3", kArrayBuffer);
  // TEXCOORD_1 needs a TEXCOORD_0 (glTF 3.7.2.1); without one of its own the primitive takes
  // the light-map UVs there too.
  const int lightmap_uv = bin.accessor(gltf, uv1, 2, kFloat, "VEC2", kArrayBuffer);
  attributes["TEXCOORD_0"] =
      uv0.empty() ? lightmap_uv : bin.accessor(gltf, uv0, 2, kFloat, "VEC2", kArrayBuffer);
  attributes["TEXCOORD_1"] = lightmap_uv;
  Json p = Json::object();
  p["attributes"] = attributes;
  p["indices"] = bin.accessor(gltf, idx, 1, kUint32, "SCALAR", kElementArrayBuffer);
  if (gltf_primitive.contains("material")) p["material"] = gltf_primitive["material"];
  if (gltf_primitive.contains("extras")) p["extras"] = gltf_primitive["extras"];
  if (gltf_primitive.contains("extensions")) {
    Json ext = gltf_primitive["extensions"];
    ext.erase(kDraco);
    if (!ext.empty()) p["extensions"] = ext;
  }
  return p;
}

}  // namespace

std::vector<uint8_t> gltf_with_lightmap_uvs(const std::string& scene_path, const Scene& scene,
                                            const Layout& layout) {
  const std::vector<uint8_t> file = read_file(scene_path);
  const size_t slash = scene_path.find_last_of('/');
  const std::string base_dir = slash == std::string::npos ? "" : scene_path.substr(0, slash + 1);
  Json gltf;
  std::vector<uint8_t> glb_bin;
  const bool glb = file.size() >= 12 && u32(file.data()) == kGlbMagic;
  try {
    if (glb) {
      if (file.size() < 20 || u32(file.data() + 16) != kChunkJson ||
          uint64_t(u32(file.data() + 12)) > file.size() - 20)
        throw CookError(scene_path + ": not a valid .glb");
      const size_t json_len = u32(file.data() + 12);
      gltf = Json::parse(file.begin() + 20, file.begin() + 20 + std::ptrdiff_t(json_len));
      const size_t bin_at = 20 + (json_len + 3) / 4 * 4;
      if (bin_at + 8 <= file.size() && u32(file.data() + bin_at + 4) == kChunkBin) {
        const size_t bin_len = u32(file.data() + bin_at);
        if (bin_len > file.size() - bin_at - 8) throw CookError(scene_path + ": truncated .glb");
        glb_bin.assign(file.begin() + std::ptrdiff_t(bin_at + 8),
                       file.begin() + std::ptrdiff_t(bin_at + 8 + bin_len));
      }
    } else {
      gltf = Json::parse(file.begin(), file.end());
    }
  } catch (const Json::exception& e) {
    throw CookError(scene_path + ": cannot read the glTF again: " + e.what());
  }

  // Every buffer into one binary chunk; every bufferView re-pointed.
  Bin bin;
  std::vector<size_t> buffer_at;
  for (Json& b : gltf.value("buffers", Json::array())) {
    const std::vector<uint8_t> data =
        b.contains("uri") ? read_uri(b["uri"].get<std::string>(), base_dir, scene_path) : glb_bin;
    buffer_at.push_back(bin.append(data));
  }
  for (Json& v : gltf["bufferViews"]) {
    const size_t b = v.value("buffer", size_t(0));
    if (b >= buffer_at.size()) throw CookError(scene_path + ": a bufferView names no buffer");
    v["buffer"] = 0;
    v["byteOffset"] = v.value("byteOffset", size_t(0)) + buffer_at[b];
  }
  // Images by URI (files beside the scene, or data: URIs) embedded, so the .glb stands alone.
  if (gltf.contains("images"))
    for (Json& img : gltf["images"]) {
      if (!img.contains("uri")) continue;
      const std::string uri = img["uri"];
      const std::vector<uint8_t> data = read_uri(uri, base_dir, scene_path);
      const bool jpeg = data.size() >= 2 && data[0] == 0xFF && data[1] == 0xD8;
      img.erase("uri");
      img["bufferView"] = bin.view(gltf, data.data(), data.size(), 0);
      img["mimeType"] = jpeg ? "image/jpeg" : "image/png";
    }

  // Baked primitives by (node, primitive).
  std::map<std::pair<int, int>, size_t> baked;
  for (size_t i = 0; i < scene.meshes.size(); ++i)
    if (!layout.meshes[i].indices.empty() && scene.meshes[i].node_index >= 0)
      baked[{scene.meshes[i].node_index, scene.meshes[i].primitive_index}] = i;
  std::map<int, int> users;  // mesh -> nodes that use it
  for (const Json& n : gltf["nodes"])
    if (n.contains("mesh")) ++users[n["mesh"].get<int>()];
  Json& nodes = gltf["nodes"];
  for (size_t node = 0; node < nodes.size(); ++node) {
    if (!nodes[node].contains("mesh")) continue;
    const int mesh = nodes[node]["mesh"];
    if (baked.lower_bound({int(node), 0}) == baked.lower_bound({int(node) + 1, 0})) continue;
    // A mesh of its own for a node that shares it: its light-map UVs are the node's.
    int target = mesh;
    if (users[mesh] > 1) {
      gltf["meshes"].push_back(gltf["meshes"][size_t(mesh)]);
      target = int(gltf["meshes"].size()) - 1;
      nodes[node]["mesh"] = target;
    }
    Json& prims = gltf["meshes"][size_t(target)]["primitives"];
    for (size_t p = 0; p < prims.size(); ++p) {
      auto it = baked.find({int(node), int(p)});
      if (it == baked.end()) continue;
      prims[p] =
          baked_primitive(prims[p], scene.meshes[it->second], layout.meshes[it->second], gltf, bin);
    }
  }
  // Draco stays listed only while some primitive still uses it.
  bool draco = false;
  for (const Json& m : gltf["meshes"])
    for (const Json& p : m["primitives"])
      draco |= p.contains("extensions") && p["extensions"].contains(kDraco);
  if (!draco)
    for (const char* list : {"extensionsUsed", "extensionsRequired"}) {
      if (!gltf.contains(list)) continue;
      Json kept = Json::array();
      for (const Json& e : gltf[list])
        if (e != kDraco) kept.push_back(e);
      if (kept.empty())
        gltf.erase(list);
      else
        gltf[list] = kept;
    }

  std::vector<uint8_t>& data = bin.bytes();
  while (data.size() % 4 != 0) data.push_back(0);
  gltf["buffers"] = Json::array({{{"byteLength", data.size()}}});
  std::string json = gltf.dump();
  while (json.size() % 4 != 0) json += ' ';
  std::vector<uint8_t> out;
  auto put = [&](uint32_t v) {
    const uint8_t* b = reinterpret_cast<const uint8_t*>(&v);
    out.insert(out.end(), b, b + 4);
  };
  put(kGlbMagic);
  put(2);
  put(uint32_t(12 + 8 + json.size() + 8 + data.size()));
  put(uint32_t(json.size()));
  put(kChunkJson);
  out.insert(out.end(), json.begin(), json.end());
  put(uint32_t(data.size()));
  put(kChunkBin);
  out.insert(out.end(), data.begin(), data.end());
  return out;
}

}  // namespace lightpatch::cooker
