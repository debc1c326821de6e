// The committed test packs stay true to the cooker; golden bytes of format version 7; hostile
// packs (truncated, bytes flipped) are refused cleanly or stay safe to use (run under ASan).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/pack_format.h"
#include "lightpatch/pack_view.h"
#include "pack_bytes.h"
#include "runtime/pack_checks.h"
#include "synthetic.h"

namespace lightpatch {
namespace {

using test::Aligned;
using test::fix_checksum;

// Golden values of tiny.lpk (format version 7).
constexpr uint64_t kTinySize = 2240;
constexpr uint32_t kTinyCrc = 0xa40180b1u;

std::string data_path(const std::string& name) {
  return std::string(LIGHTPATCH_TEST_DATA_DIR) + "/packs/" + name;
}

std::vector<uint8_t> read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

// Keeps the committed packs byte-equal to what the cooker writes today. Set
// LIGHTPATCH_REGENERATE_PACKS=1 to rewrite them after an intended change (then commit them and
// copy them to tests/fuzz/corpus/pack_load/).
void check_committed(const std::string& name, const std::vector<uint8_t>& built) {
  if (std::getenv("LIGHTPATCH_REGENERATE_PACKS") != nullptr) {
    std::ofstream f(data_path(name), std::ios::binary);
    f.write(reinterpret_cast<const char*>(built.data()), std::streamsize(built.size()));
  }
  const std::vector<uint8_t> committed = read_bytes(data_path(name));
  EXPECT_EQ(committed.size(), built.size()) << name;
  EXPECT_TRUE(committed == built) << name << " differs from the cooker's output";
}

TEST(PackFiles, CommittedPacksMatchTheCooker) {
  check_committed("small.lpk", test::build_small_pack());
  check_committed("tiny.lpk", test::build_tiny_pack());
}

TEST(PackFiles, GoldenBytesOfVersion7) {
  const std::vector<uint8_t> b = test::build_tiny_pack();
  ASSERT_GE(b.size(), 64u);
  EXPECT_EQ(std::memcmp(b.data(), "LPK1", 4), 0);
  uint32_t version;
  std::memcpy(&version, b.data() + 4, 4);
  EXPECT_EQ(version, 7u);
  uint64_t file_size;
  std::memcpy(&file_size, b.data() + 8, 8);
  EXPECT_EQ(file_size, b.size());
  // Field offsets pinned (also static_asserted in pack_format.h).
  EXPECT_EQ(offsetof(pack::PatchRecord, scale), 16u);
  EXPECT_EQ(sizeof(pack::PatchRecord), 32u);  // version 7: the second tint
  EXPECT_EQ(offsetof(pack::PatchRecord, tint), 24u);
  EXPECT_EQ(offsetof(pack::PatchRecord, tint_b), 27u);
  EXPECT_EQ(offsetof(pack::PatchRecord, reserved), 30u);
  EXPECT_EQ(offsetof(pack::Header, table_checksum), 20u);
  EXPECT_EQ(offsetof(pack::LightRecord, intensity), 20u);
  EXPECT_EQ(offsetof(pack::MeshRecord, object), 40u);
  EXPECT_EQ(offsetof(pack::MeshRecord, lightmap_scale_offset), 48u);
  EXPECT_EQ(sizeof(pack::MeshRecord), 64u);
  // Version 5: LightRecord::flags (was reserved), the moving-light and pane records.
  EXPECT_EQ(offsetof(pack::LightRecord, flags), 28u);
  EXPECT_EQ(sizeof(pack::MovingLightRecord), 48u);
  EXPECT_EQ(offsetof(pack::MovingLightRecord, radius), 40u);
  EXPECT_EQ(sizeof(pack::PaneRecord), 744u);
  EXPECT_EQ(offsetof(pack::PaneRecord, points), 40u);
  EXPECT_EQ(offsetof(pack::PaneRecord, depth), 232u);
  EXPECT_EQ(uint32_t(pack::kSectionMovingLights), 14u);
  EXPECT_EQ(uint32_t(pack::kSectionPanes), 15u);
  // The whole file: any change to the writer, the quantizer or the packer shows here.
  EXPECT_EQ(b.size(), kTinySize);
  EXPECT_EQ(crc32(b.data(), b.size()), kTinyCrc);
}

// CRC-32 bit by bit from its definition (reflected, polynomial 0xEDB88320): the reference for
// the table-driven crc32 over every alignment, length and split into chained calls.
uint32_t crc32_bitwise(const uint8_t* p, size_t n) {
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? (0xEDB88320u ^ (c >> 1)) : (c >> 1);
  }
  return ~c;
}

TEST(PackFiles, Crc32IsTheStandardCrcAtEveryAlignmentAndSplit) {
  EXPECT_EQ(crc32("123456789", 9), 0xCBF43926u);  // the standard check value
  std::vector<uint8_t> b(300);
  uint32_t x = 12345;
  for (uint8_t& v : b) v = uint8_t((x = x * 1664525u + 1013904223u) >> 24);
  for (size_t start = 0; start < 9; ++start)
    for (size_t n = 0; start + n <= b.size(); n += 7) {
      const uint32_t want = crc32_bitwise(b.data() + start, n);
      EXPECT_EQ(crc32(b.data() + start, n), want) << start << " " << n;
      const size_t half = n / 2 + (n > 4 ? start % 3 : 0);  // <= n
      EXPECT_EQ(crc32(b.data() + start + half, n - half, crc32(b.data() + start, half)), want);
    }
}

TEST(PackFiles, TruncatedAtEveryByteIsRefused) {
  for (const std::vector<uint8_t>& b : {test::build_tiny_pack(), test::build_small_pack()})
    testing::expect_truncations_refused(b.data(), b.size());
}

// Uses everything a valid view exposes (ASan catches any read out of bounds).
void exercise(const PackView& v) {
  SceneState st;
  CpuRecomposer r;
  ASSERT_EQ(st.init(v, nullptr), Status::kOk);
  ASSERT_EQ(r.init(v, nullptr), Status::kOk);
  r.rebuild(st);
  volatile float sink = r.rgb()[0];
  (void)sink;
  for (uint32_t i = 0; i < v.light_count(); ++i)
    (void)v.find_light(v.light_name(i).data, v.light_name(i).length);
  for (uint32_t i = 0; i < v.mesh_count(); ++i) {
    volatile uint32_t s = 0;
    for (uint32_t k = 0; k < v.mesh(i).index_count; ++k)
      s = s + v.mesh_vertices(i)[v.mesh_indices(i)[k]].source_vertex;
    (void)v.mesh_name(i);
  }
}

TEST(PackFiles, FlippedBytesAreRefusedOrSafe) {
  const std::vector<uint8_t> b = test::build_small_pack();
  PackView original;
  Aligned base(b, b.size());
  ASSERT_EQ(PackView::open(base.data(), b.size(), &original, nullptr), Status::kOk);
  // Every byte of the header, index and table sections (the atlas data is not validated beyond
  // its bounds: any byte there is a valid texel).
  uint64_t table_end = 0;
  const pack::SectionEntry* entries = reinterpret_cast<const pack::SectionEntry*>(base.data() + 64);
  for (uint32_t i = 0; i < original.header().section_count; ++i) {
    if (entries[i].type != pack::kSectionAtlasData)
      table_end = std::max(table_end, entries[i].offset + entries[i].length);
  }
  const testing::FlipCounts n =
      testing::flip_bytes(b, 0, table_end, 1, [](const PackView& v) { exercise(v); });
  EXPECT_GT(n.refused_raw, 0);
  EXPECT_GT(n.refused_fixed, 0);
  EXPECT_GT(n.accepted, 0);  // e.g. a colour or scale changed to another valid value
}

// Mesh records of version 2: an instance laid out by its own TEXCOORD_1 carries its scale and
// offset; unknown flags, a scale without the flag and a non-finite one are refused.
TEST(PackFiles, MeshScaleAndOffsetAreCheckedOnLoad) {
  const std::vector<uint8_t> b = test::build_small_pack();
  Aligned base(b, b.size());
  PackView v;
  ASSERT_EQ(PackView::open(base.data(), b.size(), &v, nullptr), Status::kOk);
  ASSERT_EQ(v.mesh_count(), 4u);
  const pack::MeshRecord& m = v.mesh(1);
  ASSERT_EQ(m.flags, pack::kMeshFlagTexcoord1);
  // The unit square's corners through the scale and offset give the vertices' UVs.
  const pack::MeshVertex* mv = v.mesh_vertices(1);
  const float* so = m.lightmap_scale_offset;
  const float corner[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  for (int k = 0; k < 4; ++k) {
    EXPECT_FLOAT_EQ(corner[k][0] * so[0] + so[2], mv[k].u);
    EXPECT_FLOAT_EQ(corner[k][1] * so[1] + so[3], mv[k].v);
  }
  EXPECT_EQ(v.mesh(0).flags, 0u);

  const uint64_t records = uint64_t(reinterpret_cast<const uint8_t*>(&v.mesh(0)) - base.data());
  auto refused = [&](uint32_t mesh, size_t field, const void* value, size_t n) {
    Aligned a(b, b.size());
    std::memcpy(a.data() + records + mesh * sizeof(pack::MeshRecord) + field, value, n);
    fix_checksum(a.data(), b.size());
    PackView w;
    Error e;
    const bool ok = PackView::open(a.data(), b.size(), &w, &e) == Status::kOk;
    if (!ok) {
      EXPECT_NE(std::string(e.message).find("mesh"), std::string::npos) << e.message;
    }
    return !ok;
  };
  const uint16_t unknown = 2;
  const float nan = std::nanf(""), one = 1.0f;
  EXPECT_TRUE(refused(1, offsetof(pack::MeshRecord, flags), &unknown, 2));
  EXPECT_TRUE(refused(0, offsetof(pack::MeshRecord, lightmap_scale_offset), &one, 4));
  EXPECT_TRUE(refused(1, offsetof(pack::MeshRecord, lightmap_scale_offset) + 8, &nan, 4));
  EXPECT_FALSE(refused(1, offsetof(pack::MeshRecord, lightmap_scale_offset) + 8, &one, 4));
}

// Version 3: atlas sides are multiples of 4 (no longer powers of two) up to kMaxAtlasSize. A
// version 3 pack (no probe sections) is refused with a message that says to cook again.
TEST(PackFiles, AtlasSidesAndVersionAreCheckedOnLoad) {
  const std::vector<uint8_t> b = test::build_small_pack();
  Aligned base(b, b.size());
  PackView v;
  ASSERT_EQ(PackView::open(base.data(), b.size(), &v, nullptr), Status::kOk);
  const uint64_t records = uint64_t(reinterpret_cast<const uint8_t*>(&v.atlas(0)) - base.data());
  auto open_edited = [&](uint64_t at, uint32_t value, Error* e) {
    Aligned a(b, b.size());
    std::memcpy(a.data() + at, &value, 4);
    fix_checksum(a.data(), b.size());
    PackView w;
    return PackView::open(a.data(), b.size(), &w, e);
  };
  const uint32_t width = v.atlas(0).width, height = v.atlas(0).height;
  for (const uint32_t bad : {width - 1, width + 2, 0u, 2u, pack::kMaxAtlasSize + 4}) {
    Error e;
    EXPECT_EQ(open_edited(records + offsetof(pack::AtlasRecord, width), bad, &e), Status::kCorrupt)
        << bad;
    EXPECT_NE(std::string(e.message).find("multiples of 4"), std::string::npos) << e.message;
    EXPECT_EQ(open_edited(records + offsetof(pack::AtlasRecord, height), bad, &e), Status::kCorrupt)
        << bad;
  }
  // Smaller sides that are multiples of 4 pass the atlas check (and then fail on a patch that
  // no longer fits, if any), whether or not they are powers of two.
  Error e;
  ASSERT_GT(height, 4u);
  const Status lower = open_edited(records + offsetof(pack::AtlasRecord, height), height - 4, &e);
  EXPECT_TRUE(lower == Status::kOk || std::string(e.message).find("patch") != std::string::npos)
      << e.message;
  EXPECT_EQ(open_edited(offsetof(pack::Header, version), 3u, &e), Status::kUnsupportedVersion);
  EXPECT_NE(std::string(e.message).find("cook the scene again"), std::string::npos) << e.message;
  // Version 4 (before moving lights) likewise.
  EXPECT_EQ(open_edited(offsetof(pack::Header, version), 4u, &e), Status::kUnsupportedVersion);
  EXPECT_NE(std::string(e.message).find("version 4 is not supported (this reader: 7); cook the "
                                        "scene again"),
            std::string::npos)
      << e.message;
  // Versions 5 (before the patches' tint) and 6 (before 2-channel patches) likewise.
  for (uint32_t old : {5u, 6u}) {
    EXPECT_EQ(open_edited(offsetof(pack::Header, version), old, &e), Status::kUnsupportedVersion);
    EXPECT_NE(std::string(e.message).find("version " + std::to_string(old) +
                                          " is not supported (this reader: 7); cook the "
                                          "scene again"),
              std::string::npos)
        << e.message;
  }
}

}  // namespace
}  // namespace lightpatch
