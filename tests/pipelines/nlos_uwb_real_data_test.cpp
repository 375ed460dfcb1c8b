// The NLOS-robust UWB pipeline on the Hanyang Trajectory_A recordings (real data; skipped
// without CTXFUSE_DATA_DIR's uwb-outdoor-hanyang, a failure under CI=true). Each case is scored
// with the dataset authors' protocol beside their own LS and ESKF figures read from the case's
// RMSD_results.txt. The SVM of p1 is trained on the other three cases (leave one case out), never
// on the scored one. One set of settings (nu::Settings{}) for all four.
//
// Each measured value is pinned within 3 % of itself (the runs are deterministic; 3 % leaves
// room for compiler and libm differences, and is far below the margins to the authors' figures
// that the test also asserts where we are below them).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>
#include <cstdio>
#include <string>

#include "ctxfuse/instances/nlos_uwb.hpp"
#include "support/data_dir.hpp"

namespace nu = ctxfuse::pipelines::nlos_uwb;

namespace {

struct Expected {
  const char* dir;
  double paper_rule, per_range, gate, least_squares;  // EKF variants and LS: measured 2-D RMSE [m]
  double smoother, smoother_lag9;                      // fixed-lag smoother: newest, 9 epochs back
  double ds_accuracy, ds_precision;                    // measured D-S identification
  // The self-calibrating EKF: paper rule, per-range rule, gate only; newest, then 0.9 s back.
  double cal_paper, cal_per_range, cal_gate, cal_paper_lag, cal_per_range_lag, cal_gate_lag;
};

// Measured with this file's code (docs/results.md, "NLOS-robust UWB (paper C), real data").
constexpr Expected kCases[] = {
    {"LOS/Trajectory_A/Case_1", 1.122, 0.890, 0.842, 0.871, 0.848, 0.777, 0.887, 0.384, 0.923, 0.603, 0.538, 0.658, 0.450, 0.422},
    {"LOS/Trajectory_A/Case_2", 0.699, 0.641, 0.604, 2.940, 0.598, 0.480, 0.925, 0.747, 0.604, 0.571, 0.538, 0.456, 0.444, 0.418},
    {"NLOS/Trajectory_A/Case_1", 0.907, 0.833, 0.827, 0.856, 0.837, 0.774, 0.908, 0.575, 0.746, 0.673, 0.642, 0.603, 0.570, 0.544},
    {"NLOS/Trajectory_A/Case_2", 1.009, 0.917, 0.887, 1.398, 0.883, 0.798, 0.898, 0.736, 0.837, 0.649, 0.670, 0.619, 0.503, 0.521},
};

void pin(double measured, double expected, const std::string& what) {
  EXPECT_NEAR(measured, expected, 0.03 * expected) << what;
}

class NlosUwbRealData : public ::testing::TestWithParam<Expected> {};

}  // namespace

