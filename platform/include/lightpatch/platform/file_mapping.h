// Read-only file mapping (mmap on POSIX, including Android). A pack is used straight from it.
#pragma once

#include <cstdint>

namespace lightpatch::platform {

class FileMapping {
 public:
  FileMapping() = default;
  ~FileMapping();
  FileMapping(const FileMapping&) = delete;
  FileMapping& operator=(const FileMapping&) = delete;
  FileMapping(FileMapping&& other) noexcept;
  FileMapping& operator=(FileMapping&& other) noexcept;

  // Maps the whole file read-only; data() is page-aligned. An empty file gives data() == nullptr
  // and size() == 0 (a valid pack is never empty, so the pack loader refuses it).
  // Returns false and writes a message (NUL-terminated, truncated to message_size) on failure.
  bool open(const char* path, char* message, unsigned message_size);
  void close();

  const void* data() const { return data_; }
  uint64_t size() const { return size_; }

 private:
  void* data_ = nullptr;
  uint64_t size_ = 0;
};

}  // namespace lightpatch::platform
