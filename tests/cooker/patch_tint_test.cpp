// collapse_to_tint and collapse_to_two_tints (patch_extract.h): a 3-channel patch whose light has
// one colour stored as one channel and a tint, or two colours as two channels with a tint each
// (pack_format.h, PatchRecord::tint and tint_b), within its tolerance at every texel.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "patch_extract.h"

namespace lightpatch::cooker {
namespace {

// A w x h patch whose texel (x, y) is colour(x, y) * a falloff, in 3 channels.
template <typename Colour>
SourcePatch coloured(int w, int h, Colour colour) {
  SourcePatch p;
  p.channels = 3;
  p.dest = Rect{4, 6, w, h};
  p.values.resize(size_t(w) * h * 3);
  p.significant.assign(size_t(w) * h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float falloff = 8.0f / (1.0f + 0.3f * float(x * x + y * y));
      const std::array<float, 3> c = colour(x, y);
      for (int k = 0; k < 3; ++k) p.values[(size_t(y) * w + x) * 3 + k] = c[k] * falloff;
    }
  return p;
}

// The largest difference between the tinted patch's values (what the runtime adds: value times
// tint / 255 in each channel) and the 3-channel original.
double worst(const SourcePatch& tinted, const SourcePatch& original) {
  double m = 0.0;
  const size_t n = original.values.size() / 3;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const double got = double(tinted.values[i]) * (double(tinted.tint[c]) / 255.0);
      m = std::max(m, std::fabs(got - double(original.values[3 * i + size_t(c)])));
    }
  return m;
}

// Bounce light off one albedo: a falloff in one colour. It becomes one channel with the colour's
// tint (largest channel 255), and every texel stays within the tolerance.
TEST(CollapseToTint, OneColourBecomesOneChannelWithItsTint) {
  const SourcePatch original = coloured(9, 7, [](int, int) {
    return std::array<float, 3>{0.8f, 0.5f, 0.2f};
  });
  SourcePatch p = original;
  const float tolerance = 0.01f;
  ASSERT_TRUE(collapse_to_tint(p, tolerance));
  EXPECT_EQ(p.channels, 1);
  EXPECT_EQ(p.values.size(), original.values.size() / 3);
  EXPECT_EQ(p.significant, original.significant);
  EXPECT_EQ(p.tint[0], 255);
  EXPECT_EQ(p.tint[1], 159);  // 0.5 / 0.8 * 255 = 159.4
  EXPECT_EQ(p.tint[2], 64);   // 0.2 / 0.8 * 255 = 63.75
  EXPECT_LE(worst(p, original), tolerance);
  for (float v : p.values) EXPECT_GE(v, 0.0f);
}

// Two surfaces of different albedos in one patch: no one colour fits both within the tolerance,
// and the patch is left as it was.
TEST(CollapseToTint, TwoColoursStayInThreeChannels) {
  const SourcePatch original = coloured(10, 6, [](int x, int) {
    return x < 5 ? std::array<float, 3>{0.8f, 0.5f, 0.2f} : std::array<float, 3>{0.2f, 0.5f, 0.8f};
  });
  SourcePatch p = original;
  EXPECT_FALSE(collapse_to_tint(p, 0.01f));
  EXPECT_EQ(p.channels, 3);
  EXPECT_EQ(p.values, original.values);
  EXPECT_EQ(p.tint[0], 255);
  EXPECT_EQ(p.tint[1], 255);
  EXPECT_EQ(p.tint[2], 255);
}

// A colour that drifts slowly across the patch collapses at a tolerance wider than the drift
// and not at one narrower; where it collapses, the bound holds at every texel.
TEST(CollapseToTint, TheToleranceDecides) {
  const SourcePatch original = coloured(12, 12, [](int x, int y) {
    return std::array<float, 3>{0.6f, 0.45f + 0.002f * float(x + y), 0.3f};
  });
  double drift = 0.0;  // largest departure of a channel from its patch mean colour, scaled
  for (size_t i = 0; i < original.values.size(); i += 3)
    drift = std::max(drift, double(original.values[i + 1]) * 0.022 / 0.5);
  SourcePatch loose = original;
  ASSERT_TRUE(collapse_to_tint(loose, float(drift)));
  EXPECT_LE(worst(loose, original), drift);
  SourcePatch tight = original;
  EXPECT_FALSE(collapse_to_tint(tight, float(drift) * 0.05f));
  EXPECT_EQ(tight.channels, 3);
}

// Grey light collapses with tint 255, 255, 255; a patch without light, and one of one channel,
// are left alone.
TEST(CollapseToTint, GreyDarkAndOneChannelPatches) {
  SourcePatch grey = coloured(5, 5, [](int, int) { return std::array<float, 3>{1, 1, 1}; });
  ASSERT_TRUE(collapse_to_tint(grey, 1e-4f));
  EXPECT_EQ(grey.tint[0], 255);
  EXPECT_EQ(grey.tint[1], 255);
  EXPECT_EQ(grey.tint[2], 255);
  SourcePatch dark = coloured(5, 5, [](int, int) { return std::array<float, 3>{0, 0, 0}; });
  EXPECT_FALSE(collapse_to_tint(dark, 1.0f));
  EXPECT_EQ(dark.channels, 3);
  SourcePatch one = grey;
  EXPECT_FALSE(collapse_to_tint(one, 1.0f));  // already one channel
}

// A light of one colour whose green is zero (a pure magenta): the tint's zero channel stays zero
// and the others carry the light.
TEST(CollapseToTint, AZeroChannelStaysZero) {
  const SourcePatch original = coloured(6, 4, [](int, int) {
    return std::array<float, 3>{0.3f, 0.0f, 0.9f};
  });
  SourcePatch p = original;
  ASSERT_TRUE(collapse_to_tint(p, 1e-3f));
  EXPECT_EQ(p.tint[0], 85);  // 0.3 / 0.9 * 255
  EXPECT_EQ(p.tint[1], 0);
  EXPECT_EQ(p.tint[2], 255);
  EXPECT_LE(worst(p, original), 1e-3);
}

// What the runtime adds for a 2-channel patch (value 0 times tint, value 1 times tint_b), against
// the 3-channel original: the largest difference.
double worst_two(const SourcePatch& two, const SourcePatch& original) {
  double m = 0.0;
  const size_t n = original.values.size() / 3;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const double got = double(two.values[2 * i]) * (double(two.tint[c]) / 255.0) +
                         double(two.values[2 * i + 1]) * (double(two.tint_b[c]) / 255.0);
      m = std::max(m, std::fabs(got - double(original.values[3 * i + size_t(c)])));
    }
  return m;
}

