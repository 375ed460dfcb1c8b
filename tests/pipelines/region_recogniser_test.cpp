// The region recogniser's training on several drives and its causal posteriors, against
// hand-counted references: the HMM must count transitions within each drive only (none across
// the seam between two drives), and the SVM must see every drive's epochs.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <limits>
#include <span>
#include <vector>

#include "ctxfuse/instances/region_imm.hpp"  // region_imm::run compiled once (ctxfuse::instances)
#include "ctxfuse/pipelines/region_imm.hpp"
#include "ctxfuse/pipelines/region_imm/recogniser_io.hpp"

namespace {
using namespace ctxfuse;
namespace ri = pipelines::region_imm;

// Well separated regions: (TNVS, mean C/N0) clusters far apart, a little spread in each.
ri::LabelledFeatures series(const std::vector<int>& labels, double jitter_phase) {
  ri::LabelledFeatures lf;
  auto& f = lf.features;
  const std::array<ri::Feature, 3> centre{ri::Feature(20.0, 42.0), ri::Feature(10.0, 34.0), ri::Feature(1.0, 10.0)};
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const double u = std::sin(1.7 * static_cast<double>(i) + jitter_phase), v = std::cos(2.3 * static_cast<double>(i) + jitter_phase);
    f.t.push_back(static_cast<double>(i));
    f.x.push_back(centre[static_cast<std::size_t>(labels[i])] + ri::Feature(0.8 * u, 0.8 * v));
    lf.labels.push_back(labels[i]);
  }
  return lf;
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
  const std::vector<ri::LabelledFeatures> train{a, b};
  const auto rec = ri::train_recogniser(std::span<const ri::LabelledFeatures>(train), a, quick());
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
    for (std::size_t i = 0; i < f->features.x.size(); ++i)
      if (f->labels[i] == 0) {
        outdoor_sum += f->features.x[i];
        ++outdoor_n;
      }
  EXPECT_LT((rec.hmm.means[0] - outdoor_sum / outdoor_n).norm(), 1e-12);
}

TEST(RegionRecogniser, SvmLearnsARegionSeenOnlyInTheSecondDrive) {
  // Indoor epochs exist only in drive B: an SVM trained on drive A alone cannot predict them.
  const auto a = series(run_of({{0, 40}, {1, 40}}), 0.0);
  const auto b = series(run_of({{0, 20}, {1, 20}, {2, 40}}), 0.9);
  const std::vector<ri::LabelledFeatures> train{a, b};
  const auto rec = ri::train_recogniser(std::span<const ri::LabelledFeatures>(train), b, quick());
  const auto labels = ri::svm_labels(rec.svm, series(run_of({{2, 10}}), 2.0).features);
  for (int l : labels) EXPECT_EQ(l, 2);
}

TEST(RegionRecogniser, NoTrainingDriveIsAClearError) {
  const auto a = series(run_of({{0, 10}, {1, 10}, {2, 10}}), 0.0);
  EXPECT_THROW((void)ri::train_recogniser(std::span<const ri::LabelledFeatures>(), a, quick()), std::invalid_argument);
  // Labels that do not match the epochs, or are not regions.
  auto short_labels = a;
  short_labels.labels.pop_back();
  EXPECT_THROW((void)ri::train_recogniser(short_labels, a, quick()), std::invalid_argument);
  auto bad_label = a;
  bad_label.labels[3] = 5;
  EXPECT_THROW((void)ri::train_recogniser(a, bad_label, quick()), std::invalid_argument);
}

TEST(RegionRecogniser, PosteriorsAreTheForwardRecursionAndHoldOverUnusableEpochs) {
  const auto train = series(run_of({{0, 30}, {1, 20}, {2, 30}}), 0.0);
  const auto rec = ri::train_recogniser(train, train, quick());
  auto test = series(run_of({{0, 5}, {1, 5}, {2, 5}}), 1.1).features;
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

TEST(RegionRecogniser, FeaturesAreTheSatelliteCountAndMeanCn0OfEachEpoch) {
  std::vector<messages::SatEpoch> epochs(3);
  epochs[0].t = 1.0;
  epochs[0].sats = {{1, 30.0, 10.0, 40.0}, {2, 60.0, 200.0, 45.0}, {3, messages::kUnknown, messages::kUnknown, 29.0}};
  epochs[1].t = 2.0;  // nothing tracked
  epochs[2].t = 3.0;
  epochs[2].sats = {{7, 10.0, 90.0, 33.5}};
  const auto f = ri::gnss_features(epochs);
  ASSERT_EQ(f.x.size(), 3u);
  EXPECT_EQ(f.t, (std::vector<double>{1.0, 2.0, 3.0}));
  EXPECT_EQ(f.x[0], ri::Feature(3.0, (40.0 + 45.0 + 29.0) / 3.0));  // a satellite without geometry counts
  EXPECT_EQ(f.x[1], ri::Feature(0.0, 0.0));
  EXPECT_EQ(f.x[2], ri::Feature(1.0, 33.5));
}

TEST(RegionRecogniser, SavedAndLoadedRecogniserIsTheSameToTheLastBit) {
  const auto train = series(run_of({{0, 30}, {1, 20}, {2, 30}}), 0.0);
  const auto validate = series(run_of({{0, 10}, {1, 10}, {2, 10}}), 0.7);
  const auto rec = ri::train_recogniser(train, validate, quick());
  std::stringstream file;
  ri::write_recogniser(file, rec);
  const auto back = ri::read_recogniser(file, "rec.txt");
  EXPECT_EQ(back.tuned.C, rec.tuned.C);
  EXPECT_EQ(back.tuned.gamma, rec.tuned.gamma);
  EXPECT_EQ(back.vote.weights, rec.vote.weights);
  EXPECT_EQ(back.validation_accuracy, rec.validation_accuracy);
  EXPECT_EQ(back.hmm.log_transition, rec.hmm.log_transition);
  EXPECT_EQ(back.hmm.log_initial, rec.hmm.log_initial);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(back.hmm.means[k], rec.hmm.means[k]);
    EXPECT_EQ(back.hmm.covariances[k], rec.hmm.covariances[k]);
  }
  // The same labels, decision values and posteriors on features it has not seen.
  const auto test = series(run_of({{0, 15}, {2, 5}, {1, 15}}), 2.3).features;
  const auto a = ri::recognise(rec, test), b = ri::recognise(back, test);
  EXPECT_EQ(a.svm, b.svm);
  EXPECT_EQ(a.hmm, b.hmm);
  EXPECT_EQ(a.joint, b.joint);
  const auto pa = ri::hmm_posteriors(rec, test), pb = ri::hmm_posteriors(back, test);
  for (std::size_t i = 0; i < pa.size(); ++i) EXPECT_EQ(pa[i], pb[i]) << i;
}

