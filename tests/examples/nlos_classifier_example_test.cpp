// examples/nlos_classifier.hpp against independent computations: the SVM's decision values and
// probabilities against libsvm's own svm_predict_values and svm_predict_probability on the
// same model file, the consistency probability against the paper's step table, and R against
// the paper's D-S formula R = p1 p2 / (p1 p2 + q1 q2), all written out here.
#include <gtest/gtest.h>
#include <svm.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "nlos_classifier.hpp"

namespace {
namespace nc = nlos_classifier;

struct LibsvmModel {
  svm_model* m = nullptr;
  ~LibsvmModel() { svm_free_and_destroy_model(&m); }
};

/// The example's model text, loaded by libsvm from a file.
LibsvmModel libsvm_model() {
  const auto path = std::filesystem::temp_directory_path() / ("ctxfuse_nlos_classifier_example_" + std::to_string(::getpid()) + ".model");
  std::ofstream(path) << nc::kModel;
  LibsvmModel out;
  out.m = svm_load_model(path.string().c_str());
  std::filesystem::remove(path);
  return out;
}

/// The paper's eq. 6 as a table: e up to 1, 2, 3 sigma (0.10 m) gives 0.35, 0.55, 0.70; above, 0.90.
double paper_p2(double e) { return e <= 0.1 ? 0.35 : e <= 0.2 ? 0.55 : e <= 0.3 ? 0.70 : 0.90; }

TEST(NlosClassifierExample, SvmIsLibsvmOnTheSameFile) {
  const LibsvmModel ref = libsvm_model();
  ASSERT_NE(ref.m, nullptr);
  ASSERT_EQ(svm_check_probability_model(ref.m), 1);
  int labels[2];
  svm_get_labels(ref.m, labels);
  ASSERT_EQ(labels[0], nc::kNlos);
  const auto verdicts = nc::run();
  ASSERT_EQ(verdicts.size(), nc::ranges().size());
  for (const auto& v : verdicts) {
    svm_node x[3] = {{1, v.range.range_rate}, {2, v.range.speed}, {-1, 0.0}};
    double decision = 0.0, prob[2];
    const double label_values = svm_predict_values(ref.m, x, &decision);
    const double label_prob = svm_predict_probability(ref.m, x, prob);
    EXPECT_NEAR(v.svm.decision_values[0], decision, 1e-12) << v.range.what;
    EXPECT_NEAR(v.p1, prob[0], 1e-12) << v.range.what;  // prob[0]: label 1, NLOS
    EXPECT_EQ(v.svm.label, static_cast<int>(label_prob)) << v.range.what;
    EXPECT_EQ(decision > 0 ? labels[0] : labels[1], static_cast<int>(label_values)) << v.range.what;
  }
}

TEST(NlosClassifierExample, ConsistencyAndDempsterShaferAreThePapersFormulas) {
  const auto verdicts = nc::run();
  int nlos = 0;
  for (const auto& v : verdicts) {
    const double e = std::abs(v.range.range_change) - v.range.travelled;
    EXPECT_DOUBLE_EQ(v.p2, paper_p2(e)) << v.range.what;
    const double K = v.p1 * v.p2 + (1 - v.p1) * (1 - v.p2);
    EXPECT_NEAR(v.ds.nlos_belief(), v.p1 * v.p2 / K, 1e-15) << v.range.what;
    EXPECT_NEAR(v.ds.conflict, 1 - K, 1e-15) << v.range.what;
    EXPECT_EQ(v.nlos, v.p1 * v.p2 / K > 0.8) << v.range.what;
    nlos += v.nlos;
  }
  // The table of docs/classifiers.md: the two jumps are NLOS, the rest LOS, and one range the
  // SVM alone would call NLOS (p1 > 0.5) is kept by the consistency check.
  EXPECT_EQ(nlos, 2);
  EXPECT_TRUE(verdicts[2].nlos && verdicts[5].nlos);
  EXPECT_GT(verdicts[4].p1, 0.5);
  EXPECT_FALSE(verdicts[4].nlos);
}

TEST(NlosClassifierExample, AMalformedModelIsAnErrorNamingItsLine) {
  std::string text = nc::kModel;
  text.replace(text.find("gamma 0.5"), 9, "gamma abc");
  std::istringstream in(text);
  try {
    (void)ctxfuse::classify::read_libsvm_model<2, 2>(in, "bad.model");
    FAIL() << "a model with a non-numeric gamma was read";
  } catch (const ctxfuse::classify::SvmFileError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.model:3"), std::string::npos) << e.what();
  }
}

}  // namespace
