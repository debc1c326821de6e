// The job result format (group_file.h): maps and decisions come back bit for bit, and a file cut
// short, altered or crafted to lie is refused with a message, never read past its end.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/group_file.h"
#include "lightpatch/pack_view.h"
#include "support/same_bits.h"

namespace lightpatch::test {
namespace {

using namespace lightpatch::cooker;

constexpr int kW = 9, kH = 5;
const std::array<uint8_t, 16> kHash = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};

// A map with values in one corner, a negative value, -0.0 (nonzero bits) and a denormal.
FloatImage corner_map(int channels, float scale) {
  FloatImage m(kW, kH, channels);
  for (int y = 1; y < 4; ++y)
    for (int x = 2; x < 6; ++x)
      for (int c = 0; c < channels; ++c) m.at(x, y, c) = scale * float(1 + x + 10 * y + 100 * c);
  m.at(3, 2, 0) = -0.25f;
  m.at(4, 2, 0) = -0.0f;
  m.at(5, 1, 0) = std::numeric_limits<float>::denorm_min();
  m.at(2, 3, 0) = 0.0f;  // a zero inside the rectangle
  return m;
}

// An indirect part: the block image of a layout with 2 x 2 blocks (kW / 2 x kH / 2, 3 channels).
constexpr int kBlocksW = kW / 2, kBlocksH = kH / 2;
FloatImage block_image(float scale) {
  FloatImage m(kBlocksW, kBlocksH, 3);
  for (int y = 0; y < kBlocksH; ++y)
    for (int x = 1; x < kBlocksW; ++x)
      for (int c = 0; c < 3; ++c) m.at(x, y, c) = scale * float(1 + x + 10 * y + 100 * c);
  return m;
}

GroupBake light_group() {
  GroupBake g;
  g.group = 2;
  g.seconds = 1.5;
  g.map = corner_map(3, 0.5f);
  g.indirect = block_image(0.25f);
  // The first shadow has a direct part (ShadowMap::direct; one channel in a light group).
  g.shadows.push_back({1, 0, corner_map(1, 0.01f), {}, corner_map(1, 0.004f)});
  g.shadows.push_back({1, 3, FloatImage(kW, kH, 3), block_image(-0.5f), {}});  // map all zero
  g.pair_corrections.push_back({1, 0, 3, corner_map(3, -0.02f), {}, {}});
  Decision d;
  d.kind = DecisionKind::kOverlap;
  d.stage = DecisionStage::kTraced;
  d.light = 4;
  d.object = 0;
  d.object_b = 3;
  d.taken = true;
  d.reason = "overlap peak 0.1 above half an output step";
  d.value = 0.1;
  d.bound = 0.05;
  g.decisions.push_back(d);
  Decision n;  // NaN measurements, no reason
  n.kind = DecisionKind::kTripleOverlap;
  n.light = 4;
  g.decisions.push_back(n);
  return g;
}

GroupFileExpect expect_for(const GroupBake& g) {
  GroupFileExpect e;
  e.job_hash = kHash;
  e.group = g.group;
  e.width = kW;
  e.height = kH;
  e.indirect_width = kBlocksW;
  e.indirect_height = kBlocksH;
  e.objects = 4;
  e.lights = 6;
  e.max_maps = 8;
  return e;
}

// Rewrites the file's crc after an edit, so that the reader's own checks are what refuses it.
void reseal(std::vector<uint8_t>& f) {
  GroupFileHeader h;
  std::memcpy(&h, f.data(), sizeof h);
  h.crc = 0;
  std::memcpy(f.data(), &h, sizeof h);
  h.crc = crc32(f.data(), f.size());
  std::memcpy(f.data(), &h, sizeof h);
}

// The offset after the record at `at` and its mask and values.
size_t after_record(const std::vector<uint8_t>& f, size_t at) {
  MapRecord r;
  std::memcpy(&r, f.data() + at, sizeof r);
  const size_t n = size_t(r.rect_w) * r.rect_h * r.channels;
  return at + sizeof r + (n + 7) / 8 + r.nonzero * sizeof(float);
}

std::string refusal(const std::vector<uint8_t>& f, const GroupFileExpect& e) {
  try {
    decode_group(f.data(), f.size(), e);
  } catch (const CookError& err) {
    return err.what();
  }
  return "";
}

// The reader's refusal of `f` with the map record at `at` changed by `change` (and resealed).
template <typename F>
std::string refusal_of_edit(const std::vector<uint8_t>& f, size_t at, const GroupFileExpect& e,
                            F&& change) {
  std::vector<uint8_t> bad = f;
  MapRecord r;
  std::memcpy(&r, bad.data() + at, sizeof r);
  change(r);
  std::memcpy(bad.data() + at, &r, sizeof r);
  reseal(bad);
  return refusal(bad, e);
}

TEST(GroupFile, LightGroupRoundTripsBitForBit) {
  const GroupBake g = light_group();
  const std::vector<uint8_t> f = encode_group(g, kHash);
  const GroupBake back = decode_group(f.data(), f.size(), expect_for(g));
  EXPECT_EQ(back.group, g.group);
  EXPECT_EQ(back.seconds, g.seconds);
  expect_same_bits(back.map, g.map);
  expect_same_bits(back.indirect, g.indirect);
  ASSERT_EQ(back.shadows.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back.shadows[i].light, g.shadows[i].light);
    EXPECT_EQ(back.shadows[i].object, g.shadows[i].object);
    expect_same_bits(back.shadows[i].map, g.shadows[i].map);
    expect_same_bits(back.shadows[i].indirect, g.shadows[i].indirect);
    expect_same_bits(back.shadows[i].direct, g.shadows[i].direct);
  }
  EXPECT_FALSE(back.shadows[0].direct.data.empty());
  EXPECT_TRUE(back.pair_corrections[0].direct.data.empty());
  EXPECT_TRUE(back.shadows[0].indirect.data.empty());
  EXPECT_TRUE(back.pair_corrections[0].indirect.data.empty());
  ASSERT_EQ(back.pair_corrections.size(), 1u);
  EXPECT_EQ(back.pair_corrections[0].object_a, 0);
  EXPECT_EQ(back.pair_corrections[0].object_b, 3);
  expect_same_bits(back.pair_corrections[0].map, g.pair_corrections[0].map);
  ASSERT_EQ(back.decisions.size(), 2u);
  EXPECT_EQ(back.decisions[0].kind, DecisionKind::kOverlap);
  EXPECT_EQ(back.decisions[0].reason, g.decisions[0].reason);
  EXPECT_EQ(back.decisions[0].value, 0.1);
  EXPECT_TRUE(back.decisions[0].taken);
  EXPECT_TRUE(std::isnan(back.decisions[1].value));
  EXPECT_EQ(group_file_hash(f.data(), f.size(), true), kHash);
}