TEST_P(NlosUwbRealData, BelowTheAuthorsWhereMeasuredSo) {
  const Expected& x = GetParam();
  CTXFUSE_REQUIRE_DATA(dir, std::string("uwb-outdoor-hanyang/Dynamic_measurements/") + x.dir);
  const auto training = ctxfuse::studies::other_hanyang_cases(dir);
  ASSERT_EQ(training.size(), 3u);
  const auto rep = ctxfuse::studies::evaluate_nlos_uwb_case(dir, training, nu::Settings{}, ctxfuse::studies::trajectory_a_span());
  ASSERT_TRUE(rep.svm);
  const double authors_ls = rep.authors.at("LS RMSE_2d"), authors_eskf = rep.authors.at("ESKF RMSE_2d");
  const double best_authors = std::min(authors_ls, authors_eskf);
  const double paper = rep.variant("ekf_gate_paper_rule").rmse.rmse_2d;
  const double per_range = rep.variant("ekf_gate_per_range").rmse.rmse_2d;
  const double gate = rep.variant("ekf_gate").rmse.rmse_2d;
  const double ls = rep.variant("least_squares").rmse.rmse_2d;
  const double smoother = rep.variant("smoother_gate").rmse.rmse_2d;
  const double lag9 = rep.variant("smoother_gate_lag9").rmse.rmse_2d;
  std::printf("%s: paper rule %.3f, per range %.3f, gate only %.3f, smoother %.3f / lag 9 %.3f, LS %.3f; authors LS %.3f ESKF %.3f\n",
              x.dir, paper, per_range, gate, smoother, lag9, ls, authors_ls, authors_eskf);
  pin(paper, x.paper_rule, "EKF + gate + paper epoch rule");
  pin(per_range, x.per_range, "EKF + gate + per-range rule");
  pin(gate, x.gate, "EKF + gate");
  pin(ls, x.least_squares, "least squares");
  pin(smoother, x.smoother, "smoother, newest state");
  pin(lag9, x.smoother_lag9, "smoother, 9 epochs back");
  // The gated EKF, with and without the per-range rule, is below both of the authors' figures
  // on every case; the paper's epoch rule everywhere but LOS case 1 (1.12 m against their LS
  // 1.04 m: it leaves out 21 % of the epochs on false NLOS calls).
  EXPECT_LT(gate, best_authors);
  EXPECT_LT(per_range, best_authors);
  EXPECT_LT(smoother, best_authors);
  // The state 9 epochs back has 0.9 s of later ranges: better than any causal estimate here.
  EXPECT_LT(lag9, std::min(gate, smoother));
  if (std::string(x.dir) != "LOS/Trajectory_A/Case_1") {
    EXPECT_LT(paper, best_authors);
  }
  // The self-calibrating EKF (anchor biases, the averaged report's time): below both of the
  // authors' figures with every NLOS policy on every case, and below the plain EKF of the same
  // policy; its fixed-lag output (0.9 s behind) is better still, and within the 0.6 m
  // on every case with the per-range rule or the gate alone. Not with the paper's epoch rule
  // (0.603 m on NLOS case 1): the epochs it leaves out are estimated by the motion model alone,
  // and runs of them longer than the lag are not smoothed by later ranges.
  const double cal[] = {rep.variant("calibrated_ekf_gate_paper_rule").rmse.rmse_2d, rep.variant("calibrated_ekf_gate_per_range").rmse.rmse_2d,
                        rep.variant("calibrated_ekf_gate").rmse.rmse_2d};
  const double cal_lag[] = {rep.variant("calibrated_ekf_gate_paper_rule_lag").rmse.rmse_2d,
                            rep.variant("calibrated_ekf_gate_per_range_lag").rmse.rmse_2d, rep.variant("calibrated_ekf_gate_lag").rmse.rmse_2d};
  std::printf("%s: self-calibrating EKF paper rule %.3f, per range %.3f, gate only %.3f; 0.9 s behind %.3f, %.3f, %.3f\n", x.dir,
              cal[0], cal[1], cal[2], cal_lag[0], cal_lag[1], cal_lag[2]);
  pin(cal[0], x.cal_paper, "self-calibrating EKF, paper rule");
  pin(cal[1], x.cal_per_range, "self-calibrating EKF, per-range rule");
  pin(cal[2], x.cal_gate, "self-calibrating EKF, gate only");
  pin(cal_lag[0], x.cal_paper_lag, "self-calibrating EKF, paper rule, 0.9 s behind");
  pin(cal_lag[1], x.cal_per_range_lag, "self-calibrating EKF, per-range rule, 0.9 s behind");
  pin(cal_lag[2], x.cal_gate_lag, "self-calibrating EKF, gate only, 0.9 s behind");
  const double plain[] = {paper, per_range, gate};
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT(cal[k], best_authors) << k;
    EXPECT_LT(cal[k], plain[k]) << k;
    EXPECT_LT(cal_lag[k], cal[k]) << k;
    EXPECT_LT(cal_lag[k], best_authors) << k;
    if (k > 0) {
      EXPECT_LE(cal_lag[k], 0.6) << k;
    }
  }
  // Every range entering without a gate: gross ranges (up to 19 m off) and the mirror image
  // make it several metres; the motion model alone is tens of metres off.
  EXPECT_GT(rep.variant("ekf").rmse.rmse_2d, 3.0 * gate);
  EXPECT_GT(rep.variant("motion_model_only").rmse.rmse_2d, 10.0 * gate);
  // Identification: D-S more precise than the SVM alone (the paper's point of fusing them).
  const auto& id = rep.identification;
  pin(id.ds.accuracy, x.ds_accuracy, "D-S accuracy");
  pin(id.ds.precision, x.ds_precision, "D-S precision");
  EXPECT_GT(id.ds.precision, id.svm.precision);
  EXPECT_GT(id.ds.accuracy, id.svm.accuracy);
}

