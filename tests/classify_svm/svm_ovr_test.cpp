// One-vs-rest against k binary libsvm machines trained by hand on the relabelled data (class m
// = +1, the rest = -1): our decision values must equal each machine's (oriented so that > 0
// means class m), the label their argmax and the probabilities each machine's P(class m)
// divided by the sum over machines.
#include <gtest/gtest.h>
#include <svm.h>

#include <algorithm>
#include <cstdlib>
#include <random>
#include <vector>

#include "classify_svm/svm_test_data.hpp"
#include "ctxfuse/classify/svm_train.hpp"

namespace {

using namespace ctxfuse::classify;

TEST(SvmOneVsRest, MatchesHandTrainedBinaryLibsvmMachines) {
  svm_set_print_string_function(&ctxfuse::test::quiet);
  const std::vector<int> labels = {2, 9, 4};
  const auto data = ctxfuse::test::gaussian_clusters({{0, 0}, {2, 0.5}, {0.8, 2}}, labels, 70, {0.9, 0.9}, 21);
  const SvmFeatures<2> x = data.x;
  SvmTrainOptions options;
  options.kernel = SvmKernel::rbf;
  options.multiclass = SvmMulticlass::one_vs_rest;
  options.C = 2.0;
  options.gamma = 0.9;
  options.probability = true;
  options.standardize = false;  // so that the hand-built problems see the same numbers
  options.seed = 17;
  const auto model = train_svm<2>(x, data.y, options);
  ASSERT_EQ(model.num_machines(), 3);
  ASSERT_EQ(model.num_classes, 3);

  // Hand-trained machines, independent of train_svm's internals.
  std::vector<std::vector<svm_node>> rows;
  std::vector<svm_node*> ptrs;
  for (Eigen::Index i = 0; i < x.rows(); ++i) rows.push_back({{1, x(i, 0)}, {2, x(i, 1)}, {-1, 0.0}});
  for (auto& r : rows) ptrs.push_back(r.data());
  std::vector<std::vector<double>> targets(3);
  std::vector<svm_model*> machines;
  std::vector<svm_problem> problems(3);
  for (int m = 0; m < 3; ++m) {
    for (int y : data.y) targets[static_cast<std::size_t>(m)].push_back(y == model.labels[static_cast<std::size_t>(m)] ? 1.0 : -1.0);
    problems[static_cast<std::size_t>(m)] = svm_problem{static_cast<int>(rows.size()), targets[static_cast<std::size_t>(m)].data(), ptrs.data()};
    svm_parameter p{};
    p.svm_type = C_SVC;
    p.kernel_type = RBF;
    p.gamma = 0.9;
    p.C = 2.0;
    p.cache_size = 50;
    p.eps = 1e-3;
    p.shrinking = 1;
    p.probability = 1;
    std::srand(17);
    machines.push_back(svm_train(&problems[static_cast<std::size_t>(m)], &p));
  }
  // libsvm puts +1 first for -1/+1 data whatever comes first; the orientation is still read from
  // label[0] below rather than assumed.

  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-3.0, 4.0);
  int agree = 0;
  for (int n = 0; n < 1500; ++n) {
    const Eigen::Vector2d q(u(rng), u(rng));
    const svm_node nodes[3] = {{1, q[0]}, {2, q[1]}, {-1, 0.0}};
    std::array<double, 3> f{}, p{};
    double total = 0.0;
    for (int m = 0; m < 3; ++m) {
      double dec = 0.0;
      svm_predict_values(machines[static_cast<std::size_t>(m)], nodes, &dec);
      double probs[2];
      svm_predict_probability(machines[static_cast<std::size_t>(m)], nodes, probs);
      const int positive = machines[static_cast<std::size_t>(m)]->label[0] == 1 ? 0 : 1;
      f[static_cast<std::size_t>(m)] = positive == 0 ? dec : -dec;
      p[static_cast<std::size_t>(m)] = probs[positive];
      total += probs[positive];
    }
    SvmPrediction<8> ours, decision_only;
    ASSERT_TRUE(svm_predict(model, q, ours).accepted());
    ASSERT_TRUE(svm_decision(model, q, decision_only).accepted());
    for (std::size_t m = 0; m < 3; ++m) {
      ASSERT_NEAR(ours.decision_values[m], f[m], 1e-9 * std::max(1.0, std::abs(f[m]))) << "input " << n << " machine " << m;
      ASSERT_NEAR(ours.probabilities[m], p[m] / total, 1e-6) << "input " << n << " machine " << m;
    }
    const auto by_decision = std::max_element(f.begin(), f.end()) - f.begin();
    EXPECT_EQ(decision_only.label, model.labels[static_cast<std::size_t>(by_decision)]);
    agree += ours.label == decision_only.label ? 1 : 0;
  }
  EXPECT_GT(agree, 1300);  // probability argmax and decision argmax mostly coincide
  for (auto*& m : machines) svm_free_and_destroy_model(&m);
}

}  // namespace
