// The library's lower layers (core, models, filters, policies: every header) and the inference
// headers of classify/ and features/ (through the generated all_lower_headers.hpp) compiled with
// -fno-exceptions, as embedded stacks build: construction-time checks return a Problem, steps
// return a Status, and a constructor given a setting its check refuses stops the program with
// the setting named (core/error.hpp).
#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
#error "this test must be compiled with -fno-exceptions (tests/filters/CMakeLists.txt)"
#endif

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "all_lower_headers.hpp"

namespace {
using namespace ctxfuse;

using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
using Cv = models::ConstantVelocity<L, 2>;
using Pos = models::BlockObservation<L, "p">;

Gaussian<4> prior() { return {Vector<4>(0.0, 0.0, 1.0, 0.0), SquareMatrix<4>::Identity()}; }

TEST(NoExceptions, StepsReportWithStatuses) {
  Ekf<Cv, policies::ChiSquareGate> ekf(Cv{}, prior(), {}, policies::ChiSquareGate(0.99));
  ekf.set_time(0.0);
  ASSERT_TRUE(ekf.predict_to(1.0, NoInput{}));
  EXPECT_EQ(ekf.predict_to(0.5, NoInput{}).problem, Problem::out_of_order_time);
  EXPECT_EQ(ekf.update(Pos{}, Vector<2>(std::nan(""), 0.0)).problem, Problem::non_finite_measurement);
  EXPECT_EQ(ekf.update(Pos{}, Eigen::VectorXd::Zero(3)).problem, Problem::measurement_wrong_size);
  const Status s = ekf.update(Pos{}, Vector<2>(1.0, 0.0));
  ASSERT_TRUE(s.accepted()) << describe(s.problem);
  EXPECT_NEAR(ekf.belief().mean(0), 1.0, 1e-12);  // the predicted position, measured exactly
}

TEST(NoExceptions, SettingsAreCheckedWithoutThrowing) {
  SquareMatrix<2> bad;
  bad << 0.9, 0.2, 0.1, 0.9;  // first row sums to 1.1
  EXPECT_EQ(policies::check_transition<2>(bad).problem, Problem::transition_matrix_not_stochastic);
  EXPECT_EQ(policies::check_transition<2>(bad).what, "transition matrix: a row does not sum to 1");
  EXPECT_TRUE(policies::check_transition<2>(policies::sticky_transition<2>(0.9)));
  EXPECT_EQ(policies::check_sticky(1.5).problem, Problem::invalid_setting);
  EXPECT_EQ(policies::RegionAdaptiveTransition<2>::check(policies::sticky_transition<2>(0.9), 0.5, 0.6).problem,
            Problem::invalid_setting);
  EXPECT_EQ(policies::RegionAdaptiveTransition<2>::check(bad, 0.5, 0.5).problem, Problem::transition_matrix_not_stochastic);
  EXPECT_EQ((policies::PosteriorPull<2, policies::FixedTransition<2>>::check(-0.1)).problem, Problem::invalid_setting);
  EXPECT_EQ((fkf::FederatedFilter<Cv, 2>::check_shares({0.5, 0.6})).problem, Problem::invalid_setting);
  EXPECT_TRUE((fkf::FederatedFilter<Cv, 2>::check_shares({0.5, 0.5})));
  const SettingCheck integrity = policies::check_options(policies::SnapshotIntegrityOptions{.probability = 1.0});
  EXPECT_EQ(integrity.problem, Problem::invalid_setting);
  EXPECT_EQ(integrity.what, "SnapshotIntegrity: probability must be in (0, 1)");
  EXPECT_TRUE(policies::check_options(policies::SnapshotIntegrityOptions{}));
}

TEST(NoExceptions, AnImmRunsOnCheckedSettings) {
  const SquareMatrix<2> P = policies::sticky_transition<2>(0.95);
  ASSERT_TRUE(policies::check_transition<2>(P));
  auto modes = boost::hana::make_tuple(imm::make_mode(Cv{0.05}), imm::make_mode(Cv{5.0}));
  imm::Imm filter(policies::FixedTransition<2>(P), modes, prior(), Vector<2>(0.5, 0.5));
  struct Fix {};
  const auto r = filter.cycle({}, 0.5, imm::observe(Fix{}, Pos{}, Vector<2>(0.5, 0.0)));
  ASSERT_TRUE(r.status().accepted());
  EXPECT_NEAR(filter.mode_probabilities().sum(), 1.0, 1e-12);
}

TEST(NoExceptions, ClassifiersAndExtractorsReportWithStatuses) {
  // A two-class linear SVM on one feature: f(x) = 2 x - 1 (one support vector at x = 1, weight 2).
  classify::SvmModel<1, 2> svm;
  svm.kernel = classify::SvmKernel::linear;
  svm.num_classes = 2;
  svm.labels = {1, -1};
  svm.support_vectors.resize(1, 1);
  svm.support_vectors(0, 0) = 1.0;
  svm.coefficients.resize(1, 1);
  svm.coefficients(0, 0) = 2.0;
  svm.rho[0] = 1.0;
  svm.input_mean.setZero();
  svm.input_std.setOnes();
  classify::finalize_svm_model(svm);
  classify::SvmPrediction<2> out;
  ASSERT_TRUE(classify::svm_predict(svm, Eigen::Matrix<double, 1, 1>(2.0), out));
  EXPECT_NEAR(out.decision_values[0], 3.0, 1e-15);
  EXPECT_EQ(out.label, 1);
  EXPECT_EQ(classify::svm_predict(svm, Eigen::Matrix<double, 1, 1>(std::nan("")), out).problem,
            Problem::non_finite_features);
  EXPECT_NEAR(out.decision_values[0], 3.0, 1e-15);  // untouched by the refusal

  const classify::DsResult ds = classify::combine_probabilities(1.0, 0.0);
  EXPECT_EQ(ds.status.outcome, Outcome::numerical_failure);
  EXPECT_EQ(ds.status.problem, Problem::total_conflict);

  features::NlosFeatureExtractor uwb;
  features::NlosFeatures f;
  ASSERT_TRUE(uwb.push({1.0, 10.0}, 1.0, f));
  EXPECT_EQ(uwb.push({0.5, 10.0}, 1.0, f).problem, Problem::out_of_order_time);

  const std::vector<features::SatelliteObservation> sats{{1, 30.0, 10.0, 40.0}, {1, 50.0, 90.0, 42.0}};
  features::GnssSceneExtractor<> scene;
  features::GnssSceneFeatures g;
  EXPECT_EQ(scene.push({0.0, sats}, g).problem, Problem::duplicate_satellite);
  EXPECT_EQ(features::GnssSceneConfig{.window_s = 0.0}.check().problem, Problem::invalid_setting);
  EXPECT_TRUE(features::GnssSceneConfig{}.check());
  EXPECT_EQ(classify::ConsistencyModel{.sigma_uwb = -1.0}.check().problem, Problem::invalid_setting);
  EXPECT_TRUE(classify::ConsistencyModel{}.check());
}

TEST(NoExceptions, SvmModelFilesLoadWithoutThrowing) {
  // A two-class RBF model in our format, read at a run-time dimension: f(x) = exp(-|x|^2) - 0.5.
  const std::string text =
      "ctxfuse-svm 1\ndimension 2\nkernel rbf\ngamma 1\nmulticlass ovo\nlabels 1 -1\ninput_mean 0 0\n"
      "input_std 1 1\nrho 0.5\nprobability 0\nsupport_vectors 1\n1 0 0\nend\n";
  std::istringstream in(text);
  classify::SvmModel<Eigen::Dynamic, 2> model;
  ASSERT_FALSE(classify::try_read_ctxfuse_svm_model(in, "mem", model).has_value());
  EXPECT_EQ(model.dimension(), 2);
  classify::SvmPrediction<2> out;
  const Eigen::VectorXd x = Eigen::VectorXd::Constant(2, 0.5), three = Eigen::VectorXd::Zero(3);
  ASSERT_TRUE(classify::svm_predict(model, x, out));
  EXPECT_NEAR(out.decision_values[0], std::exp(-0.5) - 0.5, 1e-15);
  EXPECT_EQ(classify::svm_predict(model, three, out).problem, Problem::features_wrong_size);

  // A malformed file: the problem names line and field, and the model is left as it was.
  std::string bad = text;
  bad.replace(bad.find("gamma 1"), 7, "gamma x");
  std::istringstream bad_in(bad);
  const auto problem = classify::try_read_ctxfuse_svm_model(bad_in, "mem", model);
  ASSERT_TRUE(problem.has_value());
  EXPECT_EQ(problem->what(), "mem:4: gamma: expected a finite number, got 'x'");
  EXPECT_EQ(model.gamma, 1.0);
  const auto missing = classify::try_load_svm_model("/nonexistent/ctxfuse.model", model);
  ASSERT_TRUE(missing.has_value());
  EXPECT_EQ(missing->field, "file");
  EXPECT_EQ(model.num_support_vectors(), 1);
}

TEST(NoExceptionsDeathTest, AThrowingReaderStopsNamingTheProblem) {
  EXPECT_DEATH((void)classify::load_svm_model<2>("/nonexistent/ctxfuse.model"),
               "ctxfuse: /nonexistent/ctxfuse.model: file: cannot open for reading");
}

TEST(NoExceptionsDeathTest, AConstructorGivenARefusedSettingStopsNamingIt) {
  SquareMatrix<2> bad;
  bad << 0.9, 0.2, 0.1, 0.9;
  EXPECT_DEATH(policies::FixedTransition<2>{bad}, "invalid setting: FixedTransition: row 0 sums to 1.1");
  EXPECT_DEATH((fkf::FederatedFilter<Cv, 2>(Cv{}, prior(), {0.5, 0.6})), "invalid setting: FederatedFilter");
}

}  // namespace
