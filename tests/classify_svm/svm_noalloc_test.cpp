// Prediction must not touch the heap: every global operator new is counted while predicting
// with RBF and linear models, one-vs-one and one-vs-rest, with and without probabilities, at a
// fixed and at a run-time dimension.
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

// The run-time dimension (SvmModel<Eigen::Dynamic>): its kernel loop keeps its values in a
// fixed stack block too; the feature vector is the caller's.
TEST(SvmNoAlloc, RuntimeDimensionPredictionNeverAllocates) {
  for (auto kernel : {SvmKernel::rbf, SvmKernel::linear}) {
    const auto fixed = ctxfuse::test::random_model<2>(kernel, SvmMulticlass::one_vs_one, 4, 1000, true, 6);
    SvmModel<Eigen::Dynamic> model;
    model.kernel = fixed.kernel;
    model.multiclass = fixed.multiclass;
    model.gamma = fixed.gamma;
    model.num_classes = fixed.num_classes;
    model.labels = fixed.labels;
    model.input_mean = fixed.input_mean;
    model.input_std = fixed.input_std;
    model.support_vectors = fixed.support_vectors;
    model.coefficients = fixed.coefficients;
    model.rho = fixed.rho;
    model.has_probability = fixed.has_probability;
    model.prob_a = fixed.prob_a;
    model.prob_b = fixed.prob_b;
    finalize_svm_model(model);
    SvmPrediction<8> out;
    Eigen::VectorXd x(2);
    double checksum = 0.0;
    const long before = g_allocations.load();
    for (int i = 0; i < 500; ++i) {
      x << 0.01 * i - 2.0, 1.0 - 0.003 * i;
      ASSERT_TRUE(svm_predict(model, x, out).accepted());
      checksum += out.probabilities[0];
    }
    EXPECT_EQ(g_allocations.load() - before, 0) << to_string(kernel);
    EXPECT_TRUE(std::isfinite(checksum));
  }
}

}  // namespace
