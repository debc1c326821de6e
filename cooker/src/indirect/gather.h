// Final gathering for indirect light (the production integrator). Indirect light is smooth, so it
// is computed on coarse texels: the texels of one chart in one k x k block of the light map (k =
// the indirect level: 1, 2, 4 or 8), split further where normals differ, and into single texels
// where a 2x2 block touches other geometry (build_coarse_grid). From every coarse texel
// N cosine-distributed rays leave its member texels; each is traced once through static geometry
// and once through the semi-dynamic objects alone, up to its static hit (the objects it crosses
// and where), and what it hits is kept as a coarse texel index (the radiance cache is the light map
// itself, at the coarse level). Bounce light of any light group and any set of present objects is
// then a sum of sparse gathers over those stored rays, with no more tracing:
//
//   I = G (rho D + rho I)        D: the group's direct irradiance, I: its indirect irradiance
//
// solved as a Neumann series (bounce by bounce). With objects present a ray ends at the first
// present object it crosses instead of its static hit; the rays that cross objects are few and
// kept apart, so an object's change to a group's bounce light is a sparse correction of the same
// sums (solve.h). Every step is linear in the light and uses the same rays, so a
// recomposed state equals bake_state of that state to rounding.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/texels.h"
#include "lightpatch/cooker/tracer.h"
#include "texel_footprint.h"