INSTANTIATE_TEST_SUITE_P(TrajectoryA, NlosUwbRealData, ::testing::ValuesIn(kCases), [](const auto& info) {
  std::string n = info.param.dir;
  std::replace(n.begin(), n.end(), '/', '_');
  return n;
});

// The reports are 3-sample moving averages (settings.range_average_samples): on the static start
// of every dynamic recording (before the reference has moved 0.3 m, less 2 s), the first
// differences of each anchor's ranges have autocorrelation about -0.5 at lag 3 and about 0 at
// lags 1 and 2. Differences of white noise have -0.5 at lag 1; of an n-sample moving average of
// white noise, -1/2 at lag n and 0 below.
TEST(NlosUwbRealDataDiagnostics, TheReportsAreThreeSampleMovingAverages) {
  for (const Expected& x : kCases) {
    CTXFUSE_REQUIRE_DATA(dir, std::string("uwb-outdoor-hanyang/Dynamic_measurements/") + x.dir);
    const auto ranges = ctxfuse::io::read_hanyang_uwb(dir).uwb_ranges();
    const auto ref = ctxfuse::io::read_hanyang_reference(dir);
    ASSERT_FALSE(ref.empty());
    double moves = ref.back().t;
    for (const auto& p : ref)
      if ((p.position - ref.front().position).head<2>().norm() > 0.3) {
        moves = p.t;
        break;
      }
    // On the 0.1 s grid of each anchor (a dropped report leaves a hole, not a shifted index).
    std::map<int, std::map<long, double>> by_anchor;
    const double t0 = ranges.front().t;
    for (const auto& r : ranges)
      if (r.t < moves - 2.0) by_anchor[r.anchor_id][std::lround((r.t - t0) / 0.1)] = r.range_m;
    std::array<double, 4> acf{};  // lags 1..4, mean over the anchors
    for (const auto& [id, grid] : by_anchor) {
      ASSERT_GE(grid.size(), 40u) << x.dir << " anchor " << id;
      std::map<long, double> d;  // first differences where both reports exist
      double mean = 0.0;
      for (const auto& [k, r] : grid)
        if (const auto next = grid.find(k + 1); next != grid.end()) d[k] = next->second - r;
      for (const auto& [k, e] : d) mean += e / static_cast<double>(d.size());
      double var = 0.0;
      for (auto& [k, e] : d) {
        e -= mean;
        var += e * e;
      }
      for (long lag = 1; lag <= 4; ++lag) {
        double c = 0.0;
        int pairs = 0;
        for (const auto& [k, e] : d)
          if (const auto other = d.find(k + lag); other != d.end()) {
            c += e * other->second;
            ++pairs;
          }
        // Normalised per pair, as var is per difference.
        acf[static_cast<std::size_t>(lag - 1)] += (c / pairs) / (var / static_cast<double>(d.size())) / static_cast<double>(by_anchor.size());
      }
    }
    std::printf("%s: %zu anchors, static start %.1f s; autocorrelation of range differences at lags 1-4: %+.2f %+.2f %+.2f %+.2f\n",
                x.dir, by_anchor.size(), moves - ref.front().t - 2.0, acf[0], acf[1], acf[2], acf[3]);
    EXPECT_LT(acf[2], -0.3) << x.dir;
    EXPECT_LT(std::abs(acf[0]), 0.15) << x.dir;
    EXPECT_LT(std::abs(acf[1]), 0.15) << x.dir;
  }
}

