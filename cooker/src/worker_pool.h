// Splitting texel and ray work over the machine's cores. Work items are independent, so results
// never depend on the thread count. Workers run with flush-to-zero / denormals-are-zero, which
// Embree recommends for speed (and which keeps tiny irradiance terms from turning into denormals).
#pragma once

#include <functional>

namespace lightpatch::cooker {

// Cores to use: `requested` if > 0, otherwise std::thread::hardware_concurrency() (at least 1).
int worker_count(int requested);

// Sets FTZ/DAZ on the calling thread (x86 SSE; no-op elsewhere).
void set_worker_fp_mode();

// Calls fn(item) for every item in [0, count), items handed out dynamically to `threads` workers
// (the calling thread is one of them). Rethrows the first exception a worker threw.
void parallel_for(int count, int threads, const std::function<void(int)>& fn);

}  // namespace lightpatch::cooker
