// Counters of heap allocations and GL object creations, kept by interposers:
// support/allocation_counters.cpp (operator new, malloc) and, in the GLES tests, gles/counters.cpp
// (glGen*/glCreate*); each forwards to the real function and counts while counting is on.
#pragma once

#include <atomic>
#include <cstdint>

namespace lightpatch::testing {

struct Counters {
  std::atomic<bool> on{false};
  std::atomic<uint64_t> news{0};
  std::atomic<uint64_t> mallocs{0};
  std::atomic<uint64_t> gl_creations{0};
};
Counters& counters();
// Whether malloc/calloc/realloc are interposed (not under AddressSanitizer, which owns them).
bool malloc_counted();

}  // namespace lightpatch::testing
