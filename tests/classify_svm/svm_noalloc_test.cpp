// Prediction must not touch the heap: every global operator new is counted while predicting
// with RBF and linear models, one-vs-one and one-vs-rest, with and without probabilities.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "classify_svm/svm_test_data.hpp"
#include "ctxfuse/classify/svm.hpp"

namespace {
std::atomic<long> g_allocations{0};
}

void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, std::align_val_t a) {
  ++g_allocations;
  if (void* p = std::aligned_alloc(static_cast<std::size_t>(a), (n + static_cast<std::size_t>(a) - 1) / static_cast<std::size_t>(a) * static_cast<std::size_t>(a))) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace {

using namespace ctxfuse::classify;

TEST(SvmNoAlloc, CounterSeesAllocations) {
  const long before = g_allocations.load();
  // An explicit call, which (unlike a new-expression) the compiler may not elide.
  void* p = ::operator new(16);
  ::operator delete(p);
  EXPECT_EQ(g_allocations.load() - before, 1);
}

TEST(SvmNoAlloc, PredictionNeverAllocates) {
  for (auto kernel : {SvmKernel::rbf, SvmKernel::linear})
    for (auto layout : {SvmMulticlass::one_vs_one, SvmMulticlass::one_vs_rest})
      for (int classes : {2, 4}) {
        const auto model = ctxfuse::test::random_model<2>(kernel, layout, classes, 1000, true, 5);
        SvmPrediction<8> out;
        double checksum = 0.0;
        const long before = g_allocations.load();
        for (int i = 0; i < 500; ++i) {
          const Eigen::Vector2d x(0.01 * i - 2.0, 1.0 - 0.003 * i);
          ASSERT_TRUE(svm_predict(model, x, out).accepted());
          checksum += out.probabilities[0];
          ASSERT_TRUE(svm_decision(model, x, out).accepted());
          checksum += out.decision_values[0];
        }
        EXPECT_EQ(g_allocations.load() - before, 0) << to_string(kernel) << ' ' << to_string(layout) << ' ' << classes;
        EXPECT_TRUE(std::isfinite(checksum));
      }
}

}  // namespace
