// predict and update must not touch the heap (support/heap_counter.hpp counts operator new
// and Eigen's own mallocs while the filters run).
#include "support/heap_counter.hpp"

#include <gtest/gtest.h>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"

namespace {
using namespace ctxfuse;

using test::heap_uses;

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
  Eskf<models::Ins15Model, policies::ChiSquareGate> f(model, b, {}, policies::ChiSquareGate(0.999));
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
  using L = Layout<StateBlock<"p", 3>, StateBlock<"v", 3>>;
  models::ConstantVelocity<L, 3> cv;
  models::RangeToPoint<L, 3> range;
  range.anchor = {5, 5, 2};
  Ekf<models::ConstantVelocity<L, 3>, policies::ChiSquareGate> f(cv, {}, {}, policies::ChiSquareGate(0.99));
  EXPECT_EQ(heap_uses([&] {
              for (int k = 0; k < 1000; ++k) {
                (void)f.predict({}, 0.1);
                (void)f.update(range, Vector<1>(7.0));
              }
            }),
            0);
}

}  // namespace