// A warm light and its bounce off a blue wall, mixed in every proportion across the patch: no
// one colour holds it, two do. It becomes 2 channels whose tints are the two colours (each
// channel's largest 255), every texel within the tolerance, every value >= 0.
TEST(CollapseToTwoTints, TwoColoursInAnyBlendBecomeTwoChannels) {
  const std::array<float, 3> warm{1.0f, 0.6f, 0.2f}, blue{0.1f, 0.3f, 0.9f};
  const SourcePatch original = coloured(12, 9, [&](int x, int y) {
    const float a = float(x) / 11.0f, b = float(y) / 8.0f;
    return std::array<float, 3>{a * warm[0] + b * blue[0], a * warm[1] + b * blue[1],
                                a * warm[2] + b * blue[2]};
  });
  SourcePatch one = original;
  ASSERT_FALSE(collapse_to_tint(one, 0.01f));
  SourcePatch p = original;
  const float tolerance = 0.01f;
  ASSERT_TRUE(collapse_to_two_tints(p, tolerance));
  EXPECT_EQ(p.channels, 2);
  EXPECT_EQ(p.values.size(), original.values.size() / 3 * 2);
  EXPECT_EQ(p.significant, original.significant);
  EXPECT_LE(worst_two(p, original), tolerance);
  for (float v : p.values) EXPECT_GE(v, 0.0f);
  // The tints are the two colours, in either order.
  const bool warm_first = p.tint[2] < p.tint_b[2];
  const uint8_t* w = warm_first ? p.tint : p.tint_b;
  const uint8_t* b = warm_first ? p.tint_b : p.tint;
  EXPECT_EQ(w[0], 255);
  EXPECT_NEAR(w[1], 153, 2);  // 0.6 * 255
  EXPECT_NEAR(w[2], 51, 2);
  EXPECT_NEAR(b[0], 28, 2);  // 0.1 / 0.9 * 255
  EXPECT_NEAR(b[1], 85, 2);
  EXPECT_EQ(b[2], 255);
}

// Three colours in one patch (three lights, or three albedos): no plane holds them, and the patch
// is left as it was; a patch of one channel, or without light, too.
TEST(CollapseToTwoTints, ThreeColoursAndOtherPatchesStayAsTheyWere) {
  const SourcePatch original = coloured(12, 6, [](int x, int) {
    return x < 4   ? std::array<float, 3>{1.0f, 0.0f, 0.0f}
           : x < 8 ? std::array<float, 3>{0.0f, 1.0f, 0.0f}
                   : std::array<float, 3>{0.0f, 0.0f, 1.0f};
  });
  SourcePatch p = original;
  EXPECT_FALSE(collapse_to_two_tints(p, 0.01f));
  EXPECT_EQ(p.channels, 3);
  EXPECT_EQ(p.values, original.values);
  SourcePatch dark = coloured(5, 5, [](int, int) { return std::array<float, 3>{0, 0, 0}; });
  EXPECT_FALSE(collapse_to_two_tints(dark, 1e-3f));
  SourcePatch grey = coloured(5, 5, [](int, int) { return std::array<float, 3>{1, 1, 1}; });
  ASSERT_TRUE(collapse_to_tint(grey, 1e-4f));
  EXPECT_FALSE(collapse_to_two_tints(grey, 1.0f));  // already one channel
}

// Two colours whose blend drifts out of their plane: the tolerance decides, and where the patch
// collapses the bound holds at every texel.
TEST(CollapseToTwoTints, TheToleranceDecides) {
  const SourcePatch original = coloured(10, 10, [](int x, int y) {
    const float a = float(x) / 9.0f, b = float(y) / 9.0f;
    return std::array<float, 3>{a, 0.5f * a + 0.5f * b + 0.01f * float(x * y) / 81.0f, b};
  });
  SourcePatch loose = original;
  ASSERT_TRUE(collapse_to_two_tints(loose, 0.05f));
  EXPECT_LE(worst_two(loose, original), 0.05);
  SourcePatch tight = original;
  EXPECT_FALSE(collapse_to_two_tints(tight, 1e-4f));
  EXPECT_EQ(tight.channels, 3);
}

}  // namespace
}  // namespace lightpatch::cooker
