// The moving lights' panes (docs/moving_lights.md): each pane's bounce light for irradiance 1 on
// its texels, solved by the session's integrator like a light group's (the same rays, the same
// series and denoiser), so a moving light's bounce light is sum_k w_k P_k with the runtime's
// weights w_k (pack_format.h, "Moving lights").
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "bake/direct_pass.h"
#include "bake/session.h"
#include "indirect/integrator.h"
#include "lightpatch/cooker/error.h"
#include "panes/anchors.h"
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

// The texels and near-hit points whose light bounces in a pane's or an anchor's map: those of
// static meshes that stop rays (cluster_panes' members; the objects are absent from these maps).
bool sends(const Scene& scene, const TexelSet& texels, uint32_t t) {
  const int32_t m = t < texels.mesh.size() ? texels.mesh[t] : -1;
  if (m < 0 || size_t(m) >= scene.meshes.size()) return false;
  const MeshInstance& mesh = scene.meshes[size_t(m)];
  return mesh.object < 0 && mesh.cast_shadows;
}

// The moving light `li` standing at anchor `a` (intensity 1, white): its direct light on the
// texels that send (sends()) and at the integrator's near-hit points. Within kAnchorNearField
// spacings of the anchor, the samples bake_state draws for that pose (a light group's: points of
// each texel's patch, a sphere light's area, penumbras drawn denser); beyond, one shadow ray from
// each texel's sample point and, at a near-hit point, the light of the texel it lies on. The
// near field is where the light changes within a texel and most of the bounce light starts (one
// ray a texel there left the small inn's anchor maps 13-22 % dark against bake-state); all of
// it drawn so cost 15 times the anchors' bounce solves.
constexpr float kAnchorNearField = 1.5f;

void anchor_direct(const BakeContext& b, int li, const pack::PaneRecord& a, FloatImage& direct,
                   SparsePointLight& at_points) {
  const Scene& scene = b.scene;
  const TexelSet& texels = b.texels;
  const Light& light = scene.lights[size_t(li)];
  Light posed = light;
  posed.position = glm::vec3(a.eye[0], a.eye[1], a.eye[2]);
  const glm::vec3 eye = posed.position;
  const float near2 = (kAnchorNearField * a.radius) * (kAnchorNearField * a.radius);
  const int max_objects = int(scene.objects.size());
  std::vector<LightSample> samples, dense;
  SampleRays batch;
  auto clear_sum = [&] {  // the objects are absent from these maps
    float sum = 0.0f;
    for (size_t i = 0; i < samples.size(); ++i)
      if (batch.counts[i] >= 0) sum += samples[i].irradiance.x;
    return sum;
  };
  direct = FloatImage(texels.width, texels.height, 1);
  for (size_t t = 0; t < texels.valid.size(); ++t) {
    if (!texels.valid[t] || !sends(scene, texels, uint32_t(t))) continue;
    const glm::vec3 x = texels.position[t];
    const glm::vec3 l = eye - x;
    if (glm::dot(l, l) < near2) {
      samples.clear();
      b.light_samples(li, t, samples, &posed);
      batch.trace(b.tracer, samples, max_objects);
      if (batch.penumbra(0, samples.size())) {
        dense.clear();
        if (b.penumbra_light_samples(li, t, dense, &posed)) {
          samples.swap(dense);
          batch.trace(b.tracer, samples, max_objects);
        }
      }
      direct.data[t] = clear_sum();
      continue;
    }
    direct.data[t] = anchor_irradiance(scene, b.tracer, light, eye, x, texels.normal[t]);
  }
  at_points.clear();
  const DirectPoints* pts = b.indirect->direct_points();
  if (!pts) return;
  for (size_t i = 0; i < pts->size(); ++i) {
    const uint32_t t = pts->texel[i];
    if (!sends(scene, texels, t)) continue;
    float e;
    if (const glm::vec3 l = eye - pts->position[i]; glm::dot(l, l) < near2) {
      samples.clear();
      b.point_light_samples(*pts, li, i, samples, &posed);
      batch.trace(b.tracer, samples, max_objects);
      e = clear_sum();
    } else {
      e = direct.data[t];
    }
    if (e > 0.0f) at_points.push_back({uint32_t(i), glm::vec3(e)});
  }
}

