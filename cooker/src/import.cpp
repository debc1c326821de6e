// glTF 2.0 import: tinygltf for parsing, Draco's API for KHR_draco_mesh_compression, then every
// piece of data the cooker uses is checked here (indices, ranges, finiteness), because tinygltf
// trusts the file.
#include "lightpatch/cooker/import.h"

// Same configuration as tiny_gltf_impl.cpp: the cooker reads glTF, it never writes images.
#define TINYGLTF_NO_STB_IMAGE_WRITE
#include <tiny_gltf.h>

#include <limits.h>
#include <stb_image.h>
#include <stdlib.h>

#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <limits>
#include <map>
#include <set>
#include <string_view>

#include "json_depth.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/cooker/printable.h"

namespace lightpatch::cooker {
namespace {

constexpr const char* kDraco = "KHR_draco_mesh_compression";
constexpr const char* kLights = "KHR_lights_punctual";
constexpr const char* kEmissiveStrength = "KHR_materials_emissive_strength";

// Extensions the cooker understands well enough that a file may require them. Others that only
// affect appearance in ways the cooker ignores may still be *used*.
const std::set<std::string>& supported_required() {
  static const std::set<std::string> s = {kDraco, kLights, kEmissiveStrength, "KHR_materials_unlit",
                                          "KHR_texture_transform"};
  return s;
}

std::string node_label(const tinygltf::Model& model, int node) {
  const std::string& n = model.nodes[size_t(node)].name;
  return "node " + std::to_string(node) + (n.empty() ? std::string() : " " + quote(n));
}

std::string mesh_label(const tinygltf::Model& model, int mesh, int prim) {
  const std::string& n = model.meshes[size_t(mesh)].name;
  return "mesh " + std::to_string(mesh) + (n.empty() ? std::string() : " " + quote(n)) +
         " primitive " + std::to_string(prim);
}

std::string text_of(const glm::vec3& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%g, %g, %g)", double(v.x), double(v.y), double(v.z));
  return buf;
}

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

float srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// [offset, offset + length) lies inside [0, size), without overflow (offsets come from the file
// and can be anything up to 2^64 - 1).
bool range_inside(uint64_t offset, uint64_t length, uint64_t size) {
  return offset <= size && length <= size - offset;
}

// ---- accessors -------------------------------------------------------------------------------

int component_size(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;
  }
}

int component_count(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return 1;
    case TINYGLTF_TYPE_VEC2:
      return 2;
    case TINYGLTF_TYPE_VEC3:
      return 3;
    case TINYGLTF_TYPE_VEC4:
      return 4;
    default:
      return 0;
  }
}

// Reads one component as double; normalized integers map to [0,1] / [-1,1] (glTF 3.11).
double read_component(const unsigned char* p, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float f;
      std::memcpy(&f, p, 4);
      return f;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      const auto v = static_cast<int8_t>(p[0]);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    case TINYGLTF_COMPONENT_TYPE_INT: {
      int32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    default:
      return 0.0;
  }
}

// Reads accessor `index` into `count * comps` doubles, checking every offset against the buffer.
std::vector<double> read_accessor(const tinygltf::Model& model, int index, int want_comps,
                                  const std::string& what) {
  const std::string label = what + " accessor " + std::to_string(index);
  if (index < 0 || size_t(index) >= model.accessors.size())
    throw CookError(label + " does not exist");
  const tinygltf::Accessor& acc = model.accessors[size_t(index)];
  const int csize = component_size(acc.componentType);
  const int comps = component_count(acc.type);
  if (csize == 0) throw CookError(label + " has an invalid componentType");
  if (comps != want_comps)
    throw CookError(label + " has " + std::to_string(comps) + " components, expected " +
                    std::to_string(want_comps));
  if (acc.sparse.isSparse) throw CookError(label + " is sparse, which is not supported");
  const size_t count = acc.count;
  if (acc.bufferView < 0) {
    // All zeros (glTF 3.6.2.3): nothing in the file bounds the count, so bound it here rather
    // than let a hostile count exhaust memory.
    if (count > (size_t(1) << 24))
      throw CookError(label + " has no bufferView and an absurd count (" + std::to_string(count) +
                      ")");
    return std::vector<double>(count * size_t(comps), 0.0);
  }
  if (size_t(acc.bufferView) >= model.bufferViews.size())
    throw CookError(label + " refers to missing bufferView " + std::to_string(acc.bufferView));
  const tinygltf::BufferView& view = model.bufferViews[size_t(acc.bufferView)];
  if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size())
    throw CookError(label + ": bufferView " + std::to_string(acc.bufferView) +
                    " refers to missing buffer " + std::to_string(view.buffer));
  const std::vector<unsigned char>& data = model.buffers[size_t(view.buffer)].data;
  const uint64_t elem = uint64_t(csize) * uint64_t(comps);
  const uint64_t stride = view.byteStride ? uint64_t(view.byteStride) : elem;
  if (stride < elem) throw CookError(label + " has a byteStride smaller than its element");
  if (!range_inside(view.byteOffset, view.byteLength, data.size()))
    throw CookError(label + ": bufferView " + std::to_string(acc.bufferView) +
                    " extends past the end of buffer " + std::to_string(view.buffer) +
                    " (missing or truncated buffer data)");
  if (count == 0) return {};
  if (uint64_t(count) > (uint64_t(1) << 40) / stride)
    throw CookError(label + " has an absurd count");
  // Both terms are bounded now (count * stride <= 2^40, the view inside the buffer): no overflow.
  const uint64_t span = (uint64_t(count) - 1) * stride + elem;
  if (!range_inside(acc.byteOffset, span, view.byteLength))
    throw CookError(label + " reads past the end of its bufferView");
  const uint64_t start = uint64_t(view.byteOffset) + uint64_t(acc.byteOffset);
  // Allocated only now that the buffer's real size bounds the count.
  std::vector<double> out(count * size_t(comps), 0.0);
  for (size_t i = 0; i < count; ++i) {
    const unsigned char* p = data.data() + start + i * stride;
    for (int c = 0; c < comps; ++c)
      out[i * size_t(comps) + size_t(c)] =
          read_component(p + c * csize, acc.componentType, acc.normalized);
  }
  return out;
}

// ---- primitive data (plain or Draco) -----------------------------------------------------------

struct RawPrimitive {
  std::vector<glm::vec3> positions, normals;
  std::vector<glm::vec2> uv0, uv1;
  std::vector<uint32_t> indices;  // as stored (mode-dependent)
  bool has_indices = false;
};

std::vector<glm::vec3> to_vec3(const std::vector<double>& d) {
  std::vector<glm::vec3> v(d.size() / 3);
  for (size_t i = 0; i < v.size(); ++i)
    v[i] = glm::vec3(float(d[3 * i]), float(d[3 * i + 1]), float(d[3 * i + 2]));
  return v;
}

std::vector<glm::vec2> to_vec2(const std::vector<double>& d) {
  std::vector<glm::vec2> v(d.size() / 2);
  for (size_t i = 0; i < v.size(); ++i) v[i] = glm::vec2(float(d[2 * i]), float(d[2 * i + 1]));
  return v;
}

