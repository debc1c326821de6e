// SceneBuilder: writes small glTF 2.0 scenes by code, for tests and the inn.
//
// Units and conventions (DESIGN.md, Contracts / Scene input):
// - lengths in metres; +Y up; triangles wind counter-clockwise seen from the front;
// - colours are linear RGB (baseColorFactor, emissiveFactor, light colours);
// - point and spot light intensity in candela, directional in lux; lights shine along the
//   node's −Z axis (use rotation_towards() to aim one); spot cone angles in radians;
// - node extras: `"semiDynamic": true` marks a semi-dynamic light or mesh node,
//   `"lightRadius": r` (metres) gives a punctual light a size for soft shadows.
//
// Usage:
//   SceneBuilder b;
//   int wood = b.add_material({.name = "wood", .base_color = {0.5f, 0.3f, 0.15f, 1.0f}});
//   int table = b.add_mesh("table", make_rounded_box({-1, 0, -0.5f}, {1, 0.8f, 0.5f}, 0.02f),
//   wood); b.add_node({.name = "table_0", .mesh = table}); int l = b.add_light({.name = "candle",
//   .type = LightType::kPoint, .intensity = 2.0f}); b.add_node({.name = "candle_0", .translation =
//   {0, 1, 0}, .light = l,
//               .semi_dynamic = true, .light_radius = 0.02f});
//   b.write("scene.glb");                       // or .gltf (+ .bin beside it), WriteOptions
//
// Output is deterministic: the same calls give the same bytes. It passes the Khronos glTF
// validator without errors: POSITION accessors carry min/max, buffer views are 4-byte aligned,
// byteLengths are exact. With WriteOptions::draco, every primitive is stored with
// KHR_draco_mesh_compression (listed in extensionsUsed and extensionsRequired); its accessors
// keep count, type and POSITION min/max and have no bufferView, and the compressed bufferView
// has no byteStride or target.
//
// Errors (bad indices, unknown references, cycles, two parents, bad light parameters, I/O) throw
// std::invalid_argument or std::runtime_error with a message naming the problem.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "lightpatch/scenegen/geometry.h"
#include "lightpatch/scenegen/shapes.h"

namespace lightpatch::scenegen {

struct Material {
  std::string name{};
  glm::vec4 base_color{0.8f, 0.8f, 0.8f, 1.0f};  // linear RGBA, albedo
  float metallic = 0.0f;
  float roughness = 1.0f;
  glm::vec3 emissive{0.0f};  // linear RGB, each in [0, 1]
  // > 1 writes KHR_materials_emissive_strength (only when `emissive` is non-zero).
  float emissive_strength = 1.0f;
  bool double_sided = false;
};

enum class IndexType { kAuto, kUint16, kUint32 };  // kAuto: uint16 when every index fits

struct Primitive {
  Geometry geometry{};
  int material = -1;  // index from add_material(), -1 for the glTF default material
  IndexType index_type = IndexType::kAuto;
};

enum class LightType { kPoint, kSpot, kDirectional };

struct Light {
  std::string name{};
  LightType type = LightType::kPoint;
  glm::vec3 color{1.0f};          // linear RGB
  float intensity = 1.0f;         // candela (point, spot) or lux (directional)
  float range = 0.0f;             // metres; 0 = infinite (omitted); ignored for directional lights
  float inner_cone_angle = 0.0f;  // spot only, radians, < outer
  float outer_cone_angle = 0.78539816339744831f;  // spot only, radians, in (0, π/2]
};

struct Node {
  std::string name{};
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // (w, x, y, z)
  glm::vec3 scale{1.0f};
  std::optional<glm::mat4> matrix{};  // when set, written instead of TRS (must be decomposable)
  int mesh = -1;                      // index from add_mesh()
  int light = -1;                     // index from add_light() (KHR_lights_punctual)
  std::vector<int> children{};        // node indices
  bool semi_dynamic = false;          // extras.semiDynamic
  float light_radius = 0.0f;          // > 0 writes extras.lightRadius (metres)
  bool cast_shadows = true;           // false writes extras.castShadows = false (a flame, a bulb)
  bool moving = false;                // extras.moving (a light the game moves)
};

enum class BufferStorage {
  kExternal,  // .gltf: binary data in `<stem>.bin` beside the .gltf
  kEmbedded,  // .gltf: binary data in a base64 data: URI
};

struct WriteOptions {
  bool draco = false;            // KHR_draco_mesh_compression for every primitive
  int draco_position_bits = 14;  // quantization bits (Draco)
  int draco_normal_bits = 10;
  int draco_texcoord_bits = 12;
  int draco_speed = 5;                               // 0 (best compression) .. 10 (fastest)
  BufferStorage storage = BufferStorage::kExternal;  // ignored for .glb
};

// Rotation that turns the node's −Z axis (where lights shine) towards `direction` (non-zero).
glm::quat rotation_towards(glm::vec3 direction);

class SceneBuilder {
 public:
  int add_material(Material material);
  int add_mesh(std::string name, std::vector<Primitive> primitives);
  int add_mesh(std::string name, Geometry geometry, int material,
               IndexType index_type = IndexType::kAuto);
  int add_light(Light light);
  // Nodes that are nobody's child are the scene's roots, in index order.
  int add_node(Node node);
  void add_child(int parent, int child);

  // Shorthands: a mesh node, and a light with its node (light and node named `name`).
  int add_mesh_node(std::string name, Geometry geometry, int material,
                    glm::vec3 translation = glm::vec3(0.0f), bool semi_dynamic = false);
  int add_light_node(std::string name, const Light& light, glm::vec3 position,
                     glm::vec3 direction = glm::vec3(0.0f, -1.0f, 0.0f), bool semi_dynamic = false,
                     float light_radius = 0.0f);

  Node& node(int index) { return nodes_.at(static_cast<std::size_t>(index)); }
  const Node& node(int index) const { return nodes_.at(static_cast<std::size_t>(index)); }
  const std::vector<Node>& nodes() const { return nodes_; }
  const std::vector<Material>& materials() const { return materials_; }
  const std::vector<Light>& lights() const { return lights_; }
  std::size_t mesh_count() const { return meshes_.size(); }
  // Triangles in the scene: each mesh counted once per node that instances it.
  std::size_t triangle_count() const;

  // The scene as a .glb file image.
  std::vector<std::uint8_t> to_glb(const WriteOptions& options = {}) const;
  // The scene as .gltf JSON text; with kExternal the buffer's uri is `bin_uri` and the binary
  // data is returned in `bin` (which must then be written beside the .gltf).
  std::string to_gltf(const WriteOptions& options, const std::string& bin_uri,
                      std::vector<std::uint8_t>* bin) const;
  // Writes `path` (.glb or .gltf, from the extension); writes to a temporary file and renames, so
  // a failure leaves no partial file.
  void write(const std::string& path, const WriteOptions& options = {}) const;

 private:
  struct Mesh {
    std::string name;
    std::vector<Primitive> primitives;
  };

  void check_graph() const;

  std::vector<Material> materials_;
  std::vector<Mesh> meshes_;
  std::vector<Light> lights_;
  std::vector<Node> nodes_;
};

}  // namespace lightpatch::scenegen
