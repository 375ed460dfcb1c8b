// A user's translation unit with both namespaces open, a common habit: the library's headers
// and its names (layouts of state blocks, models, filters, gates, statuses) compile and work
// beside Eigen's. Vector and Matrix are the two names both define (ctxfuse's fixed-size
// aliases, Eigen's 3.4 templates): with both namespaces open they are written qualified, as
// below; every other ctxfuse name is unambiguous.
#include <gtest/gtest.h>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/filters/score.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"
#include "ctxfuse/policies/gating.hpp"

using namespace Eigen;
using namespace ctxfuse;

namespace {

using Layout2 = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
using Cv = models::ConstantVelocity<Layout2, 2>;

TEST(Namespaces, BothOpenCompileAndFilter) {
  Gaussian<4> prior{Vector4d(0.0, 0.0, 1.0, 0.0), Matrix4d::Identity()};
  Ekf<Cv, policies::ChiSquareGate> filter(Cv{}, prior, {}, policies::ChiSquareGate(0.99));
  filter.set_time(0.0);
  ASSERT_TRUE(filter.predict_to(1.0, NoInput{}));
  const models::BlockObservation<Layout2, "p"> pos;
  const Status s = filter.update(pos, Vector2d(1.0, 0.0));
  ASSERT_TRUE(s.accepted()) << describe(s.problem);
  // The predicted position (1, 0) is measured exactly: the mean stays there.
  EXPECT_NEAR(filter.belief().mean(0), 1.0, 1e-12);
  EXPECT_NEAR(filter.belief().mean(1), 0.0, 1e-12);
  const VectorXd wrong = VectorXd::Zero(3);
  EXPECT_EQ(filter.update(pos, wrong).problem, Problem::measurement_wrong_size);
  ctxfuse::Vector<2> z = Vector2d::Zero();
  EXPECT_EQ(filter.score(pos, z).dof, 2);
}

}  // namespace