RawPrimitive read_plain(const tinygltf::Model& model, const tinygltf::Primitive& prim,
                        const std::string& label) {
  RawPrimitive r;
  auto attr = [&](const char* name) {
    auto it = prim.attributes.find(name);
    return it == prim.attributes.end() ? -1 : it->second;
  };
  const int pos = attr("POSITION");
  if (pos < 0) throw CookError(label + " has no POSITION attribute");
  r.positions = to_vec3(read_accessor(model, pos, 3, label + " POSITION"));
  if (attr("NORMAL") >= 0)
    r.normals = to_vec3(read_accessor(model, attr("NORMAL"), 3, label + " NORMAL"));
  if (attr("TEXCOORD_0") >= 0)
    r.uv0 = to_vec2(read_accessor(model, attr("TEXCOORD_0"), 2, label + " TEXCOORD_0"));
  if (attr("TEXCOORD_1") >= 0)
    r.uv1 = to_vec2(read_accessor(model, attr("TEXCOORD_1"), 2, label + " TEXCOORD_1"));
  if (prim.indices >= 0) {
    if (size_t(prim.indices) < model.accessors.size()) {
      const int ct = model.accessors[size_t(prim.indices)].componentType;
      if (ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
          ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
          ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        throw CookError(label + " indices accessor " + std::to_string(prim.indices) +
                        " is not an unsigned integer type");
    }
    const std::vector<double> idx = read_accessor(model, prim.indices, 1, label + " indices");
    r.indices.resize(idx.size());
    for (size_t i = 0; i < idx.size(); ++i) r.indices[i] = uint32_t(idx[i]);
    r.has_indices = true;
  }
  return r;
}

RawPrimitive read_draco(const tinygltf::Model& model, const tinygltf::Value& ext,
                        const std::string& label) {
  const std::string dl = label + " (" + kDraco + ")";
  if (!ext.IsObject() || !ext.Has("bufferView") || !ext.Get("bufferView").IsInt() ||
      !ext.Has("attributes") || !ext.Get("attributes").IsObject())
    throw CookError(dl + ": extension object needs bufferView and attributes");
  const int bv = ext.Get("bufferView").GetNumberAsInt();
  if (bv < 0 || size_t(bv) >= model.bufferViews.size())
    throw CookError(dl + " refers to missing bufferView " + std::to_string(bv));
  const tinygltf::BufferView& view = model.bufferViews[size_t(bv)];
  if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size())
    throw CookError(dl + ": bufferView " + std::to_string(bv) + " refers to a missing buffer");
  const auto& data = model.buffers[size_t(view.buffer)].data;
  if (!range_inside(view.byteOffset, view.byteLength, data.size()))
    throw CookError(dl + ": bufferView " + std::to_string(bv) +
                    " extends past the end of its buffer (missing or truncated buffer data)");
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(data.data() + view.byteOffset), view.byteLength);
  draco::Decoder decoder;
  auto status_or = decoder.DecodeMeshFromBuffer(&buffer);
  if (!status_or.ok())
    throw CookError(dl + ": Draco decoding failed: " + status_or.status().error_msg_string());
  std::unique_ptr<draco::Mesh> mesh = std::move(status_or).value();
  if (!mesh) throw CookError(dl + ": Draco decoding produced no mesh");

  const tinygltf::Value& attrs = ext.Get("attributes");
  auto read = [&](const char* name, int comps, bool required) {
    std::vector<float> out;
    if (!attrs.Has(name)) {
      if (required) throw CookError(dl + " has no " + name + " attribute");
      return out;
    }
    const tinygltf::Value& id = attrs.Get(name);
    if (!id.IsInt()) throw CookError(dl + ": attribute " + name + " id is not an integer");
    const draco::PointAttribute* a = mesh->GetAttributeByUniqueId(uint32_t(id.GetNumberAsInt()));
    if (!a)
      throw CookError(dl + ": attribute " + name + " id " + std::to_string(id.GetNumberAsInt()) +
                      " is not in the Draco data");
    if (a->num_components() != comps)
      throw CookError(dl + ": attribute " + std::string(name) + " has " +
                      std::to_string(int(a->num_components())) + " components, expected " +
                      std::to_string(comps));
    out.resize(size_t(mesh->num_points()) * size_t(comps));
    for (draco::PointIndex i(0); i < mesh->num_points(); ++i) {
      if (!a->ConvertValue<float>(a->mapped_index(i), int8_t(comps),
                                  out.data() + size_t(i.value()) * size_t(comps)))
        throw CookError(dl + ": attribute " + std::string(name) + " could not be converted");
    }
    return out;
  };
  RawPrimitive r;
  auto v3 = [](const std::vector<float>& f) {
    std::vector<glm::vec3> v(f.size() / 3);
    for (size_t i = 0; i < v.size(); ++i) v[i] = glm::vec3(f[3 * i], f[3 * i + 1], f[3 * i + 2]);
    return v;
  };
  auto v2 = [](const std::vector<float>& f) {
    std::vector<glm::vec2> v(f.size() / 2);
    for (size_t i = 0; i < v.size(); ++i) v[i] = glm::vec2(f[2 * i], f[2 * i + 1]);
    return v;
  };
  r.positions = v3(read("POSITION", 3, true));
  r.normals = v3(read("NORMAL", 3, false));
  r.uv0 = v2(read("TEXCOORD_0", 2, false));
  r.uv1 = v2(read("TEXCOORD_1", 2, false));
  r.indices.reserve(size_t(mesh->num_faces()) * 3);
  for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f)
    for (int k = 0; k < 3; ++k) r.indices.push_back(mesh->face(f)[k].value());
  r.has_indices = true;
  return r;
}

// ---- the file container ------------------------------------------------------------------------

uint32_t get_u32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

void put_u32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = uint8_t(v >> (8 * i));
}

// Checks the .glb framing (glTF 4.4) before tinygltf reads it: tinygltf 2.7 accepts a BIN chunk
// whose declared length runs up to 8 bytes past the end of the file (it forgets the chunk header)
// and then reads past the buffer, and its errors do not say that a file was cut short.
void check_glb_container(const uint8_t* data, size_t size, const std::string& name) {
  auto bad = [&](const std::string& what) {
    return CookError(name + ": invalid glTF binary: " + what);
  };
  if (size < 20) throw bad("truncated: " + std::to_string(size) + " bytes, a .glb header needs 20");
  const uint32_t version = get_u32(data + 4);
  if (version != 2) throw bad("container version " + std::to_string(version) + ", expected 2");
  const uint64_t length = get_u32(data + 8);
  if (length > size)
    throw bad("truncated: the header declares " + std::to_string(length) + " bytes, the file has " +
              std::to_string(size));
  const uint64_t json_length = get_u32(data + 12);
  if (get_u32(data + 16) != 0x4E4F534Au) throw bad("the first chunk is not JSON");
  const uint64_t json_end = 20 + json_length;
  if (json_length == 0 || json_end > length)
    throw bad("truncated: the JSON chunk declares " + std::to_string(json_length) +
              " bytes, past the end of the file");
  if (json_end == length) return;  // no BIN chunk
  if (json_end + 8 > length) throw bad("truncated: incomplete BIN chunk header");
  const uint64_t bin_length = get_u32(data + json_end);
  if (get_u32(data + json_end + 4) != 0x004E4942u) throw bad("the second chunk is not BIN");
  if (json_end + 8 + bin_length > length)
    throw bad("truncated: the BIN chunk declares " + std::to_string(bin_length) + " bytes, only " +
              std::to_string(length - json_end - 8) + " are left");
}

