// The EKF of the gated UWB fusion with the IMU as process model (pipelines/nlos_uwb/imu_ekf.hpp)
// against the filter written out by hand: the prediction over buffered IMU pieces equals one
// EKF step of the planar IMU model per sample (clipped at both ends), an epoch's ranges are
// applied each at its own time with the textbook scalar update, and bad input (no IMU, a time
// before the clock, a gross range through the gate) leaves the belief as it was.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/pipelines/nlos_uwb/imu_ekf.hpp"

namespace {
using namespace ctxfuse;
namespace nu = pipelines::nlos_uwb;
using L = models::PlanarLayout;

// A sample every 10 ms from t = 0: turning and accelerating a little, different every time.
messages::ImuSample sample(int k) {
  messages::ImuSample s;
  s.t = 0.01 * k;
  s.gyro << 0.0, 0.0, 0.05 * std::sin(0.3 * k);
  s.accel << 0.4 * std::cos(0.2 * k), 0.1 * std::sin(0.5 * k), 9.81;
  return s;
}

// Started by fixes moving east at 2 m/s (an alignment after 5 m), then fed IMU pieces from the
// start time on; returns the start time.
double started_with_imu(nu::ImuRangeEkf<policies::NoGate>& est, int samples_after) {
  const Eigen::Matrix2d P = Eigen::Matrix2d::Identity() * 0.01;
  for (int k = 0; k <= 40 && !est.started(); ++k) (void)est.start(0.1 * k, Eigen::Vector2d(0.2 * k, 0.0), P);
  EXPECT_TRUE(est.started());
  const double t0 = est.time();
  const int k0 = static_cast<int>(std::lround(t0 / 0.01));
  for (int k = k0; k < k0 + samples_after; ++k) est.add_imu(0.01 * k, 0.01, sample(k));
  return t0;
}

// The same prediction written out: one ekf::predict of PlanarImuModel per sample in force,
// clipped to [t0, t1].
void predict_by_samples(Gaussian<L::size>& b, double t0, double t1, const models::PlanarImuModel& m) {
  for (int k = 0; 0.01 * k < t1; ++k) {
    const double a = std::max(t0, 0.01 * k), e = std::min(t1, 0.01 * (k + 1));
    if (e <= a + 1e-12) continue;
    ASSERT_TRUE(ekf::predict(m, b, models::planar_input(sample(k)), e - a).accepted());
  }
}

TEST(NlosImuEkf, PredictionOverBufferedPiecesEqualsOneStepPerSample) {
  const nu::Settings s;
  const nu::ImuFusionSettings imu;
  nu::ImuRangeEkf<policies::NoGate> est(s, imu);
  const double t0 = started_with_imu(est, 50);
  Gaussian<L::size> ref = est.belief();
  const double x0 = est.position().x();
  const double t1 = t0 + 0.237;  // ends inside a sample
  ASSERT_TRUE(est.predict_to(t1).accepted());
  predict_by_samples(ref, t0, t1, imu.model());
  EXPECT_LT((est.belief().mean - ref.mean).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((est.belief().cov - ref.cov).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(est.position().x() - x0, 0.4);  // it moved: 2 m/s over 0.237 s
}

TEST(NlosImuEkf, EpochRangesAreAppliedEachAtItsOwnTimeWithTheScalarUpdate) {
  const nu::Settings s;
  const nu::ImuFusionSettings imu;
  nu::ImuRangeEkf<policies::NoGate> est(s, imu);
  const double t0 = started_with_imu(est, 50);
  std::array<messages::UwbRange, 3> epoch{};
  const double times[3] = {t0 + 0.104, t0 + 0.131, t0 + 0.162};
  const Eigen::Vector3d anchors[3] = {{0.0, 20.0, 2.5}, {30.0, -10.0, 2.0}, {-5.0, -15.0, 3.0}};
  for (int a = 0; a < 3; ++a) {
    auto& r = epoch[static_cast<std::size_t>(a)];
    r.t = times[a];
    r.anchor_id = a;
    r.anchor_position = anchors[a];
    r.range_m = 18.0 + 3.0 * a;
  }
  const std::array<bool, 3> attach{true, false, true};  // the middle one left out by a policy
  std::array<Status, 3> st{};
  Gaussian<L::size> ref = est.belief();
  ASSERT_TRUE(est.apply_epoch(epoch, attach, st).accepted());
  EXPECT_TRUE(st[0].accepted());
  EXPECT_TRUE(st[2].accepted());
  double t = t0;
  for (int a : {0, 2}) {
    predict_by_samples(ref, t, times[a], imu.model());
    t = times[a];
    // Textbook: h = |(p, h_tag) - anchor|, H = (p - a_xy)' / h on the position columns.
    const Eigen::Vector2d d = L::get<"p">(ref.mean) - anchors[a].head<2>();
    const double dz = s.tag_height_m - anchors[a].z();
    const double r = std::sqrt(d.squaredNorm() + dz * dz);
    Matrix<1, L::size> H = Matrix<1, L::size>::Zero();
    H(0, 0) = d.x() / r;
    H(0, 1) = d.y() / r;
    const double S = (H * ref.cov * H.transpose())(0, 0) + s.range_sigma_m * s.range_sigma_m;
    const Vector<L::size> K = ref.cov * H.transpose() / S;
    ref.mean += K * (epoch[static_cast<std::size_t>(a)].range_m - r);
    ref.cov = (SquareMatrix<L::size>::Identity() - K * H) * ref.cov;
  }
  EXPECT_DOUBLE_EQ(est.time(), times[2]);
  EXPECT_LT((est.belief().mean - ref.mean).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((est.belief().cov - ref.cov).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(NlosImuEkf, NoImuOrATimeBeforeTheClockIsRefusedAndChangesNothing) {
  const nu::Settings s;
  nu::ImuRangeEkf<policies::NoGate> est(s, nu::ImuFusionSettings{});
  EXPECT_EQ(est.predict_to(1.0).problem, Problem::time_not_set);
  const double t0 = started_with_imu(est, 0);  // no IMU at all
  const Gaussian<L::size> before = est.belief();
  EXPECT_EQ(est.predict_to(t0 + 0.1).problem, Problem::non_finite_input);
  EXPECT_EQ(est.time(), t0);
  EXPECT_EQ(est.belief().mean, before.mean);
  EXPECT_EQ(est.belief().cov, before.cov);
  EXPECT_EQ(est.predict_to(t0 - 0.1).problem, Problem::out_of_order_time);
  EXPECT_EQ(est.predict_to(std::nan("")).problem, Problem::non_finite_dt);
  EXPECT_EQ(est.time(), t0);
  messages::UwbRange bad;
  bad.t = t0;
  bad.anchor_position = Eigen::Vector3d(0.0, 20.0, 2.5);
  bad.range_m = -1.0;
  EXPECT_EQ(est.update(bad).problem, Problem::measurement_out_of_domain);
  bad.range_m = std::nan("");
  EXPECT_EQ(est.update(bad).problem, Problem::non_finite_measurement);
  EXPECT_EQ(est.belief().mean, before.mean);
}

TEST(NlosImuEkf, TheGateRefusesAGrossRangeAndKeepsTheBelief) {
  const nu::Settings s;
  nu::ImuRangeEkf<> est(s, nu::ImuFusionSettings{});
  const Eigen::Matrix2d P = Eigen::Matrix2d::Identity() * 0.01;
  for (int k = 0; k <= 40 && !est.started(); ++k) (void)est.start(0.1 * k, Eigen::Vector2d(0.2 * k, 0.0), P);
  ASSERT_TRUE(est.started());
  const Gaussian<L::size> before = est.belief();
  const Eigen::Vector2d p = est.position();
  messages::UwbRange r;
  r.t = est.time();
  r.anchor_position = Eigen::Vector3d(p.x(), p.y() + 20.0, s.tag_height_m);
  r.range_m = 70.0;  // 50 m long
  EXPECT_EQ(est.update(r).outcome, Outcome::gated);
  EXPECT_EQ(est.belief().mean, before.mean);
  r.range_m = 20.05;  // nominal
  EXPECT_TRUE(est.update(r).accepted());
  EXPECT_NE(est.belief().mean, before.mean);
}

}  // namespace
