// Our inference against libsvm itself: the same model file read by svm_load_model and by our
// loader (and converted in memory from svm_train's result) must give libsvm's decision values to
// 1e-9, its probabilities to 1e-6 and the same labels, for many inputs.
#include <gtest/gtest.h>
#include <svm.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "classify_svm/svm_test_data.hpp"
#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_io.hpp"
#include "ctxfuse/classify/svm_train.hpp"

namespace {

using namespace ctxfuse::classify;

struct Case {
  const char* name;
  int kernel;  // LINEAR or RBF
  int classes;
  bool sparse;  // omit zero features from the libsvm problem (tests missing indices)
};

// Hand-built libsvm problem, independent of our own training helpers.
struct HandProblem {
  std::vector<std::vector<svm_node>> rows;
  std::vector<svm_node*> ptrs;
  std::vector<double> y;
  svm_problem prob{};
};

std::unique_ptr<HandProblem> make_problem(const ctxfuse::test::LabelledSet& s, bool sparse) {
  auto p = std::make_unique<HandProblem>();
  for (Eigen::Index i = 0; i < s.x.rows(); ++i) {
    std::vector<svm_node> row;
    for (Eigen::Index f = 0; f < s.x.cols(); ++f)
      if (!sparse || s.x(i, f) != 0.0) row.push_back({static_cast<int>(f + 1), s.x(i, f)});
    row.push_back({-1, 0.0});
    p->rows.push_back(std::move(row));
    p->y.push_back(s.y[static_cast<std::size_t>(i)]);
  }
  for (auto& r : p->rows) p->ptrs.push_back(r.data());
  p->prob.l = static_cast<int>(p->rows.size());
  p->prob.x = p->ptrs.data();
  p->prob.y = p->y.data();
  return p;
}

template <int Dim>
void run_case(const Case& c) {
  svm_set_print_string_function(&ctxfuse::test::quiet);
  std::vector<std::vector<double>> centres = {{0, 0, 0}, {2, 1, -1}, {-1, 2, 1}, {1, -2, 2}};
  std::vector<int> labels = {7, -3, 12, 4};
  centres.resize(static_cast<std::size_t>(c.classes));
  labels.resize(static_cast<std::size_t>(c.classes));
  for (auto& ctr : centres) ctr.resize(Dim);
  auto data = ctxfuse::test::gaussian_clusters(centres, labels, 60, std::vector<double>(Dim, 1.0), 11);
  // Some exact zeros so that the sparse problem really drops entries.
  for (Eigen::Index i = 0; i < data.x.rows(); i += 7) data.x(i, i % Dim) = 0.0;
  auto problem = make_problem(data, c.sparse);

  svm_parameter param{};
  param.svm_type = C_SVC;
  param.kernel_type = c.kernel;
  param.gamma = 0.7;
  param.C = 3.0;
  param.cache_size = 50;
  param.eps = 1e-3;
  param.shrinking = 1;
  param.probability = 1;
  ASSERT_EQ(svm_check_parameter(&problem->prob, &param), nullptr);
  std::srand(5);
  svm_model* trained = svm_train(&problem->prob, &param);
  ASSERT_NE(trained, nullptr);
  const auto path = std::filesystem::temp_directory_path() /
                    ("ctxfuse_svm_libsvm_" + std::string(c.name) + "_" + std::to_string(::getpid()) + ".model");
  ASSERT_EQ(svm_save_model(path.string().c_str(), trained), 0);
  svm_model* reference = svm_load_model(path.string().c_str());
  ASSERT_NE(reference, nullptr);

  const auto from_file = load_svm_model<Dim>(path);
  const auto from_memory = svm_model_from_libsvm<Dim>(*trained);
  ASSERT_EQ(from_file.num_classes, c.classes);
  ASSERT_EQ(from_file.num_support_vectors(), reference->l);
  ASSERT_TRUE(from_file.has_probability);

  const int machines = c.classes * (c.classes - 1) / 2;
  std::vector<double> dec(static_cast<std::size_t>(machines)), prob(static_cast<std::size_t>(c.classes));
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  int checked = 0;
  for (int n = 0; n < 2000; ++n) {
    Eigen::Matrix<double, Dim, 1> x;
    for (int f = 0; f < Dim; ++f) x[f] = n < 1000 ? u(rng) : data.x(n % data.x.rows(), f) + 0.01 * u(rng);
    std::vector<svm_node> nodes;
    for (int f = 0; f < Dim; ++f) nodes.push_back({f + 1, x[f]});
    nodes.push_back({-1, 0.0});
    // The file holds support vectors to 8 significant digits, so the file-loaded models are
    // compared with each other and the in-memory conversion with the in-memory libsvm model.
    for (const auto& [model, libsvm_model] : {std::pair{&from_file, reference}, std::pair{&from_memory, trained}}) {
      const double vote_label = svm_predict_values(libsvm_model, nodes.data(), dec.data());
      const double prob_label = svm_predict_probability(libsvm_model, nodes.data(), prob.data());
      SvmPrediction<8> decision, predicted;
      ASSERT_TRUE(svm_decision(*model, x, decision).accepted());
      ASSERT_TRUE(svm_predict(*model, x, predicted).accepted());
      ASSERT_EQ(decision.num_machines, machines);
      for (int m = 0; m < machines; ++m) {
        const double tol = 1e-9 * std::max(1.0, std::abs(dec[static_cast<std::size_t>(m)]));
        ASSERT_NEAR(decision.decision_values[static_cast<std::size_t>(m)], dec[static_cast<std::size_t>(m)], tol)
            << c.name << " machine " << m << " input " << n;
      }
      EXPECT_EQ(decision.label, static_cast<int>(vote_label)) << c.name << " input " << n;
      ASSERT_TRUE(predicted.has_probabilities);
      double total = 0.0;
      for (int k = 0; k < c.classes; ++k) {
        ASSERT_NEAR(predicted.probabilities[static_cast<std::size_t>(k)], prob[static_cast<std::size_t>(k)], 1e-6)
            << c.name << " class " << k << " input " << n;
        total += predicted.probabilities[static_cast<std::size_t>(k)];
      }
      EXPECT_NEAR(total, 1.0, 1e-12);
      EXPECT_EQ(predicted.label, static_cast<int>(prob_label)) << c.name << " input " << n;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 4000);
  svm_free_and_destroy_model(&reference);
  svm_free_and_destroy_model(&trained);
  std::filesystem::remove(path);
}

TEST(SvmLibsvmEquivalence, BinaryLinear) { run_case<2>({"binary_linear", LINEAR, 2, false}); }
TEST(SvmLibsvmEquivalence, BinaryRbf) { run_case<2>({"binary_rbf", RBF, 2, false}); }
TEST(SvmLibsvmEquivalence, BinaryRbfSparseFile) { run_case<3>({"binary_rbf_sparse", RBF, 2, true}); }
TEST(SvmLibsvmEquivalence, ThreeClassLinear) { run_case<3>({"three_linear", LINEAR, 3, false}); }
TEST(SvmLibsvmEquivalence, ThreeClassRbf) { run_case<2>({"three_rbf", RBF, 3, false}); }
TEST(SvmLibsvmEquivalence, ThreeClassRbfSparseFile) { run_case<3>({"three_rbf_sparse", RBF, 3, true}); }
TEST(SvmLibsvmEquivalence, FourClassRbf) { run_case<3>({"four_rbf", RBF, 4, false}); }

}  // namespace
