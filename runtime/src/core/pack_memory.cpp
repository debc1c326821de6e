#include "lightpatch/pack_memory.h"

#include <cstdlib>
#include <cstring>

namespace lightpatch {

PackMemory::~PackMemory() {
  close();
}

void PackMemory::close() {
  view_ = PackView();
  std::free(copy_);
  copy_ = nullptr;
}

Status PackMemory::open(const void* data, uint64_t size, Error* error) {
  close();
  if (data == nullptr) return set_error(error, Status::kInvalidArgument, "pack: no data");
  const void* bytes = data;
  if (reinterpret_cast<uintptr_t>(data) % 8 != 0) {
    if (size > SIZE_MAX) return set_error(error, Status::kOutOfMemory, "pack: too large to copy");
    copy_ = std::malloc(size ? size_t(size) : 1);  // malloc aligns for any scalar type
    if (!copy_) {
      return set_error(error, Status::kOutOfMemory, "pack: cannot copy %llu bytes",
                       static_cast<unsigned long long>(size));
    }
    std::memcpy(copy_, data, size_t(size));
    bytes = copy_;
  }
  const Status s = PackView::open(bytes, size, &view_, error);
  if (s != Status::kOk) close();
  return s;
}

}  // namespace lightpatch
