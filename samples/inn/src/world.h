// World: the inn as the game sees it, built once at start from the scene's glTF file (positions,
// materials, light and node positions) and the cooked pack (the light-map UVs of every baked mesh,
// and the indices of its semi-dynamic lights and objects).
//
// The pack's kMeshes section names each baked primitive by glTF node index and primitive index,
// and each of its vertices by the source vertex it came from; the glTF file gives that vertex's
// position. Geometry is therefore drawn with exactly the layout the cooker baked.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "lightpatch/pack_view.h"

namespace lightpatch::inn {

class GltfScene;

// One vertex as the GPU reads it (see SceneRenderer).
struct WorldVertex {
  float position[3];     // world space, metres
  float lightmap_uv[2];  // glTF convention (v = 0 is the light map's top row)
  uint8_t albedo[4];     // linear RGB * 255, alpha unused
  float emissive[3];     // linear radiance of an emissive surface
  float flame;  // pack light index whose flame this is (its emission follows the light), or -1
};
static_assert(sizeof(WorldVertex) == 40);

struct IndexRange {
  uint32_t first = 0;  // into World::indices
  uint32_t count = 0;
};

enum class LightKind { kCandle, kTorch, kFire, kOther };

struct WorldLight {
  std::string name;
  LightKind kind = LightKind::kOther;
  glm::vec3 position{0.0f};
  bool moving = false;  // the pack flags it moving (the lantern): position is its authored pose
  float range = 0.0f;   // a moving light's range (metres; 0: unlimited)
};

struct WorldObject {
  std::string name;
  IndexRange range;  // triangles of the object
  glm::vec3 center{0.0f};
  glm::vec3 bounds_min{0.0f}, bounds_max{0.0f};
};

// A run of static triangles in one cell of a world-space grid, and their bounds: what a draw that
// sees only part of the world (the lantern's shadow faces) culls by.
struct WorldChunk {
  IndexRange range;
  glm::vec3 bounds_min{0.0f}, bounds_max{0.0f};
};

struct World {
  static constexpr float kChunkSize = 2.0f;  // metres: the grid cells of `chunks`

  std::vector<WorldVertex> vertices;
  std::vector<uint32_t> indices;
  IndexRange static_range;  // everything that is not a semi-dynamic object
  // static_range's triangles sorted by grid cell (kChunkSize), one chunk per non-empty cell, in
  // index order: together exactly static_range.
  std::vector<WorldChunk> chunks;
  std::vector<WorldLight> lights;    // per pack light index
  std::vector<WorldObject> objects;  // per pack object index
  bool double_sided = false;         // some material is double-sided: draw without culling
  glm::vec3 bounds_min{0.0f}, bounds_max{0.0f};
};

// Calls draw(IndexRange) once for each run of consecutive static chunks that keep(chunk) accepts,
// merged into one range: a pass that culls by chunk issues one draw per run, not per chunk.
template <typename Keep, typename Draw>
void for_each_chunk_run(const World& world, const Keep& keep, const Draw& draw) {
  IndexRange run{0, 0};
  for (const WorldChunk& ch : world.chunks) {
    if (!keep(ch)) continue;
    if (run.count > 0 && run.first + run.count == ch.range.first) {
      run.count += ch.range.count;
      continue;
    }
    if (run.count > 0) draw(run);
    run = ch.range;
  }
  if (run.count > 0) draw(run);
}

// Builds the world. Throws std::runtime_error when the pack has no kMeshes section or does not
// match the scene (a baked node or primitive missing, a source vertex out of range).
World build_world(const GltfScene& scene, const PackView& pack);

// Name as std::string.
std::string to_string(const Name& name);

}  // namespace lightpatch::inn
