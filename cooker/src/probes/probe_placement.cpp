// Where the probes go: a regular grid over the scene's bounds, trimmed of the points that lie
// inside solid geometry, and the probes the scene places; each probe's reach along the axes.
#include <algorithm>
#include <cmath>
#include <string>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/probes.h"
#include "probes/probe_rays.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

constexpr float kAutoSpacing = 1.0f;  // metres: a character's scale

uint64_t grid_points(const glm::vec3& extent, float spacing) {
  return uint64_t(CentredGrid::points_along(extent.x, spacing)) *
         uint64_t(CentredGrid::points_along(extent.y, spacing)) *
         uint64_t(CentredGrid::points_along(extent.z, spacing));
}

// Free distance along +X, -X, +Y, -Y, +Z, -Z to static geometry, capped at `cap`.
void measure_reach(const Tracer& tracer, const glm::vec3& p, float cap, float reach[6]) {
  static const glm::vec3 kAxes[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                     {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  for (int a = 0; a < 6; ++a) {
    const Hit h = tracer.intersect(p, kAxes[a], 0.0f, cap, false);
    reach[a] = h.hit ? std::min(h.t, cap) : cap;
  }
}

}  // namespace

ProbeBake place_probes(const Scene& scene, const Tracer& tracer, const ProbeOptions& options,
                       Report& report) {
  ProbeBake out;
  if (!options.enabled) return out;
  if (!(options.spacing >= 0.0f) || !std::isfinite(options.spacing))
    throw CookError("probe spacing must be a finite number of metres >= 0 (0: auto)");
  const glm::vec3 extent = scene.bounds_max - scene.bounds_min;
  float spacing = options.spacing > 0.0f ? options.spacing : kAutoSpacing;
  if (options.spacing > 0.0f) {
    if (grid_points(extent, spacing) > pack::kMaxProbeGridPoints)
      throw CookError("a probe spacing of " + std::to_string(spacing) + " m needs " +
                      std::to_string(grid_points(extent, spacing)) +
                      " grid points over the scene's bounds, more than the pack's " +
                      std::to_string(pack::kMaxProbeGridPoints) + "; use a larger spacing");
  } else {
    while (grid_points(extent, spacing) > kMaxAutoGridPoints) spacing *= 1.25f;
  }
  const CentredGrid grid(scene.bounds_min, extent, spacing);
  const size_t count = grid.count();
  const int threads = worker_count(options.threads);

  std::vector<uint8_t> inside(count, 0);
  parallel_for(int(count), threads, [&](int i) {
    set_worker_fp_mode();
    inside[size_t(i)] = inside_solid(tracer, grid.point(size_t(i))) ? 1 : 0;
  });

  out.has_grid = true;
  out.grid_origin = grid.origin;
  out.grid_spacing = spacing;
  out.grid_size = grid.size;
  out.grid_index.assign(count, pack::kNone32);
  for (size_t i = 0; i < count; ++i) {
    if (inside[i]) continue;
    out.grid_index[i] = uint32_t(out.probes.size());
    ProbeBake::Probe probe;
    probe.position = grid.point(i);
    out.probes.push_back(std::move(probe));
  }
  const size_t grid_kept = out.probes.size();
  for (const ProbePoint& placed : scene.probes) {
    ProbeBake::Probe probe;
    probe.position = placed.position;
    probe.name = placed.name;
    out.probes.push_back(std::move(probe));
  }
  if (out.probes.size() > pack::kMaxProbes)
    throw CookError(std::to_string(out.probes.size()) + " light probes, more than the pack's " +
                    std::to_string(pack::kMaxProbes) + "; use a larger probe spacing");
  parallel_for(int(out.probes.size()), threads, [&](int i) {
    set_worker_fp_mode();
    measure_reach(tracer, out.probes[size_t(i)].position, spacing, out.probes[size_t(i)].reach);
  });

  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& r = report.root()["probes"];
  r["spacing_m"] = spacing;
  r["grid"] = {grid.size.x, grid.size.y, grid.size.z};
  r["grid_points"] = count;
  r["grid_probes"] = grid_kept;
  r["inside_geometry"] = count - grid_kept;
  r["placed_probes"] = scene.probes.size();
  return out;
}

}  // namespace lightpatch::cooker
