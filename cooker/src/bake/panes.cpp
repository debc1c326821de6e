// The moving lights' panes (docs/moving_lights.md): each pane's bounce light for irradiance 1 on
// its texels, solved by the session's integrator like a light group's (the same rays, the same
// series and denoiser), so a moving light's bounce light is sum_k w_k P_k with the runtime's
// weights w_k (pack_format.h, "Moving lights").
#include <algorithm>
#include <chrono>
#include <cmath>

#include "bake/session.h"
#include "indirect/integrator.h"
#include "panes/pane_cluster.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

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
  // Panes are independent solves: one per worker, so both cores stay busy through the solves'
  // serial parts (the coarse source, the denoiser, the magnification).
  parallel_for(int(maps.panes.size()), b.threads, [&](int k) {
    set_worker_fp_mode();
    PaneMap& pane = maps.panes[size_t(k)];
    FloatImage direct(texels.width, texels.height, 1);
    for (uint32_t t : pane.texels) direct.data[t] = 1.0f;
    PointLight at_points;
    if (points) {
      at_points = PointLight(pts->width, pts->height, 1);
      for (size_t p = 0; p < pts->size(); ++p)
        if (pane_of[pts->texel[p]] == k) at_points.data[p] = 1.0f;
    }
    GroupBounce g = b.indirect->prepare(direct, points ? &at_points : nullptr, threshold);
    FloatImage fine(texels.width, texels.height, 3);
    b.indirect->add(std::move(g.indirect), fine, &pane.indirect);
    // The pack stores a pane on the indirect map alone where its blocks divide the page
    // (pack_builder.cpp): then the block image is all the cook keeps (PaneMap).
    for (float v : fine.data)
      if (std::isfinite(v)) pane.peak = std::max(pane.peak, v);
    if (!(blocks_divide && !pane.indirect.data.empty())) pane.map = std::move(fine);
    progress.advance();
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
