#include "world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "gltf_scene.h"

namespace lightpatch::inn {
namespace {

LightKind kind_of(const std::string& name) {
  if (name.rfind("candle", 0) == 0) return LightKind::kCandle;
  if (name.rfind("torch", 0) == 0) return LightKind::kTorch;
  if (name.rfind("fire", 0) == 0) return LightKind::kFire;
  return LightKind::kOther;
}

uint8_t unorm8(float v) {
  return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
}

// A flame mesh belongs to the semi-dynamic light closest to it (the generator puts each light at
// its flame's centre); emissive surfaces farther than this from every such light are static
// (embers) and always glow.
constexpr float kFlameReach = 0.35f;

}  // namespace

std::string to_string(const Name& name) {
  return std::string(name.data, name.length);
}

World build_world(const GltfScene& scene, const PackView& pack) {
  if (pack.mesh_count() == 0) {
    throw std::runtime_error(
        "the pack has no light-map UVs of its meshes (kMeshes section); cook it again");
  }
  World w;
  // Lights: the pack's order, positions from the glTF nodes of the same name.
  w.lights.resize(pack.light_count());
  for (uint32_t l = 0; l < pack.light_count(); ++l) {
    WorldLight& wl = w.lights[l];
    // A moving lights' pane (pack_format.h) is no light of the scene: unnamed, kind kOther.
    if (pack.light_is_pane(l)) continue;
    wl.name = to_string(pack.light_name(l));
    wl.kind = kind_of(wl.name);
    if (const int32_t k = pack.moving_index(l); k >= 0) {
      wl.moving = true;
      wl.range = pack.moving_light(static_cast<uint32_t>(k)).range;
    }
    bool found = false;
    for (const GltfLight& gl : scene.lights()) {
      if (gl.name == wl.name) {
        wl.position = gl.position;
        found = true;
        break;
      }
    }
    if (!found)
      throw std::runtime_error("pack light '" + wl.name + "' is not a light of the scene");
  }
  w.objects.resize(pack.object_count());
  for (uint32_t o = 0; o < pack.object_count(); ++o)
    w.objects[o].name = to_string(pack.object_name(o));

  // Vertices of every baked primitive; triangles sorted into static, then object by object.
  std::vector<std::vector<uint32_t>> object_indices(pack.object_count());
  std::vector<uint32_t> static_indices;
  for (uint32_t m = 0; m < pack.mesh_count(); ++m) {
    const pack::MeshRecord& mr = pack.mesh(m);
    const int node = static_cast<int>(mr.node_index);
    const int prim = static_cast<int>(mr.primitive);
    if (mr.node_index >= scene.nodes().size() || prim >= scene.primitive_count(node)) {
      throw std::runtime_error("pack mesh " + std::to_string(m) + " ('" +
                               to_string(pack.mesh_name(m)) + "') names node " +
                               std::to_string(mr.node_index) + " primitive " +
                               std::to_string(mr.primitive) +
                               ", which the scene does not have: "
                               "was the pack cooked from this scene?");
    }
    const std::vector<glm::vec3> positions = scene.world_positions(node, prim);
    const int mat = scene.primitive_material(node, prim);
    const GltfMaterial material =
        mat >= 0 ? scene.materials()[static_cast<size_t>(mat)] : GltfMaterial{};
    if (material.double_sided) w.double_sided = true;
    const bool emissive = material.emissive != glm::vec3(0.0f);
    const uint32_t base = static_cast<uint32_t>(w.vertices.size());
    const pack::MeshVertex* mv = pack.mesh_vertices(m);
    for (uint32_t v = 0; v < mr.vertex_count; ++v) {
      if (mv[v].source_vertex >= positions.size()) {
        throw std::runtime_error("pack mesh " + std::to_string(m) + " vertex " + std::to_string(v) +
                                 " refers to source vertex " + std::to_string(mv[v].source_vertex) +
                                 " of a primitive with " + std::to_string(positions.size()) +
                                 " vertices: was the pack cooked from this scene?");
      }
      const glm::vec3 p = positions[mv[v].source_vertex];
      WorldVertex wv{};
      wv.position[0] = p.x;
      wv.position[1] = p.y;
      wv.position[2] = p.z;
      wv.lightmap_uv[0] = mv[v].u;
      wv.lightmap_uv[1] = mv[v].v;
      wv.albedo[0] = unorm8(material.albedo.r);
      wv.albedo[1] = unorm8(material.albedo.g);
      wv.albedo[2] = unorm8(material.albedo.b);
      wv.albedo[3] = 255;
      wv.emissive[0] = material.emissive.r;
      wv.emissive[1] = material.emissive.g;
      wv.emissive[2] = material.emissive.b;
      wv.flame = -1.0f;
      if (emissive) {
        float best = kFlameReach;
        for (uint32_t l = 0; l < w.lights.size(); ++l) {
          const float d = glm::distance(w.lights[l].position, p);
          if (d < best) {
            best = d;
            wv.flame = static_cast<float>(l);
          }
        }
      }
      w.vertices.push_back(wv);
    }
    std::vector<uint32_t>& out =
        mr.object == pack::kNone16 ? static_indices : object_indices[mr.object];
    const uint32_t* idx = pack.mesh_indices(m);
    for (uint32_t i = 0; i < mr.index_count; ++i) out.push_back(base + idx[i]);
  }

  // Static triangles by grid cell of their centroid (a stable sort: the order within a cell is
  // the pack's), one chunk per cell.
  {
    const size_t triangles = static_indices.size() / 3;
    std::vector<std::pair<uint64_t, uint32_t>> key(triangles);
    for (size_t t = 0; t < triangles; ++t) {
      glm::vec3 c(0.0f);
      for (int k = 0; k < 3; ++k) {
        const float* p = w.vertices[static_indices[t * 3 + size_t(k)]].position;
        c += glm::vec3(p[0], p[1], p[2]) / 3.0f;
      }
      uint64_t cell = 0;
      for (int a = 0; a < 3; ++a) {
        // Cells of 2 m over +-2^20 m: 21 bits an axis.
        const float f = std::floor(c[a] / World::kChunkSize) + float(1 << 20);
        cell = (cell << 21) | uint64_t(std::clamp(f, 0.0f, float((1 << 21) - 1)));
      }
      key[t] = {cell, static_cast<uint32_t>(t)};
    }
    std::stable_sort(key.begin(), key.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<uint32_t> sorted = static_indices;
    for (size_t i = 0; i < triangles; ++i) {
      for (int k = 0; k < 3; ++k)
        sorted[i * 3 + size_t(k)] = static_indices[size_t(key[i].second) * 3 + size_t(k)];
      if (i == 0 || key[i].first != key[i - 1].first) {
        WorldChunk ch;
        ch.range.first = static_cast<uint32_t>(i * 3);
        ch.bounds_min = glm::vec3(std::numeric_limits<float>::max());
        ch.bounds_max = glm::vec3(-std::numeric_limits<float>::max());
        w.chunks.push_back(ch);
      }
      WorldChunk& ch = w.chunks.back();
      ch.range.count += 3;
      for (int k = 0; k < 3; ++k) {
        const float* p = w.vertices[sorted[i * 3 + size_t(k)]].position;
        ch.bounds_min = glm::min(ch.bounds_min, glm::vec3(p[0], p[1], p[2]));
        ch.bounds_max = glm::max(ch.bounds_max, glm::vec3(p[0], p[1], p[2]));
      }
    }
    static_indices = std::move(sorted);
  }
  w.static_range = {0, static_cast<uint32_t>(static_indices.size())};
  w.indices = std::move(static_indices);
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const WorldVertex& v : w.vertices) {
    lo = glm::min(lo, glm::vec3(v.position[0], v.position[1], v.position[2]));
    hi = glm::max(hi, glm::vec3(v.position[0], v.position[1], v.position[2]));
  }
  w.bounds_min = lo;
  w.bounds_max = hi;
  for (uint32_t o = 0; o < pack.object_count(); ++o) {
    WorldObject& wo = w.objects[o];
    wo.range = {static_cast<uint32_t>(w.indices.size()),
                static_cast<uint32_t>(object_indices[o].size())};
    glm::vec3 olo(std::numeric_limits<float>::max()), ohi(-std::numeric_limits<float>::max());
    for (uint32_t i : object_indices[o]) {
      const WorldVertex& v = w.vertices[i];
      olo = glm::min(olo, glm::vec3(v.position[0], v.position[1], v.position[2]));
      ohi = glm::max(ohi, glm::vec3(v.position[0], v.position[1], v.position[2]));
    }
    if (object_indices[o].empty()) olo = ohi = glm::vec3(0.0f);
    wo.bounds_min = olo;
    wo.bounds_max = ohi;
    wo.center = 0.5f * (olo + ohi);
    w.indices.insert(w.indices.end(), object_indices[o].begin(), object_indices[o].end());
  }
  return w;
}

}  // namespace lightpatch::inn