// tinygltf 2.7, built without its own Draco decoder (tiny_gltf_impl.cpp says why), rejects a
// primitive whose `indices` accessor has no bufferView, which is exactly how
// KHR_draco_mesh_compression stores it. The Draco path never reads that accessor (the indices come
// from the Draco data), so drop `indices` from Draco primitives before tinygltf parses the JSON.
// Returns false (leaving the input as it is) when there is nothing to change or the JSON does not
// parse (tinygltf then reports the error).
bool draco_indices_patch(const uint8_t* data, size_t size, bool glb, std::vector<uint8_t>* out) {
  const char* text = reinterpret_cast<const char*>(glb ? data + 20 : data);
  const size_t text_size = glb ? size_t(get_u32(data + 12)) : size;
  if (std::string_view(text, text_size).find(kDraco) == std::string_view::npos) return false;
  nlohmann::json doc = nlohmann::json::parse(text, text + text_size, nullptr, false);
  if (doc.is_discarded() || !doc.is_object() || !doc.contains("meshes") ||
      !doc["meshes"].is_array())
    return false;
  bool changed = false;
  for (nlohmann::json& mesh : doc["meshes"]) {
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
      continue;
    for (nlohmann::json& prim : mesh["primitives"]) {
      if (prim.is_object() && prim.contains("indices") && prim.contains("extensions") &&
          prim["extensions"].is_object() && prim["extensions"].contains(kDraco)) {
        prim.erase("indices");
        changed = true;
      }
    }
  }
  if (!changed) return false;
  std::string json = doc.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  if (!glb) {
    out->assign(json.begin(), json.end());
    return true;
  }
  while (json.size() % 4 != 0) json.push_back(' ');
  if (uint64_t(size) - text_size + json.size() > std::numeric_limits<uint32_t>::max()) return false;
  // Header and JSON chunk anew, everything after the old JSON chunk as it was.
  const size_t rest = size - (20 + text_size);
  out->assign(20 + json.size() + rest, 0);
  std::memcpy(out->data(), data, 8);
  put_u32(out->data() + 8, uint32_t(get_u32(data + 8) - text_size + json.size()));
  put_u32(out->data() + 12, uint32_t(json.size()));
  put_u32(out->data() + 16, 0x4E4F534Au);
  std::memcpy(out->data() + 20, json.data(), json.size());
  std::memcpy(out->data() + 20 + json.size(), data + 20 + text_size, rest);
  return true;
}

// ---- files and images tinygltf loads -----------------------------------------------------------

// What tinygltf's file and image callbacks share with the import (their user_data): the folders
// files may come from, the images to decode and the pixel budget. The first refusal is kept here
// and reported in the import's own words once tinygltf gives up (or warns and goes on: a missing
// image is only a warning to it).
struct LoadContext {
  std::vector<std::string> roots;  // resolved (realpath) folders
  std::set<int> base_colour_images;
  uint64_t max_texture_pixels = 0;
  uint64_t texture_pixels = 0;
  std::string refusal;
  void refuse(const std::string& why) {
    if (refusal.empty()) refusal = why;
  }
};

bool inside_folder(const std::string& path, const std::string& folder) {
  if (folder == "/") return true;
  return path.size() > folder.size() && path.compare(0, folder.size(), folder) == 0 &&
         path[folder.size()] == '/';
}

std::string resolved(const std::string& path) {
  char real[PATH_MAX];
  return ::realpath(path.c_str(), real) ? std::string(real) : std::string();
}

// tinygltf looks a uri up in the scene's folder, then in the working directory; both candidates
// pass here. Only files under an allowed folder, links resolved, exist for it.
bool file_exists(const std::string& path, void* user) {
  auto* ctx = static_cast<LoadContext*>(user);
  const std::string real = resolved(path);
  if (real.empty()) return false;
  for (const std::string& root : ctx->roots)
    if (inside_folder(real, root)) return true;
  ctx->refuse("the file " + quote_path(path) + " (" + quote_path(real) +
              ") is outside the scene's folder" +
              (ctx->roots.empty() ? std::string() : " " + quote_path(ctx->roots[0])) +
              "; buffers and images come from there or below unless " + kUriRootOption +
              " DIR allows files under DIR");
  return false;
}

// No `~` or `$VAR` expansion (tinygltf's default runs wordexp on the uri).
std::string expand_file_path(const std::string& path, void*) {
  return path;
}

// Regular files within the input size limit only (io.h).
bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                     void* user) {
  try {
    *out = read_file(path);
    return true;
  } catch (const CookError& e) {
    static_cast<LoadContext*>(user)->refuse(e.what());
    if (err) *err = e.what();
    return false;
  }
}

bool write_whole_file(std::string* err, const std::string&, const std::vector<unsigned char>&,
                      void*) {
  if (err) *err = "the cooker writes no glTF files";
  return false;
}

// Decodes the images base colours use (no other image is ever sampled), each after its header's
// size is checked against what is left of the pixel budget.
bool load_image(tinygltf::Image* image, const int index, std::string* err, std::string* warn,
                int req_width, int req_height, const unsigned char* bytes, int size, void* user) {
  auto* ctx = static_cast<LoadContext*>(user);
  if (!ctx->base_colour_images.count(index)) return true;
  int w = 0, h = 0, comp = 0;
  if (size > 0 && stbi_info_from_memory(bytes, size, &w, &h, &comp) && w > 0 && h > 0) {
    const uint64_t pixels = uint64_t(w) * uint64_t(h);
    if (pixels > ctx->max_texture_pixels - ctx->texture_pixels) {
      ctx->refuse("image " + std::to_string(index) +
                  (image->name.empty() ? std::string() : " " + quote(image->name)) + " is " +
                  std::to_string(w) + "x" + std::to_string(h) + " (" + std::to_string(pixels) +
                  " pixels); with the base-colour images before it that is over the limit of " +
                  std::to_string(ctx->max_texture_pixels) + " texture pixels (" +
                  kMaxTexturePixelsOption + " N raises it)");
      return false;
    }
    ctx->texture_pixels += pixels;
  }
  // Undecodable data: tinygltf's loader says so. Its options default to RGBA8/RGBA16.
  return tinygltf::LoadImageData(image, index, err, warn, req_width, req_height, bytes, size,
                                 nullptr);
}

