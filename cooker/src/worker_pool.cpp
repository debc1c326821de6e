#include "worker_pool.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#if defined(__SSE__) || defined(__x86_64__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#define LIGHTPATCH_HAS_SSE 1
#endif

namespace lightpatch::cooker {

int worker_count(int requested) {
  if (requested > 0) return requested;
  const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : static_cast<int>(n);
}

void set_worker_fp_mode() {
#ifdef LIGHTPATCH_HAS_SSE
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
}

void parallel_for(int count, int threads, const std::function<void(int)>& fn) {
  if (count <= 0) return;
  threads = std::max(1, std::min(threads, count));
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  std::atomic<bool> failed{false};
  auto work = [&] {
    set_worker_fp_mode();
    for (;;) {
      if (failed.load(std::memory_order_relaxed)) return;
      const int item = next.fetch_add(1);
      if (item >= count) return;
      try {
        fn(item);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        failed.store(true);
        return;
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<size_t>(threads - 1));
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
#ifdef LIGHTPATCH_HAS_SSE
  const unsigned saved_csr = _mm_getcsr();  // the caller's FP mode is restored afterwards
  work();
  _mm_setcsr(saved_csr);
#else
  work();
#endif
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace lightpatch::cooker
