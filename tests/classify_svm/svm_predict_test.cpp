// Inference against closed forms and brute-force references: kernel sums written out by hand,
// Platt's sigmoid in its naive form, coupling against a direct solve of its optimality system,
// voting rules, standardisation, and bad input leaving the output untouched.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "classify_svm/svm_test_data.hpp"
#include "ctxfuse/classify/svm.hpp"

namespace {

using namespace ctxfuse::classify;
using ctxfuse::Problem;

SvmModel<2, 3> two_sv_model(SvmKernel kernel) {
  SvmModel<2, 3> m;
  m.kernel = kernel;
  m.gamma = 0.5;
  m.num_classes = 2;
  m.labels = {1, -1, 0};
  m.support_vectors.resize(2, 2);
  m.support_vectors << 1.0, 2.0, -1.0, 0.5;
  m.coefficients.resize(1, 2);
  m.coefficients << 0.75, -1.25;
  m.rho[0] = 0.1;
  finalize_svm_model(m);
  return m;
}

TEST(SvmPredict, RbfDecisionValueMatchesHandSum) {
  const auto m = two_sv_model(SvmKernel::rbf);
  const Eigen::Vector2d x(0.3, -0.4);
  // |x - sv1|^2 = 0.49 + 5.76 = 6.25, |x - sv2|^2 = 1.69 + 0.81 = 2.5
  const double expected = 0.75 * std::exp(-0.5 * 6.25) - 1.25 * std::exp(-0.5 * 2.5) - 0.1;
  SvmPrediction<3> out;
  ASSERT_TRUE(svm_decision(m, x, out).accepted());
  EXPECT_NEAR(out.decision_values[0], expected, 1e-15);
  EXPECT_EQ(out.label, expected > 0 ? 1 : -1);
  EXPECT_EQ(out.num_machines, 1);
}

TEST(SvmPredict, LinearDecisionValueMatchesHandSum) {
  const auto m = two_sv_model(SvmKernel::linear);
  const Eigen::Vector2d x(0.3, -0.4);
  const double expected = 0.75 * (0.3 * 1.0 - 0.4 * 2.0) - 1.25 * (-0.3 - 0.4 * 0.5) - 0.1;
  SvmPrediction<3> out;
  ASSERT_TRUE(svm_decision(m, x, out).accepted());
  EXPECT_NEAR(out.decision_values[0], expected, 1e-15);
  EXPECT_EQ(out.label, 1);  // expected = 0.15 > 0
}

TEST(SvmPredict, ManySupportVectorsSpanSeveralKernelBlocks) {
  // 1000 SVs cross the 256-wide block boundary several times; compare with a scalar loop.
  const auto m = ctxfuse::test::random_model<3>(SvmKernel::rbf, SvmMulticlass::one_vs_one, 3, 1000, false, 4);
  const Eigen::Vector3d x(0.5, -1.0, 2.0);
  const Eigen::Vector3d xs = (x - m.input_mean).cwiseQuotient(m.input_std);
  SvmPrediction<8> out;
  ASSERT_TRUE(svm_decision(m, x, out).accepted());
  for (int p = 0; p < 3; ++p) {
    double sum = 0.0;
    for (int s = 0; s < 1000; ++s) sum += m.coefficients(p, s) * std::exp(-m.gamma * (xs - m.support_vectors.row(s).transpose()).squaredNorm());
    EXPECT_NEAR(out.decision_values[static_cast<std::size_t>(p)], sum - m.rho[static_cast<std::size_t>(p)], 1e-12);
  }
}

TEST(SvmPredict, StandardisationIsAppliedBeforeTheKernel) {
  auto scaled = two_sv_model(SvmKernel::rbf);
  scaled.input_mean = Eigen::Vector2d(10.0, -3.0);
  scaled.input_std = Eigen::Vector2d(4.0, 0.5);
  finalize_svm_model(scaled);
  const auto plain = two_sv_model(SvmKernel::rbf);
  const Eigen::Vector2d raw(11.2, -3.2);
  SvmPrediction<3> a, b;
  ASSERT_TRUE(svm_decision(scaled, raw, a).accepted());
  ASSERT_TRUE(svm_decision(plain, Eigen::Vector2d(1.2 / 4.0, -0.2 / 0.5), b).accepted());
  EXPECT_NEAR(a.decision_values[0], b.decision_values[0], 1e-15);
}

TEST(SvmPredict, PlattSigmoidEqualsNaiveFormWhereThatIsAccurate) {
  for (double f : {-30.0, -3.0, -0.2, 0.0, 0.4, 2.5, 30.0})
    for (double a : {-2.0, -0.5, 0.7})
      for (double b : {-1.0, 0.0, 0.3}) {
        const double naive = 1.0 / (1.0 + std::exp(a * f + b));
        EXPECT_NEAR(svm_detail::platt_probability(f, a, b), naive, 1e-15 + 1e-12 * naive) << f << ' ' << a << ' ' << b;
      }
  // Deep in the tails: relative accuracy for tiny p, and no overflow to NaN for huge |a f + b|.
  const double tail = std::exp(-40.0) / (1.0 + std::exp(-40.0));
  EXPECT_NEAR(svm_detail::platt_probability(40.0, 1.0, 0.0), tail, 1e-15 * tail);
  EXPECT_EQ(svm_detail::platt_probability(-1e6, 1.0, 0.0), 1.0);
  EXPECT_EQ(svm_detail::platt_probability(1e6, 1.0, 0.0), 0.0);
}

TEST(SvmPredict, CouplingSolvesItsOptimalityConditions) {
  // min p'Qp s.t. sum p = 1 has the KKT system [Q 1; 1' 0][p; -b] = [0; 1]; solve it directly.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  for (int k : {3, 4, 6}) {
    for (int trial = 0; trial < 20; ++trial) {
      std::array<double, 64> r{};
      for (int i = 0; i < k; ++i)
        for (int j = i + 1; j < k; ++j) {
          r[static_cast<std::size_t>(i * k + j)] = u(rng);
          r[static_cast<std::size_t>(j * k + i)] = 1.0 - r[static_cast<std::size_t>(i * k + j)];
        }
      Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(k, k);
      for (int i = 0; i < k; ++i)
        for (int j = 0; j < k; ++j) {
          if (i == j) {
            for (int s = 0; s < k; ++s)
              if (s != i) Q(i, i) += r[static_cast<std::size_t>(s * k + i)] * r[static_cast<std::size_t>(s * k + i)];
          } else {
            Q(i, j) = -r[static_cast<std::size_t>(j * k + i)] * r[static_cast<std::size_t>(i * k + j)];
          }
        }
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(k + 1, k + 1);
      A.topLeftCorner(k, k) = Q;
      A.topRightCorner(k, 1).setOnes();
      A.bottomLeftCorner(1, k).setOnes();
      Eigen::VectorXd rhs = Eigen::VectorXd::Zero(k + 1);
      rhs[k] = 1.0;
      const Eigen::VectorXd exact = A.fullPivLu().solve(rhs).head(k);
      std::array<double, 8> p{};
      svm_detail::couple_pairwise<8>(k, r, p.data());
      double total = 0.0;
      for (int i = 0; i < k; ++i) {
        total += p[static_cast<std::size_t>(i)];
        // libsvm stops once max|Qp - p'Qp| < 0.005/k, so agreement is to a few 1e-3.
        EXPECT_NEAR(p[static_cast<std::size_t>(i)], exact[i], 5e-3) << "k " << k << " trial " << trial;
      }
      EXPECT_NEAR(total, 1.0, 1e-12);
    }
  }
}