// Reads what the callbacks need from the JSON before tinygltf does: the images base colours use,
// and every image bufferView's range, checked against its buffer's byteLength (tinygltf hands the
// decoder a pointer byteOffset bytes into the buffer without checking; the buffer's data is
// exactly byteLength bytes once tinygltf accepts it). Anything else malformed is left to tinygltf.
void scan_images(const char* text, size_t size, const std::string& name, LoadContext* ctx) {
  if (std::string_view(text, size).find("\"images\"") == std::string_view::npos) return;
  using nlohmann::json;
  static const std::set<std::string> kept = {"images", "bufferViews", "buffers", "textures",
                                             "materials"};
  // Keep only what is read below; drop uris (base64 buffers can be most of the file).
  const json::parser_callback_t keep = [](int depth, json::parse_event_t event, json& parsed) {
    if (event != json::parse_event_t::key) return true;
    if (depth == 1) return parsed.is_string() && kept.count(parsed.get<std::string>()) > 0;
    return !(depth == 3 && parsed == "uri");
  };
  const json doc = json::parse(text, text + size, keep, false);
  if (doc.is_discarded() || !doc.is_object()) return;
  auto array = [&](const char* key) -> const json& {
    static const json empty = json::array();
    auto it = doc.find(key);
    return it != doc.end() && it->is_array() ? *it : empty;
  };
  // tinygltf's rules: indices and sizes are unsigned JSON integers; an absent byteOffset is 0.
  auto unsigned_at = [](const json& o, const char* key, uint64_t* v) {
    if (!o.is_object()) return false;
    auto it = o.find(key);
    if (it == o.end() || !it->is_number_unsigned()) return false;
    *v = it->get<uint64_t>();
    return true;
  };
  const json &images = array("images"), &views = array("bufferViews"), &buffers = array("buffers");
  for (size_t i = 0; i < images.size(); ++i) {
    uint64_t v = 0, b = 0, offset = 0, length = 0, buffer_length = 0;
    if (!unsigned_at(images[i], "bufferView", &v) || v >= views.size()) continue;
    const json& view = views[size_t(v)];
    if (!unsigned_at(view, "buffer", &b) || b >= buffers.size() ||
        !unsigned_at(view, "byteLength", &length) ||
        !unsigned_at(buffers[size_t(b)], "byteLength", &buffer_length))
      continue;
    unsigned_at(view, "byteOffset", &offset);
    if (!range_inside(offset, length, buffer_length))
      throw CookError(name + ": image " + std::to_string(i) + ": bufferView " + std::to_string(v) +
                      " (bytes " + std::to_string(offset) + "+" + std::to_string(length) +
                      ") extends past the end of buffer " + std::to_string(b) + " (" +
                      std::to_string(buffer_length) + " bytes)");
    if (length > uint64_t(std::numeric_limits<int>::max()))
      throw CookError(name + ": image " + std::to_string(i) + ": bufferView " + std::to_string(v) +
                      " is larger than 2 GiB, which the image decoder does not take");
  }
  const json &materials = array("materials"), &textures = array("textures");
  for (const json& m : materials) {
    uint64_t texture = 0, image = 0;
    if (!m.is_object() || !m.contains("pbrMetallicRoughness")) continue;
    const json& pbr = m["pbrMetallicRoughness"];
    if (!pbr.is_object() || !pbr.contains("baseColorTexture")) continue;
    if (unsigned_at(pbr["baseColorTexture"], "index", &texture) && texture < textures.size() &&
        unsigned_at(textures[size_t(texture)], "source", &image) &&
        image <= uint64_t(std::numeric_limits<int>::max()))
      ctx->base_colour_images.insert(int(image));
  }
}

uint64_t saturating_add(uint64_t a, uint64_t b) {
  return a > std::numeric_limits<uint64_t>::max() - b ? std::numeric_limits<uint64_t>::max()
                                                      : a + b;
}

uint64_t saturating_mul(uint64_t a, uint64_t b) {
  return b != 0 && a > std::numeric_limits<uint64_t>::max() / b
             ? std::numeric_limits<uint64_t>::max()
             : a * b;
}

bool surface_mode(int mode) {
  return mode < 0 || mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_TRIANGLE_STRIP ||
         mode == TINYGLTF_MODE_TRIANGLE_FAN;
}

// World coordinates beyond this are refused: float spacing there is 6 cm, and the cross
// products of the zero-area test and the tracer's epsilons stay finite well within it.
constexpr float kMaxCoordinate = 1.0e6f;

// Finite and within kMaxCoordinate on every axis.
bool within_world(const glm::vec3& v) {
  return finite(v) && std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}) <= kMaxCoordinate;
}

// ---- the importer ------------------------------------------------------------------------------

class Importer {
 public:
  Importer(const std::string& path, const tinygltf::Model& model, const ImportLimits& limits)
      : path_(path), model_(model), limits_(limits) {}

  Scene run();

 private:
  glm::mat4 local_matrix(int node) const;
  void visit(int node, const glm::mat4& parent, int depth);
  void add_mesh_node(int node, const glm::mat4& world);
  void add_light_node(int node, const glm::mat4& world);
  int texture_for(int gltf_texture);
  void read_materials();
  void check_scene_size(const std::vector<int>& roots) const;
  uint64_t accessor_count(int accessor) const;
  void count_read(const std::string& label, uint64_t triangles, uint64_t vertices);
  std::string err(const std::string& what) const { return path_ + ": " + what; }

  const std::string& path_;
  const tinygltf::Model& model_;
  const ImportLimits& limits_;
  uint64_t triangles_read_ = 0, vertices_read_ = 0;
  Scene scene_;
  std::vector<int> visited_;
  std::map<int, int> image_to_texture_;
  int default_material_ = 0;
};

glm::mat4 Importer::local_matrix(int node) const {
  const tinygltf::Node& n = model_.nodes[size_t(node)];
  glm::mat4 m(1.0f);
  if (n.matrix.size() == 16) {
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[c][r] = float(n.matrix[size_t(c * 4 + r)]);
  } else {
    glm::mat4 t(1.0f), r(1.0f), s(1.0f);
    if (n.translation.size() == 3)
      t = glm::translate(
          glm::mat4(1.0f),
          glm::vec3(float(n.translation[0]), float(n.translation[1]), float(n.translation[2])));
    if (n.rotation.size() == 4) {
      glm::quat q(float(n.rotation[3]), float(n.rotation[0]), float(n.rotation[1]),
                  float(n.rotation[2]));
      const float len = glm::length(q);
      if (!(len > 0.0f) || !std::isfinite(len))
        throw CookError(err(node_label(model_, node) + " has an invalid rotation quaternion"));
      r = glm::mat4_cast(q / len);
    }
    if (n.scale.size() == 3)
      s = glm::scale(glm::mat4(1.0f),
                     glm::vec3(float(n.scale[0]), float(n.scale[1]), float(n.scale[2])));
    m = t * r * s;
  }
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r]))
        throw CookError(err(node_label(model_, node) + " has a non-finite transform"));
  return m;
}

bool extras_flag(const tinygltf::Value& extras, const char* key, const std::string& where);

void Importer::visit(int node, const glm::mat4& parent, int depth) {
  if (node < 0 || size_t(node) >= model_.nodes.size())
    throw CookError(err("reference to missing node " + std::to_string(node)));
  if (visited_[size_t(node)])
    throw CookError(
        err(node_label(model_, node) + " is reached twice (a cycle or a node with two parents)"));
  if (depth > 1024) throw CookError(err("node hierarchy is deeper than 1024 levels"));
  visited_[size_t(node)] = 1;
  const glm::mat4 world = parent * local_matrix(node);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(world[c][r]))
        throw CookError(err(node_label(model_, node) +
                            ": its world transform overflows (its and its parents' scales "
                            "multiply beyond the float range)"));
  const tinygltf::Node& n = model_.nodes[size_t(node)];
  if (n.mesh >= 0) add_mesh_node(node, world);
  add_light_node(node, world);
  // A light probe the scene places (probes.h) at the node's origin.
  if (extras_flag(n.extras, "lightProbe", err(node_label(model_, node))))
    scene_.probes.push_back({n.name, glm::vec3(world[3])});
  for (int child : n.children) visit(child, world, depth + 1);
}

// A boolean of a node's extras: true/false, or 1/0 as Blender writes boolean custom properties.
// Anything else is an error naming `where` (a misspelt value must not silently bake a static
// node).
bool extras_flag(const tinygltf::Value& extras, const char* key, const std::string& where) {
  if (!extras.IsObject() || !extras.Has(key)) return false;
  const tinygltf::Value& v = extras.Get(key);
  if (v.IsBool()) return v.Get<bool>();
  if (v.IsNumber() && (v.GetNumberAsDouble() == 0.0 || v.GetNumberAsDouble() == 1.0))
    return v.GetNumberAsDouble() != 0.0;
  throw CookError(where + ": extras." + key + " must be true or false (or 1 or 0)");
}

