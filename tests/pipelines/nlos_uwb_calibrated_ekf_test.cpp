// The self-calibrating EKF of the UWB pipeline (pipelines/nlos_uwb/calibrated_ekf.hpp) on a
// synthetic site shaped like the Hanyang one (4 anchors within 1.9 m x 1.7 m, 0.5 m and 1.97 m
// high, tag at 1 m) with a tag on an elongated loop out to 42 m at 1 m/s, 10 Hz ranges with
// 2 cm white noise:
//   - with no bias states and one sample per report it is RangeEkf, update for update;
//   - given per-anchor biases, it learns them and its track is far better than RangeEkf's;
//   - given reports that average the last 3 raw ranges, the averaging model removes the
//     along-track lag that a range-now model has (speed x one period);
//   - a restart keeps the biases; refused inputs leave the belief as it was;
//   - the fixed-lag output is 0.9 s behind and closer to the truth than the newest state.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/pipelines/nlos_uwb/calibrated_ekf.hpp"
#include "ctxfuse/pipelines/nlos_uwb/estimators.hpp"
#include "ctxfuse/sim/random.hpp"

namespace {
using namespace ctxfuse;
namespace nu = pipelines::nlos_uwb;

constexpr double kPeriod = 0.1, kSpeed = 1.0;
const std::array<Eigen::Vector3d, 4> kAnchors{Eigen::Vector3d(0.69, 0.87, 0.5), Eigen::Vector3d(2.5775, -0.87, 1.97),
                                              Eigen::Vector3d(2.5775, 0.87, 1.97), Eigen::Vector3d(2.5775, -0.87, 0.5)};
constexpr std::array<int, 4> kIds{12, 3, 5, 9};

/// The loop: an ellipse centred 22 m out, semi-axes 20 m (out) and 6 m (across), run at
/// kSpeed (arc length parametrised numerically); position and unit direction of travel.
struct Loop {
  std::vector<Eigen::Vector2d> points;  // every 1 cm of arc
  Loop() {
    const int n = 200000;
    Eigen::Vector2d prev(2.0, 0.0);
    points.push_back(prev);
    double carry = 0.0;
    for (int i = 1; i <= n; ++i) {
      const double a = std::numbers::pi + 2.0 * std::numbers::pi * i / n;
      const Eigen::Vector2d q(22.0 + 20.0 * std::cos(a), 6.0 * std::sin(a));
      carry += (q - prev).norm();
      prev = q;
      while (carry >= 0.01) {
        points.push_back(q);
        carry -= 0.01;
      }
    }
  }
  Eigen::Vector2d at(double t) const {
    const auto i = static_cast<std::size_t>(std::llround(kSpeed * t / 0.01)) % points.size();
    return points[i];
  }
  Eigen::Vector2d direction(double t) const { return (at(t + 0.05) - at(t - 0.05)).normalized(); }
};

/// Epochs of 4 ranges (one per anchor, 2 ms apart) every 0.1 s for `seconds`: each report is
/// the mean of the last `samples` raw ranges (one period apart) plus the anchor's bias.
std::vector<std::array<messages::UwbRange, 4>> epochs(const Loop& loop, double seconds, int samples, const std::array<double, 4>& bias,
                                               std::uint64_t seed) {
  sim::Rng rng(seed, sim::Stream::uwb);
  std::vector<std::array<messages::UwbRange, 4>> out;
  for (int k = 1; k * kPeriod <= seconds; ++k) {
    std::array<messages::UwbRange, 4> e;
    for (std::size_t a = 0; a < 4; ++a) {
      const double t = k * kPeriod + 0.002 * static_cast<double>(a);
      double sum = 0.0;
      for (int j = 0; j < samples; ++j) {
        const Eigen::Vector2d p = loop.at(t - j * kPeriod);
        sum += (Eigen::Vector3d(p.x(), p.y(), 1.0) - kAnchors[a]).norm() + 0.02 * rng.normal();
      }
      e[a].t = t;
      e[a].anchor_id = kIds[a];
      e[a].anchor_position = kAnchors[a];
      e[a].range_m = sum / samples + bias[a];
    }
    out.push_back(e);
  }
  return out;
}

struct Errors {
  double rms = 0.0, along_mean = 0.0, lagged_rms = 0.0;
  std::vector<Eigen::Vector2d> positions;
};

/// Runs the estimator from the true start over the epochs, every range attached; errors over
/// the epochs after `settle` seconds (the newest state's, and the lagged output's if any).
template <class E>
Errors track(E& est, const Loop& loop, const std::vector<std::array<messages::UwbRange, 4>>& ep, double settle) {
  Errors out;
  const double t0 = ep.front()[0].t;
  EXPECT_TRUE(est.start(t0, loop.at(t0), Eigen::Matrix2d::Identity() * 0.01).accepted());
  std::array<bool, 4> attach{true, true, true, true};
  double sq = 0.0, along = 0.0, lagged_sq = 0.0;
  int n = 0;
  for (std::size_t k = 1; k < ep.size(); ++k) {
    std::array<Status, 4> st{};
    EXPECT_TRUE(est.apply_epoch(ep[k], attach, st).accepted());
    out.positions.push_back(est.position());
    const double t = est.time();
    if (t < settle) continue;
    const Eigen::Vector2d e = est.position() - loop.at(t);
    sq += e.squaredNorm();
    along += e.dot(loop.direction(t));
    if constexpr (requires { est.output_time(); }) lagged_sq += (est.output_position() - loop.at(est.output_time())).squaredNorm();
    ++n;
  }
  out.rms = std::sqrt(sq / n);
  out.along_mean = along / n;
  out.lagged_rms = std::sqrt(lagged_sq / n);
  return out;
}

nu::Settings raw_reports() {
  nu::Settings s;
  s.range_average_samples = 1;  // the synthetic sensor's, unless a test says otherwise
  return s;
}

constexpr std::array<double, 4> kNoBias{0.0, 0.0, 0.0, 0.0};
constexpr std::array<double, 4> kBias{0.10, 0.02, 0.07, -0.03};  // within the data sheet's +-10 cm

TEST(CalibratedEkf, WithoutBiasStatesAndAveragingItIsTheRangeEkf) {
  const Loop loop;
  const auto ep = epochs(loop, 60.0, 1, kBias, 1);
  nu::Settings s = raw_reports();
  s.anchor_bias_sigma_m = 0.0;
  nu::CalibratedRangeEkf<> cal(s);
  nu::RangeEkf<> plain(s);
  const Errors a = track(cal, loop, ep, 0.0), b = track(plain, loop, ep, 0.0);
  ASSERT_EQ(a.positions.size(), b.positions.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < a.positions.size(); ++k) worst = std::max(worst, (a.positions[k] - b.positions[k]).norm());
  EXPECT_LT(worst, 1e-9);
}

TEST(CalibratedEkf, LearnsTheAnchorBiasesAndKeepsTheTrackOnTheLoop) {
  const Loop loop;
  const double lap = static_cast<double>(loop.points.size()) * 0.01 / kSpeed;  // ~90 s
  const auto ep = epochs(loop, 3.0 * lap, 1, kBias, 2);
  const nu::Settings s = raw_reports();
  nu::CalibratedRangeEkf<> cal(s);
  nu::RangeEkf<> plain(s);
  const Errors a = track(cal, loop, ep, lap), b = track(plain, loop, ep, lap);
  std::printf("loop %.0f s: RangeEkf RMS %.3f m, calibrated %.3f m; biases", lap, b.rms, a.rms);
  for (std::size_t i = 0; i < 4; ++i) {
    double bias = 0.0, sigma = 0.0;
    ASSERT_TRUE(cal.anchor_bias(kIds[i], bias, sigma));
    std::printf(" %+.3f (%.3f)", bias, sigma);
    EXPECT_LT(std::abs(bias - kBias[i]), 3.0 * sigma) << "anchor " << kIds[i];
    EXPECT_LT(sigma, 0.012);  // learned: the prior was 0.10
  }
  std::printf("\n");
  EXPECT_GT(b.rms, 0.8);   // a few cm of bias between anchors 1.9 m apart: a metre out there
  EXPECT_LT(a.rms, 0.15);  // the 2 cm ranging noise over this geometry
  double unused = 0.0;
  EXPECT_FALSE(cal.anchor_bias(42, unused, unused));
}

TEST(CalibratedEkf, TheAveragingModelRemovesTheAlongTrackLag) {
  const Loop loop;
  const auto ep = epochs(loop, 120.0, 3, kNoBias, 3);
  nu::Settings with = raw_reports();
  with.range_average_samples = 3;
  with.anchor_bias_sigma_m = 0.0;
  nu::Settings without = with;
  without.range_average_samples = 1;
  nu::CalibratedRangeEkf<> a(with), b(without);
  const Errors ea = track(a, loop, ep, 10.0), eb = track(b, loop, ep, 10.0);
  std::printf("along-track mean error: averaging modelled %+.3f m, range-now model %+.3f m (speed x period %.3f m)\n",
              ea.along_mean, eb.along_mean, kSpeed * kPeriod);
  EXPECT_NEAR(eb.along_mean, -kSpeed * kPeriod, 0.3 * kSpeed * kPeriod);  // one period late
  EXPECT_LT(std::abs(ea.along_mean), 0.05 * kSpeed * kPeriod);
  EXPECT_LT(ea.rms, eb.rms);
}

TEST(CalibratedEkf, TheFixedLagOutputIsBehindByTheLagAndCloser) {
  const Loop loop;
  const auto ep = epochs(loop, 120.0, 1, kBias, 4);
  const nu::Settings s = raw_reports();
  nu::CalibratedRangeEkf<policies::ChiSquareGate, true> est(s);
  const Errors e = track(est, loop, ep, 30.0);
  std::printf("newest RMS %.3f m, %.1f s behind %.3f m\n", e.rms, s.smoothed_output_lag_s, e.lagged_rms);
  // The newest record at least the lag back: within one epoch (4 records) of it.
  EXPECT_LE(est.output_time(), est.time() - s.smoothed_output_lag_s + 1e-6);
  EXPECT_GT(est.output_time(), est.time() - s.smoothed_output_lag_s - kPeriod);
  EXPECT_LT(e.lagged_rms, 0.8 * e.rms);
}

TEST(CalibratedEkf, ARestartKeepsTheBiasesAndRefusalsChangeNothing) {
  const Loop loop;
  const auto ep = epochs(loop, 60.0, 1, kBias, 5);
  nu::CalibratedRangeEkf<> est(raw_reports());
  track(est, loop, ep, 0.0);
  const Gaussian<12> before = est.belief();
  // Refused: a NaN range, a negative one, one beyond reach, a prediction back in time.
  messages::UwbRange r = ep.back()[0];
  for (double bad : {std::nan(""), -1.0, 1e6}) {
    r.range_m = bad;
    EXPECT_EQ(est.update(r).outcome, Outcome::invalid_input) << bad;
  }
  EXPECT_EQ(est.predict_to(est.time() - 0.5).problem, Problem::out_of_order_time);
  EXPECT_EQ(est.belief().mean, before.mean);
  EXPECT_EQ(est.belief().cov, before.cov);
  // Stop and start again elsewhere: position and velocity from the fix, the biases as learned.
  est.stop();
  EXPECT_FALSE(est.started());
  ASSERT_TRUE(est.start(est.time() + 1.0, Eigen::Vector2d(5.0, 1.0), Eigen::Matrix2d::Identity() * 0.25).accepted());
  EXPECT_EQ(est.position(), Eigen::Vector2d(5.0, 1.0));
  EXPECT_EQ(est.belief().mean.tail<8>(), before.mean.tail<8>());
  const SquareMatrix<8> bias_cov = est.belief().cov.bottomRightCorner(8, 8);
  EXPECT_EQ(bias_cov, SquareMatrix<8>(before.cov.bottomRightCorner(8, 8)));
  EXPECT_EQ(est.belief().cov.topRightCorner(4, 8).norm(), 0.0);
}

}  // namespace