TEST(SvmPredict, ConsistentPairwiseProbabilitiesAreRecovered) {
  const std::array<double, 4> truth = {0.5, 0.3, 0.15, 0.05};
  std::array<double, 64> r{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (i != j) r[static_cast<std::size_t>(i * 4 + j)] = truth[static_cast<std::size_t>(i)] / (truth[static_cast<std::size_t>(i)] + truth[static_cast<std::size_t>(j)]);
  std::array<double, 8> p{};
  svm_detail::couple_pairwise<8>(4, r, p.data());
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(p[static_cast<std::size_t>(i)], truth[static_cast<std::size_t>(i)], 2e-3);
}

TEST(SvmPredict, OneVsOneVoteBreaksTiesTowardsTheFirstClass) {
  // Three classes, decision values (0,1)>0 -> 0, (0,2)<0 -> 2, (1,2)>0 -> 1: one vote each.
  SvmModel<1, 3> m;
  m.kernel = SvmKernel::linear;
  m.num_classes = 3;
  m.labels = {4, 5, 6};
  m.support_vectors.setOnes(1, 1);
  m.coefficients.setZero(3, 1);
  m.rho = {-1.0, 1.0, -1.0};
  finalize_svm_model(m);
  SvmPrediction<3> out;
  ASSERT_TRUE(svm_decision(m, Eigen::Matrix<double, 1, 1>(0.0), out).accepted());
  EXPECT_EQ(out.class_index, 0);
  EXPECT_EQ(out.label, 4);
  m.rho = {1.0, 1.0, -1.0};  // now 1 beats 0, 2 beats 0, 1 beats 2: class 1 has two votes
  finalize_svm_model(m);
  ASSERT_TRUE(svm_decision(m, Eigen::Matrix<double, 1, 1>(0.0), out).accepted());
  EXPECT_EQ(out.label, 5);
}

TEST(SvmPredict, OneVsRestPicksLargestDecisionAndNormalisesSigmoids) {
  auto m = ctxfuse::test::random_model<2, 4>(SvmKernel::rbf, SvmMulticlass::one_vs_rest, 4, 30, true, 9);
  const Eigen::Vector2d x(0.2, 1.1);
  SvmPrediction<4> out;
  ASSERT_TRUE(svm_predict(m, x, out).accepted());
  ASSERT_EQ(out.num_machines, 4);
  std::array<double, 4> sig{};
  double total = 0.0;
  for (std::size_t i = 0; i < 4; ++i) {
    sig[i] = 1.0 / (1.0 + std::exp(m.prob_a[i] * out.decision_values[i] + m.prob_b[i]));
    total += sig[i];
  }
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(out.probabilities[i], sig[i] / total, 1e-14);
  SvmPrediction<4> decision_only;
  ASSERT_TRUE(svm_decision(m, x, decision_only).accepted());
  const auto best = std::max_element(out.decision_values.begin(), out.decision_values.begin() + 4) - out.decision_values.begin();
  EXPECT_EQ(decision_only.class_index, best);
  EXPECT_FALSE(decision_only.has_probabilities);
}

TEST(SvmPredict, BadInputLeavesOutputUntouched) {
  const auto m = two_sv_model(SvmKernel::rbf);
  SvmPrediction<3> out;
  out.label = 77;
  out.decision_values[0] = 123.0;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(svm_predict(m, Eigen::Vector2d(nan, 0.0), out).problem, Problem::non_finite_features);
  EXPECT_EQ(svm_predict(m, Eigen::Vector2d(0.0, std::numeric_limits<double>::infinity()), out).problem, Problem::non_finite_features);
  EXPECT_EQ(svm_predict(m, Eigen::Vector2d(1e200, 0.0), out).problem, Problem::feature_magnitude);
  EXPECT_EQ(out.label, 77);
  EXPECT_EQ(out.decision_values[0], 123.0);
  EXPECT_EQ(describe(Problem::non_finite_features), "feature vector contains NaN or Inf");
  EXPECT_EQ(svm_predict(m, Eigen::Vector2d(nan, 0.0), out).outcome, ctxfuse::Outcome::invalid_input);
}

TEST(SvmPredict, FinalizeRejectsInconsistentModels) {
  auto m = two_sv_model(SvmKernel::rbf);
  m.coefficients.resize(2, 2);
  EXPECT_THROW(finalize_svm_model(m), std::invalid_argument);
  m = two_sv_model(SvmKernel::rbf);
  m.gamma = -1.0;
  EXPECT_THROW(finalize_svm_model(m), std::invalid_argument);
  m = two_sv_model(SvmKernel::rbf);
  m.input_std[1] = 0.0;
  EXPECT_THROW(finalize_svm_model(m), std::invalid_argument);
  m = two_sv_model(SvmKernel::rbf);
  m.labels[1] = m.labels[0];
  EXPECT_THROW(finalize_svm_model(m), std::invalid_argument);
}

}  // namespace

