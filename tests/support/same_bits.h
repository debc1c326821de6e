// Two cooker float images equal bit for bit (-0.0 and NaN payloads included): what a store that
// claims to give an image back, or a file that round-trips one, must keep.
#pragma once

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>

#include "lightpatch/cooker/maps.h"

namespace lightpatch::test {

inline void expect_same_bits(const cooker::FloatImage& a, const cooker::FloatImage& b) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  ASSERT_EQ(a.channels, b.channels);
  ASSERT_EQ(a.data.size(), b.data.size());
  for (size_t i = 0; i < a.data.size(); ++i)
    ASSERT_EQ(std::bit_cast<uint32_t>(a.data[i]), std::bit_cast<uint32_t>(b.data[i])) << i;
}

}  // namespace lightpatch::test
