// Counts every call of the global operator new (plain and nothrow) in the test binary that includes this
// header (include it in exactly one source file of that binary).
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace patchscan::test {
inline std::atomic<long> gAllocations{0};
}

// The replacement new below takes its memory from malloc, so free is the matching release
// (GCC cannot see through the replacement and warns at some optimization levels).
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

void* operator new(std::size_t n) {
  ++patchscan::test::gAllocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
// The nothrow forms (std::stable_sort's buffer uses them) must come from the same malloc,
// or a sanitizer's own nothrow new would meet the free above.
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  ++patchscan::test::gAllocations;
  return std::malloc(n ? n : 1);
}
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