// What each half of the self-calibrating EKF does (gate only, no NLOS rule, all four cases):
// anchor biases alone, the averaging model alone, both. Measured, printed, and each part
// asserted to help on its own on NLOS case 1.
TEST(NlosUwbRealDataDiagnostics, AnchorBiasesAndAveragingEachHelp) {
  std::array<std::array<double, 4>, 4> rmse{};  // [case][plain, biases, averaging, both]
  for (std::size_t c = 0; c < 4; ++c) {
    CTXFUSE_REQUIRE_DATA(dir, std::string("uwb-outdoor-hanyang/Dynamic_measurements/") + kCases[c].dir);
    const auto ranges = ctxfuse::io::read_hanyang_uwb(dir).uwb_ranges();
    const auto ref = ctxfuse::io::read_hanyang_reference(dir);
    const std::span<const ctxfuse::messages::UwbRange> rs(ranges);
    for (int v = 0; v < 4; ++v) {
      nu::Settings s;
      s.anchor_bias_sigma_m = (v == 1 || v == 3) ? s.anchor_bias_sigma_m : 0.0;
      s.range_average_samples = (v == 2 || v == 3) ? s.range_average_samples : 1;
      const auto t = nu::run(rs, nu::CalibratedRangeEkf<>(s), nu::NoNlosHandling{}, nu::NlosClassifier(s), s);
      rmse[c][static_cast<std::size_t>(v)] = ctxfuse::studies::hanyang_rmse_2d(ctxfuse::studies::timed_points(t), ref, ctxfuse::studies::trajectory_a_span()).rmse_2d;
    }
    std::printf("%s: plain %.3f, anchor biases %.3f, averaging %.3f, both %.3f m\n", kCases[c].dir, rmse[c][0], rmse[c][1],
                rmse[c][2], rmse[c][3]);
    EXPECT_NEAR(rmse[c][0], kCases[c].gate, 5e-4) << "no bias state and one sample: RangeEkf (the table's rounding)";
    EXPECT_LT(rmse[c][1], rmse[c][0]) << kCases[c].dir;
    EXPECT_LT(rmse[c][3], rmse[c][0]) << kCases[c].dir;
  }
  const auto& nlos1 = rmse[2];
  EXPECT_LT(nlos1[2], nlos1[0]);
  EXPECT_LT(nlos1[3], std::min(nlos1[1], nlos1[2]));
}

