// The region recogniser's training on several drives and its causal posteriors, against
// hand-counted references: the HMM must count transitions within each drive only (none across
// the seam between two drives), and the SVM must see every drive's epochs.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <span>
#include <vector>

#include "ctxfuse/pipelines/region_imm.hpp"

namespace {
using namespace ctxfuse;
namespace ri = pipelines::region_imm;

// Well separated regions: (TNVS, mean C/N0) clusters far apart, a little spread in each.
ri::FeatureSeries series(const std::vector<int>& labels, double jitter_phase) {
  ri::FeatureSeries f;
  const std::array<ri::Feature, 3> centre{ri::Feature(20.0, 42.0), ri::Feature(10.0, 34.0), ri::Feature(1.0, 10.0)};
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const double u = std::sin(1.7 * static_cast<double>(i) + jitter_phase), v = std::cos(2.3 * static_cast<double>(i) + jitter_phase);
    f.t.push_back(static_cast<double>(i));
    f.x.push_back(centre[static_cast<std::size_t>(labels[i])] + ri::Feature(0.8 * u, 0.8 * v));
    f.truth.push_back(labels[i]);
  }
  return f;
}

std::vector<int> run_of(std::initializer_list<std::pair<int, int>> runs) {
  std::vector<int> out;
  for (auto [label, n] : runs) out.insert(out.end(), static_cast<std::size_t>(n), label);
  return out;
}

ri::RecogniserOptions quick() {
  ri::RecogniserOptions o;
  o.tune.pso.swarm_size = 3;
  o.tune.pso.iterations = 2;
  return o;
}

TEST(RegionRecogniser, HmmCountsTransitionsWithinEachDriveOnly) {
  // Drive A: outdoor -> transition -> indoor; drive B: outdoor -> transition. Concatenated,
  // an indoor -> outdoor transition would appear at the seam; within the drives there is none.
  const auto a = series(run_of({{0, 30}, {1, 20}, {2, 30}}), 0.0);
  const auto b = series(run_of({{0, 25}, {1, 25}}), 0.4);
  const std::vector<ri::FeatureSeries> train{a, b};
  const auto rec = ri::train_recogniser(std::span<const ri::FeatureSeries>(train), a, quick());
  // Hand counts with the default pseudo-count 1 on every cell:
  //   from outdoor:    0->0: 29 + 24, 0->1: 1 + 1, 0->2: 0
  //   from transition: 1->1: 19 + 24, 1->2: 1, 1->0: 0
  //   from indoor:     2->2: 29, 2->0: 0 (the seam must not add one)
  const double p = 1.0;
  const std::array<std::array<double, 3>, 3> counts{{{53 + p, 2 + p, 0 + p}, {0 + p, 43 + p, 1 + p}, {0 + p, 0 + p, 29 + p}}};
  for (int i = 0; i < 3; ++i) {
    const double row = counts[i][0] + counts[i][1] + counts[i][2];
    for (int j = 0; j < 3; ++j)
      EXPECT_NEAR(std::exp(rec.hmm.log_transition(i, j)), counts[i][j] / row, 1e-12) << i << "->" << j;
  }
  // Initial state: both drives start outdoors.
  EXPECT_NEAR(std::exp(rec.hmm.log_initial(0)), (2.0 + p) / (2.0 + 3.0 * p), 1e-12);
  // Emission means pool both drives' epochs of each region.
  ri::Feature outdoor_sum = ri::Feature::Zero();
  int outdoor_n = 0;
  for (const auto* f : {&a, &b})
    for (std::size_t i = 0; i < f->x.size(); ++i)
      if (f->truth[i] == 0) {
        outdoor_sum += f->x[i];
        ++outdoor_n;
      }
  EXPECT_LT((rec.hmm.means[0] - outdoor_sum / outdoor_n).norm(), 1e-12);
}

TEST(RegionRecogniser, SvmLearnsARegionSeenOnlyInTheSecondDrive) {
  // Indoor epochs exist only in drive B: an SVM trained on drive A alone cannot predict them.
  const auto a = series(run_of({{0, 40}, {1, 40}}), 0.0);
  const auto b = series(run_of({{0, 20}, {1, 20}, {2, 40}}), 0.9);
  const std::vector<ri::FeatureSeries> train{a, b};
  const auto rec = ri::train_recogniser(std::span<const ri::FeatureSeries>(train), b, quick());
  const auto labels = ri::svm_labels(rec.svm, series(run_of({{2, 10}}), 2.0));
  for (int l : labels) EXPECT_EQ(l, 2);
}

TEST(RegionRecogniser, NoTrainingDriveIsAClearError) {
  const auto a = series(run_of({{0, 10}, {1, 10}, {2, 10}}), 0.0);
  EXPECT_THROW((void)ri::train_recogniser(std::span<const ri::FeatureSeries>(), a, quick()), std::invalid_argument);
}

TEST(RegionRecogniser, PosteriorsAreTheForwardRecursionAndHoldOverUnusableEpochs) {
  const auto train = series(run_of({{0, 30}, {1, 20}, {2, 30}}), 0.0);
  const auto rec = ri::train_recogniser(train, train, quick());
  auto test = series(run_of({{0, 5}, {1, 5}, {2, 5}}), 1.1);
  test.x[7] = ri::Feature(std::numeric_limits<double>::quiet_NaN(), 30.0);  // a corrupted epoch
  const auto post = ri::hmm_posteriors(rec, test);
  ASSERT_EQ(post.size(), test.x.size());
  // The forward recursion written plainly in the linear domain (fine for 15 epochs):
  // alpha_1 = pi .* b(x_1), alpha_t = (alpha_{t-1}' A)' .* b(x_t), normalised each step.
  const Eigen::Matrix3d A = rec.hmm.log_transition.array().exp().matrix();
  Eigen::Vector3d alpha = Eigen::Vector3d::Zero();
  bool first = true;
  for (std::size_t t = 0; t < test.x.size(); ++t) {
    if (test.x[t].allFinite()) {
      Eigen::Vector3d b;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d d = test.x[t] - rec.hmm.means[static_cast<std::size_t>(k)];
        const Eigen::Matrix2d S = rec.hmm.covariances[static_cast<std::size_t>(k)];
        b(k) = std::exp(-0.5 * d.dot(S.inverse() * d)) / (2.0 * std::numbers::pi * std::sqrt(S.determinant()));
      }
      const Eigen::Vector3d prior = first ? Eigen::Vector3d(rec.hmm.log_initial.array().exp().matrix()) : Eigen::Vector3d(A.transpose() * alpha);
      alpha = prior.cwiseProduct(b);
      alpha /= alpha.sum();
      first = false;
    }
    EXPECT_LT((post[t] - alpha).cwiseAbs().maxCoeff(), 1e-9) << "epoch " << t;
    EXPECT_NEAR(post[t].sum(), 1.0, 1e-12);
  }
  EXPECT_EQ(post[7], post[6]);  // the corrupted epoch repeats the previous posterior
}

}  // namespace
