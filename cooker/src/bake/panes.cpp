// The moving lights' panes (docs/moving_lights.md): each pane's bounce light for irradiance 1 on
// its texels, solved by the session's integrator like a light group's (the same rays, the same
// series and denoiser), so a moving light's bounce light is sum_k w_k P_k with the runtime's
// weights w_k (pack_format.h, "Moving lights").
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "bake/session.h"
#include "indirect/integrator.h"
#include "panes/pane_cluster.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {
// Panes solved side by side (IndirectIntegrator::prepare_many). Eight (kChangeBatch) took the
// same CPU time on the small inn for 1.17x the cook's peak memory: each holds its series.
constexpr size_t kPaneBatch = 4;

// The panes' indices in the Z order of their eyes over the panes' bounds: a batch of neighbours
// lights mostly the same receivers (the refinement appends split panes at the end).
std::vector<uint32_t> in_space_order(const std::vector<PaneMap>& panes) {
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const PaneMap& p : panes) {
    const glm::vec3 e(p.record.eye[0], p.record.eye[1], p.record.eye[2]);
    lo = glm::min(lo, e);
    hi = glm::max(hi, e);
  }
  const glm::vec3 extent = glm::max(hi - lo, glm::vec3(1e-6f));
  auto interleave = [](uint32_t v) {  // 10 bits to every third of 30
    uint64_t x = v & 0x3FFu;
    x = (x | (x << 16)) & 0x30000FFull;
    x = (x | (x << 8)) & 0x300F00Full;
    x = (x | (x << 4)) & 0x30C30C3ull;
    x = (x | (x << 2)) & 0x9249249ull;
    return x;
  };
  std::vector<std::pair<uint64_t, uint32_t>> keyed(panes.size());
  for (size_t i = 0; i < panes.size(); ++i) {
    const pack::PaneRecord& r = panes[i].record;
    uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const float u = (r.eye[a] - lo[a]) / extent[a];
      key |= interleave(uint32_t(std::clamp(u, 0.0f, 1.0f) * 1023.0f)) << a;
    }
    keyed[i] = {key, uint32_t(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<uint32_t> order(panes.size());
  for (size_t i = 0; i < panes.size(); ++i) order[i] = keyed[i].second;
  return order;
}
}  // namespace

void BakeSession::bake_panes(BakedMaps& maps, Progress& progress, Report& report) const {
  const BakeContext& b = impl_->ctx;
  const Scene& scene = b.scene;
  const TexelSet& texels = b.texels;
  maps.moving_lights.clear();
  maps.panes.clear();
  for (size_t i = 0; i < scene.lights.size(); ++i)
    if (scene.lights[i].moving) maps.moving_lights.push_back(int(i));
  if (maps.moving_lights.empty()) return;
  impl_->trace_shared(progress, report);
  if (!b.indirect) return;  // direct light only: a moving light then has no baked light at all

  const auto start = std::chrono::steady_clock::now();
  progress.begin("panes", 1);
  PaneClusterOptions co;
  co.panes = b.options.panes > 0 ? b.options.panes : kDefaultPanes;
  co.threads = b.threads;
  // Irradiance on a texel no gather ray reads bounces nowhere: a pane there would be wasted.
  const std::vector<uint8_t> senders = b.indirect->read_texels();
  co.senders = &senders;
  maps.panes = cluster_panes(scene, texels, b.tracer, co);
  const double cluster_s = progress.end();

  const std::vector<int32_t> pane_of = pane_of_texels(maps.panes, texels.valid.size());
  const DirectPoints* pts = b.indirect->direct_points();
  const bool points = pts && pts->size() > 0;
  const float threshold = pane_significance(scene, b.output_step);
  const int s = b.layout.align;
  const bool blocks_divide = s > 1 && texels.width % s == 0 && texels.height % s == 0;
  progress.begin("pane bounce light", maps.panes.size());
  // Panes in batches of neighbours (in_space_order): a batch's solves share each bounce's pass
  // over the stored rays where their receivers overlap (the same bits as alone), and batches run
  // one per worker, so both cores stay busy through the serial parts (the coarse sources, the
  // denoiser, the magnification).
  const size_t n_panes = maps.panes.size();
  // Each pane's direct points, listed once (a walk over every point per pane cost more than
  // the pane's first bounce on small panes).
  std::vector<std::vector<uint32_t>> points_in(points ? n_panes : 0);
  if (points)
    for (size_t p = 0; p < pts->size(); ++p)
      if (const int32_t k = pane_of[pts->texel[p]]; k >= 0)
        points_in[size_t(k)].push_back(uint32_t(p));
  const std::vector<uint32_t> order = in_space_order(maps.panes);
  const int batches = int((n_panes + kPaneBatch - 1) / kPaneBatch);
  parallel_for(batches, b.threads, [&](int batch) {
    set_worker_fp_mode();
    const size_t first = size_t(batch) * kPaneBatch;
    const size_t count = std::min(kPaneBatch, n_panes - first);
    std::vector<FloatImage> direct(count);
    std::vector<SparsePointLight> at_points(points ? count : 0);
    for (size_t j = 0; j < count; ++j) {
      const size_t k = order[first + j];
      direct[j] = FloatImage(texels.width, texels.height, 1);
      for (uint32_t t : maps.panes[k].texels) direct[j].data[t] = 1.0f;
      if (points)
        for (uint32_t p : points_in[k]) at_points[j].push_back({p, glm::vec3(1.0f)});
    }
    std::vector<GroupBounce> solved =
        b.indirect->prepare_many(std::move(direct), at_points, threshold, 1);
    for (size_t j = 0; j < count; ++j) {
      PaneMap& pane = maps.panes[order[first + j]];
      // The pack stores a pane on the indirect map alone where its blocks divide the page
      // (pack_builder.cpp): then the block image is all the cook keeps (PaneMap), and the
      // light-map-sized map is never made.
      if (blocks_divide) {
        pane.peak = b.indirect->add_blocks(std::move(solved[j].indirect), pane.indirect);
      } else {
        FloatImage fine(texels.width, texels.height, 3);
        b.indirect->add(std::move(solved[j].indirect), fine, &pane.indirect);
        for (float v : fine.data)
          if (std::isfinite(v)) pane.peak = std::max(pane.peak, v);
        pane.map = std::move(fine);
      }
      progress.advance();
    }
  });
  const double bounce_s = progress.end();
  size_t pane_texels = 0;
  for (const PaneMap& p : maps.panes) pane_texels += p.texels.size();
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& r = report.root()["panes"];
  r["moving_lights"] = maps.moving_lights.size();
  r["requested"] = co.panes;
  r["panes"] = maps.panes.size();
  r["texels"] = pane_texels;
  r["threshold"] = threshold;
  r["cluster_seconds"] = cluster_s;
  r["bounce_seconds"] = bounce_s;
  r["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace lightpatch::cooker
