// Counts heap use in tests that assert "no allocation in predict/update". Include it FIRST in
// the test's one source file (it arms Eigen's malloc guard before Eigen is seen, and replaces
// the global operator new/delete of that executable):
//   EXPECT_EQ(ctxfuse::test::heap_uses([&] { filter.predict(u, dt); }), 0);
// Two counters: operator new (std containers, anything C++) and Eigen's own aligned malloc,
// which does not go through operator new; Eigen's EIGEN_RUNTIME_NO_MALLOC guard reports the
// latter through eigen_assert, which is routed to a counter so that NDEBUG cannot compile it out.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace ctxfuse::test {
inline std::atomic<long> g_eigen_mallocs{0};
inline std::atomic<long> g_allocations{0};
}  // namespace ctxfuse::test

#ifdef EIGEN_WORLD_VERSION
#error "include support/heap_counter.hpp before any Eigen header"
#endif
#define EIGEN_RUNTIME_NO_MALLOC
#define eigen_assert(x)                                                                  \
  do {                                                                                   \
    if (!(x)) ::ctxfuse::test::g_eigen_mallocs.fetch_add(1, std::memory_order_relaxed); \
  } while (0)

#include <Eigen/Core>

void* operator new(std::size_t n) {
  ::ctxfuse::test::g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace ctxfuse::test {

/// Heap uses (operator new calls + Eigen mallocs) while `f` runs.
template <class F>
long heap_uses(F&& f) {
  const long before = g_allocations.load() + g_eigen_mallocs.load();
  Eigen::internal::set_is_malloc_allowed(false);
  f();
  Eigen::internal::set_is_malloc_allowed(true);
  return g_allocations.load() + g_eigen_mallocs.load() - before;
}

}  // namespace ctxfuse::test