// A node's extras.lightmapScale: the texel density factor of its meshes, in (0, 1024].
float extras_density(const tinygltf::Value& extras, const std::string& where) {
  if (!extras.IsObject() || !extras.Has("lightmapScale")) return 1.0f;
  const tinygltf::Value& v = extras.Get("lightmapScale");
  const double k = v.IsNumber() ? v.GetNumberAsDouble() : -1.0;
  if (!(k > 0.0 && k <= 1024.0))
    throw CookError(where +
                    ": extras.lightmapScale must be a number in (0, 1024] (a factor of "
                    "the texel density)");
  return static_cast<float>(k);
}

// A flag whose absence means `absent` (castShadows: only an explicit false turns it off).
bool extras_flag_or(const tinygltf::Value& extras, const char* key, bool absent,
                    const std::string& where) {
  if (!extras.IsObject() || !extras.Has(key)) return absent;
  return extras_flag(extras, key, where);
}

int Importer::texture_for(int gltf_texture) {
  if (gltf_texture < 0 || size_t(gltf_texture) >= model_.textures.size())
    throw CookError(err("material refers to missing texture " + std::to_string(gltf_texture)));
  const int image = model_.textures[size_t(gltf_texture)].source;
  if (image < 0 || size_t(image) >= model_.images.size()) {
    scene_.notes.push_back("texture " + std::to_string(gltf_texture) +
                           " has no usable image; its material uses baseColorFactor only");
    return -1;
  }
  auto it = image_to_texture_.find(image);
  if (it != image_to_texture_.end()) return it->second;
  const tinygltf::Image& img = model_.images[size_t(image)];
  const int comps = img.component;
  const int bytes = img.bits == 16 ? 2 : (img.bits == 8 ? 1 : 0);
  if (img.width <= 0 || img.height <= 0 || comps <= 0 || bytes == 0 ||
      img.image.size() < size_t(img.width) * size_t(img.height) * size_t(comps) * size_t(bytes)) {
    scene_.notes.push_back("image " + std::to_string(image) + " " + quote(img.name) +
                           " could not be decoded; its material uses baseColorFactor only");
    image_to_texture_[image] = -1;
    return -1;
  }
  Texture tex;
  tex.width = img.width;
  tex.height = img.height;
  tex.linear_rgb.resize(size_t(img.width) * size_t(img.height));
  float lut[256];
  for (int i = 0; i < 256; ++i) lut[i] = srgb_to_linear(float(i) / 255.0f);
  for (size_t p = 0; p < tex.linear_rgb.size(); ++p) {
    glm::vec3 c;
    for (int k = 0; k < 3; ++k) {
      const int ch = std::min(k, comps >= 3 ? 2 : 0);  // grey images replicate channel 0
      const size_t at = (p * size_t(comps) + size_t(ch)) * size_t(bytes);
      if (bytes == 1) {
        c[k] = lut[img.image[at]];
      } else {
        uint16_t v;
        std::memcpy(&v, &img.image[at], 2);
        c[k] = srgb_to_linear(float(v) / 65535.0f);
      }
    }
    tex.linear_rgb[p] = c;
  }
  const int index = int(scene_.textures.size());
  scene_.textures.push_back(std::move(tex));
  image_to_texture_[image] = index;
  return index;
}

void Importer::read_materials() {
  for (size_t i = 0; i < model_.materials.size(); ++i) {
    const tinygltf::Material& gm = model_.materials[i];
    Material m;
    m.name = gm.name;
    const auto& f = gm.pbrMetallicRoughness.baseColorFactor;
    if (f.size() >= 3) m.albedo = glm::vec3(float(f[0]), float(f[1]), float(f[2]));
    if (gm.emissiveFactor.size() == 3)
      m.emissive = glm::vec3(float(gm.emissiveFactor[0]), float(gm.emissiveFactor[1]),
                             float(gm.emissiveFactor[2]));
    auto ext = gm.extensions.find(kEmissiveStrength);
    if (ext != gm.extensions.end() && ext->second.IsObject() &&
        ext->second.Has("emissiveStrength") && ext->second.Get("emissiveStrength").IsNumber())
      m.emissive *= float(ext->second.Get("emissiveStrength").GetNumberAsDouble());
    if (!finite(m.albedo) || !finite(m.emissive) ||
        glm::any(glm::lessThan(m.albedo, glm::vec3(0))) ||
        glm::any(glm::lessThan(m.emissive, glm::vec3(0))))
      throw CookError(err("material " + std::to_string(i) + " " + quote(gm.name) +
                          " has a negative or non-finite colour"));
    // Albedo above 1 would create energy in bounces.
    m.albedo = glm::min(m.albedo, glm::vec3(1.0f));
    if (gm.pbrMetallicRoughness.baseColorTexture.index >= 0) {
      m.albedo_texture = texture_for(gm.pbrMetallicRoughness.baseColorTexture.index);
      if (gm.pbrMetallicRoughness.baseColorTexture.texCoord != 0)
        scene_.notes.push_back("material " + quote(gm.name) +
                               ": base colour texture uses TEXCOORD_" +
                               std::to_string(gm.pbrMetallicRoughness.baseColorTexture.texCoord) +
                               "; the cooker samples it at TEXCOORD_0");
    }
    scene_.materials.push_back(std::move(m));
  }
  default_material_ = int(scene_.materials.size());
  Material def;
  def.name = "default";
  def.albedo = glm::vec3(1.0f);  // glTF default material: baseColorFactor (1,1,1,1)
  scene_.materials.push_back(def);
}

// Converts strips and fans to lists; returns false for points and lines.
bool triangle_list(int mode, const std::vector<uint32_t>& in, std::vector<uint32_t>* out) {
  out->clear();
  if (mode == TINYGLTF_MODE_TRIANGLES || mode < 0) {
    for (size_t i = 0; i + 2 < in.size(); i += 3)
      out->insert(out->end(), {in[i], in[i + 1], in[i + 2]});
    return true;
  }
  if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t i = 0; i + 2 < in.size(); ++i) {
      if (i % 2 == 0)
        out->insert(out->end(), {in[i], in[i + 1], in[i + 2]});
      else
        out->insert(out->end(), {in[i + 1], in[i], in[i + 2]});
    }
    return true;
  }
  if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (size_t i = 1; i + 1 < in.size(); ++i) out->insert(out->end(), {in[0], in[i], in[i + 1]});
    return true;
  }
  return false;
}

