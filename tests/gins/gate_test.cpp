// The one-tailed chi-square gate on the GNSS position update of the geodetic INS: a 50 m jump
// is refused (belief untouched), and fixes drawn from the filter's own predictive distribution
// are accepted at the gate's probability.
#include <gtest/gtest.h>

#include <iostream>

#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins_updates.hpp"
#include "ctxfuse/sim/random.hpp"
#include "states.hpp"

namespace {
using namespace ctxfuse;
using namespace ctxfuse::models;
using test::Nav15;

struct GateSetup {
  Nav15 model;
  eskf::Belief<Nav15> belief;
  GnssGeodeticPosition<NavState> gnss;
  Eigen::Matrix3d P_pos_ned = Eigen::Vector3d(1.0, 1.0, 4.0).asDiagonal();  // [m^2]
  Eigen::Matrix3d R_ned = Eigen::Vector3d(0.25, 0.25, 1.0).asDiagonal();    // [m^2]
  GateSetup() {
    belief.nominal = test::sample_nav_state();
    belief.cov = Vector<15>::Constant(1e-4).asDiagonal();
    belief.cov.topLeftCorner<3, 3>() = P_pos_ned;
    gnss.lever_arm = {0.3, 0.0, -1.0};
    gnss.R = geodetic_position_noise(belief.nominal.get<"p">(), R_ned);
  }
  /// A fix at the antenna, `offset_ned` metres away, as (lat, lon, h).
  Vector<3> fix(const Eigen::Vector3d& offset_ned) const {
    const Vector<3> antenna = gnss.predict(belief.nominal, nullptr);
    return earth::GeodeticRetraction::inject(antenna, offset_ned);
  }
};

TEST(GinsGate, RejectsAFiftyMetreJumpAndLeavesTheBeliefAlone) {
  GateSetup s;
  const policies::ChiSquareGate gate(0.99);
  eskf::Belief<Nav15> b = s.belief;
  const Status st = eskf::update(s.model, s.gnss, b, s.fix({50.0, 0.0, 0.0}), gate);
  EXPECT_EQ(st.outcome, Outcome::gated);
  // NIS of 50 m north against S_nn = 1 + 0.25 m^2 (plus 1e-4 m^2 of attitude times the 1 m
  // lever arm): 2000 (threshold 11.34 at 3 dof).
  EXPECT_NEAR(st.nis, 2500.0 / 1.25, 0.5);
  EXPECT_NEAR(st.gate_threshold, 11.3449, 1e-3);
  EXPECT_EQ(b.cov, s.belief.cov);
  EXPECT_TRUE(b.nominal.get<"p">() == s.belief.nominal.get<"p">());
  // A nominal fix 1 m off passes and moves the estimate.
  EXPECT_TRUE(eskf::update(s.model, s.gnss, b, s.fix({1.0, -0.5, 0.3}), gate).accepted());
}

TEST(GinsGate, AcceptsNominalFixesAtTheGateProbability) {
  // Truth drawn from the belief, fix from the truth with the receiver's noise: the innovation is
  // N(0, H P H' + R), so the NIS is chi-square with 3 dof and the acceptance rate is 1 - alpha.
  GateSetup s;
  sim::Rng rng(17);
  const int n = 20000;
  const Eigen::Matrix3d Lp = s.P_pos_ned.llt().matrixL(), Lr = s.R_ned.llt().matrixL();
  for (const double probability : {0.99, 0.95}) {
    const policies::ChiSquareGate gate(probability);
    int accepted = 0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d e = Lp * rng.normals<3>();
      const Eigen::Vector3d noise = Lr * rng.normals<3>();
      Vector<15> dx = Vector<15>::Zero();
      dx.head<3>() = e;
      const NavState truth = s.model.inject(s.belief.nominal, dx);
      const Vector<3> z = earth::GeodeticRetraction::inject(s.gnss.predict(truth, nullptr), noise);
      eskf::Belief<Nav15> b = s.belief;
      accepted += eskf::update(s.model, s.gnss, b, z, gate).accepted() ? 1 : 0;
    }
    const double rate = static_cast<double>(accepted) / n;
    const double sd = std::sqrt(probability * (1.0 - probability) / n);
    std::cout << "gate " << probability << ": accepted " << rate << " of 20000 nominal fixes\n";
    EXPECT_NEAR(rate, probability, 4.0 * sd) << "acceptance " << rate << " vs " << probability;
  }
}

}  // namespace