namespace {

TEST(SvmRbfKernel, ExponentialMatchesLibmToAFewUlp) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-708.0, 0.0);
  double worst = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const double t = i < 1000 ? -1e-3 * i : u(rng);
    const double ref = std::exp(t);
    worst = std::max(worst, std::abs(ctxfuse::classify::svm_detail::exp_nonpositive(t) - ref) / ref);
  }
  EXPECT_LT(worst, 4 * std::numeric_limits<double>::epsilon());
  EXPECT_EQ(ctxfuse::classify::svm_detail::exp_nonpositive(0.0), 1.0);
}

// The kernel evaluates exp(-gamma d2) from d2 with gamma folded into its constants, so the
// accuracy is checked over the whole clamped range of d2 for several gammas. Reference: libm's
// exp of the rounded product t, corrected by the product's rounding error t_lo (exp(t + t_lo) =
// exp(t) (1 + t_lo) up to t_lo^2 / 2, and |t_lo| <= 2^-53 |t| < 1e-13 for |t| <= 708).
TEST(SvmRbfKernel, ExponentialOfScaledDistanceMatchesLibmToAFewUlp) {
  using namespace ctxfuse::classify::svm_detail;
  std::mt19937_64 rng(13);
  for (const double gamma : {0.5, 1.0 / 3.0, 7.3, 1e-3, 123.4}) {
    const RbfExp e = rbf_exp_constants(gamma);
    std::uniform_real_distribution<double> u(0.0, e.d2_max);
    double worst = 0.0;
    for (int i = 0; i < 100000; ++i) {
      const double d2 = i < 1000 ? 1e-3 * i / gamma : u(rng);
      const double t = -gamma * d2;
      const double t_lo = std::fma(-gamma, d2, -t);
      const double ref = std::exp(t) * (1.0 + t_lo);
      worst = std::max(worst, std::abs(exp_neg_gamma(d2, e) - ref) / ref);
    }
    EXPECT_LT(worst, 4 * std::numeric_limits<double>::epsilon()) << "gamma " << gamma;
    EXPECT_EQ(exp_neg_gamma(0.0, e), 1.0) << "gamma " << gamma;
  }
}