void Importer::add_mesh_node(int node, const glm::mat4& world) {
  const tinygltf::Node& n = model_.nodes[size_t(node)];
  if (size_t(n.mesh) >= model_.meshes.size())
    throw CookError(
        err(node_label(model_, node) + " refers to missing mesh " + std::to_string(n.mesh)));
  const std::string where = err(node_label(model_, node));
  const bool semi = extras_flag(n.extras, "semiDynamic", where);
  const bool exclude = extras_flag(n.extras, "lightmapExclude", where);
  const float density = extras_density(n.extras, where);
  int object = -1;
  if (semi) {
    object = int(scene_.objects.size());
    Object o;
    o.name = n.name;
    o.node_index = node;
    scene_.objects.push_back(o);
  }
  const glm::mat3 m3(world);
  const glm::mat3 normal_matrix = glm::inverseTranspose(m3);
  const bool mirrored = glm::determinant(m3) < 0.0f;
  const tinygltf::Mesh& mesh = model_.meshes[size_t(n.mesh)];
  for (size_t p = 0; p < mesh.primitives.size(); ++p) {
    const tinygltf::Primitive& prim = mesh.primitives[p];
    const std::string label = node_label(model_, node) + " " + mesh_label(model_, n.mesh, int(p));
    if (!surface_mode(prim.mode)) {  // before reading: its accessors may be as large as any
      scene_.notes.push_back(label + ": primitive mode " + std::to_string(prim.mode) +
                             " (points/lines) is not a surface and was skipped");
      continue;
    }
    auto draco = prim.extensions.find(kDraco);
    RawPrimitive raw;
    try {
      raw = draco != prim.extensions.end() ? read_draco(model_, draco->second, label)
                                           : read_plain(model_, prim, label);
    } catch (const CookError& e) {
      throw CookError(err(e.what()));  // the readers name node, mesh and accessor; add the file
    }
    const size_t nv = raw.positions.size();
    if (!raw.normals.empty() && raw.normals.size() != nv)
      throw CookError(err(label + ": NORMAL count differs from POSITION count"));
    if (!raw.uv0.empty() && raw.uv0.size() != nv)
      throw CookError(err(label + ": TEXCOORD_0 count differs from POSITION count"));
    if (!raw.uv1.empty() && raw.uv1.size() != nv)
      throw CookError(err(label + ": TEXCOORD_1 count differs from POSITION count"));
    if (!raw.has_indices) {
      raw.indices.resize(nv);
      for (size_t i = 0; i < nv; ++i) raw.indices[i] = uint32_t(i);
    }
    for (size_t i = 0; i < nv; ++i) {
      if (!finite(raw.positions[i]))
        throw CookError(err(label + ": POSITION " + std::to_string(i) + " is NaN or infinite"));
      if (!raw.normals.empty() && !finite(raw.normals[i]))
        throw CookError(err(label + ": NORMAL " + std::to_string(i) + " is NaN or infinite"));
      if (!raw.uv1.empty()) {
        const glm::vec2 t = raw.uv1[i];
        constexpr float kTol = 1e-5f;
        if (!(t.x >= -kTol && t.x <= 1 + kTol && t.y >= -kTol && t.y <= 1 + kTol))
          throw CookError(err(label + ": TEXCOORD_1 " + std::to_string(i) + " (" +
                              std::to_string(t.x) + ", " + std::to_string(t.y) +
                              ") is outside [0,1]"));
        raw.uv1[i] = glm::clamp(t, glm::vec2(0.0f), glm::vec2(1.0f));
      }
      if (!raw.uv0.empty() && !(std::isfinite(raw.uv0[i].x) && std::isfinite(raw.uv0[i].y)))
        throw CookError(err(label + ": TEXCOORD_0 " + std::to_string(i) + " is NaN or infinite"));
    }
    for (size_t i = 0; i < raw.indices.size(); ++i)
      if (raw.indices[i] >= nv)
        throw CookError(err(label + ": index " + std::to_string(i) + " = " +
                            std::to_string(raw.indices[i]) + " is past the vertex count " +
                            std::to_string(nv)));
    std::vector<uint32_t> tris;
    triangle_list(prim.mode, raw.indices, &tris);
    count_read(label, tris.size() / 3, nv);
    if (tris.empty()) {
      scene_.notes.push_back(label + ": no triangles, skipped");
      continue;
    }
    MeshInstance mi;
    mi.name = n.name;
    mi.node_index = node;
    mi.primitive_index = int(p);
    mi.cast_shadows = extras_flag_or(n.extras, "castShadows", true, where);
    mi.object = object;
    mi.world = world;
    mi.lightmap_scale = density;
    mi.lightmap_exclude = exclude;
    if (prim.material >= 0) {
      if (size_t(prim.material) >= model_.materials.size())
        throw CookError(
            err(label + " refers to missing material " + std::to_string(prim.material)));
      mi.material = prim.material;
    } else {
      mi.material = default_material_;
    }
    mi.positions.resize(nv);
    for (size_t i = 0; i < nv; ++i) {
      const glm::vec3 q = glm::vec3(world * glm::vec4(raw.positions[i], 1));
      if (!within_world(q))
        throw CookError(err(label + ": vertex " + std::to_string(i) + " lies at " + text_of(q) +
                            " in the world, beyond +-" + std::to_string(int(kMaxCoordinate)) +
                            " m (too large a scale or translation in the node or its parents?)"));
      mi.positions[i] = q;
    }
    // Drop zero-area triangles; the threshold is relative to the primitive's size.
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (const auto& q : mi.positions) {
      lo = glm::min(lo, q);
      hi = glm::max(hi, q);
    }
    const float diag = glm::length(hi - lo);
    const float min_cross = 1e-12f * diag * diag;
    std::vector<uint32_t> kept;
    for (size_t t = 0; t + 2 < tris.size(); t += 3) {
      uint32_t a = tris[t], b = tris[t + 1], c = tris[t + 2];
      if (mirrored) std::swap(b, c);  // keep front faces front (glTF 3.7.4)
      const glm::vec3 cr =
          glm::cross(mi.positions[b] - mi.positions[a], mi.positions[c] - mi.positions[a]);
      if (!(glm::length(cr) > min_cross)) continue;
      kept.insert(kept.end(), {a, b, c});
    }
    if (kept.empty()) {
      // The longest axis of the world transform (a determinant would underflow first).
      char scale[32];
      std::snprintf(scale, sizeof scale, "%g",
                    std::max({glm::length(glm::dvec3(m3[0])), glm::length(glm::dvec3(m3[1])),
                              glm::length(glm::dvec3(m3[2]))}));
      throw CookError(err(label + " has only zero-area triangles (" +
                          std::to_string(tris.size() / 3) +
                          " triangles; the node's world scale is " + scale + ")"));
    }
    if (kept.size() != tris.size())
      scene_.notes.push_back(label + ": dropped " +
                             std::to_string((tris.size() - kept.size()) / 3) +
                             " zero-area triangles");
    if (!raw.normals.empty()) {
      mi.normals.resize(nv);
      for (size_t i = 0; i < nv; ++i) {
        const glm::vec3 w = normal_matrix * raw.normals[i];
        const float len = glm::length(w);
        mi.normals[i] = len > 0.0f ? w / len : glm::vec3(0.0f);
      }
      mi.uv0 = raw.uv0;
      mi.uv1 = raw.uv1;
      mi.indices = std::move(kept);
      // Zero-length normals in the file: use the area-weighted face normal instead.
      std::vector<glm::vec3> face_sum(nv, glm::vec3(0.0f));
      bool need = false;
      for (size_t i = 0; i < nv; ++i) need |= mi.normals[i] == glm::vec3(0.0f);
      if (need) {
        for (size_t t = 0; t < mi.indices.size(); t += 3) {
          const uint32_t a = mi.indices[t], b = mi.indices[t + 1], c = mi.indices[t + 2];
          const glm::vec3 cr =
              glm::cross(mi.positions[b] - mi.positions[a], mi.positions[c] - mi.positions[a]);
          face_sum[a] += cr;
          face_sum[b] += cr;
          face_sum[c] += cr;
        }
        for (size_t i = 0; i < nv; ++i)
          if (mi.normals[i] == glm::vec3(0.0f)) {
            const float len = glm::length(face_sum[i]);
            mi.normals[i] = len > 0.0f ? face_sum[i] / len : glm::vec3(0, 1, 0);
          }
      }
    } else {
      // glTF 3.7.2.1: without normals, flat normals. Unweld so each triangle has its own.
      MeshInstance flat = mi;
      flat.positions.clear();
      for (size_t t = 0; t < kept.size(); t += 3) {
        const glm::vec3 pa = mi.positions[kept[t]], pb = mi.positions[kept[t + 1]],
                        pc = mi.positions[kept[t + 2]];
        const glm::vec3 nrm = glm::normalize(glm::cross(pb - pa, pc - pa));
        for (int k = 0; k < 3; ++k) {
          const uint32_t src = kept[t + size_t(k)];
          flat.indices.push_back(uint32_t(flat.positions.size()));
          flat.gltf_vertex.push_back(src);
          flat.positions.push_back(mi.positions[src]);
          flat.normals.push_back(nrm);
          if (!raw.uv0.empty()) flat.uv0.push_back(raw.uv0[src]);
          if (!raw.uv1.empty()) flat.uv1.push_back(raw.uv1[src]);
        }
      }
      mi = std::move(flat);
    }
    if (object >= 0) scene_.objects[size_t(object)].meshes.push_back(int(scene_.meshes.size()));
    scene_.meshes.push_back(std::move(mi));
  }
  if (object >= 0 && scene_.objects[size_t(object)].meshes.empty())
    throw CookError(err("semi-dynamic " + node_label(model_, node) + " has no triangles"));
}

