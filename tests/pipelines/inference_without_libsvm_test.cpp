// The pipelines' inference headers do not need libsvm: this test's target has neither libsvm's
// include directory nor its library, so any of these headers that included svm.h (SVM
// training) would not compile here. The region recogniser and the NLOS classifier then run:
// the classifier without an SVM decides on the consistency probability alone (D-S with one
// source), which is checked against the consistency model of the same settings.
#include <gtest/gtest.h>

#include "ctxfuse/pipelines/nlos_uwb/classifier.hpp"
#include "ctxfuse/pipelines/nlos_uwb/run.hpp"
#include "ctxfuse/pipelines/region_imm/recogniser.hpp"
#include "ctxfuse/pipelines/region_imm/recogniser_io.hpp"

#if defined(LIBSVM_VERSION)
#error "an inference header included libsvm's svm.h"
#endif

namespace {
using namespace ctxfuse::pipelines;

TEST(InferenceWithoutLibsvm, NlosClassifierWithoutAModelUsesTheConsistencyAlone) {
  const nlos_uwb::Settings s;
  nlos_uwb::NlosClassifier c(s);
  EXPECT_FALSE(c.has_svm());
  ctxfuse::messages::UwbRange r;
  r.anchor_id = 3;
  r.anchor_position = {10.0, 0.0, 2.0};
  r.t = 10.0;
  r.range_m = 12.0;
  (void)c.classify(r, 0.0);  // the first range of an anchor has no difference yet
  r.t = 10.1;
  r.range_m = 14.0;  // 2 m in 0.1 s while the platform stands still: e = |d_rho| - d_d = 2 m
  nlos_uwb::SvmInput in;
  const nlos_uwb::RangeVerdict v = c.classify(r, 0.0, &in);
  EXPECT_TRUE(std::isnan(v.p1));
  EXPECT_NEAR(in.range_rate_mps, 20.0, 1e-9);
  EXPECT_DOUBLE_EQ(v.p2, s.consistency().nlos_probability(2.0));
  EXPECT_DOUBLE_EQ(v.R, v.p2);
  EXPECT_EQ(v.nlos, v.R > s.nlos_belief_threshold);
}

TEST(InferenceWithoutLibsvm, RegionFeaturesComeFromTheReceiverEpochs) {
  std::vector<ctxfuse::messages::SatEpoch> epochs(2);
  epochs[0].t = 1.0;
  epochs[1].t = 2.0;
  epochs[1].sats.resize(2);
  epochs[1].sats[0].cn0_dbhz = 30.0;
  epochs[1].sats[1].cn0_dbhz = 40.0;
  const region_imm::FeatureSeries f = region_imm::gnss_features(epochs);
  ASSERT_EQ(f.x.size(), 2u);
  EXPECT_EQ(f.x[0], Eigen::Vector2d(0.0, 0.0));
  EXPECT_EQ(f.x[1], Eigen::Vector2d(2.0, 35.0));
}

}  // namespace