// The same bound on every compiled block variant (the vector ones use their own table and
// polynomial), kernel values only: one feature column c with x = 0, so d2 = c * c as the block
// rounds it; the clamp is crossed too.
TEST(SvmRbfKernel, EveryCompiledVariantMatchesLibmToAFewUlp) {
  using namespace ctxfuse::classify::svm_detail;
  constexpr int n = kRbfBlock;
  std::mt19937_64 rng(14);
  for (const double gamma : {0.5, 1.0 / 3.0, 7.3, 1e-3, 123.4}) {
    const RbfExp e = rbf_exp_constants(gamma);
    std::uniform_real_distribution<double> u(0.0, std::sqrt(1.05 * e.d2_max));
    std::array<double, n> column{}, out{};
    std::array<double, 3> worst{};
    for (int round = 0; round < 400; ++round) {
      for (int i = 0; i < n; ++i)
        column[static_cast<std::size_t>(i)] = round == 0 ? std::sqrt(1e-3 * i / gamma) : u(rng);
      const auto check = [&](int variant) {
        for (int i = 0; i < n; ++i) {
          const auto k = static_cast<std::size_t>(i);
          const double d2 = std::min(column[k] * column[k], e.d2_max);
          const double t = -gamma * d2;
          const double t_lo = std::fma(-gamma, d2, -t);
          const double ref = std::exp(t) * (1.0 + t_lo);
          auto& w = worst[static_cast<std::size_t>(variant)];
          w = std::max(w, std::abs(out[k] - ref) / ref);
        }
      };
      rbf_block_baseline<1>({column.data()}, {0.0}, e, out.data());
      check(0);
#ifdef CTXFUSE_SVM_RUNTIME_AVX2
      if (cpu_has_avx2_fma()) {
        rbf_block_avx2<1>({column.data()}, {0.0}, e, out.data());
        check(1);
      }
      if (cpu_has_avx512f()) {
        rbf_block_avx512<1>({column.data()}, {0.0}, e, out.data());
        check(2);
      }
#endif
    }
    const char* names[] = {"baseline", "avx2", "avx512"};
    for (std::size_t v = 0; v < worst.size(); ++v)
      EXPECT_LT(worst[v], 4 * std::numeric_limits<double>::epsilon()) << names[v] << " gamma " << gamma;
    // The worst errors in eps per variant, in the test's XML output (--gtest_output=xml).
    RecordProperty("worst_eps_gamma_" + std::to_string(gamma),
                   std::to_string(worst[0] / std::numeric_limits<double>::epsilon()) + " " +
                       std::to_string(worst[1] / std::numeric_limits<double>::epsilon()) + " " +
                       std::to_string(worst[2] / std::numeric_limits<double>::epsilon()));
  }
}

