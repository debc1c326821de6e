// Pack bytes a game holds in memory rather than maps from a file: an asset read into a buffer, or
// an Android APK asset (AAssetManager), which the APK aligns to 4 bytes only. PackView::open needs
// the bytes 8-byte aligned (its records hold 64-bit fields, read in place); PackMemory views
// aligned bytes in place and copies unaligned ones, once, into an aligned block it owns.
#pragma once

#include <cstdint>

#include "lightpatch/pack_view.h"
#include "lightpatch/status.h"

namespace lightpatch {

class PackMemory {
 public:
  PackMemory() = default;
  ~PackMemory();
  PackMemory(const PackMemory&) = delete;
  PackMemory& operator=(const PackMemory&) = delete;

  // Validates `size` bytes at `data` (PackView::open's checks). 8-byte aligned bytes are viewed in
  // place and must then stay alive and unchanged while view() is used; others are copied (and may
  // be freed once open() returns). kOutOfMemory when the copy cannot be made.
  Status open(const void* data, uint64_t size, Error* error);
  void close();

  const PackView& view() const { return view_; }
  bool copied() const { return copy_ != nullptr; }

 private:
  PackView view_;
  void* copy_ = nullptr;
};

}  // namespace lightpatch
