// Packs held in memory the game owns: PackView::open needs 8-byte alignment and says so; an APK
// asset is aligned to 4 bytes only, and PackMemory copies such bytes once and recomposes exactly
// as from aligned bytes (viewed in place, not copied).
#include "lightpatch/pack_memory.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/scene_state.h"
#include "runtime/synthetic_pack.h"

namespace lightpatch {
namespace {

TEST(PackMemory, FourByteAlignedBytesAreCopiedAndRecomposeTheSame) {
  const testing::SyntheticPack pack = testing::make_synthetic_pack(testing::SyntheticOptions{});
  // The pack at offset 4 of an 8-byte aligned buffer: 4-byte aligned, as in an APK.
  std::vector<uint64_t> storage(pack.size / 8 + 2);
  uint8_t* at4 = reinterpret_cast<uint8_t*>(storage.data()) + 4;
  std::memcpy(at4, pack.data(), pack.size);

  PackView view;
  Error error;
  EXPECT_EQ(PackView::open(at4, pack.size, &view, &error), Status::kInvalidArgument);
  EXPECT_NE(std::string(error.message).find("8-byte aligned"), std::string::npos);

  PackMemory in_place, copied;
  ASSERT_EQ(in_place.open(pack.data(), pack.size, &error), Status::kOk) << error.message;
  EXPECT_FALSE(in_place.copied());
  EXPECT_EQ(in_place.view().bytes(), pack.data());
  ASSERT_EQ(copied.open(at4, pack.size, &error), Status::kOk) << error.message;
  EXPECT_TRUE(copied.copied());
  std::memset(at4, 0, pack.size);  // the caller may free its buffer once the copy is made

  SceneState state;
  ASSERT_EQ(state.init(in_place.view(), &error), Status::kOk);
  CpuRecomposer a, b;
  ASSERT_EQ(a.init(in_place.view(), &error), Status::kOk);
  ASSERT_EQ(b.init(copied.view(), &error), Status::kOk);
  ASSERT_EQ(a.rebuild(state), Status::kOk);
  ASSERT_EQ(b.rebuild(state), Status::kOk);
  const size_t n = size_t(a.width()) * a.height() * 3;
  EXPECT_EQ(std::memcmp(a.rgb(), b.rgb(), n * sizeof(float)), 0);
}

TEST(PackMemory, DamagedBytesAreRefusedLikePackViewRefusesThem) {
  const testing::SyntheticPack pack = testing::make_synthetic_pack(testing::SyntheticOptions{});
  std::vector<uint64_t> storage(pack.size / 8 + 2);
  uint8_t* at4 = reinterpret_cast<uint8_t*>(storage.data()) + 4;
  std::memcpy(at4, pack.data(), pack.size);
  at4[0] ^= 0xFF;  // the magic
  PackMemory m;
  Error error;
  EXPECT_EQ(m.open(at4, pack.size, &error), Status::kBadMagic);
  EXPECT_FALSE(m.view().valid());
  EXPECT_FALSE(m.copied());
  EXPECT_EQ(m.open(at4, 10, &error), Status::kTruncated);
}

}  // namespace
}  // namespace lightpatch
