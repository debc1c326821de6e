// How well a light probe's SH gives the irradiance of a surface: probes 5 mm in front of N
// texels of a scene (chosen evenly over the valid texels), lit from the cook's maps like the
// pack's probes, their irradiance facing the texel's normal against the texel's own in bake-state
// of the authored state. Reports relative RMSE, median ratio and signed bias for the order-2 SH
// the pack stores (9 coefficients per channel) and for order 1 (its first 4 coefficients, the
// irradiance an L1 probe would hold), with the bytes of an entry of each, over all those texels
// and over those at least 0.5 m from every point or spot light (where moving things take their
// light; beside a candle no low order resolves its near field).
//
//   bench_probe_accuracy SCENE.glb [--quality draft|preview|production] [--texels N]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/probes.h"
#include "lightpatch/spherical_harmonics.h"

using namespace lightpatch;
using namespace lightpatch::cooker;

namespace {

struct Errors {
  double num = 0, den = 0, bias = 0;
  std::vector<double> ratios;
  void add(const glm::vec3& x, const glm::vec3& r) {
    for (int c = 0; c < 3; ++c) {
      num += double(x[c] - r[c]) * double(x[c] - r[c]);
      den += double(r[c]) * double(r[c]);
      bias += double(x[c] - r[c]);
    }
    const double lr = 0.2126 * r.x + 0.7152 * r.y + 0.0722 * r.z;
    const double lx = 0.2126 * x.x + 0.7152 * x.y + 0.0722 * x.z;
    if (lr > 0.0) ratios.push_back(lx / lr);
  }
  void print(const char* name, size_t entry_bytes, double sum_ref) {
    std::sort(ratios.begin(), ratios.end());
    const double median = ratios.empty() ? 0.0 : ratios[ratios.size() / 2];
    std::printf("%-8s entry %3zu B  rel. RMSE %6.2f %%  median ratio %.4f  bias %+.2f %%\n", name,
                entry_bytes, 100.0 * std::sqrt(num / std::max(den, 1e-30)), median,
                100.0 * bias / std::max(sum_ref, 1e-30));
  }
};

glm::vec3 evaluate(const float* sh, const glm::vec3& n, uint32_t coefficients) {
  float y[pack::kProbeShCount];
  sh_basis(n.x, n.y, n.z, y);
  glm::vec3 e(0.0f);
  for (uint32_t k = 0; k < coefficients; ++k)
    for (int c = 0; c < 3; ++c) e[c] += sh[k * 3 + c] * y[k];
  return glm::max(e, glm::vec3(0.0f));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_probe_accuracy SCENE.glb [--quality Q] [--texels N]\n");
    return 2;
  }
  BakeOptions bake;
  int texel_count = 400;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--quality")) bake.quality = parse_quality(argv[i + 1]);
    if (!std::strcmp(argv[i], "--texels")) texel_count = std::max(1, std::atoi(argv[i + 1]));
  }
  try {
    Progress progress(true);
    Report report;
    const PreparedScene p = prepare_scene(argv[1], LayoutOptions{}, progress, report);
    BakedMaps maps;
    BakeOptions no_probes = bake;
    no_probes.probes.enabled = false;
    cook_pack(p, no_probes, progress, report, &maps);
    const FloatImage state = cook_state(p, StateSpec{}, bake, progress, report);
    std::vector<size_t> valid;
    for (size_t t = 0; t < p.texels.valid.size(); ++t)
      if (p.texels.valid[t]) valid.push_back(t);
    ProbeBake probes;
    std::vector<size_t> at;
    const size_t step = std::max<size_t>(1, valid.size() / size_t(texel_count));
    for (size_t i = step / 2; i < valid.size(); i += step) {
      ProbeBake::Probe probe;
      probe.position = p.texels.position[valid[i]] + 0.005f * p.texels.normal[valid[i]];
      probes.probes.push_back(probe);
      at.push_back(valid[i]);
    }
    const ProbeOptions po = probe_options(bake);
    const auto sh =
        bake_state_probes(probes, p.scene, p.layout, p.texels, *p.tracer, state, StateSpec{}, po);
    Errors l2, l1, far2, far1;
    double sum_ref = 0.0, sum_far = 0.0;
    for (size_t i = 0; i < at.size(); ++i) {
      const size_t t = at[i];
      const glm::vec3 r(state.data[t * 3], state.data[t * 3 + 1], state.data[t * 3 + 2]);
      const glm::vec3 n = p.texels.normal[t];
      l2.add(evaluate(sh[i].data(), n, 9), r);
      l1.add(evaluate(sh[i].data(), n, 4), r);
      sum_ref += double(r.x + r.y + r.z);
      float nearest = 1e30f;
      for (const Light& l : p.scene.lights)
        if (l.type != LightType::kDirectional)
          nearest = std::min(nearest, glm::length(l.position - probes.probes[i].position));
      if (nearest >= 0.5f) {
        far2.add(evaluate(sh[i].data(), n, 9), r);
        far1.add(evaluate(sh[i].data(), n, 4), r);
        sum_far += double(r.x + r.y + r.z);
      }
    }
    std::printf("%s, %s, %zu probes in front of texels, %d rays each\n", argv[1],
                quality_name(bake.quality), at.size(), po.rays);
    l2.print("order 2", 4 + 27 * 4, sum_ref);
    l1.print("order 1", 4 + 12 * 4, sum_ref);
    std::printf("%zu of them at least 0.5 m from every point or spot light:\n", far2.ratios.size());
    far2.print("order 2", 4 + 27 * 4, sum_far);
    far1.print("order 1", 4 + 12 * 4, sum_far);
  } catch (const CookError& e) {
    std::fprintf(stderr, "bench_probe_accuracy: %s\n", e.what());
    return 1;
  }
  return 0;
}