namespace lightpatch::cooker {

constexpr uint32_t kNoTexel = 0xFFFFFFFFu;

// What texel_of_hit reads of the texel under a hit, in one place: with the texel set's arrays
// apart, every gather ray paid a cache miss in each.
struct TexelSurface {
  int32_t mesh = -1;  // -1: not valid
  glm::vec3 normal{0.0f};
};
std::vector<TexelSurface> texel_surfaces(const TexelSet& texels);

// The texel under a hit's light-map UV, kNoTexel for a mesh outside the light map.
uint32_t texel_under(const Layout& layout, const TexelSet& texels, const Hit& h);

// The light-map texel a hit lands on: the texel under its light-map UV when that texel samples the
// same side of the same mesh; otherwise, of the texels within two of it that do, the one whose
// sample point lies nearest the hit; kNoTexel if none. `surfaces`: texel_surfaces(texels);
// `under`: texel_under() of the hit.
uint32_t texel_of_hit(const TexelSet& texels, const std::vector<TexelSurface>& surfaces,
                      const Hit& h, const glm::vec3& point, uint32_t under);

// The coarse texels of one indirect level.
struct CoarseGrid {
  int level = 1;                        // k: fine texels per coarse texel per axis
  int width = 0, height = 0;            // blocks: ceil(fine / k)
  std::vector<uint32_t> coarse_of;      // fine texel -> coarse texel (kNoTexel if not valid)
  std::vector<uint32_t> member_offset;  // coarse -> [offset, next offset) into members
  std::vector<uint32_t> members;        // fine texels, in row order
  std::vector<uint32_t> block_of;       // coarse -> block index (by * width + bx)
  std::vector<uint32_t> block_offset;   // block -> [offset, next) into block_coarse
  std::vector<uint32_t> block_coarse;   // coarse texels of each block
  std::vector<uint32_t> chart;          // coarse -> chart (connected valid texels of a region)
  std::vector<glm::vec3> position;      // coarse -> mean member position
  std::vector<glm::vec3> normal;        // coarse -> normalized mean member normal
  std::vector<glm::vec3> albedo;        // coarse -> mean member albedo
  // Neighbours that continue each coarse texel's surface: for step s = 1, 2, 4 blocks
  // (kLinkSteps) and the 8 directions around it, the coarse texel of that block with the same
  // chart, a normal within the clustering cone and an unblocked line of sight, or kNoTexel.
  // kLinks entries per coarse texel. The denoiser and the magnification read only these, so
  // nothing is ever blended through a wall.
  static constexpr int kLinkSteps = 3;
  static constexpr int kLinks = kLinkSteps * 8;
  std::vector<uint32_t> links;
  // 1 for a coarse texel of one texel, split from a block that touches other geometry
  // (build_coarse_grid): the magnification gives that texel its own value.
  std::vector<uint8_t> fine;
  // 0 for a coarse texel whose members are all buried in solid geometry (gather.cpp): it has no
  // value of its own, and neighbours do not read it.
  std::vector<uint8_t> alive;
  size_t size() const { return chart.size(); }
  uint32_t member_count(uint32_t c) const { return member_offset[c + 1] - member_offset[c]; }
  // Direction d (0..7) of (dx, dy) in {-1, 0, 1}^2 without (0, 0), row by row.
  static int direction(int dx, int dy) {
    const int i = (dy + 1) * 3 + (dx + 1);
    return i < 4 ? i : i - 1;
  }
  uint32_t link(uint32_t c, int step_index, int dx, int dy) const {
    return links[size_t(c) * kLinks + size_t(step_index) * 8 + size_t(direction(dx, dy))];
  }
};

// Groups the valid texels into coarse texels of level k (1, 2, 4 or 8): per block, by chart, by
// normal, and by line of sight (`tracer`, may be null in tests: a floor texel beyond a wall that
// stands on it is not grouped with the floor inside), and links the neighbours. With
// `split_contacts` and a tracer, a 2x2 block with other geometry within two blocks of its
// texels (short probe rays, static geometry and every object) gives each texel a coarse texel of
// its own (`fine`): at a crate's foot bounce light changes within a block, and one value per block
// blurred it (docs/accuracy.md, section (m)).
CoarseGrid build_coarse_grid(const TexelSet& texels, int level, const Tracer* tracer, int threads,
                             bool split_contacts = false);

// A ray that crosses semi-dynamic objects before its static hit: what it hits in each.
struct Crossing {
  uint32_t ray = 0;    // index within its coarse texel's rays
  uint32_t first = 0;  // into GatherOperator::crossing_hits
  uint32_t count = 0;  // objects crossed, nearest first
};
struct CrossingHit {
  int32_t object = 0;          // Scene::objects index
  uint32_t coarse = kNoTexel;  // coarse texel hit on the object (kNoTexel: its back, or unmapped)
};

// Gather rays that land within kNearHitSpacings texel spacings (of the texel they land on) of
// the surface they leave: a face a centimetre above a table, the floor at a wall's foot. The
// radiance cache holds the mean of the texel they land on, but such rays land where the
// receiver's own surroundings shape the light (the part of a candle-lit table under the face, in
// its shadow): their first bounce reads the direct light at their hit points instead (solve.h),
// one shadow ray per light each (the many hits of a texel average it). Only rays that cross no
// semi-dynamic object before their hit are listed, so no state moves them. The rays of one coarse
// texel that land on one texel keep at most kNearPerTexel hit points, the first in ray order,
// each standing for `count` rays. Rays from a mesh that stops no ray (a flame, a bulb)
// keep the cache: such a texel lends its light to no other.
// Chosen on the small inn (docs/accuracy.md, section (e)): within 0.5 spacings the gain was lost,
// 2 added nothing to 1; one point for all of a texel's hits (their centroid, or the first) lost
// it too, 16 kept most of what every hit gave at a fraction of the points.
constexpr float kNearHitSpacings = 1.0f;
constexpr int kNearPerTexel = 16;
struct NearHit {
  glm::vec3 point{0.0f};     // where the first of its rays lands (static surface, world space)
  uint32_t ray = 0;          // the first of its rays (index within its coarse texel's rays)
  uint32_t fine = kNoTexel;  // the light-map texel they land on (its albedo and normal)
  uint32_t count = 1;        // how many rays it stands for
};

struct GatherOptions {
  int rays = 256;  // per coarse texel
  uint64_t seed = 1;
  int threads = 1;
  // Parallel to the texels, or null: each ray leaves its own point of its texel's patch
  // (texel_footprint.h), as the direct light and the reference path tracer sample it; null: the
  // texel's sample point (one texel sample, draft).
  const std::vector<TexelFootprint>* footprints = nullptr;
  // 2x2 blocks that touch other geometry gather per texel (build_coarse_grid).
  bool split_contacts = false;
};

// The rays a coarse texel split at a contact (CoarseGrid::fine) traces of the `rays` of every
// other: half (at least 16), so that a split 2x2 block costs two blocks' rays.
int fine_ray_count(int rays);

struct GatherOperator {
  CoarseGrid grid;
  int rays = 0;
  // The rays coarse texel c traced: a prefix of its `rays` slots, the rest kNoTexel.
  int traced_rays(uint32_t c) const { return grid.fine[c] ? fine_ray_count(rays) : rays; }
  // Static hit of every ray (objects absent) as a coarse texel, kNoTexel for a miss or the back
  // of a surface: rays * grid.size() entries, coarse texel c's rays at [c * rays, (c+1) * rays).
  std::vector<uint32_t> hit;
  // The series reads fewer rays as its light grows smoother and dimmer: the first bounce every
  // ray, the second the first quarter, every later one the first sixteenth (prefixes of a
  // low-discrepancy sequence, as well spread as the whole; at least kMinLevelRays). weight[L][c]:
  // 1 / the rays of level L that coarse texel c keeps (a buried member's are dropped), 0 if none.
  static constexpr int kLevels = 3;
  int level_rays[kLevels] = {0, 0, 0};
  std::vector<float> weight[kLevels];
  // The level of the series' b-th bounce (0-based).
  static int level_of(int bounce) { return bounce < kLevels ? bounce : kLevels - 1; }
  size_t buried_texels = 0;
  // Per light-map texel, 1 where it is buried (its sample point inside solid geometry: its rays
  // are dropped, and rays that land on it go to a neighbour that is not).
  std::vector<uint8_t> buried;
  // Mean albedo (largest channel) over the texels that gather, at most 0.995: how slowly the
  // bounce series converges.
  float mean_albedo = 0.0f;
  std::vector<uint32_t> crossing_offset;  // coarse -> [offset, next) into crossings
  std::vector<Crossing> crossings;
  std::vector<CrossingHit> crossing_hits;
  std::vector<std::vector<uint32_t>> coarse_crossing;  // object -> coarse texels with a crossing
  // Near hits (NearHit; only with GatherOptions::footprints), in coarse texel and ray order.
  std::vector<uint32_t> near_offset;  // coarse -> [offset, next) into near
  std::vector<NearHit> near;
  // Activity: receivers are grouped in tiles of kTile x kTile blocks; sources[t] lists the tiles
  // whose coarse texels tile t's rays can reach (static and object hits), so a gather of a sparse
  // source only visits the receivers that can see it.
  static constexpr int kTile = 8;
  int tiles_x = 0, tiles_y = 0;
  std::vector<uint32_t> tile_of;                   // coarse -> tile
  std::vector<std::vector<uint32_t>> tile_coarse;  // tile -> its coarse texels
  std::vector<std::vector<uint32_t>> sources;      // tile -> source tiles (sorted, unique)
  uint64_t rays_traced = 0;
};

// Traces every coarse texel's gather rays. `layout` maps hits to light-map texels.
GatherOperator build_gather(const Scene& scene, const Layout& layout, const TexelSet& texels,
                            const Tracer& tracer, int level, const GatherOptions& options);

}  // namespace lightpatch::cooker
