// SHA-256 (FIPS 180-4) for the content hashes that name a cook's jobs (cook_jobs.h): a digest of
// everything that determines a job's output. Streaming; values are fed as their little-endian
// bytes, strings and arrays with their length first, so that no two inputs share a byte stream.
#pragma once

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

namespace lightpatch::cooker {

class ContentHash {
 public:
  ContentHash();
  void bytes(const void* data, size_t size);
  template <typename T>
  void value(const T& v) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>);
    bytes(&v, sizeof v);
  }
  void value(const glm::vec2& v) { bytes(&v, sizeof v); }
  void value(const glm::vec3& v) { bytes(&v, sizeof v); }
  void text(const std::string& s);
  template <typename T>
  void array(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    value(uint64_t(v.size()));
    bytes(v.data(), v.size() * sizeof(T));
  }
  void digest(const std::array<uint8_t, 32>& d) { bytes(d.data(), d.size()); }
  // The digest; the object is spent afterwards.
  std::array<uint8_t, 32> finish();

 private:
  void block(const uint8_t* p);
  std::array<uint32_t, 8> h_;
  std::array<uint8_t, 64> buffer_{};
  size_t used_ = 0;
  uint64_t length_ = 0;
};

using Digest = std::array<uint8_t, 32>;

std::string hex(const uint8_t* data, size_t size);

}  // namespace lightpatch::cooker
