// TiledImage (maps.h): a pane's maps held without their all-zero tiles, given back bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/maps.h"
#include "support/same_bits.h"

namespace lightpatch::cooker {
namespace {

uint32_t bits(float v) {
  uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// A page whose sides are not whole tiles, lit in one corner region and at a few single texels:
// -0.0 and NaN (whose bits are not zero) among them, as a map may carry them.
FloatImage lit_corner(int channels) {
  const int s = TiledImage::kSide;
  FloatImage m(5 * s + 3, 4 * s + 7, channels);
  for (int y = s + 2; y < 2 * s + 5; ++y)
    for (int x = 2 * s - 3; x < 3 * s + 1; ++x)
      for (int c = 0; c < channels; ++c) m.at(x, y, c) = 0.01f * float(x + 3 * y + c);
  m.at(5 * s + 2, 4 * s + 6, channels - 1) = 2.5f;  // the last texel, in a partial tile
  m.at(0, 4 * s + 1, 0) = -0.0f;
  m.at(4 * s + 1, 0, 0) = std::numeric_limits<float>::quiet_NaN();
  return m;
}

TEST(TiledImage, GivesBackTheImageBitForBitAndKeepsOnlyTheLitTiles) {
  for (int channels : {1, 3}) {
    const FloatImage m = lit_corner(channels);
    const TiledImage t(m);
    lightpatch::test::expect_same_bits(t.dense(), m);
    EXPECT_EQ(t.width(), m.width);
    EXPECT_EQ(t.height(), m.height);
    EXPECT_EQ(t.channels(), channels);
    // The lit region crosses 2 x 3 tiles (x 1..3 and y 1..2 of tiles), and the last texel, the
    // -0.0 and the NaN one tile each.
    const size_t tile = size_t(TiledImage::kSide) * TiledImage::kSide * size_t(channels);
    EXPECT_EQ(t.stored_floats(), (3 * 2 + 3) * tile);
    EXPECT_LT(t.stored_floats(), m.data.size());
    // Every texel reads as in the image, a texel of a dropped tile as null.
    for (int y = 0; y < m.height; ++y) {
      for (int x = 0; x < m.width; ++x) {
        const float* v = t.texel(x, y);
        for (int c = 0; c < channels; ++c) {
          const float want = m.at(x, y, c);
          if (!v) {
            ASSERT_EQ(bits(want), 0u) << x << ", " << y;
          } else {
            ASSERT_EQ(bits(v[c]), bits(want)) << x << ", " << y;
          }
        }
      }
    }
    EXPECT_EQ(t.texel(0, 0), nullptr);
    // The peak ignores NaN, as a scan of the dense image from 0 does.
    EXPECT_EQ(t.peak(), 2.5f);
  }
}

TEST(TiledImage, AnImageOfZerosHoldsNothingAndAnEmptyOneStaysEmpty) {
  const FloatImage zeros(40, 33, 3);
  const TiledImage t(zeros);
  EXPECT_FALSE(t.empty());
  EXPECT_EQ(t.stored_floats(), 0u);
  EXPECT_EQ(t.peak(), 0.0f);
  lightpatch::test::expect_same_bits(t.dense(), zeros);

  const TiledImage none{FloatImage{}};
  EXPECT_TRUE(none.empty());
  EXPECT_TRUE(none.dense().data.empty());

  FloatImage wrong(4, 4, 3);
  wrong.data.pop_back();
  EXPECT_THROW(TiledImage{wrong}, CookError);
}

}  // namespace
}  // namespace lightpatch::cooker