TEST(RegionRecogniser, MalformedRecogniserFilesNameTheLineAndField) {
  const auto train = series(run_of({{0, 30}, {1, 20}, {2, 30}}), 0.0);
  std::stringstream good;
  ri::write_recogniser(good, ri::train_recogniser(train, train, quick()));
  const std::string text = good.str();
  auto message = [](const std::string& content) {
    std::istringstream in(content);
    try {
      (void)ri::read_recogniser(in, "rec.txt");
    } catch (const ri::RecogniserFileError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("hello\n"), "rec.txt:1: not a region recogniser file (expected 'ctxfuse-region-recogniser 1')");
  // The second line cut short: two numbers where three belong.
  std::string cut = text;
  const auto l2 = cut.find('\n') + 1;
  cut.replace(l2, cut.find('\n', l2) - l2, "tuned 1 2");
  EXPECT_EQ(message(cut), "rec.txt:2: field 'tuned': expected 3 numbers, found 2");
  std::string word = text;
  word.replace(l2, word.find('\n', l2) - l2, "tuned 1 x 3");
  EXPECT_EQ(message(word), "rec.txt:2: field 'tuned': 'x' is not a number");
  // Truncated before the SVM.
  const std::string truncated = text.substr(0, text.find("svm_lines"));
  EXPECT_NE(message(truncated).find("field 'svm_lines': file ends before this record"), std::string::npos) << message(truncated);
  // A covariance that is not positive definite.
  std::string bad_cov = text;
  const auto st = bad_cov.find("hmm_state 1");
  bad_cov.replace(st, bad_cov.find('\n', st) - st, "hmm_state 1 10 30 1 2 2 1");
  EXPECT_NE(message(bad_cov).find("field 'hmm_state'"), std::string::npos) << message(bad_cov);
}

}  // namespace

namespace {

// The causal recognition is, at every epoch, the SVM's label, the argmax of the HMM's forward
// posterior and the joint vote of those two; changing the features from epoch k on changes
// no label before k.
TEST(RegionRecogniser, CausalRecognitionReadsNoLaterEpoch) {
  const auto a = series(run_of({{0, 30}, {1, 20}, {2, 30}}), 0.0);
  const auto b = series(run_of({{0, 25}, {1, 25}, {2, 10}}), 0.4);
  const std::vector<ri::LabelledFeatures> train{a, b};
  const auto rec = ri::train_recogniser(std::span<const ri::LabelledFeatures>(train), a, quick());
  const auto test = series(run_of({{0, 20}, {1, 10}, {2, 20}, {1, 10}, {0, 20}}), 1.3).features;
  const ri::Recognition r = ri::recognise_causal(rec, test);
  const auto post = ri::hmm_posteriors(rec, test);
  const auto svm = ri::svm_labels(rec.svm, test);
  ASSERT_EQ(r.hmm.size(), test.x.size());
  for (std::size_t i = 0; i < test.x.size(); ++i) {
    Eigen::Index best = 0;
    post[i].maxCoeff(&best);
    EXPECT_EQ(r.hmm[i], static_cast<int>(best)) << i;
    EXPECT_EQ(r.svm[i], svm[i]) << i;
    EXPECT_EQ(r.joint[i], rec.vote({svm[i], static_cast<int>(best)})) << i;
  }
  auto changed = test;
  const std::size_t k = 35;
  for (std::size_t i = k; i < changed.x.size(); ++i) changed.x[i] = ri::Feature(1.0, 10.0);  // indoor from k on
  const ri::Recognition c = ri::recognise_causal(rec, changed);
  for (std::size_t i = 0; i < k; ++i) {
    EXPECT_EQ(c.svm[i], r.svm[i]) << i;
    EXPECT_EQ(c.hmm[i], r.hmm[i]) << i;
    EXPECT_EQ(c.joint[i], r.joint[i]) << i;
  }
  EXPECT_NE(c.joint.back(), r.joint.back());  // the change itself is seen
}

}  // namespace
