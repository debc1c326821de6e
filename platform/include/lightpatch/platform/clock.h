// Monotonic clock for frame timing and benchmarks.
#pragma once

#include <cstdint>

namespace lightpatch::platform {

// Nanoseconds from an arbitrary fixed origin; never goes backwards.
uint64_t monotonic_ns();

inline double elapsed_ms(uint64_t start_ns, uint64_t end_ns) {
  return static_cast<double>(end_ns - start_ns) * 1e-6;
}

}  // namespace lightpatch::platform
