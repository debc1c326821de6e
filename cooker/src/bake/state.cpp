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
  const int w = texels.width, h = texels.height;
  FloatImage out(w, h, 3);
  const int max_objects = static_cast<int>(scene.objects.size());
  progress.begin("bake state", static_cast<uint64_t>(h));
  parallel_for(h, b.threads, [&](int y) {
    std::vector<LightSample> samples;
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
      const size_t t = texels.index(x, y);
      if (!texels.valid[t]) continue;
      glm::vec3 e(0.0f);
      for (size_t li = 0; li < scene.lights.size(); ++li) {
        if (max3(radiant[li]) <= 0.0f) continue;
        samples.clear();
        b.light_samples(static_cast<int>(li), t, samples);
        batch.trace(b.tracer, samples, max_objects);
        float sum = 0.0f;
        for (size_t i = 0; i < samples.size(); ++i)
          if (unblocked(i)) sum += samples[i].irradiance.x;
        e += radiant[li] * sum;
      }
      samples.clear();
      b.emissive_samples(t, samples);
      batch.trace(b.tracer, samples, max_objects);
      for (size_t i = 0; i < samples.size(); ++i)
        if (unblocked(i)) e += samples[i].irradiance;
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = e[c];
    }
    progress.advance();
  });
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
    const FloatImage direct = out;
    b.indirect->add_state(direct, visible, threshold, out);
    report.stage_time("bake.state_bounce", progress.end());
  }
  report_bake(*impl_, report);
  return out;
}

}  // namespace lightpatch::cooker