TEST(GroupFile, StoresOnlyTheNonzeroValuesOfTheSmallestRectangle) {
  const GroupBake g = light_group();
  const std::vector<uint8_t> f = encode_group(g, kHash);
  MapRecord own;
  std::memcpy(&own, f.data() + sizeof(GroupFileHeader), sizeof own);
  EXPECT_EQ(own.rect_x, 2);
  EXPECT_EQ(own.rect_y, 1);
  EXPECT_EQ(own.rect_w, 4);
  EXPECT_EQ(own.rect_h, 3);
  EXPECT_EQ(own.nonzero, 4u * 3u * 3u - 1u);  // the one +0.0 inside the rectangle is a bit
}

TEST(GroupFile, StaticGroupRoundTrips) {
  GroupBake g;
  g.group = 0;
  g.map = corner_map(3, 2.0f);
  g.static_shadows.push_back({2, corner_map(3, 0.1f), block_image(1.0f), corner_map(3, 0.05f)});
  const std::vector<uint8_t> f = encode_group(g, kHash);
  const GroupBake back = decode_group(f.data(), f.size(), expect_for(g));
  ASSERT_EQ(back.static_shadows.size(), 1u);
  EXPECT_EQ(back.static_shadows[0].object, 2);
  expect_same_bits(back.static_shadows[0].map, g.static_shadows[0].map);
  expect_same_bits(back.static_shadows[0].indirect, g.static_shadows[0].indirect);
  expect_same_bits(back.static_shadows[0].direct, g.static_shadows[0].direct);
  expect_same_bits(back.map, g.map);
}

TEST(GroupFile, IndirectPartsOfAnotherBlockSizeAreRefused) {
  const GroupBake g = light_group();
  const std::vector<uint8_t> f = encode_group(g, kHash);
  GroupFileExpect e = expect_for(g);
  e.indirect_width = e.indirect_height = 0;  // a layout without blocks
  EXPECT_NE(refusal(f, e).find("bad indirect flag"), std::string::npos) << refusal(f, e);
  e = expect_for(g);
  e.indirect_width = kBlocksW + 1;
  EXPECT_NE(refusal(f, e).find("indirect part does not match"), std::string::npos) << refusal(f, e);
}

TEST(GroupFile, DirectPartsMustMatchTheirMapAndGroup) {
  const GroupBake g = light_group();
  const GroupFileExpect e = expect_for(g);
  const std::vector<uint8_t> f = encode_group(g, kHash);
  // The own map, its indirect part, then the first shadow and its direct part.
  const size_t part = after_record(f, sizeof(GroupFileHeader));
  const size_t shadow = after_record(f, part);
  const size_t direct = after_record(f, shadow);
  MapRecord r;
  std::memcpy(&r, f.data() + shadow, sizeof r);
  ASSERT_EQ(r.parts, 4u);
  std::memcpy(&r, f.data() + direct, sizeof r);
  ASSERT_EQ(r.parts, 8u);
  ASSERT_EQ(r.channels, 1u);
  auto edit = [&](size_t at, auto&& change) { return refusal_of_edit(f, at, e, change); };
  EXPECT_NE(edit(direct, [](MapRecord& m) { m.object = 1; }).find("direct part does not match"),
            std::string::npos);
  EXPECT_NE(edit(direct, [](MapRecord& m) { m.width = kW / 2; }).find("direct part"),
            std::string::npos);
  EXPECT_NE(edit(direct, [](MapRecord& m) { m.parts = 2; }).find("direct part does not match"),
            std::string::npos);
  EXPECT_NE(edit(shadow, [](MapRecord& m) { m.parts = 16; }).find("bad part flags"),
            std::string::npos);
  // A light group's direct part is grey: three channels are refused (read as a wrong record).
  GroupBake coloured = light_group();
  coloured.shadows[0].direct = corner_map(3, 0.004f);
  const std::vector<uint8_t> c = encode_group(coloured, kHash);
  EXPECT_NE(refusal(c, e).find("direct part does not match"), std::string::npos) << refusal(c, e);
}

