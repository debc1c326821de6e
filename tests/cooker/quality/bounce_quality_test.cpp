// Bounce light against the path tracer where final gathering is most easily fooled (seconds, so
// labelled "reference", not "unit"): the thin-panel and low-slab rooms of gltf_files.h, imported
// as a content tool writes them. The reference traces only the texels each check reads
// (ReferenceOptions::region), many samples each.
// - Beside a thin object: a 2 cm panel 5 cm in front of a lit wall. The wall behind the panel gets
//   only what comes through the gap; a gather on 2x2 blocks, or a denoiser that cannot see the
//   panel (a semi-dynamic object, absent from the static hits), brightened it 3-13x.
// - Speckle: on a wall lit only by bounce light, the high-frequency energy (discrete Laplacian) of
//   the cook's map is at most twice the reference's, and a cook that speckles fails that bar.
// - Just above a partly lit floor: gather rays that land within a texel read the light where they
//   land, not the mean of the texel they land on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "gltf_files.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/reference_integrator.h"

namespace lightpatch::cooker {
namespace {

constexpr int kPage = 128;  // the accuracy sweep's page for this scene (docs/accuracy.md)

// A test scene of gltf_files.h, imported from glTF bytes as a content tool writes them.
struct TestRoom {
  PreparedScene p;
  explicit TestRoom(const scenegen::SceneBuilder& builder) {
    const std::vector<uint8_t> glb = test::join_glb(test::parts_of(builder));
    Scene scene = import_gltf_memory(glb.data(), glb.size(), "room.glb", "");
    LayoutOptions lo;
    lo.lightmap_size = kPage;
    Progress progress(true);
    Report report;
    p = prepare_scene(std::move(scene), lo, progress, report);
  }
  std::vector<uint8_t> region(const std::function<bool(glm::vec3, glm::vec3)>& in) const {
    std::vector<uint8_t> r(p.texels.valid.size(), 0);
    for (size_t t = 0; t < r.size(); ++t)
      r[t] = p.texels.valid[t] && in(p.texels.position[t], p.texels.normal[t]);
    return r;
  }
  ReferenceBake reference(const StateSpec& state, std::vector<uint8_t> region, int samples) const {
    ReferenceOptions ro;
    ro.samples = samples;
    ro.region = std::move(region);
    Progress progress(true);
    Report report;
    return bake_reference(p.scene, p.texels, *p.tracer, state, ro, progress, report);
  }
  FloatImage cook(const StateSpec& state, const BakeOptions& o) const {
    Progress progress(true);
    Report report;
    return bake_state(p.scene, p.layout, p.texels, *p.tracer, state, o, progress, report);
  }
};

BakeOptions preset(Quality q) {
  BakeOptions o;
  o.quality = q;
  return o;
}

float lum(const FloatImage& m, size_t t) {
  return (m.data[3 * t] + m.data[3 * t + 1] + m.data[3 * t + 2]) / 3.0f;
}

// Relative RMSE, the reference's noise over the same texels, signed bias and median ratio.
struct Agreement {
  double rmse = 0.0, noise = 0.0, bias = 0.0, median = 0.0;
  double excess() const { return std::sqrt(std::max(0.0, rmse * rmse - noise * noise)); }
};

Agreement agreement(const FloatImage& cook, const ReferenceBake& ref,
                    const std::vector<uint8_t>& region) {
  double e2 = 0.0, r2 = 0.0, se2 = 0.0, sc = 0.0, sr = 0.0;
  std::vector<double> ratios;
  for (size_t t = 0; t < region.size(); ++t) {
    if (!region[t]) continue;
    for (size_t c = 0; c < 3; ++c) {
      const double x = cook.data[3 * t + c], r = ref.map.data[3 * t + c];
      const double se = ref.std_error.data[3 * t + c];
      e2 += (x - r) * (x - r);
      r2 += r * r;
      se2 += se * se;
      sc += x;
      sr += r;
    }
    if (lum(ref.map, t) > 0.0f) ratios.push_back(double(lum(cook, t)) / lum(ref.map, t));
  }
  Agreement a;
  a.rmse = std::sqrt(e2 / r2);
  a.noise = std::sqrt(se2 / r2);
  a.bias = sc / sr - 1.0;
  std::nth_element(ratios.begin(), ratios.begin() + long(ratios.size() / 2), ratios.end());
  a.median = ratios[ratios.size() / 2];
  return a;
}

double mean_lum(const FloatImage& m, const std::vector<uint8_t>& region) {
  double s = 0.0;
  size_t n = 0;
  for (size_t t = 0; t < region.size(); ++t)
    if (region[t]) s += lum(m, size_t(t)), ++n;
  return n > 0 ? s / double(n) : 0.0;
}

// A face 1.5 cm above a floor that a candle lights up to the face's edge and a little under it
// (the small inn's worst texels). Its gather rays land within a texel, on floor texels whose patch
// is partly lit: read from the cache, those texels' means made the slab's underside up to 2x too
// bright next to its lit edge and 3-4x beyond; lit where they land (gather.h NearHit), it follows
// the path tracer. Gathered per texel and not denoised, so the check sees the gather alone:
// preview's 2x2 blocks and the denoiser blur the underside's 600:1 gradient over 25 cm (printed).
TEST(BounceQuality, AFaceJustAboveAPartlyLitFloorAgreesWithThePathTracer) {
  const TestRoom room(test::low_slab_room());
  const std::vector<uint8_t> underside = room.region([](glm::vec3 q, glm::vec3 n) {
    return n.y < -0.9f && q.y < 0.03f && std::fabs(q.x) < 0.3f && std::fabs(q.z) < 0.3f;
  });
  // Its half towards the candle, where the floor below turns from lit to dark.
  std::vector<uint8_t> candle_half = underside;
  for (size_t t = 0; t < candle_half.size(); ++t)
    candle_half[t] = candle_half[t] && room.p.texels.position[t].x > 0.0f;
  size_t n = 0;
  for (uint8_t v : candle_half) n += v;
  ASSERT_GT(n, 8u);
  const ReferenceBake ref = room.reference({}, underside, 4096);
  BakeOptions per_texel = preset(Quality::kProduction);
  per_texel.indirect_scale = 1;
  per_texel.denoise = 0;
  struct Case {
    const char* name;
    BakeOptions options;
    bool checked;
  };
  for (const Case& c : {Case{"production, per texel, not denoised", per_texel, true},
                        Case{"preview", preset(Quality::kPreview), false},
                        Case{"production", preset(Quality::kProduction), false}}) {
    const FloatImage cook = room.cook({}, c.options);
    const Agreement a = agreement(cook, ref, candle_half);
    std::printf(
        "slab underside (candle half, %zu texels), %s: rel. RMSE %.2f %% (reference noise %.2f "
        "%%), bias %+.2f %%, median ratio %.3f\n",
        n, c.name, 100 * a.rmse, 100 * a.noise, 100 * a.bias, a.median);
    if (!c.checked) continue;
    // Bars: measured (18.8 %, 1.134, -5.8 % at 1024 rays a texel; 14.6 %, 1.158, -4.5 % since
    // production gathers 256 per texel and sphere lights' samples share their exact light) +
    // about 15 %. Without the near hits the same cook had 34.3 %, a median ratio of 1.668 and a
    // bias of +11.6 %.
    EXPECT_LT(a.excess(), 0.22) << c.name;
    EXPECT_NEAR(a.median, 1.0, 0.2) << c.name;
    EXPECT_LT(std::fabs(a.bias), 0.07) << c.name;
  }
}

// A crate standing on a floor (the accuracy sweep's test room): the floor in front of a side the
// lamp does not light lies in the crate's shadow, so that side's bounce light falls to a sixth
// within 15 cm of the floor. Preview's 2x2 blocks, one value each, magnified and denoised, had
// that band at twice the path tracer's (the room's worst texels); with --contact-texels, blocks
// that touch other geometry gather per texel (gather.h, build_coarse_grid).
TEST(BounceQuality, ACratesSideWhereItStandsOnTheFloorAgreesWithThePathTracer) {
  const TestRoom room(test::small_room(0.1f));
  // The crate (x -0.75..-0.25, z 0.05..0.55, 0.5 m high): its sides' texels within 15 cm of the
  // floor, a texel in from the corners.
  const std::vector<uint8_t> band = room.region([](glm::vec3 q, glm::vec3 n) {
    const bool side =
        std::fabs(n.y) < 0.1f && q.x > -0.76f && q.x < -0.24f && q.z > 0.04f && q.z < 0.56f;
    const bool inner =
        std::fabs(n.x) > 0.9f ? std::fabs(q.z - 0.3f) < 0.2f : std::fabs(q.x + 0.5f) < 0.2f;
    return side && inner && q.y < 0.15f;
  });
  size_t n = 0;
  for (uint8_t v : band) n += v;
  ASSERT_GT(n, 16u);
  const ReferenceBake ref = room.reference({}, band, 4096);
  std::vector<float> lums;
  for (size_t t = 0; t < band.size(); ++t)
    if (band[t]) lums.push_back(lum(ref.map, t));
  std::nth_element(lums.begin(), lums.begin() + long(lums.size() / 4), lums.end());
  const float quarter = lums[lums.size() / 4];
  std::vector<uint8_t> dim = band;
  size_t n_dim = 0;
  for (size_t t = 0; t < dim.size(); ++t) {
    dim[t] = dim[t] && lum(ref.map, t) <= quarter;
    n_dim += dim[t];
  }
  BakeOptions contact = preset(Quality::kPreview);
  contact.contact_texels = true;
  struct Case {
    const char* name;
    BakeOptions options;
    bool checked;
  };
  for (const Case& c : {Case{"preview", preset(Quality::kPreview), false},
                        Case{"preview --contact-texels", contact, true},
                        Case{"production", preset(Quality::kProduction), false}}) {
    const FloatImage cook = room.cook({}, c.options);
    const Agreement a = agreement(cook, ref, band);
    // The dimmest quarter of the band (the shadowed side's foot), where the blur showed: the
    // relative RMSE above is mostly the lit sides'.
    const Agreement d = agreement(cook, ref, dim);
    std::printf(
        "crate's foot (%zu texels), %s: rel. RMSE %.2f %% (reference noise %.2f %%, own %.2f %%), "
        "bias %+.2f %%, median ratio %.3f; its dimmest %zu: own %.2f %%, bias %+.2f %%, median "
        "ratio %.3f\n",
        n, c.name, 100 * a.rmse, 100 * a.noise, 100 * a.excess(), 100 * a.bias, a.median, n_dim,
        100 * d.excess(), 100 * d.bias, d.median);
    // Bars: measured (own 3.45 %, median ratio 1.008; the dimmest quarter own 17.1 %, bias
    // +11.4 %, median ratio 1.076) + about 25 %. Plain preview's dimmest quarter, +58.7 %, must
    // fail the bias bar: the check sees the blur.
    constexpr double kDimBias = 0.15;
    if (!c.checked) {
      if (c.options.quality == Quality::kPreview) {
        EXPECT_GT(d.bias, kDimBias) << c.name;
      }
      continue;
    }
    EXPECT_LT(a.excess(), 0.045) << c.name;
    EXPECT_NEAR(a.median, 1.0, 0.03) << c.name;
    EXPECT_LT(std::fabs(a.bias), 0.02) << c.name;
    EXPECT_LT(d.excess(), 0.22) << c.name;
    EXPECT_LT(std::fabs(d.bias), kDimBias) << c.name;
    EXPECT_NEAR(d.median, 1.0, 0.12) << c.name;
  }
}

TEST(BounceQuality, ThinPanelBesideALitWallAgreesWithThePathTracer) {
  const TestRoom room(test::thin_panel_room());
  // The panel's faces, the wall behind and around it and the floor before it.
  const std::vector<uint8_t> near_panel = room.region(
      [](glm::vec3 q, glm::vec3) { return q.x > 1.45f && std::fabs(q.z) < 1.0f && q.y < 1.75f; });
  // The wall in the panel's shadow, 5 cm behind it, a texel in from its edges.
  const std::vector<uint8_t> behind = room.region([](glm::vec3 q, glm::vec3 n) {
    return q.x > 1.99f && n.x < -0.9f && std::fabs(q.z) < 0.5f && q.y > 0.1f && q.y < 1.2f;
  });
  const ReferenceBake ref = room.reference({}, near_panel, 4096);
  const double ref_behind = mean_lum(ref.map, behind);
  // Bars: measured + about 15 %. Before the denoiser's near field saw objects, preview had the
  // wall behind the panel at 13x the path tracer's. Preview's 2x2 blocks still straddle the
  // panel's shadow on the wall (about 3x there); production gathers per texel and resolves it
  // (it had 2.8x and 7.0 % with the same blocks).
  struct Case {
    const char* name;
    BakeOptions options;
    double max_excess, max_behind;
  };
  for (const Case& c : {Case{"preview", preset(Quality::kPreview), 0.095, 3.8},
                        Case{"production", preset(Quality::kProduction), 0.031, 1.6}}) {
    const FloatImage cook = room.cook({}, c.options);
    const Agreement a = agreement(cook, ref, near_panel);
    const double behind_ratio = mean_lum(cook, behind) / ref_behind;
    std::printf(
        "thin panel, %s: rel. RMSE %.2f %% (reference noise %.2f %%, own %.2f %%), bias %+.2f %%, "
        "median ratio %.3f; wall behind the panel %.4f against %.4f (x%.2f)\n",
        c.name, 100 * a.rmse, 100 * a.noise, 100 * a.excess(), 100 * a.bias, a.median,
        mean_lum(cook, behind), ref_behind, behind_ratio);
    EXPECT_LT(a.excess(), c.max_excess) << c.name;
    EXPECT_NEAR(a.median, 1.0, 0.03) << c.name;
    EXPECT_LT(std::fabs(a.bias), 0.03) << c.name;
    EXPECT_GT(behind_ratio, 0.6) << c.name;
    EXPECT_LT(behind_ratio, c.max_behind) << c.name;
  }
}

// sum over the region's interior texels (all four neighbours in it) of the discrete Laplacian's
// square, over sum of the value's square: the map's high-frequency energy.
// With `se` (the reference's standard errors), the part of that energy its noise alone accounts
// for: the Laplacian of independent noise has variance 16 se^2 + the 4 neighbours' se^2.
double laplacian_energy(const FloatImage& m, const std::vector<uint8_t>& region,
                        const FloatImage* se = nullptr) {
  double lap2 = 0.0, v2 = 0.0;
  const int w = m.width, h = m.height;
  for (int y = 1; y + 1 < h; ++y) {
    for (int x = 1; x + 1 < w; ++x) {
      const size_t t = size_t(y) * size_t(w) + size_t(x);
      if (!region[t] || !region[t - 1] || !region[t + 1] || !region[t - size_t(w)] ||
          !region[t + size_t(w)])
        continue;
      const double v = lum(m, t);
      const double lap =
          4.0 * v - lum(m, t - 1) - lum(m, t + 1) - lum(m, t - size_t(w)) - lum(m, t + size_t(w));
      if (se) {
        // The channels share their paths: the luminance's standard error is the channels' mean.
        auto var = [&](size_t u) { return double(lum(*se, u)) * lum(*se, u); };
        lap2 += 16.0 * var(t) + var(t - 1) + var(t + 1) + var(t - size_t(w)) + var(t + size_t(w));
      } else {
        lap2 += lap * lap;
      }
      v2 += v * v;
    }
  }
  return v2 > 0.0 ? lap2 / v2 : 0.0;
}

TEST(BounceQuality, ABounceLitWallIsAsSmoothAsThePathTracersAndSpeckleFails) {
  const TestRoom room(test::thin_panel_room());
  StateSpec lamp_off;
  LightOverride off;
  off.has_on = true;
  off.on = false;
  lamp_off.lights["lamp"] = off;
  // The -X wall: the spot reaches only the floor, so with the lamp off this wall has bounce light
  // only.
  const std::vector<uint8_t> wall = room.region([](glm::vec3 q, glm::vec3 n) {
    return q.x < -1.99f && n.x > 0.9f && q.y > 0.05f && q.y < 2.45f && std::fabs(q.z) < 1.95f;
  });
  const ReferenceBake ref = room.reference(lamp_off, wall, 4096);
  const double ref_hf = laplacian_energy(ref.map, wall);
  const double ref_noise_hf = laplacian_energy(ref.map, wall, &ref.std_error);
  std::printf("bounce-lit wall, path tracer: Laplacian energy %.3g, of which its noise %.3g\n",
              ref_hf, ref_noise_hf);
  struct Case {
    const char* name;
    BakeOptions options;
    bool smooth;
  };
  BakeOptions speckle = preset(Quality::kDraft);
  speckle.gather_rays = 16;
  speckle.indirect_scale = 1;
  speckle.denoise = 0;
  for (const Case& c : {Case{"preview", preset(Quality::kPreview), true},
                        Case{"production", preset(Quality::kProduction), true},
                        Case{"16 rays a texel, no denoising", speckle, false}}) {
    const FloatImage cook = room.cook(lamp_off, c.options);
    const double hf = laplacian_energy(cook, wall);
    const Agreement a = agreement(cook, ref, wall);
    std::printf(
        "bounce-lit wall, %s: Laplacian energy %.3g against the reference's %.3g (x%.2f); rel. "
        "RMSE %.2f %% (reference noise %.2f %%), bias %+.2f %%, median ratio %.3f\n",
        c.name, hf, ref_hf, hf / ref_hf, 100 * a.rmse, 100 * a.noise, 100 * a.bias, a.median);
    if (c.smooth) {
      EXPECT_LT(hf, 2.0 * ref_hf) << c.name;
      EXPECT_LT(a.excess(), 0.03) << c.name;
      EXPECT_NEAR(a.median, 1.0, 0.03) << c.name;
    } else {
      EXPECT_GT(hf, 2.0 * ref_hf) << c.name << ": the measure must see speckle";
    }
  }
}

}  // namespace
}  // namespace lightpatch::cooker