// The moving light the anchors are baked for: every moving light must be a point light of the
// same range and radius, as the anchors' maps are theirs (pack_format.h, "Anchors").
int anchor_light(const Scene& scene, const std::vector<int>& moving) {
  const Light& first = scene.lights[size_t(moving.front())];
  for (int li : moving) {
    const Light& l = scene.lights[size_t(li)];
    if (l.type != LightType::kPoint)
      throw CookError("--anchors: moving light '" + l.name +
                      "' is not a point light (a spot's bounce light needs panes)");
    if (l.range != first.range || l.radius != first.radius)
      throw CookError("--anchors: moving lights '" + first.name + "' and '" + l.name +
                      "' differ in range or radius (the anchors are baked for one of each)");
  }
  return moving.front();
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
  const bool anchors = b.options.anchor_spacing > 0.0f;
  const int anchor_li = anchors ? anchor_light(scene, maps.moving_lights) : -1;
  progress.begin(anchors ? "anchors" : "panes", 1);
  PaneClusterOptions co;
  co.panes = b.options.panes > 0 ? b.options.panes : kDefaultPanes;
  co.threads = b.threads;
  if (anchors) {
    maps.panes = place_anchors(scene, b.tracer, b.options.anchor_spacing, b.threads);
  } else {
    // Irradiance on a texel no gather ray reads bounces nowhere: a pane there would be wasted.
    const std::vector<uint8_t> senders = b.indirect->read_texels();
    co.senders = &senders;
    maps.panes = cluster_panes(scene, texels, b.tracer, co);
  }
  const double cluster_s = progress.end();

  const std::vector<int32_t> pane_of = pane_of_texels(maps.panes, texels.valid.size());
  const DirectPoints* pts = b.indirect->direct_points();
  const bool points = pts && pts->size() > 0;
  const float threshold = pane_significance(scene, b.output_step);
  const int s = b.layout.align;
  const bool blocks_divide = s > 1 && texels.width % s == 0 && texels.height % s == 0;
  progress.begin(anchors ? "anchor bounce light" : "pane bounce light", maps.panes.size());
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
    SparsePointLight unused;
    for (size_t j = 0; j < count; ++j) {
      const size_t k = order[first + j];
      if (anchors) {  // the moving light standing at the anchor
        anchor_direct(b, anchor_li, maps.panes[k].record, direct[j],
                      points ? at_points[j] : unused);
        continue;
      }
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
      FloatImage blocks;
      if (blocks_divide) {
        pane.peak = b.indirect->add_blocks(std::move(solved[j].indirect), blocks);
      } else {
        FloatImage fine(texels.width, texels.height, 3);
        b.indirect->add(std::move(solved[j].indirect), fine, &blocks);
        pane.map = TiledImage(fine);  // its significance: the finalized map's peak()
      }
      pane.indirect = TiledImage(blocks);
      progress.advance();
    }
  });
  const double bounce_s = progress.end();
  size_t pane_texels = 0;
  for (const PaneMap& p : maps.panes) pane_texels += p.texels.size();
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& r = report.root()["panes"];
  r["moving_lights"] = maps.moving_lights.size();
  r["basis"] = anchors ? "anchors" : "panes";
  if (anchors) r["anchor_spacing_m"] = b.options.anchor_spacing;
  r["requested"] = anchors ? 0 : co.panes;
  r["panes"] = maps.panes.size();
  r["texels"] = pane_texels;
  r["threshold"] = threshold;
  r["cluster_seconds"] = cluster_s;
  r["bounce_seconds"] = bounce_s;
  r["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace lightpatch::cooker
