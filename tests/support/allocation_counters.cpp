// Heap allocation counters for the tests that check "no allocation per frame": this file's
// definitions of operator new and (outside AddressSanitizer) malloc, calloc and realloc forward
// to the real ones and count while counting is on. Linked into the test binaries that use them.
#include "support/counters.h"

#include <dlfcn.h>

#include <cstdlib>
#include <new>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LP_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define LP_ASAN 1
#endif

namespace lightpatch::testing {
Counters& counters() {
  static Counters c;
  return c;
}
#if defined(LP_ASAN)
bool malloc_counted() {
  return false;
}
#else
bool malloc_counted() {
  return true;
}
#endif
}  // namespace lightpatch::testing

using lightpatch::testing::counters;

namespace {
void count_new() {
  if (counters().on.load(std::memory_order_relaxed)) counters().news.fetch_add(1);
}
}  // namespace

// operator new/delete.
void* operator new(size_t n) {
  count_new();
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](size_t n) {
  count_new();
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new(size_t n, const std::nothrow_t&) noexcept {
  count_new();
  return std::malloc(n ? n : 1);
}
void* operator new[](size_t n, const std::nothrow_t&) noexcept {
  count_new();
  return std::malloc(n ? n : 1);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, size_t) noexcept {
  std::free(p);
}

#if !defined(LP_ASAN)
// malloc family through glibc's internal entry points. Only calls made from this executable (the
// runtime and platform are static libraries linked into it) are counted: the GL driver (Mesa's
// llvmpipe) allocates inside glDrawElements, which is the driver's business, not the runtime's.
namespace {
bool from_this_executable(void* caller) {
  static const void* exe_base = [] {
    Dl_info self{};
    dladdr(reinterpret_cast<void*>(&lightpatch::testing::counters), &self);
    return self.dli_fbase;
  }();
  Dl_info info{};
  return dladdr(caller, &info) != 0 && info.dli_fbase == exe_base;
}
void count_malloc(void* caller) {
  if (counters().on.load(std::memory_order_relaxed) && from_this_executable(caller)) {
    counters().mallocs.fetch_add(1);
  }
}
}  // namespace
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* malloc(size_t n) {
  count_malloc(__builtin_return_address(0));
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t m) {
  count_malloc(__builtin_return_address(0));
  return __libc_calloc(n, m);
}
void* realloc(void* p, size_t n) {
  count_malloc(__builtin_return_address(0));
  return __libc_realloc(p, n);
}
}
#endif