TEST(GroupFile, EveryTruncationIsRefused) {
  const GroupBake g = light_group();
  const std::vector<uint8_t> f = encode_group(g, kHash);
  for (size_t n = 0; n < f.size(); ++n) {
    // A copy of exactly n bytes, so that reading past it is caught by the sanitizers.
    const std::vector<uint8_t> cut(f.begin(), f.begin() + long(n));
    EXPECT_THROW(decode_group(cut.data(), cut.size(), expect_for(g)), CookError) << n;
    EXPECT_THROW(group_file_hash(cut.data(), cut.size(), true), CookError) << n;
  }
}

TEST(GroupFile, EveryAlteredByteIsRefused) {
  const GroupBake g = light_group();
  const std::vector<uint8_t> f = encode_group(g, kHash);
  for (size_t i = 0; i < f.size(); ++i) {
    std::vector<uint8_t> bad = f;
    bad[i] ^= 0x5a;
    EXPECT_THROW(decode_group(bad.data(), bad.size(), expect_for(g)), CookError) << i;
  }
}

TEST(GroupFile, CraftedFilesWithAValidChecksumAreRefusedByTheirContent) {
  const GroupBake g = light_group();
  const GroupFileExpect e = expect_for(g);
  const std::vector<uint8_t> f = encode_group(g, kHash);
  const size_t map0 = sizeof(GroupFileHeader);
  auto edit_map0 = [&](auto&& change) { return refusal_of_edit(f, map0, e, change); };
  EXPECT_NE(edit_map0([](MapRecord& r) { r.rect_w = 60000; }), "");
  EXPECT_NE(edit_map0([](MapRecord& r) { r.width = 10; }).find("light map"), std::string::npos);
  EXPECT_NE(edit_map0([](MapRecord& r) { r.channels = 2; }), "");
  EXPECT_NE(edit_map0([](MapRecord& r) { r.nonzero += 1; }), "");
  EXPECT_NE(edit_map0([](MapRecord& r) { r.nonzero = ~uint64_t(0); }), "");
  EXPECT_NE(edit_map0([](MapRecord& r) { r.role = 1; }), "");
  {
    std::vector<uint8_t> bad = f;  // a huge map count
    GroupFileHeader h;
    std::memcpy(&h, bad.data(), sizeof h);
    h.map_count = 0xFFFFFFFFu;
    std::memcpy(bad.data(), &h, sizeof h);
    reseal(bad);
    EXPECT_NE(refusal(bad, e).find("map count"), std::string::npos);
  }
  {
    // An object index out of range in the first shadow record (after the own map and its
    // indirect part).
    std::vector<uint8_t> bad = f;
    const size_t part = after_record(bad, map0);
    MapRecord r;
    std::memcpy(&r, bad.data() + part, sizeof r);
    ASSERT_EQ(r.parts, 2u);
    r.light = 0;  // the part names another owner than its map
    std::memcpy(bad.data() + part, &r, sizeof r);
    reseal(bad);
    EXPECT_NE(refusal(bad, e).find("indirect part does not match"), std::string::npos);
    bad = f;
    const size_t shadow = after_record(bad, part);
    std::memcpy(&r, bad.data() + shadow, sizeof r);
    ASSERT_EQ(r.role, 1u);
    r.object = 4;
    std::memcpy(bad.data() + shadow, &r, sizeof r);
    reseal(bad);
    EXPECT_NE(refusal(bad, e).find("owner"), std::string::npos);
  }
  {
    // A NaN among the stored values.
    std::vector<uint8_t> bad = f;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    MapRecord own;
    std::memcpy(&own, bad.data() + map0, sizeof own);
    const size_t n = size_t(own.rect_w) * own.rect_h * own.channels;
    std::memcpy(bad.data() + map0 + sizeof own + (n + 7) / 8, &nan, sizeof nan);
    reseal(bad);
    EXPECT_NE(refusal(bad, e).find("non-finite"), std::string::npos);
  }
  // The plan it is read for.
  GroupFileExpect other = e;
  other.job_hash[0] ^= 1;
  EXPECT_NE(refusal(f, other).find("another job"), std::string::npos);
  other = e;
  other.group = 3;
  EXPECT_NE(refusal(f, other).find("group"), std::string::npos);
  other = e;
  other.objects = 3;  // object 3 no longer exists
  EXPECT_NE(refusal(f, other), "");
  other = e;
  other.max_maps = 3;
  EXPECT_NE(refusal(f, other).find("map count"), std::string::npos);
}

}  // namespace
}  // namespace lightpatch::test