TEST(SvmRbfKernel, EveryCompiledVariantAgreesWithScalarFormula) {
  using namespace ctxfuse::classify::svm_detail;
  constexpr int n = kRbfBlock;
  std::array<double, n> c0{}, c1{}, c2{}, out{};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  for (int i = 0; i < n; ++i) {
    c0[static_cast<std::size_t>(i)] = u(rng);
    c1[static_cast<std::size_t>(i)] = u(rng);
    c2[static_cast<std::size_t>(i)] = u(rng);
  }
  const std::array<double, 3> x = {0.3, -1.2, 2.2};
  c0[7] = 1e140;  // far beyond the clamp: the kernel value must be ~0, not garbage
  c1[9] = -3e149;
  const RbfExp e = rbf_exp_constants(0.7);
  const auto check = [&](const char* name) {
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const double d2 = (c0[k] - x[0]) * (c0[k] - x[0]) + (c1[k] - x[1]) * (c1[k] - x[1]) + (c2[k] - x[2]) * (c2[k] - x[2]);
      const double ref = std::exp(-0.7 * std::min(d2, 708.0 / 0.7));
      // gamma d2 reaches ~40 here, so one rounding of d2 moves the result by ~1e-14 relative.
      ASSERT_NEAR(out[k], ref, 1e-13 * ref + 1e-300) << name << " element " << i;
    }
  };
  rbf_block_baseline<3>({c0.data(), c1.data(), c2.data()}, x, e, out.data());
  check("baseline");
#ifdef CTXFUSE_SVM_RUNTIME_AVX2
  if (cpu_has_avx2_fma()) {
    out.fill(0.0);
    rbf_block_avx2<3>({c0.data(), c1.data(), c2.data()}, x, e, out.data());
    check("avx2");
  }
  if (cpu_has_avx512f()) {
    out.fill(0.0);
    rbf_block_avx512<3>({c0.data(), c1.data(), c2.data()}, x, e, out.data());
    check("avx512");
  }
#endif
}

}  // namespace