void Importer::add_light_node(int node, const glm::mat4& world) {
  const tinygltf::Node& n = model_.nodes[size_t(node)];
  auto ext = n.extensions.find(kLights);
  if (ext == n.extensions.end()) return;
  if (!ext->second.IsObject() || !ext->second.Has("light") || !ext->second.Get("light").IsInt())
    throw CookError(err(node_label(model_, node) + ": " + kLights + " needs a light index"));
  const int li = ext->second.Get("light").GetNumberAsInt();
  if (li < 0 || size_t(li) >= model_.lights.size())
    throw CookError(
        err(node_label(model_, node) + " refers to missing light " + std::to_string(li)));
  const tinygltf::Light& gl = model_.lights[size_t(li)];
  const std::string label = node_label(model_, node) + " light " + std::to_string(li);
  Light l;
  l.name = n.name;
  l.node_index = node;
  if (gl.type == "point")
    l.type = LightType::kPoint;
  else if (gl.type == "spot")
    l.type = LightType::kSpot;
  else if (gl.type == "directional")
    l.type = LightType::kDirectional;
  else
    throw CookError(err(label + " has unknown type " + quote(gl.type)));
  l.position = glm::vec3(world * glm::vec4(0, 0, 0, 1));
  if (!within_world(l.position))
    throw CookError(err(label + ": the light lies beyond +-" + std::to_string(int(kMaxCoordinate)) +
                        " m in the world (too large a scale or translation in the node or its "
                        "parents?)"));
  const glm::vec3 d = glm::mat3(world) * glm::vec3(0, 0, -1);
  if (!(glm::length(d) > 0.0f))
    throw CookError(err(label + ": the node's transform collapses the light direction"));
  l.direction = glm::normalize(d);
  if (gl.color.size() == 3)
    l.color = glm::vec3(float(gl.color[0]), float(gl.color[1]), float(gl.color[2]));
  l.intensity = float(gl.intensity);
  l.range = float(gl.range);
  l.inner_cone = float(gl.spot.innerConeAngle);
  l.outer_cone = float(gl.spot.outerConeAngle);
  if (!finite(l.color) || glm::any(glm::lessThan(l.color, glm::vec3(0))))
    throw CookError(err(label + " has a negative or non-finite colour"));
  if (!std::isfinite(l.intensity) || l.intensity < 0)
    throw CookError(err(label + " has a negative or non-finite intensity"));
  if (!std::isfinite(l.range) || l.range < 0)
    throw CookError(err(label + " has a negative or non-finite range"));
  // The schema asks inner < outer, but exporters write inner == outer for a hard-edged cone
  // (Blender, spot blend 0); the falloff handles it (a step at the edge), so it is accepted.
  if (l.type == LightType::kSpot && !(l.inner_cone >= 0 && l.inner_cone <= l.outer_cone &&
                                      l.outer_cone > 0 && l.outer_cone <= 1.5707964f))
    throw CookError(err(label + ": spot cone angles need 0 <= inner <= outer <= pi/2, outer > 0"));
  l.semi_dynamic = extras_flag(n.extras, "semiDynamic", err(label));
  l.moving = extras_flag(n.extras, "moving", err(label));
  if (l.moving && l.type == LightType::kDirectional)
    throw CookError(err(label + ": extras.moving is for point and spot lights (a directional light "
                                "has no position)"));
  if (l.moving) l.semi_dynamic = true;
  if (n.extras.IsObject() && n.extras.Has("lightRadius")) {
    const tinygltf::Value& r = n.extras.Get("lightRadius");
    if (!r.IsNumber() || !std::isfinite(r.GetNumberAsDouble()) || r.GetNumberAsDouble() < 0)
      throw CookError(err(label + ": extras.lightRadius must be a number >= 0 (metres)"));
    l.radius = float(r.GetNumberAsDouble());
  }
  scene_.lights.push_back(l);
}

uint64_t Importer::accessor_count(int accessor) const {
  return accessor >= 0 && size_t(accessor) < model_.accessors.size()
             ? uint64_t(model_.accessors[size_t(accessor)].count)
             : 0;
}

// The scene's size before any accessor is read: triangles and vertices of every surface
// primitive, once per node that instances its mesh. Draco primitives count their POSITION
// accessor here and their triangles as they are decoded (count_read).
void Importer::check_scene_size(const std::vector<int>& roots) const {
  std::vector<uint64_t> uses(model_.meshes.size(), 0);
  std::vector<uint8_t> seen(model_.nodes.size(), 0);
  std::vector<int> stack(roots.rbegin(), roots.rend());
  while (!stack.empty()) {
    const int node = stack.back();
    stack.pop_back();
    // Missing nodes, cycles and second parents: visit() reports them.
    if (node < 0 || size_t(node) >= model_.nodes.size() || seen[size_t(node)]) continue;
    seen[size_t(node)] = 1;
    const tinygltf::Node& n = model_.nodes[size_t(node)];
    if (n.mesh >= 0 && size_t(n.mesh) < uses.size()) ++uses[size_t(n.mesh)];
    stack.insert(stack.end(), n.children.rbegin(), n.children.rend());
  }
  // Per mesh, all its instances; the scene's sums saturate.
  std::vector<uint64_t> mesh_triangles(uses.size(), 0), mesh_vertices(uses.size(), 0);
  uint64_t triangles = 0, vertices = 0;
  for (size_t m = 0; m < uses.size(); ++m) {
    if (uses[m] == 0) continue;
    uint64_t t = 0, v = 0;
    for (const tinygltf::Primitive& prim : model_.meshes[m].primitives) {
      if (!surface_mode(prim.mode)) continue;
      auto position = prim.attributes.find("POSITION");
      const uint64_t positions =
          position == prim.attributes.end() ? 0 : accessor_count(position->second);
      v = saturating_add(v, positions);
      if (prim.extensions.count(kDraco)) continue;
      const uint64_t corners = prim.indices >= 0 ? accessor_count(prim.indices) : positions;
      const bool list = prim.mode < 0 || prim.mode == TINYGLTF_MODE_TRIANGLES;
      t = saturating_add(t, list ? corners / 3 : (corners >= 3 ? corners - 2 : 0));
    }
    mesh_triangles[m] = saturating_mul(t, uses[m]);
    mesh_vertices[m] = saturating_mul(v, uses[m]);
    triangles = saturating_add(triangles, mesh_triangles[m]);
    vertices = saturating_add(vertices, mesh_vertices[m]);
  }
  auto refuse = [&](const std::vector<uint64_t>& per_mesh, uint64_t count, const char* what,
                    uint64_t limit, const char* option) {
    const size_t most =
        size_t(std::max_element(per_mesh.begin(), per_mesh.end()) - per_mesh.begin());
    const std::string& name = model_.meshes[most].name;
    throw CookError(err("the scene has " + std::to_string(count) + " " + what +
                        ", each mesh counted once per node that instances it (the most: mesh " +
                        std::to_string(most) + (name.empty() ? std::string() : " " + quote(name)) +
                        ", " + std::to_string(per_mesh[most]) + " in " +
                        std::to_string(uses[most]) + " node(s)), over the limit of " +
                        std::to_string(limit) + " " + what + " (" + option + " N raises it)"));
  };
  if (triangles > limits_.max_triangles)
    refuse(mesh_triangles, triangles, "triangles", limits_.max_triangles, kMaxTrianglesOption);
  if (vertices > limits_.max_vertices)
    refuse(mesh_vertices, vertices, "vertices", limits_.max_vertices, kMaxVerticesOption);
}

