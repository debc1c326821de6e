// Checks shared by the pack tests: a committed pack (tests/data/packs, also the pack_load fuzz
// seeds) equals what the test builds (LIGHTPATCH_REGENERATE_PACKS=1 rewrites it after an intended
// change: then commit it and copy it to tests/fuzz/corpus/pack_load/); every truncation of a pack
// is refused with a message; flipped bytes are refused or give a view safe to use.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "lightpatch/pack_view.h"
#include "pack/pack_bytes.h"
#include "runtime/synthetic_pack.h"

namespace lightpatch::testing {

// Opens the pack; on failure returns the message (empty on success).
inline std::string open_message(const SyntheticPack& bytes, PackView* view = nullptr) {
  PackView v;
  Error error;
  if (bytes.open(view ? view : &v, &error)) return "";
  EXPECT_NE(error.message[0], '\0');
  return error.message[0] ? error.message : "refused without a message";
}

inline std::string pack_data_path(const std::string& name) {
  return std::string(LIGHTPATCH_TEST_DATA_DIR) + "/packs/" + name;
}

// `size` bytes at `built` against the committed file `name`, and against the pinned golden size
// and CRC-32 of the whole file.
inline void expect_committed_pack(const uint8_t* built, uint64_t size, const std::string& name,
                                  uint64_t golden_size, uint32_t golden_crc) {
  if (std::getenv("LIGHTPATCH_REGENERATE_PACKS") != nullptr) {
    std::ofstream f(pack_data_path(name), std::ios::binary);
    f.write(reinterpret_cast<const char*>(built), std::streamsize(size));
  }
  std::ifstream f(pack_data_path(name), std::ios::binary);
  const std::vector<uint8_t> committed((std::istreambuf_iterator<char>(f)),
                                       std::istreambuf_iterator<char>());
  ASSERT_EQ(committed.size(), size) << name;
  EXPECT_EQ(std::memcmp(committed.data(), built, size), 0) << name << " differs from the build";
  EXPECT_EQ(size, golden_size) << name;
  EXPECT_EQ(crc32(built, size), golden_crc) << name;
}

// Every prefix of the pack (in 8-byte aligned storage) is refused with a message.
inline void expect_truncations_refused(const void* bytes, uint64_t size) {
  for (uint64_t n = 0; n < size; ++n) {
    std::vector<uint64_t> words(n / 8 + 1);
    std::memcpy(words.data(), bytes, n);
    PackView v;
    Error e;
    ASSERT_NE(PackView::open(words.data(), n, &v, &e), Status::kOk) << "accepted " << n << " bytes";
    ASSERT_FALSE(v.valid());
    ASSERT_NE(e.message[0], '\0');
  }
}

// Flips each byte in [begin, end) (every `step`-th) with the masks 0xFF, 0x01 and 0x80, and opens
// the result as it is and with its table checksum made right; `use(view)` runs on every view
// opened (under ASan: any read out of bounds fails). Refusals must have a message.
struct FlipCounts {
  int refused_raw = 0;    // refused as flipped (mostly the checksum)
  int refused_fixed = 0;  // refused with the checksum made right: by the record validation
  int accepted = 0;       // valid with the checksum made right (another valid value)
};
template <typename Use>
FlipCounts flip_bytes(const std::vector<uint8_t>& b, uint64_t begin, uint64_t end, uint64_t step,
                      Use&& use) {
  FlipCounts n;
  for (uint64_t i = begin; i < end; i += step) {
    for (uint8_t mask : {uint8_t(0xFF), uint8_t(0x01), uint8_t(0x80)}) {
      test::Aligned a(b, b.size());
      a.data()[i] ^= mask;
      PackView v;
      if (PackView::open(a.data(), b.size(), &v, nullptr) != Status::kOk)
        ++n.refused_raw;
      else
        use(v);
      test::fix_checksum(a.data(), b.size());
      Error e;
      if (PackView::open(a.data(), b.size(), &v, &e) != Status::kOk) {
        ++n.refused_fixed;
        EXPECT_NE(e.message[0], '\0') << "byte " << i;
      } else {
        ++n.accepted;
        use(v);
      }
    }
  }
  return n;
}

}  // namespace lightpatch::testing
