// GltfScene: what the game reads from the inn's glTF file (the cooker's input) to draw and walk
// the scene: node world transforms and names, punctual light positions, materials (albedo and
// emission) and, on demand, a primitive's world-space positions (plain accessors or
// KHR_draco_mesh_compression, decoded with Draco's API exactly as the cooker decodes it, so that
// vertex indices agree with the pack's MeshVertex::source_vertex).
//
// The game draws albedo from baseColorFactor only (the inn has no textures); textures are not
// decoded. Errors (unreadable file, missing data, indices out of range) throw std::runtime_error
// with a message naming the node or primitive.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace lightpatch::inn {

struct GltfMaterial {
  glm::vec3 albedo{0.8f};    // linear RGB (baseColorFactor)
  glm::vec3 emissive{0.0f};  // linear RGB radiance scale (emissiveFactor * emissive strength)
  bool double_sided = false;
};

struct GltfLight {
  std::string name;  // node name
  int node = -1;
  glm::vec3 position{0.0f};  // world space, metres
  glm::vec3 direction{0.0f, 0.0f, -1.0f};
  bool semi_dynamic = false;
};

struct GltfNode {
  std::string name;
  int mesh = -1;
  bool semi_dynamic = false;
  bool in_scene = false;  // reached from the default scene's roots
  glm::mat4 world{1.0f};
};

class GltfScene {
 public:
  explicit GltfScene(const std::string& path);
  ~GltfScene();
  GltfScene(const GltfScene&) = delete;
  GltfScene& operator=(const GltfScene&) = delete;

  const std::vector<GltfNode>& nodes() const { return nodes_; }
  const std::vector<GltfLight>& lights() const { return lights_; }
  const std::vector<GltfMaterial>& materials() const { return materials_; }

  // Number of primitives of a node's mesh (0 for nodes without a mesh).
  int primitive_count(int node) const;
  // Material index of a node's primitive, or -1 for the default material.
  int primitive_material(int node, int primitive) const;
  // World-space positions of a node's primitive, in the file's (or Draco's) vertex order.
  std::vector<glm::vec3> world_positions(int node, int primitive) const;

 private:
  struct Model;
  std::unique_ptr<Model> model_;  // the parsed file (tinygltf), kept for on-demand decoding
  std::string path_;
  std::vector<GltfNode> nodes_;
  std::vector<GltfLight> lights_;
  std::vector<GltfMaterial> materials_;
};

}  // namespace lightpatch::inn
