// One scene state baked directly, as a conventional light mapper would: the ground truth a
// recomposition must match. The same samples as the groups' direct passes and the same bounce
// light (the integrator's state solve), so a single-object state equals B + sum f_l (C_l - S_ol).
#include <mutex>

#include "bake/direct_pass.h"
#include "bake/session.h"
#include "indirect/integrator.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

FloatImage BakeSession::bake_state(const StateSpec& state, Progress& progress,
                                   Report& report) const {
  impl_->trace_shared(progress, report);
  const BakeContext& b = impl_->ctx;
  const Scene& scene = b.scene;
  const TexelSet& texels = b.texels;
  const ResolvedState resolved = resolve_state(scene, state);
  const std::vector<glm::vec3>& radiant = resolved.radiant;
  const std::vector<uint8_t>& visible = resolved.visible;
  const int max_objects = static_cast<int>(scene.objects.size());
  // The state's direct light at every receiver of a w x h image (the light map, or the
  // integrator's DirectPoints): valid(t), light_samples(li, t, out) (in a penumbra,
  // penumbra_samples(li, t, out) instead where it gives any), emissive_samples(t, out).
  // The moving lights at the state's pose: the same random numbers as at the authored one.
  std::vector<Light> posed(scene.lights.size());
  bool any_moving = false;
  for (size_t li = 0; li < scene.lights.size(); ++li) {
    posed[li] = scene.lights[li];
    if (!scene.lights[li].moving) continue;
    posed[li].position = resolved.position[li];
    posed[li].direction = resolved.direction[li];
    any_moving = any_moving || max3(radiant[li]) > 0.0f;
  }
  // `moving`: the moving lights only (else every other light and the emissive surfaces).
  auto direct = [&](int w, int h, const auto& valid, const auto& light_samples,
                    const auto& penumbra_samples, const auto& emissive_samples, bool advance,
                    bool moving) {
    FloatImage out(w, h, 3);
    parallel_for(h, b.threads, [&](int y) {
      std::vector<LightSample> samples, dense;
      SampleRays batch;  // traced as the groups' direct passes trace them
      auto unblocked = [&](size_t i) {
        const int n = batch.counts[i];
        if (n < 0) return false;
        const int* hit = batch.objects_of(i);
        for (int j = 0; j < n; ++j)
          if (visible[static_cast<size_t>(hit[j])]) return false;
        return true;
      };
      for (int x = 0; x < w; ++x) {
        const size_t t = size_t(y) * size_t(w) + size_t(x);
        if (!valid(t)) continue;
        glm::vec3 e(0.0f);
        for (size_t li = 0; li < scene.lights.size(); ++li) {
          if (max3(radiant[li]) <= 0.0f || scene.lights[li].moving != moving) continue;
          const Light* pose = moving ? &posed[li] : nullptr;
          samples.clear();
          light_samples(static_cast<int>(li), t, samples, pose);
          batch.trace(b.tracer, samples, max_objects);
          if (batch.penumbra(0, samples.size())) {
            dense.clear();
            if (penumbra_samples(static_cast<int>(li), t, dense, pose)) {
              samples.swap(dense);
              batch.trace(b.tracer, samples, max_objects);
            }
          }
          float sum = 0.0f;
          for (size_t i = 0; i < samples.size(); ++i)
            if (unblocked(i)) sum += samples[i].irradiance.x;
          e += radiant[li] * sum;
        }
        if (!moving) {
          samples.clear();
          emissive_samples(t, samples);
          batch.trace(b.tracer, samples, max_objects);
          for (size_t i = 0; i < samples.size(); ++i)
            if (unblocked(i)) e += samples[i].irradiance;
        }
        for (int c = 0; c < 3; ++c) out.at(x, y, c) = e[c];
      }
      if (advance) progress.advance();
    });
    return out;
  };
  progress.begin("bake state", static_cast<uint64_t>(texels.height) * (any_moving ? 2 : 1));
  auto texel_image = [&](bool moving) {
    return direct(
        texels.width, texels.height, [&](size_t t) { return texels.valid[t] != 0; },
        [&](int li, size_t t, std::vector<LightSample>& o, const Light* pose) {
          b.light_samples(li, t, o, pose);
        },
        [&](int li, size_t t, std::vector<LightSample>& o, const Light* pose) {
          return b.penumbra_light_samples(li, t, o, pose);
        },
        [&](size_t t, std::vector<LightSample>& o) { b.emissive_samples(t, o); }, true, moving);
  };
  const DirectPoints* pts = b.indirect ? b.indirect->direct_points() : nullptr;
  const bool points = pts && pts->size() > 0;
  auto point_image = [&](bool moving) {
    return direct(
        pts->width, pts->height, [&](size_t i) { return i < pts->size(); },
        [&](int li, size_t i, std::vector<LightSample>& o, const Light* pose) {
          b.point_light_samples(*pts, li, i, o, pose);
        },
        [](int, size_t, std::vector<LightSample>&, const Light*) { return false; },
        [&](size_t i, std::vector<LightSample>& o) { b.point_emissive_samples(*pts, i, o); }, false,
        moving);
  };
  FloatImage out = texel_image(false);
  FloatImage at_points;
  if (points) at_points = point_image(false);
  // The moving lights' direct light: a source of bounce light; in the map only for pictures.
  FloatImage moving_direct, moving_points;
  if (any_moving) {
    moving_direct = texel_image(true);
    if (points) moving_points = point_image(true);
  }
  report.stage_time("bake.state", progress.end());
  if (b.indirect) {
    // The state's bounce light in one solve: every group's direct light at its state's colour
    // is one source, the visible objects are present. Its significance is the finest of the
    // groups' (each at its state's brightness), so the state is solved at least as finely as
    // the decomposition's maps.
    progress.begin("bounce light", 1);
    float threshold = b.static_step;
    for (size_t li = 0; li < scene.lights.size(); ++li) {
      if (scene.lights[li].semi_dynamic && max3(radiant[li]) > 0.0f)
        threshold = std::min(threshold, b.lights[li].threshold * max3(radiant[li]));
    }
    FloatImage direct_light = out;
    if (any_moving) {
      for (size_t i = 0; i < direct_light.data.size(); ++i)
        direct_light.data[i] += moving_direct.data[i];
      for (size_t i = 0; i < at_points.data.size(); ++i) at_points.data[i] += moving_points.data[i];
    }
    b.indirect->add_state(direct_light, points ? &at_points : nullptr, visible, threshold, out);
    report.stage_time("bake.state_bounce", progress.end());
  }
  if (any_moving && b.options.moving_direct) {
    for (size_t i = 0; i < out.data.size(); ++i) out.data[i] += moving_direct.data[i];
  }
  report_bake(*impl_, report);
  return out;
}

}  // namespace lightpatch::cooker
