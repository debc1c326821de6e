// What the loader refuses beyond the format's ranges (pack_view.h, RecomposeLimits: light maps past
// the memory the runtime states; names that are not UTF-8) and what check_authored_map_bound
// (planner.h) refuses as Runtime::open does (light maps that could exceed the float range), so
// that a pack `verify` accepts is one the runtime opens.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/pack_format.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/planner.h"
#include "lightpatch/scene_state.h"
#include "lightpatch/utf8.h"
#include "pack_bytes.h"
#include "synthetic.h"

namespace lightpatch {
namespace {

using test::Aligned;

const std::vector<uint8_t>& small_pack() {
  static const std::vector<uint8_t> bytes = test::build_small_pack();
  return bytes;
}

// A copy of the small pack with `edit` applied to its bytes and the checksum fixed.
struct Edited {
  Aligned bytes;
  template <typename Edit>
  explicit Edited(Edit edit) : bytes(small_pack(), small_pack().size()) {
    edit(bytes.data());
    test::fix_checksum(bytes.data(), bytes.size);
  }
  Status open(const RecomposeLimits& limits, std::string* message, PackView* view) {
    Error e;
    const Status s = PackView::open(bytes.data(), bytes.size, limits, view, &e);
    *message = e.message;
    return s;
  }
};

template <typename T>
T* record(uint8_t* d, uint32_t section, uint32_t index) {
  pack::Header h;
  std::memcpy(&h, d, sizeof(h));
  for (uint32_t i = 0; i < h.section_count; ++i) {
    pack::SectionEntry e;
    std::memcpy(&e, d + sizeof(h) + i * sizeof(e), sizeof(e));
    if (e.type == section) return reinterpret_cast<T*>(d + e.offset) + index;
  }
  return nullptr;
}

uint8_t* strings(uint8_t* d) {
  return record<uint8_t>(d, pack::kSectionStrings, 0);
}

// What check_authored_map_bound says of a pack (after PackView::open accepted it).
Status authored_bound(Edited& e, std::string* message) {
  PackView view;
  if (Status s = e.open(RecomposeLimits(), message, &view); s != Status::kOk) return s;
  Error error;
  const Status s = check_authored_map_bound(view, &error);
  *message = error.message;
  return s;
}

TEST(PackLimits, APatchScaleTheRuntimeCannotSumIsRefused) {
  // Patch 0 is the base map's (groups sorted by kind): its factor is 1. A scale of 1e38 made
  // recompose fail with a non-finite texel after verify had accepted it.
  Edited big(
      [](uint8_t* d) { record<pack::PatchRecord>(d, pack::kSectionPatches, 0)->scale = 1e38f; });
  std::string m;
  EXPECT_EQ(authored_bound(big, &m), Status::kOutOfRange);
  EXPECT_NE(m.find("the authored light map could reach 1e+38, beyond the 1e+36 the runtime opens"),
            std::string::npos)
      << m;

  // Bright but within the bound: accepted, and the CPU recomposer's map stays finite.
  Edited bright(
      [](uint8_t* d) { record<pack::PatchRecord>(d, pack::kSectionPatches, 0)->scale = 1e30f; });
  ASSERT_EQ(authored_bound(bright, &m), Status::kOk) << m;
  PackView view;
  ASSERT_EQ(bright.open(RecomposeLimits(), &m, &view), Status::kOk) << m;
  SceneState state;
  CpuRecomposer recomposer;
  ASSERT_EQ(state.init(view, nullptr), Status::kOk);
  ASSERT_EQ(recomposer.init(view, nullptr), Status::kOk);
  ASSERT_EQ(recomposer.rebuild(state), Status::kOk);
  const float* rgb = recomposer.rgb();
  float peak = 0.0f;
  for (uint64_t i = 0; i < uint64_t(view.lightmap_width()) * view.lightmap_height() * 3; ++i) {
    ASSERT_TRUE(std::isfinite(rgb[i])) << "texel value " << i;
    peak = std::max(peak, rgb[i]);
  }
  EXPECT_GT(peak, 1e28f);  // the raised scale reached the map
}

TEST(PackLimits, ALightAuthoredPastTheBoundIsRefused) {
  Edited brightest(
      [](uint8_t* d) { record<pack::LightRecord>(d, pack::kSectionLights, 0)->intensity = 3e38f; });
  std::string m;
  EXPECT_EQ(authored_bound(brightest, &m), Status::kOutOfRange);
  EXPECT_NE(m.find("beyond the 1e+36 the runtime opens"), std::string::npos) << m;
}

TEST(PackLimits, ALightMapPastTheStatedMemoryIsRefusedBeforeAnyAllocation) {
  // 16384 x 16384 texels in a pack of a few kB: the runtime would allocate 2-3 GB for it.
  Edited huge([](uint8_t* d) {
    auto* h = reinterpret_cast<pack::Header*>(d);
    h->lightmap_width = pack::kMaxLightmapSize;
    h->lightmap_height = pack::kMaxLightmapSize;
  });
  PackView view;
  std::string m;
  EXPECT_EQ(huge.open(RecomposeLimits(), &m, &view), Status::kOverLimit);
  EXPECT_NE(m.find("16384x16384"), std::string::npos) << m;
  EXPECT_NE(m.find("max_lightmap_texels"), std::string::npos) << m;
  RecomposeLimits raised;
  raised.max_lightmap_texels = uint64_t(pack::kMaxLightmapSize) * pack::kMaxLightmapSize;
  EXPECT_EQ(huge.open(raised, &m, &view), Status::kOk) << m;
}

TEST(PackLimits, NamesMustBeUtf8) {
  struct Case {
    const char* bytes;  // written over the start of light 0's name
    bool valid;
  };
  const Case cases[] = {
      {"\xFF", false},          // never in UTF-8
      {"\xC0\xAF", false},      // overlong '/'
      {"\xED\xA0\x80", false},  // a UTF-16 surrogate
      {"\x80", false},          // a lone continuation byte
      {"\xC3\xA4", true},       // a-umlaut
      {"\x1B[", true},          // a terminal escape is UTF-8; the tools print it escaped
  };
  for (const Case& c : cases) {
    Edited e([&](uint8_t* d) {
      const auto* l = record<pack::LightRecord>(d, pack::kSectionLights, 0);
      ASSERT_GE(l->name_length, std::strlen(c.bytes));
      std::memcpy(strings(d) + l->name_offset, c.bytes, std::strlen(c.bytes));
    });
    PackView view;
    std::string m;
    const Status s = e.open(RecomposeLimits(), &m, &view);
    if (c.valid) {
      EXPECT_EQ(s, Status::kOk) << m;
    } else {
      EXPECT_EQ(s, Status::kCorrupt) << c.bytes;
      EXPECT_NE(m.find("light 0: name is not valid UTF-8"), std::string::npos) << m;
    }
  }
}

TEST(Utf8, DecodesWhatRfc3629AllowsAndNothingElse) {
  uint32_t cp = 0;
  EXPECT_EQ(utf8_decode("A", 1, &cp), 1u);
  EXPECT_EQ(cp, 0x41u);
  EXPECT_EQ(utf8_decode("\xE2\x82\xAC", 3, &cp), 3u);  // euro sign
  EXPECT_EQ(cp, 0x20ACu);
  EXPECT_EQ(utf8_decode("\xF4\x8F\xBF\xBF", 4, &cp), 4u);  // U+10FFFF
  EXPECT_EQ(cp, 0x10FFFFu);
  EXPECT_EQ(utf8_decode("\xF4\x90\x80\x80", 4, &cp), 0u);  // above U+10FFFF
  EXPECT_EQ(utf8_decode("\xE2\x82", 2, &cp), 0u);          // cut short
  EXPECT_EQ(utf8_decode("\xE0\x80\xAF", 3, &cp), 0u);      // overlong
  EXPECT_TRUE(utf8_valid("", 0));
  EXPECT_TRUE(utf8_valid("caf\xC3\xA9", 5));
  EXPECT_FALSE(utf8_valid("caf\xC3", 4));
}

}  // namespace
}  // namespace lightpatch