// What stays of NLOS case 1's error in the plain EKF (docs/results.md): measured, never applied
// to the runs.
TEST(NlosUwbRealDataDiagnostics, TimeOffsetGeometryAndProcessNoise) {
  CTXFUSE_REQUIRE_DATA(dir, "uwb-outdoor-hanyang/Dynamic_measurements/NLOS/Trajectory_A/Case_1");
  const nu::Settings s;
  const auto ranges = ctxfuse::io::read_hanyang_uwb(dir).uwb_ranges();
  const auto ref = ctxfuse::io::read_hanyang_reference(dir);
  const std::span<const ctxfuse::messages::UwbRange> rs(ranges);
  const auto span = ctxfuse::studies::trajectory_a_span();
  const auto ekf = nu::run(rs, nu::RangeEkf<>(s), nu::NoNlosHandling{}, nu::NlosClassifier(s), s);
  const auto ls = nu::least_squares_track(rs, s);
  auto shifted = [&](const nu::Track& t, double shift) {
    auto pts = ctxfuse::studies::timed_points(t);
    for (auto& p : pts) p.t += shift;
    return ctxfuse::studies::hanyang_rmse_2d(pts, ref, span).rmse_2d;
  };
  // (1) A time offset between ranges and reference: both the EKF and the filter-free LS are
  // best with their times moved 0.4 s earlier, by the same amount: not filter lag.
  const double ekf0 = shifted(ekf, 0.0), ekf4 = shifted(ekf, -0.4), ls0 = shifted(ls, 0.0), ls4 = shifted(ls, -0.4);
  std::printf("time shift -0.4 s: EKF %.3f -> %.3f m, LS %.3f -> %.3f m\n", ekf0, ekf4, ls0, ls4);
  EXPECT_LT(ekf4, 0.95 * ekf0);
  EXPECT_LT(ls4, 0.95 * ls0);
  for (double other : {-0.6, -0.2, 0.2}) {
    EXPECT_GT(shifted(ekf, other), ekf4) << other;
    EXPECT_GT(shifted(ls, other), ls4) << other;
  }
  // Along-track mean error: about -0.4 m at no shift (the estimate trails), near 0 at -0.4 s.
  auto along_mean = [&](double shift) {
    double sum = 0.0;
    int n = 0;
    const auto r = ctxfuse::studies::hanyang_rmse_2d(ctxfuse::studies::timed_points(ekf), ref, span);
    for (const auto& e : ekf.estimates) {
      const double t = e.t + shift;
      if (t < r.t_begin || t > r.t_end) continue;
      const Eigen::Vector3d a = ctxfuse::studies::reference_at(ref, t), b = ctxfuse::studies::reference_at(ref, t + 0.2);
      const Eigen::Vector2d d = (b - a).head<2>();
      if (!(d.norm() > 0.05)) continue;  // standing: no along-track direction
      sum += (e.position - a.head<2>()).dot(d.normalized());
      ++n;
    }
    return sum / n;
  };
  const double along0 = along_mean(0.0), along4 = along_mean(-0.4);
  std::printf("along-track mean error: %.3f m at 0 s, %.3f m at -0.4 s\n", along0, along4);
  EXPECT_LT(along0, -0.3);
  EXPECT_LT(std::abs(along4), 0.1);
  // (2) Geometry: the error grows with the distance from the anchors (1.9 x 1.7 m apart).
  auto by_distance = [&](const nu::Track& track) {
    const auto r = ctxfuse::studies::hanyang_rmse_2d(ctxfuse::studies::timed_points(track), ref, span);
    std::array<double, 7> sq{};
    std::array<int, 7> n{};
    for (const auto& e : track.estimates) {
      if (e.t < r.t_begin || e.t > r.t_end) continue;
      const Eigen::Vector3d p = ctxfuse::studies::reference_at(ref, e.t);
      const auto bin = static_cast<std::size_t>(std::min(6.0, std::hypot(p.x() - 2.0, p.y()) / 8.0));
      sq[bin] += (e.position - p.head<2>()).squaredNorm();
      ++n[bin];
    }
    std::vector<double> out;
    for (std::size_t b = 0; b < sq.size(); ++b)
      if (n[b] > 0) {
        out.push_back(std::sqrt(sq[b] / n[b]));
        std::printf("  %2zu-%2zu m from the anchors: %4d estimates, RMSE %.3f m\n", 8 * b, 8 * b + 8, n[b], out.back());
      }
    return out;
  };
  const auto plain_bins = by_distance(ekf);
  ASSERT_GE(plain_bins.size(), 5u);
  EXPECT_GT(plain_bins.back(), 2.5 * plain_bins.front());
  // The self-calibrating EKF (anchor biases, averaged reports): the far error comes down, and
  // part of the time offset goes (the averaging is one period of it); the rest stays.
  const auto cal = nu::run(rs, nu::CalibratedRangeEkf<>(s), nu::NoNlosHandling{}, nu::NlosClassifier(s), s);
  std::printf("self-calibrating EKF by distance:\n");
  const auto cal_bins = by_distance(cal);
  ASSERT_EQ(cal_bins.size(), plain_bins.size());
  EXPECT_LT(cal_bins.back(), 0.8 * plain_bins.back());
  double best_shift = 0.0, best = shifted(cal, 0.0);
  for (double shift : {-0.5, -0.4, -0.3, -0.2, -0.1, 0.1}) {
    const double e = shifted(cal, shift);
    std::printf("self-calibrating EKF, time shift %+.1f s: %.3f m (none: %.3f m)\n", shift, e, shifted(cal, 0.0));
    if (e < best) best = e, best_shift = shift;
  }
  EXPECT_LT(best_shift, -0.1);  // a time offset stays beyond the averaging's period
  // Gross ranges: the largest range residual against the reference, in metres.
  double worst = 0.0;
  for (const auto& rec : ekf.ranges)
    if (const double e = ctxfuse::studies::range_residual(rec.range, ref, s.tag_height_m); std::abs(e) > std::abs(worst)) worst = e;
  std::printf("largest range residual %.2f m\n", worst);
  EXPECT_GT(std::abs(worst), 10.0);
  // (3) Not the process noise: q ten times smaller or three times larger moves it < 3 %.
  for (double q : {0.1, 3.0}) {
    nu::Settings sq_settings;
    sq_settings.accel_psd = q;
    const auto t = nu::run(rs, nu::RangeEkf<>(sq_settings), nu::NoNlosHandling{}, nu::NlosClassifier(sq_settings), sq_settings);
    const double e = ctxfuse::studies::hanyang_rmse_2d(ctxfuse::studies::timed_points(t), ref, span).rmse_2d;
    std::printf("q = %.1f m^2/s^3: %.3f m (q = 1: %.3f m)\n", q, e, ekf0);
    EXPECT_NEAR(e, ekf0, 0.03 * ekf0);
  }
}
