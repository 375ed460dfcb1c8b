// The NLOS paper's simulation protocol (studies/nlos_uwb_sim.hpp) on a short simulated drive
// (one garage lap, one training drive, 200 SVM rows per class: test sizes; the full-size numbers are
// in docs/results.md, section nlos_uwb_sim). Asserts the protocol's properties and the
// orderings that hold on every seed measured, not the paper's figures.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <utility>

#include "ctxfuse/instances/nlos_uwb.hpp"

namespace {
using namespace ctxfuse;
namespace nu = pipelines::nlos_uwb;

ctxfuse::studies::NlosSimReport short_drive_report(double episode_mean_s) {
    sim::DriveConfig base;
    base.route.duration_s = 150.0;
    base.route.indoor_laps = 1;
    ctxfuse::studies::NlosSimProtocol p;
    p.training_seed_offsets = {101};
    p.episode_mean_s = episode_mean_s;
    nu::Settings s;
    s.svm_rows_per_class = 200;
    return ctxfuse::studies::evaluate_nlos_uwb_sim(base, 1, p, s);
}

void print(const char* what, const ctxfuse::studies::NlosSimReport& r) {
  std::printf("%s: %zu ranges, %.1f %% NLOS\n", what, r.ranges, 100.0 * r.nlos_share());
  const std::pair<const char*, const ctxfuse::studies::Identification*> ids[] = {{"svm_vu", &r.svm_vu}, {"svm", &r.svm}, {"consistency", &r.consistency}, {"ds", &r.ds}};
  for (const auto& [name, id] : ids)
    std::printf("  %-12s P %.2f R %.2f A %.2f %%\n", name, 100 * id->precision, 100 * id->recall, 100 * id->accuracy);
  for (const auto& v : r.variants)
    std::printf("  %-22s n %5zu RMSE %7.3f MAX %7.3f STD %7.3f median %6.3f m\n", v.name.c_str(), v.errors.count, v.errors.horizontal.rmse,
                v.errors.horizontal.max, v.errors.horizontal.std, v.errors.horizontal.at(50));
}

const ctxfuse::studies::NlosSimReport& report() {
  static const ctxfuse::studies::NlosSimReport rep = [] {
    auto r = short_drive_report(std::nan(""));
    print("simulator's 1.5 s NLOS episodes", r);
    return r;
  }();
  return rep;
}

TEST(NlosUwbSim, ProtocolGivesAtLeastHalfTheRangesNlos) {
  const auto& r = report();
  ASSERT_GT(r.ranges, 1000u);
  // Transient chain at 0.5 plus wall crossings: at least half, and not all.
  EXPECT_GE(r.nlos_share(), 0.5);
  EXPECT_LE(r.nlos_share(), 0.7);
  EXPECT_EQ(r.drive_ranges.ranges.size(), r.ranges);
  EXPECT_GT(r.training_rows, 1000u);
}

TEST(NlosUwbSim, EveryRangeIsScoredByEveryClassifier) {
  const auto& r = report();
  // Only the anchors' first ranges (no range rate yet) lack evidence.
  for (const auto* id : {&r.svm_vu, &r.svm, &r.consistency, &r.ds}) {
    EXPECT_GE(id->scored + 16, r.ranges);
    EXPECT_GT(id->precision, r.nlos_share());  // a random guess's precision is the NLOS share
  }
  // D-S fusing the SVM with the consistency model is more precise than consistency alone.
  EXPECT_GT(r.ds.precision, r.consistency.precision);
}

TEST(NlosUwbSim, GraphBeatsSnapshotLeastSquaresAndImuOnlyDrifts) {
  const auto& r = report();
  const auto& ls = r.variant("least_squares").errors;
  const auto& graph = r.variant("graph").errors;
  const auto& imu = r.variant("imu_only").errors;
  // The smoother starts on the simulator's simultaneous ranges and keeps estimating.
  EXPECT_GE(graph.count, ls.count);
  EXPECT_LT(graph.horizontal.rmse, 0.25 * ls.horizontal.rmse);
  EXPECT_LT(graph.horizontal.max, ls.horizontal.max);
  EXPECT_GT(imu.horizontal.rmse, 10.0 * graph.horizontal.rmse);
  // The paper's rule leaves out the epochs it judges NLOS.
  EXPECT_GT(r.variant("graph_paper_rule").epochs_left_out, 100u);
  EXPECT_EQ(r.variant("graph").epochs_left_out, 0u);
}

// The paper's graph: IMU factors between the states instead of the constant-velocity motion
// model. The IMU carries the turns and braking that the motion model can only smooth over, so
// the graph without NLOS handling is better in RMSE and far better in MAX, and the paper's rule
// then gains over it (seeds 1-5 in docs/results.md).
TEST(NlosUwbSim, ImuFactorsBeatTheMotionModelAndThePaperRuleGainsWithThem) {
  const auto& r = report();
  const auto& cv = r.variant("graph").errors;
  const auto& imu = r.variant("graph_imu").errors;
  const auto& proposed = r.variant("graph_imu_paper_rule").errors;
  EXPECT_GT(imu.count, 1000u);
  EXPECT_LT(imu.horizontal.rmse, 0.95 * cv.horizontal.rmse);
  EXPECT_LT(imu.horizontal.max, 0.6 * cv.horizontal.max);
  EXPECT_LT(proposed.horizontal.rmse, imu.horizontal.rmse);
  EXPECT_GT(r.variant("graph_imu_paper_rule").epochs_left_out, 100u);
}

// The EKF of the same IMU fusion and rule (imu_ekf.hpp) against the graph: the graph reports its
// newest state, so it gains only from relinearising the window; on seeds 1-5 of the full drive
// the two RMSE differ by <= 0.02 m (docs/results.md). Here within 3 % (measured 1.2 %), both below
// the constant-velocity EKF of the same rule.
TEST(NlosUwbSim, TheImuEkfMatchesTheImuGraphOfTheSameRule) {
  const auto& r = report();
  const auto& ekf = r.variant("ekf_imu_paper_rule").errors;
  const auto& graph = r.variant("graph_imu_paper_rule").errors;
  std::printf("ekf_imu_paper_rule RMSE %.3f m, graph_imu_paper_rule %.3f m\n", ekf.horizontal.rmse, graph.horizontal.rmse);
  EXPECT_GT(ekf.count, 1000u);
  EXPECT_LT(std::abs(ekf.horizontal.rmse - graph.horizontal.rmse), 0.03 * graph.horizontal.rmse);
  EXPECT_LT(ekf.horizontal.rmse, r.variant("ekf_gate_paper_rule").errors.horizontal.rmse);
  EXPECT_GT(r.variant("ekf_imu_paper_rule").epochs_left_out, 100u);
}

// Why recall stays low: v_u and d_rho are differences of consecutive ranges, so a bias that
// persists through an episode shows only at its ends. With one-epoch episodes (each NLOS range
// its own draw, as an error added per range would be) the same classifiers find most of them.
TEST(NlosUwbSim, PerRangeNlosDrawsAreFoundFarMoreOftenThanEpisodes) {
  const auto& episodes = report();
  const auto per_range = short_drive_report(0.1);
  print("one-epoch NLOS episodes (diagnostic)", per_range);
  EXPECT_GT(per_range.svm.recall, episodes.svm.recall + 0.2);
  EXPECT_GT(per_range.svm_vu.recall, episodes.svm_vu.recall + 0.2);
  EXPECT_GT(per_range.ds.precision, episodes.ds.precision);
  // Leaving out the epochs it judges NLOS then pays: the median error of the paper's rule.
  EXPECT_LT(per_range.variant("graph_paper_rule").errors.horizontal.at(50), per_range.variant("graph").errors.horizontal.at(50));
  // With the IMU factors it pays in the RMSE too.
  EXPECT_LT(per_range.variant("graph_imu_paper_rule").errors.horizontal.rmse, 0.75 * per_range.variant("graph_imu").errors.horizontal.rmse);
}

}  // namespace
