// Where the anchors stand and what each sees (anchors.h).
#include "panes/anchors.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "direct_light.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/moving_lights.h"
#include "panes/pane_cluster.h"
#include "probes/probe_rays.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

std::vector<PaneMap> place_anchors(const Scene& scene, const Tracer& tracer, float spacing,
                                   int threads) {
  if (!(spacing > 0.0f) || !std::isfinite(spacing))
    throw CookError("anchor spacing must be a finite number of metres > 0");
  const glm::vec3 extent = glm::max(scene.bounds_max - scene.bounds_min, glm::vec3(0.0f));
  double points = 1.0;  // counted in doubles before the grid's ints are made
  for (int a = 0; a < 3; ++a) points *= std::floor(double(extent[a]) / double(spacing)) + 1.0;
  // Every lattice point is tested; the pack holds at most kMaxPanes of them, and a lattice far
  // larger than that is a spacing mistake whatever lies inside solid geometry.
  if (points > 16.0 * double(pack::kMaxPanes))
    throw CookError("an anchor spacing of " + std::to_string(spacing) + " m makes " +
                    std::to_string(uint64_t(points)) +
                    " lattice points over the scene's bounds; use a larger spacing");
  const CentredGrid grid(scene.bounds_min, extent, spacing);
  const size_t count = grid.count();
  std::vector<uint8_t> inside(count, 0);
  const int workers = worker_count(threads);
  parallel_for(int(count), workers, [&](int i) {
    set_worker_fp_mode();
    inside[size_t(i)] = inside_solid(tracer, grid.point(size_t(i))) ? 1 : 0;
  });
  std::vector<PaneMap> out;
  for (size_t i = 0; i < count; ++i) {
    if (inside[i]) continue;
    PaneMap a;
    const glm::vec3 p = grid.point(i);
    for (int k = 0; k < 3; ++k) a.record.eye[k] = p[k];
    a.record.normal[2] = 1.0f;
    a.record.radius = spacing;
    a.record.depth_range = std::max(scene.scale(), 1e-3f);
    out.push_back(std::move(a));
  }
  if (out.size() > pack::kMaxPanes)
    throw CookError(std::to_string(out.size()) + " anchors at a spacing of " +
                    std::to_string(spacing) + " m, over the pack's limit of " +
                    std::to_string(pack::kMaxPanes) + "; use a larger spacing");
  const float eps = tracer.epsilon();
  parallel_for(int(out.size()), workers, [&](int k) {
    set_worker_fp_mode();
    pack::PaneRecord& r = out[size_t(k)].record;
    const glm::vec3 eye(r.eye[0], r.eye[1], r.eye[2]);
    constexpr uint32_t n = pack::kPaneDepthSize;
    for (uint32_t y = 0; y < n; ++y) {
      for (uint32_t x = 0; x < n; ++x) {
        float dir[3];
        anchor_depth_direction(x, y, dir);
        r.depth[y * n + x] = depth_code(tracer, eye, dir, eps, r.depth_range);
      }
    }
  });
  return out;
}

float anchor_irradiance(const Scene& scene, const Tracer& tracer, const Light& light,
                        const glm::vec3& eye, const glm::vec3& x, const glm::vec3& n) {
  const glm::vec3 l = eye - x;
  const float d2 = glm::dot(l, l), d = std::sqrt(d2);
  if (!(d > 0.0f)) return 0.0f;
  const glm::vec3 dir = l / d;
  const float cos_x = glm::dot(n, dir);
  const float window = range_window(light.range, d);
  if (!(cos_x > 0.0f) || !(window > 0.0f)) return 0.0f;
  const float eps = tracer.epsilon();
  if (tracer.occluded_static(x, dir, eps, d - eps)) return 0.0f;
  const float floor2 = std::max(light.radius * light.radius, 1e-8f * scene.scale() * scene.scale());
  return cos_x / std::max(d2, floor2) * window;
}

}  // namespace lightpatch::cooker
