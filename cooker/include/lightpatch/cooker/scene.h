// The cooker's in-memory scene: the glTF node hierarchy flattened to world space.
//
// Units: metres; light intensity in candela (point, spot) or lux (directional); colours linear
// RGB. Produced by import_gltf() (import.h) or built directly by tests.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace lightpatch::cooker {

struct Texture {
  int width = 0;
  int height = 0;
  std::vector<glm::vec3> linear_rgb;  // row 0 = top (glTF uv v = 0), already sRGB-decoded
};

struct Material {
  std::string name;
  glm::vec3 albedo{0.8f};    // baseColorFactor.rgb (linear)
  int albedo_texture = -1;   // index into Scene::textures, multiplied with albedo; uses uv0
  glm::vec3 emissive{0.0f};  // emissiveFactor * KHR_materials_emissive_strength: exitance scale
                             // (an emissive surface radiates L = emissive, W/m^2/sr-like units,
                             // so its exitance is pi * emissive)
};

// One primitive of one mesh node instance, in world space.
struct MeshInstance {
  std::string name;         // glTF node name (may be empty for unmarked static nodes)
  int node_index = -1;      // glTF node index (-1 for scenes built in code)
  int primitive_index = 0;  // primitive within the node's mesh
  int object = -1;          // index into Scene::objects if the node is semi-dynamic, else -1
  int material = 0;         // index into Scene::materials (import adds a default material)
  // false (extras.castShadows: false): the mesh occludes no light and stops no ray (a flame, a
  // bulb or lamp glass around its light); it is still lit and baked.
  bool cast_shadows = true;
  std::vector<glm::vec3> positions;  // world space
  std::vector<glm::vec3> normals;    // world space, unit length (import generates if absent)
  std::vector<glm::vec2> uv0;        // TEXCOORD_0 or empty
  std::vector<glm::vec2> uv1;        // TEXCOORD_1 (light-map UVs in [0,1]) or empty
  std::vector<uint32_t> indices;     // triangle list, every index < positions.size()
  // The glTF vertex (of the primitive's attributes) behind each vertex, where the importer
  // unwelded the primitive (no normals: one vertex per triangle corner); empty: the same index.
  std::vector<uint32_t> gltf_vertex;
  glm::mat4 world{1.0f};          // the node's world transform (positions are already in it)
  float lightmap_scale = 1.0f;    // the node's extras.lightmapScale: texel density factor, > 0
  bool lightmap_exclude = false;  // the node's extras.lightmapExclude: an occluder, not baked
};

enum class LightType { kPoint, kSpot, kDirectional };

struct Light {
  std::string name;  // glTF node name
  int node_index = -1;
  LightType type = LightType::kPoint;
  glm::vec3 position{0.0f};                // world space (point, spot)
  glm::vec3 direction{0.0f, 0.0f, -1.0f};  // world space unit vector the light shines along
  glm::vec3 color{1.0f};                   // linear RGB
  float intensity = 1.0f;                  // candela (point, spot) or lux (directional)
  float range = 0.0f;                      // metres; 0 = infinite (KHR_lights_punctual)
  float inner_cone = 0.0f;                 // radians (spot)
  float outer_cone = 0.785398163f;         // radians (spot), pi/4 default per the spec
  float radius = 0.0f;                     // metres; > 0 gives soft shadows (extras.lightRadius)
  bool semi_dynamic = false;
  // extras.moving (point and spot lights; implies semi_dynamic): the game moves it. The cook
  // bakes none of its light into the maps; its bounce light comes from the panes
  // (docs/moving_lights.md), and its direct light is the game's.
  bool moving = false;
};

// A semi-dynamic object: a glTF mesh node marked semiDynamic, possibly several primitives.
struct Object {
  std::string name;
  int node_index = -1;
  std::vector<int> meshes;  // indices into Scene::meshes
};

// A light probe the scene places: a node with extras "lightProbe": true (probes.h).
struct ProbePoint {
  std::string name;  // glTF node name
  glm::vec3 position{0.0f};
};

struct Scene {
  std::vector<MeshInstance> meshes;
  std::vector<Material> materials;
  std::vector<Texture> textures;
  std::vector<Light> lights;
  std::vector<Object> objects;
  std::vector<ProbePoint> probes;
  // Import decisions worth telling the user (degenerate triangles dropped, ...).
  std::vector<std::string> notes;

  // Axis-aligned bounds of all mesh positions; its diagonal sets every scene-scaled epsilon.
  glm::vec3 bounds_min{0.0f};
  glm::vec3 bounds_max{0.0f};
  void compute_bounds();
  float scale() const;  // length of the bounds diagonal, > 0 for any non-empty scene
  size_t triangle_count() const;
};

}  // namespace lightpatch::cooker
