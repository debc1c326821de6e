// Cooker maps -> patches -> atlases -> CPU recomposition reproduces the float maps within the
// quantization bound.
//
// The bound, per texel and channel, for one map X reconstructed from its patches:
//   |X_rec - X| <= t_X + sum over X's patches covering the texel of e_enc * scale
// with t_X the significance threshold (half an 8-bit output step, divided by the light's
// authored factor for C_l and S_ol: values below it are not stored) and e_enc the encoding's
// worst case (patch_decode.h: 1/510 linear, 1/255 square). A recomposed C_l - S_ol adds the two.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/pack_builder.h"
#include "lightpatch/cooker/probes.h"
#include "lightpatch/cooker/report.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/group_rules.h"
#include "lightpatch/light_probes.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/patch_decode.h"
#include "pack_bytes.h"
#include "synthetic.h"

namespace lightpatch {
namespace {

using namespace cooker;

struct Built {
  test::Synthetic s;
  std::vector<uint8_t> bytes;
  PackView view;
  Report report;
};

void build(Built& b, const test::SyntheticOptions& o,
           EncodingPolicy policy = EncodingPolicy::kAuto) {
  b.s = test::make_synthetic(o);
  PackOptions po;
  po.encoding = policy;
  b.bytes = build_pack(b.s.scene, b.s.layout, b.s.maps, po, b.report);
  Error e;
  ASSERT_EQ(PackView::open(b.bytes.data(), b.bytes.size(), &b.view, &e), Status::kOk) << e.message;
}

float authored_factor(const Scene& scene, int scene_light) {
  float s_max = 0.0f;
  auto m3 = [](const glm::vec3& v) { return std::max({v.x, v.y, v.z}); };
  for (const Light& l : scene.lights) s_max = std::max(s_max, m3(l.color) * l.intensity);
  const Light& l = scene.lights[size_t(scene_light)];
  return std::max(m3(l.color) * l.intensity, 1e-2f * s_max);
}

// Adds the bound of `group`'s patches to `bound` (per texel).
void add_patch_bounds(const PackView& v, int32_t group, std::vector<double>& bound) {
  if (group < 0) return;
  const pack::GroupRecord& g = v.group(uint32_t(group));
  for (uint32_t i = g.first_patch; i < g.first_patch + g.patch_count; ++i) {
    const pack::PatchRecord& p = v.patch(i);
    // A 2-channel patch adds two codes' values, each times a tint of at most 1.
    const double e = double(p.scale) *
                     (p.encoding == pack::kEncodingSquare ? kSquareErrorBound : kLinearErrorBound) *
                     1.0001 * (p.channel_count == 2 ? 2.0 : 1.0);
    for (int y = p.dest_y; y < p.dest_y + p.height; ++y) {
      for (int x = p.dest_x; x < p.dest_x + p.width; ++x)
        bound[size_t(y) * v.lightmap_width() + x] += e;
    }
  }
}

void set_all(SceneState& st, const PackView& v, bool lights_on, bool objects_visible) {
  for (uint32_t l = 0; l < v.light_count(); ++l) st.set_light_on(l, lights_on);
  for (uint32_t o = 0; o < v.object_count(); ++o) st.set_object_visible(o, objects_visible);
}

uint64_t atlas_texels(const PackView& v) {
  uint64_t t = 0;
  for (uint32_t i = 0; i < v.atlas_count(); ++i)
    t += uint64_t(v.atlas(i).width) * v.atlas(i).height;
  return t;
}

// A synthetic scene packed with `po` (a: tinted patches split into the alpha plane where the
// rules say so) and with fill_alpha off (b: no patch split).
struct SplitAndWhole {
  std::vector<uint8_t> split, whole;
  Report report_split, report_whole;
  PackView a, b;
};

void build_split_and_whole(const test::Synthetic& s, PackOptions po, SplitAndWhole& out) {
  out.split = build_pack(s.scene, s.layout, s.maps, po, out.report_split);
  po.fill_alpha = false;
  out.whole = build_pack(s.scene, s.layout, s.maps, po, out.report_whole);
  ASSERT_EQ(PackView::open(out.split.data(), out.split.size(), &out.a, nullptr), Status::kOk);
  ASSERT_EQ(PackView::open(out.whole.data(), out.whole.size(), &out.b, nullptr), Status::kOk);
}

// Packs `a` and `b` of the same maps recompose every state to the same bits: rebuilds with all
// lights on or off and all objects visible or hidden, then light changes through the incremental
// path (recoloured, dimmed, switched off).
void expect_same_recomposition(const PackView& a, const PackView& b) {
  SceneState st;
  CpuRecomposer ra, rb;
  ASSERT_EQ(st.init(a, nullptr), Status::kOk);
  ASSERT_EQ(ra.init(a, nullptr), Status::kOk);
  ASSERT_EQ(rb.init(b, nullptr), Status::kOk);
  const size_t n = size_t(ra.width()) * ra.height() * 3;
  for (int state = 0; state < 4; ++state) {
    set_all(st, a, (state & 1) != 0, (state & 2) != 0);
    ASSERT_EQ(ra.rebuild(st), Status::kOk);
    ASSERT_EQ(rb.rebuild(st), Status::kOk);
    EXPECT_TRUE(std::equal(ra.rgb(), ra.rgb() + n, rb.rgb())) << "state " << state;
  }
  // Light changes through the incremental path: recoloured, dimmed, switched off.
  for (uint32_t l = 0; l < a.light_count(); ++l) {
    const float rgb[3] = {0.2f + 0.2f * float(l), 1.0f, 0.5f};
    ASSERT_EQ(st.set_light_color(l, rgb), Status::kOk);
    ASSERT_EQ(st.set_light_intensity(l, 0.5f + float(l)), Status::kOk);
    ASSERT_EQ(ra.apply(st), Status::kOk);
    ASSERT_EQ(rb.apply(st), Status::kOk);
    EXPECT_TRUE(std::equal(ra.rgb(), ra.rgb() + n, rb.rgb())) << "light " << l;
    ASSERT_EQ(st.set_light_on(l, false), Status::kOk);
    ASSERT_EQ(ra.apply(st), Status::kOk);
    ASSERT_EQ(rb.apply(st), Status::kOk);
    EXPECT_TRUE(std::equal(ra.rgb(), ra.rgb() + n, rb.rgb())) << "light " << l << " off";
  }
}

// Compares the recomposed map against `expected(x, y, c)` within bound + slack; returns the
// largest error seen.
template <typename F>
double expect_within(const CpuRecomposer& r, const std::vector<double>& bound, F expected,
                     const char* what) {
  double worst = 0.0;
  int failures = 0;
  for (uint32_t y = 0; y < r.height(); ++y) {
    for (uint32_t x = 0; x < r.width(); ++x) {
      for (int c = 0; c < 3; ++c) {
        const double want = expected(int(x), int(y), c);
        const double got = r.rgb()[(size_t(y) * r.width() + x) * 3 + c];
        const double err = std::fabs(got - want);
        worst = std::max(worst, err);
        const double b = bound[size_t(y) * r.width() + x] + 1e-6 * std::fabs(want) + 1e-9;
        if (err > b && failures++ < 5) {
          ADD_FAILURE() << what << ": texel (" << x << "," << y << ") channel " << c << ": got "
                        << got << ", want " << want << ", bound " << b;
        }
      }
    }
  }
  return worst;
}

class RoundTrip : public ::testing::TestWithParam<EncodingPolicy> {};

TEST_P(RoundTrip, RecomposedMapsMatchTheFloatMapsWithinTheQuantizationBound) {
  Built b;
  build(b, test::SyntheticOptions{}, GetParam());
  const PackView& v = b.view;
  const BakedMaps& maps = b.s.maps;
  const size_t n = size_t(v.lightmap_width()) * v.lightmap_height();
  SceneState st;
  CpuRecomposer r;
  ASSERT_EQ(st.init(v, nullptr), Status::kOk);
  ASSERT_EQ(r.init(v, nullptr), Status::kOk);

  // Base: every light off.
  set_all(st, v, false, true);
  r.rebuild(st);
  std::vector<double> base_bound(n, 0.5 * maps.output_step);
  add_patch_bounds(v, v.base_group(), base_bound);
  const double base_err = expect_within(
      r, base_bound, [&](int x, int y, int c) { return maps.base.at(x, y, c); }, "base");
  EXPECT_GT(base_err, 0.0);  // 8 bits cannot be exact on a gradient: the test measures something

  for (uint32_t l = 0; l < v.light_count(); ++l) {
    const FloatImage& cm = maps.contribution[l];
    const double t = 0.5 * maps.output_step / authored_factor(b.s.scene, maps.lights[l]);
    std::vector<double> cb(n, t);
    add_patch_bounds(v, v.contribution_group(l), cb);
    const float white[3] = {1, 1, 1};
    // C_l alone: this light on (white, intensity 1), all objects hidden; subtract the base.
    set_all(st, v, false, false);
    st.set_light_on(l, true);
    st.set_light_color(l, white);
    st.set_light_intensity(l, 1.0f);
    r.rebuild(st);
    std::vector<double> with_base = cb;
    for (size_t i = 0; i < n; ++i) with_base[i] += base_bound[i];
    expect_within(
        r, with_base,
        [&](int x, int y, int c) {
          return double(maps.base.at(x, y, c)) + cm.at(x, y, cm.channels == 3 ? c : 0);
        },
        "contribution");
    for (uint32_t o = 0; o < v.object_count(); ++o) {
      const ShadowMap* sm = nullptr;
      for (const ShadowMap& s : maps.shadows) {
        if (s.light == int(l) && s.object == int(o)) sm = &s;
      }
      if (sm == nullptr) {
        EXPECT_LT(v.shadow_group(l, o), 0);
        continue;
      }
      // A pack holds a shadow group exactly when the shadow map has a significant texel.
      bool significant = false;
      for (float x : sm->map.data) significant = significant || std::fabs(x) > t;
      EXPECT_EQ(significant, v.shadow_group(l, o) >= 0) << "light " << l << " object " << o;
      std::vector<double> sb = with_base;
      for (size_t i = 0; i < n; ++i) sb[i] += t;
      add_patch_bounds(v, v.shadow_group(l, o), sb);
      st.set_object_visible(o, true);
      r.rebuild(st);
      expect_within(
          r, sb,
          [&](int x, int y, int c) {
            const int k = cm.channels == 3 ? c : 0;
            return double(maps.base.at(x, y, c)) + cm.at(x, y, k) - sm->map.at(x, y, k);
          },
          "contribution minus shadow");
      st.set_object_visible(o, false);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Encodings, RoundTrip,
                         ::testing::Values(EncodingPolicy::kAuto, EncodingPolicy::kLinear,
                                           EncodingPolicy::kSquare));

TEST(PackBuilder, ReportsMeasuredErrorsAndTheChosenEncodingIsNoWorse) {
  Built b;
  build(b, test::SyntheticOptions{});
  const auto& enc = b.report.root()["pack"]["encoding"];
  const double lin = enc["linear"]["relative_rmse"].get<double>();
  const double sq = enc["square"]["relative_rmse"].get<double>();
  const double chosen = enc["chosen"]["relative_rmse"].get<double>();
  EXPECT_GT(lin, 0.0);
  EXPECT_GT(sq, 0.0);
  // Per patch the smaller squared error is kept, so the total cannot exceed either candidate.
  EXPECT_LE(chosen, std::min(lin, sq) * (1 + 1e-9));
  EXPECT_LT(chosen, 0.01);  // well inside the 1% relative RMSE bar
  EXPECT_EQ(enc["patches_linear"].get<int>() + enc["patches_square"].get<int>(),
            b.report.root()["pack"]["patches"].get<int>());
  const double ratio = b.report.root()["pack"]["atlas_to_lightmap_ratio"].get<double>();
  EXPECT_GT(ratio, 0.0);
  RecordProperty("linear_relative_rmse", std::to_string(lin));
  RecordProperty("square_relative_rmse", std::to_string(sq));
  RecordProperty("chosen_relative_rmse", std::to_string(chosen));
  RecordProperty("atlas_to_lightmap_ratio", std::to_string(ratio));
}

TEST(PackBuilder, PatchesFollowRegionsSignsAndGroups) {
  Built b;
  build(b, test::SyntheticOptions{});
  const PackView& v = b.view;
  // The black region (bottom-right) carries no base patch; no patch crosses two regions.
  const auto& regions = b.s.layout.regions;
  int negative = 0;
  for (uint32_t i = 0; i < v.patch_count(); ++i) {
    const pack::PatchRecord& p = v.patch(i);
    const Rect r{p.dest_x, p.dest_y, p.width, p.height};
    int inside = 0;
    for (const Region& g : regions) {
      if (r.x >= g.rect.x && r.y >= g.rect.y && r.x + r.w <= g.rect.x + g.rect.w &&
          r.y + r.h <= g.rect.y + g.rect.h) {
        ++inside;
        if (&g == &regions[3]) {
          EXPECT_NE(v.group(p.group).kind, pack::kGroupBase);
        }
      }
    }
    EXPECT_EQ(inside, 1) << "patch " << i;
    negative += (p.flags & pack::kFlagNegative) ? 1 : 0;
    if (p.flags & pack::kFlagNegative) {
      EXPECT_EQ(v.group(p.group).kind, pack::kGroupShadow);
    }
  }
  EXPECT_GT(negative, 0);  // the bounce rims are kept, not clipped
  // Light 0 is tinted, in one colour (1, 0.8, 0.6): its patches are 1-channel with that colour
  // as their tint (255, 204, 153), or 3-channel where the tint exceeds half an output step and
  // one colour does not fit (decided per patch); the others 1-channel and grey; the base map
  // 3-channel, split into its three channels apart (each drawing into its own map channel), or
  // 1-channel with a tint where one colour fits a piece.
  int tinted = 0;
  for (uint32_t i = 0; i < v.patch_count(); ++i) {
    const pack::PatchRecord& p = v.patch(i);
    const pack::GroupRecord& g = v.group(p.group);
    if (g.kind == pack::kGroupBase) {
      EXPECT_TRUE(p.channel_count == 3 ||
                  (p.channel_count == 1 &&
                   (pack::patch_destination(p.flags) >= 0 || pack::patch_has_tint(p))));
    } else if (g.light == 0) {
      EXPECT_TRUE(p.channel_count == 3 || p.channel_count == 1);
      if (p.channel_count == 1 && pack::patch_has_tint(p)) {
        ++tinted;
        EXPECT_EQ(p.tint[0], 255) << "patch " << i;
        EXPECT_EQ(p.tint[1], 204) << "patch " << i;
        EXPECT_EQ(p.tint[2], 153) << "patch " << i;
      }
    } else {
      EXPECT_EQ(p.channel_count, 1);
      EXPECT_FALSE(pack::patch_has_tint(p)) << "patch " << i;
    }
  }
  EXPECT_GT(tinted, 0);
  EXPECT_EQ(v.mesh_count(), 4u);
  EXPECT_TRUE(v.mesh_name(2).equals("region_2", 8));
  EXPECT_EQ(v.mesh(0).object, 0);
  EXPECT_EQ(v.mesh(3).object, pack::kNone16);
}

// Patches touch in the atlas (no gutter): what lies around a patch never reaches the map. Every
// channel-texel no patch covers is overwritten with garbage and every state of lights and objects
// recomposes to the same bits.
TEST(PackBuilder, UnusedAtlasTexelsNeverReachTheMap) {
  Built b;
  build(b, test::SyntheticOptions{});
  test::Aligned copy(b.bytes, b.bytes.size());
  const uint64_t filled = test::fill_unused_atlas_texels(b.view, b.bytes.data(), copy.data(), 7u);
  EXPECT_GT(filled, 0u);
  PackView garbage;
  Error e;
  ASSERT_EQ(PackView::open(copy.data(), copy.size, &garbage, &e), Status::kOk) << e.message;
  SceneState st;
  CpuRecomposer clean, dirty;
  ASSERT_EQ(st.init(b.view, nullptr), Status::kOk);
  ASSERT_EQ(clean.init(b.view, nullptr), Status::kOk);
  ASSERT_EQ(dirty.init(garbage, nullptr), Status::kOk);
  const size_t n = size_t(clean.width()) * clean.height() * 3;
  for (int state = 0; state < 4; ++state) {
    set_all(st, b.view, (state & 1) != 0, (state & 2) != 0);
    ASSERT_EQ(clean.rebuild(st), Status::kOk);
    ASSERT_EQ(dirty.rebuild(st), Status::kOk);
    EXPECT_TRUE(std::equal(clean.rgb(), clean.rgb() + n, dirty.rgb())) << "state " << state;
  }
}

// Tinted patches of the groups without a light stored as three 1-channel patches (one map
// channel each) fill the alpha plane that 3-channel patches leave empty: with every light's
// patches kept tinted and only the tinted light (few grey patches), part of the base map is split,
// the atlases shrink, and every state recomposes to the same bits as the pack without the split.
TEST(PackBuilder, SplittingTintedPatchesFillsTheAlphaPlaneAndRecomposesTheSame) {
  test::SyntheticOptions o;
  o.lights = 1;
  test::Synthetic s = test::make_synthetic(o);
  PackOptions po;
  po.keep_colour = true;
  po.tile_size = 8;  // base tiles small enough to split some
  SplitAndWhole packs;
  ASSERT_NO_FATAL_FAILURE(build_split_and_whole(s, po, packs));
  const PackView &a = packs.a, &b = packs.b;
  uint32_t one_channel_destinations = 0;
  for (uint32_t i = 0; i < a.patch_count(); ++i) {
    const int d = pack::patch_destination(a.patch(i).flags);
    if (d < 0) continue;
    ++one_channel_destinations;
    EXPECT_EQ(a.patch(i).channel_count, 1);
    EXPECT_FALSE(group_has_light(a.group(a.patch(i).group).kind));
  }
  const int split_patches =
      packs.report_split.root()["pack"]["split_for_alpha"]["patches"].get<int>();
  std::printf("%d patches split, atlas texels %llu -> %llu\n", split_patches,
              static_cast<unsigned long long>(atlas_texels(b)),
              static_cast<unsigned long long>(atlas_texels(a)));
  EXPECT_GT(split_patches, 0);
  EXPECT_EQ(one_channel_destinations, 3u * uint32_t(split_patches));
  EXPECT_EQ(a.patch_count(), b.patch_count() + 2u * uint32_t(split_patches));
  EXPECT_LT(atlas_texels(a), atlas_texels(b));
  expect_same_recomposition(a, b);
}

// Where tinted light contributions dominate (bounce light tinted by the albedos, as in the inns;
// here 16 tinted lights, like the full inn's 17), the base map's split patches fill only part of
// the alpha plane the 3-channel patches leave empty (15 % of the atlas bytes stayed empty when
// only they were split). Contribution patches are split too, from the light whose change draws
// the fewest texels, never beyond the costliest light change of the unsplit pack, where that
// takes fewer atlas bytes (the committed small.lpk, whose patches are large against its atlas,
// gains nothing and splits none). The atlases hold the patches with little waste and fewer
// bytes, no light change draws more texels than the costliest one did, the shadows (drawn on
// object toggles) stay whole, and every state, rebuilt or reached through light changes,
// recomposes to the same bits as the pack without the split.
TEST(PackBuilder, TintedContributionsFillTheAlphaPlaneWithinTheCostliestLightChange) {
  test::SyntheticOptions o;
  o.width = 96;
  o.height = 80;
  o.lights = 16;
  o.tinted_lights = 16;
  test::Synthetic s = test::make_synthetic(o);
  PackOptions po;
  po.keep_colour = true;
  po.tile_size = 8;
  SplitAndWhole packs;
  ASSERT_NO_FATAL_FAILURE(build_split_and_whole(s, po, packs));
  const PackView &a = packs.a, &b = packs.b;
  auto atlas_bytes = [](const PackView& v) { return 4 * atlas_texels(v); };
  auto patch_bytes = [](const PackView& v) {
    uint64_t t = 0;
    for (uint32_t i = 0; i < v.patch_count(); ++i)
      t += uint64_t(v.patch(i).width) * v.patch(i).height * v.patch(i).channel_count;
    return t;
  };
  // Texels drawn by the groups of a light (its change, every object visible).
  auto light_change = [](const PackView& v, uint32_t light) {
    uint64_t t = 0;
    for (uint32_t i = 0; i < v.patch_count(); ++i) {
      const pack::GroupRecord& g = v.group(v.patch(i).group);
      if (group_has_light(g.kind) && g.light == light)
        t += uint64_t(v.patch(i).width) * v.patch(i).height;
    }
    return t;
  };
  const double waste_split = 1.0 - double(patch_bytes(a)) / double(atlas_bytes(a));
  const double waste_whole = 1.0 - double(patch_bytes(b)) / double(atlas_bytes(b));
  int lit_split = 0;  // contribution patches stored a channel at a time
  for (uint32_t i = 0; i < a.patch_count(); ++i) {
    const uint16_t kind = a.group(a.patch(i).group).kind;
    if (pack::patch_destination(a.patch(i).flags) == 0)
      lit_split += kind == pack::kGroupContribution;
    if (pack::patch_destination(a.patch(i).flags) >= 0) {
      EXPECT_TRUE(kind == pack::kGroupContribution || !group_has_light(kind)) << "patch " << i;
    }
  }
  std::printf("%d contribution patches split; atlas bytes %llu -> %llu, waste %.1f %% -> %.1f %%\n",
              lit_split, static_cast<unsigned long long>(atlas_bytes(b)),
              static_cast<unsigned long long>(atlas_bytes(a)), 100.0 * waste_whole,
              100.0 * waste_split);
  EXPECT_GT(lit_split, 0);
  EXPECT_LE(waste_split, 0.05);
  EXPECT_LT(atlas_bytes(a), atlas_bytes(b));
  EXPECT_EQ(patch_bytes(a), patch_bytes(b));
  uint64_t costliest_split = 0, costliest_whole = 0;
  bool some_light_pays_more = false;
  for (uint32_t l = 0; l < a.light_count(); ++l) {
    costliest_split = std::max(costliest_split, light_change(a, l));
    costliest_whole = std::max(costliest_whole, light_change(b, l));
    some_light_pays_more = some_light_pays_more || light_change(a, l) > light_change(b, l);
  }
  EXPECT_TRUE(some_light_pays_more);
  EXPECT_EQ(costliest_split, costliest_whole);
  ASSERT_EQ(a.group_count(), b.group_count());
  for (uint32_t g = 0; g < a.group_count(); ++g) {
    const uint16_t kind = a.group(g).kind;
    if (kind == pack::kGroupShadow || kind == pack::kGroupPairCorrection) {
      EXPECT_EQ(a.group(g).patch_count, b.group(g).patch_count) << "group " << g;
    }
  }
  expect_same_recomposition(a, b);
}

// Atlas sides are multiples of 4, and the atlases come close to the fewest texels that can hold
// the patches: a quarter of their channel-texels, and at least one texel per texel of the
// 3-channel patches (each takes channels 0-2 of its rectangle). The synthetic pack's patches are
// large against its atlas, so rounding shows more than in a cooked scene's.
TEST(PackBuilder, AtlasesAreMultiplesOfFourNearTheLowerBound) {
  Built b;
  build(b, test::SyntheticOptions{});
  const PackView& v = b.view;
  uint64_t texels = 0, channel_texels = 0, rgb = 0;
  for (uint32_t a = 0; a < v.atlas_count(); ++a) {
    EXPECT_EQ(v.atlas(a).width % pack::kAtlasAlign, 0u);
    EXPECT_EQ(v.atlas(a).height % pack::kAtlasAlign, 0u);
    texels += uint64_t(v.atlas(a).width) * v.atlas(a).height;
  }
  for (uint32_t i = 0; i < v.patch_count(); ++i) {
    const uint64_t t = uint64_t(v.patch(i).width) * v.patch(i).height;
    channel_texels += t * v.patch(i).channel_count;
    if (v.patch(i).channel_count == 3) rgb += t;
  }
  const uint64_t bound = std::max(rgb, (channel_texels + 3) / 4);
  std::printf("%u atlases, %llu texels, lower bound %llu, waste %.1f %%\n", v.atlas_count(),
              static_cast<unsigned long long>(texels), static_cast<unsigned long long>(bound),
              100.0 * (1.0 - double(channel_texels) / double(4 * texels)));
  EXPECT_LE(double(texels), 1.15 * double(bound));
}

TEST(PackBuilder, RejectsBadInput) {
  test::Synthetic s = test::make_synthetic(test::SyntheticOptions{});
  Report report;
  s.maps.contribution[1].at(5, 5, 0) = NAN;
  EXPECT_THROW(build_pack(s.scene, s.layout, s.maps, PackOptions{}, report), CookError);
  s = test::make_synthetic(test::SyntheticOptions{});
  s.maps.shadows[0].object = 7;
  EXPECT_THROW(build_pack(s.scene, s.layout, s.maps, PackOptions{}, report), CookError);
  s = test::make_synthetic(test::SyntheticOptions{});
  s.maps.base = FloatImage(4, 4, 3);
  EXPECT_THROW(build_pack(s.scene, s.layout, s.maps, PackOptions{}, report), CookError);
  s = test::make_synthetic(test::SyntheticOptions{});
  PackOptions bad;
  bad.max_atlas_size = 102;  // not a multiple of 4
  EXPECT_THROW(build_pack(s.scene, s.layout, s.maps, bad, report), CookError);
}

TEST(PackBuilder, LargePatchesAreTiledToTheMaximumAtlasSize) {
  test::SyntheticOptions o;
  o.width = 80;
  o.height = 80;
  test::Synthetic s = test::make_synthetic(o);
  Report report;
  PackOptions po;
  po.max_atlas_size = 16;  // regions are 38 texels wide: base patches must be cut into tiles
  const std::vector<uint8_t> bytes = build_pack(s.scene, s.layout, s.maps, po, report);
  PackView v;
  ASSERT_EQ(PackView::open(bytes.data(), bytes.size(), &v, nullptr), Status::kOk);
  EXPECT_GT(v.atlas_count(), 1u);
  for (uint32_t i = 0; i < v.atlas_count(); ++i) EXPECT_LE(v.atlas(i).width, 16u);
  SceneState st;
  CpuRecomposer r;
  ASSERT_EQ(st.init(v, nullptr), Status::kOk);
  ASSERT_EQ(r.init(v, nullptr), Status::kOk);
  set_all(st, v, false, true);
  r.rebuild(st);
  std::vector<double> bound(size_t(80) * 80, 0.5 * s.maps.output_step);
  add_patch_bounds(v, v.base_group(), bound);
  expect_within(
      r, bound, [&](int x, int y, int c) { return s.maps.base.at(x, y, c); }, "tiled base");
}

// A probe bake through the pack builder: sets sorted by owner (given in any order), empty ones
// dropped, names in the strings, the grid and its indices, every coefficient as baked; the
// report's "probes" counts; two sets of one owner refused.
TEST(RoundTrip, ProbesArePackedSortedAndReported) {
  test::SyntheticOptions o;
  test::Synthetic s = test::make_synthetic(o);
  ASSERT_GE(s.maps.lights.size(), 2u);
  ASSERT_GE(s.scene.objects.size(), 1u);
  ProbeBake bake;
  for (int i = 0; i < 5; ++i) {
    ProbeBake::Probe p;
    p.position = glm::vec3(0.5f * float(i % 2), 1.0f, 0.5f * float(i / 2));
    for (float& r : p.reach) r = 0.5f;
    if (i == 4) p.name = "hand_probe";
    bake.probes.push_back(p);
  }
  bake.has_grid = true;
  bake.grid_origin = glm::vec3(0.0f, 1.0f, 0.0f);
  bake.grid_spacing = 0.5f;
  bake.grid_size = glm::ivec3(2, 1, 3);
  bake.grid_index = {0, 1, 2, 3, pack::kNone32, pack::kNone32};
  auto entry = [](uint32_t probe, float v) {
    pack::ProbeEntry e{};
    e.probe = probe;
    for (uint32_t k = 0; k < kProbeShFloats; ++k) e.sh[k] = v + 0.01f * float(k);
    return e;
  };
  auto add_set = [&](uint16_t kind, int light, int object, std::vector<pack::ProbeEntry> e) {
    ProbeBake::Set set;
    set.kind = kind;
    set.light = light;
    set.object = object;
    set.entries = std::move(e);
    bake.sets.push_back(set);
  };
  add_set(pack::kGroupShadow, 1, 0, {entry(2, -0.5f)});
  add_set(pack::kGroupContribution, 1, -1, {entry(0, 2.0f), entry(3, 1.0f)});
  add_set(pack::kGroupContribution, 0, -1, {});  // reaches nothing: dropped
  add_set(pack::kGroupBase, -1, -1, {entry(0, 1.0f), entry(1, 1.0f), entry(4, 3.0f)});
  add_set(pack::kGroupStaticShadow, -1, 0, {entry(4, -0.25f)});
  Report report;
  const std::vector<uint8_t> bytes =
      build_pack(s.scene, s.layout, s.maps, PackOptions{}, report, &bake);
  PackView v;
  Error e;
  ASSERT_EQ(PackView::open(bytes.data(), bytes.size(), &v, &e), Status::kOk) << e.message;
  ASSERT_EQ(v.probe_count(), 5u);
  EXPECT_EQ(v.find_probe("hand_probe", 10), 4);
  EXPECT_EQ(v.probe_name(0).length, 0u);
  ASSERT_TRUE(v.has_probe_grid());
  EXPECT_EQ(v.probe_grid().size[2], 3u);
  EXPECT_EQ(v.probe_grid_indices()[4], pack::kNone32);
  ASSERT_EQ(v.probe_set_count(), 4u);
  const uint16_t kinds[4] = {pack::kGroupBase, pack::kGroupContribution, pack::kGroupShadow,
                             pack::kGroupStaticShadow};
  for (uint32_t i = 0; i < 4; ++i) EXPECT_EQ(v.probe_set(i).kind, kinds[i]) << i;
  EXPECT_EQ(v.probe_set(1).light, 1u);
  EXPECT_EQ(v.probe_set(1).object_a, pack::kNone16);
  EXPECT_EQ(v.probe_set(2).object_a, 0u);
  EXPECT_EQ(v.probe_set(3).light, pack::kNone16);
  ASSERT_EQ(v.probe_entry_count(), 7u);
  EXPECT_EQ(v.probe_entry(v.probe_set(1).first_entry + 1).probe, 3u);
  EXPECT_EQ(v.probe_entry(v.probe_set(0).first_entry + 2).sh[26], 3.0f + 0.01f * 26.0f);
  const nlohmann::json& j = report.root()["pack"]["probes"];
  EXPECT_EQ(j["count"], 5);
  EXPECT_EQ(j["named"], 1);
  EXPECT_EQ(j["sets"], 4);
  EXPECT_EQ(j["entries"], 7);
  EXPECT_EQ(j["grid"]["points_with_probe"], 4);
  EXPECT_EQ(j["bytes"], v.probe_bytes());

  add_set(pack::kGroupBase, -1, -1, {entry(2, 1.0f)});
  Report again;
  EXPECT_THROW(build_pack(s.scene, s.layout, s.maps, PackOptions{}, again, &bake), CookError);
}

}  // namespace
}  // namespace lightpatch
