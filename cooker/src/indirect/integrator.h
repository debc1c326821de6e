// Bounce light for a bake (BakeOptions::integrator; DESIGN.md, "The method in one screen"): one
// instance per bake, shared by its light groups and the states it bakes, built once (final
// gathering traces its rays then). Every result is linear in the light and comes from the same
// random numbers, so C_l, S_ol = C_l - T_ol, the pair corrections and bake_state of any state
// agree: a recomposed state equals bake_state of that state.
#pragma once

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "bake/context.h"
#include "bake/direct_pass.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/report.h"

namespace lightpatch::cooker {

// An integrator's result in its own linear representation (final gathering: coarse texels).
// Sums and differences of such maps are meaningful; add() turns one into light-map irradiance.
using BounceMap = std::vector<glm::vec3>;

// One group's bounce light with no object present, and what its changes start from.
struct GroupBounce {
  BounceMap indirect;
  // What the integrator keeps for the changes (final gathering: what the group's surfaces send
  // on, by the series term that reads it).
  std::vector<BounceMap> sends;
  float peak = 0.0f;  // largest irradiance of `indirect`
  int bounces = 0;
  uint64_t gathers = 0;  // the work it took (final gathering: stored rays read)
};

// A linear combination of fine maps: the direct light a slot's objects block, or the joint
// change of a pair (its two slots less the light both block).
struct FineSum {
  std::vector<std::pair<const SparseMap*, float>> sparse;
  std::vector<std::pair<const FloatImage*, float>> dense;
  glm::vec3 at(size_t texel) const;
};

// One change for IndirectIntegrator::changes().
struct ChangeRequest {
  const GroupBounce* group = nullptr;  // the prepared group it changes
  float threshold = 0.0f;              // the group's significance, as for prepare()
  std::vector<uint8_t> present;        // one byte per Scene object
  FineSum blocked;                     // the direct light they block (fine)
  FineSum blocked_points;              // the same at direct_points() (empty without them)
};

// Points where an integrator's bounce light reads the direct light itself instead of its cache
// (final gathering: its near hits, gather.h NearHit), as an image so that a direct pass traces
// them as it traces the light map: point i is pixel i, row by row. They are in space order, so
// that an object's shadow covers few rows of its sparse shadow map.
struct DirectPoints {
  static constexpr int kWidth = 256;
  int width = kWidth, height = 0;
  std::vector<glm::vec3> position, normal;  // one per point
  std::vector<uint32_t> index;              // point -> the integrator's own entry
  std::vector<uint32_t> texel;              // point -> the light-map texel it lies on
  size_t size() const { return position.size(); }
};

// The direct light a pass or a state gives the DirectPoints, beside its light map.
using PointLight = FloatImage;
// The same where few points are lit: (point, RGB irradiance) in ascending point order, each point
// at most once; the others 0.
using SparsePointLight = std::vector<std::pair<uint32_t, glm::vec3>>;

// One group's light for IndirectIntegrator::prepare().
struct GroupLight {
  const FloatImage* direct = nullptr;  // fine, 1 or 3 channels, the group's units
  const PointLight* points = nullptr;  // the same at direct_points() (null when it has none)
  float threshold = 0.0f;              // the group's significance (terms far below it are dropped)
};

class IndirectIntegrator {
 public:
  virtual ~IndirectIntegrator() = default;
  // The points whose direct light the group passes and states hand to prepare(), changes() and
  // add_state() (`points`), or null: none.
  virtual const DirectPoints* direct_points() const { return nullptr; }
  // The bounce light of each group's direct light, `threads` wide, each the same bits as
  // prepared alone; groups whose receivers overlap share each bounce's pass over the
  // integrator's rays (several lights of one room).
  virtual std::vector<GroupBounce> prepare(const std::vector<GroupLight>& groups,
                                           int threads) const = 0;
  // prepare() of several direct lights at once, `threads` wide, each the same bits as alone but
  // without `sends` (for light no object changes: the moving lights' panes); lights whose
  // receivers overlap share each bounce's pass over the integrator's rays. `points`: empty, or
  // one per light, the light at direct_points() (a pane lights few of them). Each image is freed
  // once read.
  virtual std::vector<GroupBounce> prepare_many(std::vector<FloatImage> direct,
                                                const std::vector<SparsePointLight>& points,
                                                float threshold, int threads) const = 0;
  // What the objects of each request change in its prepared group's bounce light,
  // I(no object) - I(present), given the direct light they block: for each request the map it
  // would get alone. Solved together, `threads` wide, so that several share each pass over the
  // integrator's rays (best where requests of one object's changes to several groups are
  // neighbours). `seconds` (may be null): each request's share of the solve's thread-seconds
  // (wall time x threads), by the work it took. `progress` (may be null) advances by each request
  // solved.
  virtual std::vector<BounceMap> changes(const std::vector<ChangeRequest>& requests, int threads,
                                         std::vector<double>* seconds,
                                         Progress* progress) const = 0;
  // A cheap bound of the first bounce of a change for objects that block no direct light.
  virtual float first_change(const GroupBounce& group,
                             const std::vector<uint8_t>& present) const = 0;
  // Adds a bounce map to a fine map (3 channels) as light-map irradiance, magnified along each
  // surface (never across a crease, a contact or a chart's edge). With an indirect map
  // (Layout::align > 1) `blocks` (may be null) also receives its block image (block_image(),
  // what the pack's indirect map holds); the pack's light map then holds the difference, which
  // may be negative where the indirect map's bilinear filter blends across a crease inside a
  // chart. Without one `blocks` is left as it is.
  virtual void add(BounceMap map, FloatImage& fine, FloatImage* blocks) const = 0;
  // add()'s block image of a map (Layout::align > 1) into `blocks` and the largest finite value
  // add() would add to a zero map, without the light-map-sized map: for maps the pack holds on
  // the indirect map alone (the moving lights' panes).
  virtual float add_blocks(BounceMap map, FloatImage& blocks) const = 0;
  // A whole state's bounce light from its direct light (3 channels; `points` at direct_points(),
  // null when it has none) with the objects `present`,
  // added to `fine` as add() does. `threshold`: the finest significance among the state's groups.
  virtual void add_state(const FloatImage& direct, const PointLight* points,
                         const std::vector<uint8_t>& present, float threshold,
                         FloatImage& fine) const = 0;
  // Per light-map texel, 1 where some gather ray reads its light (a ray's static hit lands on its
  // coarse texel, or a near hit on the texel itself), its own rays see some surface and it is not
  // buried in solid geometry, else 0: light on the others (the outside of a closed room, a floor
  // under a rug, which no light reaches either) bounces to no texel.
  virtual std::vector<uint8_t> read_texels() const = 0;
  // Settings and statistics for the report.
  virtual nlohmann::json describe() const = 0;
};

struct GatherOperator;

// Traced gather rays kept between processes (a cook's job folder, job_dir.h): the integrator
// asks it before tracing and hands it what it traced.
class GatherStore {
 public:
  virtual ~GatherStore() = default;
  // true: `op` now holds this bake's operator, as build_gather would make it.
  virtual bool load(GatherOperator& op, Progress& progress) = 0;
  virtual void save(const GatherOperator& op, Progress& progress) = 0;
};

// Final gathering (gather.h): traces the gather rays of the context's texels, or loads them from
// `store` (may be null).
std::unique_ptr<IndirectIntegrator> make_gather_integrator(const BakeContext& b, GatherStore* store,
                                                           Progress& progress, Report& report);

}  // namespace lightpatch::cooker