// What the import has read so far, against the same limits: Draco data can decode to more than
// its accessors declare.
void Importer::count_read(const std::string& label, uint64_t triangles, uint64_t vertices) {
  triangles_read_ = saturating_add(triangles_read_, triangles);
  vertices_read_ = saturating_add(vertices_read_, vertices);
  auto refuse = [&](uint64_t count, const char* what, uint64_t limit, const char* option) {
    throw CookError(err("the scene reaches " + std::to_string(count) + " " + what + " at " + label +
                        ", over the limit of " + std::to_string(limit) + " " + what + " (" +
                        option + " N raises it)"));
  };
  if (triangles_read_ > limits_.max_triangles)
    refuse(triangles_read_, "triangles", limits_.max_triangles, kMaxTrianglesOption);
  if (vertices_read_ > limits_.max_vertices)
    refuse(vertices_read_, "vertices", limits_.max_vertices, kMaxVerticesOption);
}

Scene Importer::run() {
  for (const std::string& ext : model_.extensionsRequired)
    if (!supported_required().count(ext))
      throw CookError(err("requires unsupported extension " + quote(ext)));
  read_materials();
  visited_.assign(model_.nodes.size(), 0);
  std::vector<int> roots;
  if (!model_.scenes.empty()) {
    const int s = model_.defaultScene >= 0 ? model_.defaultScene : 0;
    if (size_t(s) >= model_.scenes.size())
      throw CookError(err("default scene " + std::to_string(s) + " does not exist"));
    roots = model_.scenes[size_t(s)].nodes;
  } else {
    // No scenes: every node that is nobody's child is a root.
    std::vector<int> is_child(model_.nodes.size(), 0);
    for (const auto& n : model_.nodes)
      for (int c : n.children)
        if (c >= 0 && size_t(c) < is_child.size()) is_child[size_t(c)] = 1;
    for (size_t i = 0; i < model_.nodes.size(); ++i)
      if (!is_child[i]) roots.push_back(int(i));
  }
  check_scene_size(roots);
  for (int r : roots) visit(r, glm::mat4(1.0f), 0);
  if (model_.scenes.empty()) {
    // Every node is a root or some node's child; one that no root reaches hangs in a cycle.
    for (size_t i = 0; i < model_.nodes.size(); ++i)
      if (!visited_[i])
        throw CookError(err(node_label(model_, int(i)) +
                            " is in a cycle of child references, or below one (the file has no "
                            "scene, so the roots are the nodes that are nobody's child)"));
  }
  if (scene_.meshes.empty()) throw CookError(err("the scene has no triangles to bake"));

  // Names of semi-dynamic nodes are how the scene state addresses them.
  std::map<std::string, int> seen;
  for (const Object& o : scene_.objects) {
    if (o.name.empty())
      throw CookError(err("semi-dynamic mesh node " + std::to_string(o.node_index) +
                          " has no name (scene states address objects by node name)"));
    auto [it, fresh] = seen.emplace(o.name, o.node_index);
    if (!fresh)
      throw CookError(err("semi-dynamic mesh nodes " + std::to_string(it->second) + " and " +
                          std::to_string(o.node_index) + " share the name " + quote(o.name)));
  }
  seen.clear();
  for (const Light& l : scene_.lights) {
    if (!l.semi_dynamic) continue;
    if (l.name.empty())
      throw CookError(err("semi-dynamic light node " + std::to_string(l.node_index) +
                          " has no name (scene states address lights by node name)"));
    auto [it, fresh] = seen.emplace(l.name, l.node_index);
    if (!fresh)
      throw CookError(err("semi-dynamic light nodes " + std::to_string(it->second) + " and " +
                          std::to_string(l.node_index) + " share the name " + quote(l.name)));
  }
  scene_.compute_bounds();
  return std::move(scene_);
}

}  // namespace

Scene import_gltf(const std::string& path, const ImportLimits& limits) {
  const std::vector<uint8_t> bytes = read_file(path);  // CookError names the file and the reason
  const size_t slash = path.find_last_of('/');
  return import_gltf_memory(bytes.data(), bytes.size(), path,
                            slash == std::string::npos ? std::string() : path.substr(0, slash + 1),
                            limits);
}

Scene import_gltf_memory(const uint8_t* data, size_t size, const std::string& name,
                         const std::string& base_dir, const ImportLimits& limits) {
  if (size == 0) throw CookError(name + ": empty file");
  // tinygltf takes 32-bit sizes.
  if (size > std::numeric_limits<uint32_t>::max())
    throw CookError(name + ": larger than 4 GiB, which glTF loaders do not support");
  const bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  if (glb) check_glb_container(data, size, name);
  const char* json_text = reinterpret_cast<const char*>(glb ? data + 20 : data);
  const size_t json_size = glb ? size_t(get_u32(data + 12)) : size;
  // tinygltf turns `extras` and `extensions` into its Value tree recursively.
  if (json_deeper_than(json_text, json_size, kMaxJsonDepth))
    throw CookError(name + ": invalid glTF: JSON nested deeper than " +
                    std::to_string(kMaxJsonDepth) + " levels");
  LoadContext context;
  context.max_texture_pixels = limits.max_texture_pixels;
  // The scene's folder first: messages name it.
  if (const std::string real = resolved(base_dir.empty() ? "." : base_dir); !real.empty())
    context.roots.push_back(real);
  for (const std::string& folder : limits.uri_roots) {
    const std::string real = resolved(folder);
    if (real.empty())
      throw CookError(std::string(kUriRootOption) + " " + quote(folder) + ": no such folder");
    context.roots.push_back(real);
  }
  scan_images(json_text, json_size, name, &context);
  std::vector<uint8_t> patched;
  if (draco_indices_patch(data, size, glb, &patched)) {
    data = patched.data();
    size = patched.size();
  }
  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks(
      {&file_exists, &expand_file_path, &read_whole_file, &write_whole_file, &context});
  loader.SetImageLoader(&load_image, &context);
  tinygltf::Model model;
  std::string error, warning;
  const bool ok =
      glb ? loader.LoadBinaryFromMemory(&model, &error, &warning, data, uint32_t(size), base_dir)
          : loader.LoadASCIIFromString(&model, &error, &warning,
                                       reinterpret_cast<const char*>(data), uint32_t(size),
                                       base_dir);
  if (!context.refusal.empty()) throw CookError(name + ": " + context.refusal);
  if (!ok) {
    while (!error.empty() && (error.back() == '\n' || error.back() == '\r')) error.pop_back();
    throw CookError(name + ": invalid glTF" + (glb ? " binary" : "") + ": " +
                    (error.empty() ? std::string("unknown error") : printable(error, 400)));
  }
  return Importer(name, model, limits).run();
}

}  // namespace lightpatch::cooker
