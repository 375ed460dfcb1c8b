// predict and update must not touch the heap: count every allocation through a replaced
// global operator new while the filters run. Eigen's dynamic storage goes through malloc,
// not operator new, so Eigen's own runtime guard (EIGEN_RUNTIME_NO_MALLOC) is armed too and
// its assertion, which NDEBUG would otherwise compile out, is routed to a counter.
#include <atomic>
#include <cstdlib>
#include <new>

namespace {
std::atomic<long> g_eigen_mallocs{0};
}
#define EIGEN_RUNTIME_NO_MALLOC
#define eigen_assert(x)                                              \
  do {                                                               \
    if (!(x)) g_eigen_mallocs.fetch_add(1, std::memory_order_relaxed); \
  } while (0)

#include <gtest/gtest.h>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"

namespace {
std::atomic<long> g_allocations{0};
}

void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace {
using namespace ctxfuse;

// Counts both kinds of heap use while `f` runs.
template <class F>
long heap_uses(F&& f) {
  const long before = g_allocations.load() + g_eigen_mallocs.load();
  Eigen::internal::set_is_malloc_allowed(false);
  f();
  Eigen::internal::set_is_malloc_allowed(true);
  return g_allocations.load() + g_eigen_mallocs.load() - before;
}

TEST(Allocation, CountersSeeHeapAllocations) {
  // Through a volatile pointer, so the compiler may not elide the new-expression.
  static int* volatile sink = nullptr;
  EXPECT_GE(heap_uses([] {
              sink = new int(3);
              delete sink;
            }),
            1);
  EXPECT_GE(heap_uses([] {
              Eigen::MatrixXd m(20, 20);  // Eigen's malloc path must be seen too
              m.setZero();
            }),
            1);
}

TEST(Allocation, EskfPredictAndGatedUpdateNeverAllocate) {
  models::Ins15Model model;
  models::GnssPosition<> gnss;
  gnss.lever_arm = {0.2, 0.0, 1.0};
  eskf::Belief<models::Ins15Model> b;
  b.cov = SquareMatrix<15>::Identity() * 0.01;
  Eskf<models::Ins15Model, ChiSquareGate> f(model, b, {}, ChiSquareGate(0.999));
  models::ImuSample u;
  u.accel = {0.1, 0.0, 9.81};
  u.gyro = {0.0, 0.0, 0.1};

  int accepted = 0;
  EXPECT_EQ(heap_uses([&] {
              for (int k = 0; k < 1000; ++k) {
                accepted += f.predict(u, 0.01).accepted();
                if (k % 10 == 0) accepted += f.update(gnss, Vector<3>(0.01 * k, 0.0, 1.0)).accepted();
                if (k % 100 == 0) (void)f.update(gnss, Vector<3>(1e6, 0.0, 1.0));  // gated path
              }
              (void)f.predict(u, -1.0);  // rejection path
            }),
            0);
  EXPECT_GT(accepted, 1000);
}

TEST(Allocation, EkfNeverAllocates) {
  using L = Layout<Block<"p", 3>, Block<"v", 3>>;
  models::ConstantVelocity<L, 3> cv;
  models::RangeToPoint<L, 3> range;
  range.anchor = {5, 5, 2};
  Ekf<models::ConstantVelocity<L, 3>, ChiSquareGate> f(cv, {}, {}, ChiSquareGate(0.99));
  EXPECT_EQ(heap_uses([&] {
              for (int k = 0; k < 1000; ++k) {
                (void)f.predict({}, 0.1);
                (void)f.update(range, Vector<1>(7.0));
              }
            }),
            0);
}

}  // namespace
