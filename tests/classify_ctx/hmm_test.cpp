// GaussianHmm against independent references: brute-force path enumeration for Viterbi and
// for the forward filter, and recovery of known parameters from sampled sequences.
#include <gtest/gtest.h>

#include <ctxfuse/classify/hmm.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

namespace {

using ctxfuse::classify::GaussianHmm;
using ctxfuse::Problem;
using Hmm = GaussianHmm<3, 2>;
using Obs = Hmm::Observation;
using Cov = Hmm::Covariance;

struct LinearModel {
  std::array<double, 3> pi;
  std::array<std::array<double, 3>, 3> a;
  std::array<std::array<double, 2>, 3> mean;
  std::array<std::array<double, 3>, 3> cov;  // (sxx, sxy, syy) per state
};

const LinearModel kModel{
    {0.5, 0.3, 0.2},
    {{{0.8, 0.15, 0.05}, {0.1, 0.7, 0.2}, {0.05, 0.15, 0.8}}},
    {{{20.0, 40.0}, {12.0, 33.0}, {4.0, 25.0}}},
    {{{4.0, 1.0, 3.0}, {6.0, -2.0, 5.0}, {3.0, 0.5, 8.0}}}};

Hmm build(const LinearModel& m) {
  Eigen::Vector3d pi(m.pi[0], m.pi[1], m.pi[2]);
  Eigen::Matrix3d a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a(i, j) = m.a[i][j];
  std::array<Obs, 3> means;
  std::array<Cov, 3> covs;
  for (int k = 0; k < 3; ++k) {
    means[k] << m.mean[k][0], m.mean[k][1];
    covs[k] << m.cov[k][0], m.cov[k][1], m.cov[k][1], m.cov[k][2];
  }
  return ctxfuse::classify::make_gaussian_hmm<3, 2>(pi, a, means, covs);
}

// 2-D normal density written out with the closed-form 2x2 inverse and determinant.
double pdf(const LinearModel& m, int k, const Obs& x) {
  const double sxx = m.cov[k][0], sxy = m.cov[k][1], syy = m.cov[k][2];
  const double det = sxx * syy - sxy * sxy;
  const double dx = x[0] - m.mean[k][0], dy = x[1] - m.mean[k][1];
  const double q = (syy * dx * dx - 2 * sxy * dx * dy + sxx * dy * dy) / det;
  return std::exp(-0.5 * q) / (2 * std::numbers::pi * std::sqrt(det));
}

double path_joint(const LinearModel& m, const std::vector<int>& path, const std::vector<Obs>& x) {
  double p = m.pi[path[0]] * pdf(m, path[0], x[0]);
  for (std::size_t t = 1; t < path.size(); ++t)
    p *= m.a[path[t - 1]][path[t]] * pdf(m, path[t], x[t]);
  return p;
}

std::vector<int> decode(int index, int length) {
  std::vector<int> path(length);
  for (int t = length - 1; t >= 0; --t) {
    path[t] = index % 3;
    index /= 3;
  }
  return path;
}

std::vector<Obs> test_observations() {
  // Chosen between the clusters so that several paths compete.
  std::vector<Obs> x(6);
  x[0] << 18.0, 38.0;
  x[1] << 15.0, 36.0;
  x[2] << 9.0, 30.0;
  x[3] << 11.0, 31.0;
  x[4] << 5.0, 27.0;
  x[5] << 16.0, 37.0;
  return x;
}

TEST(GaussianHmm, EmissionMatchesClosedFormDensity) {
  const Hmm hmm = build(kModel);
  const Obs x = test_observations()[2];
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(hmm.log_emission(k, x), std::log(pdf(kModel, k, x)), 1e-12);
}

TEST(GaussianHmm, ViterbiMatchesBruteForceOver729Paths) {
  const Hmm hmm = build(kModel);
  const auto x = test_observations();
  double best = -1.0;
  int best_index = -1;
  for (int i = 0; i < 729; ++i) {
    const double p = path_joint(kModel, decode(i, 6), x);
    if (p > best) {
      best = p;
      best_index = i;
    }
  }
  const auto result = ctxfuse::classify::viterbi<3, 2>(hmm, x);
  EXPECT_EQ(result.path, decode(best_index, 6));
  EXPECT_NEAR(result.log_probability, std::log(best), 1e-9);
}

TEST(GaussianHmm, ViterbiMatchesBruteForceOnRandomSequences) {
  const Hmm hmm = build(kModel);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ux(2.0, 22.0), uy(23.0, 42.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Obs> x(6);
    for (auto& o : x) o << ux(rng), uy(rng);
    double best = -1.0;
    int best_index = -1;
    for (int i = 0; i < 729; ++i) {
      const double p = path_joint(kModel, decode(i, 6), x);
      if (p > best) {
        best = p;
        best_index = i;
      }
    }
    const auto result = ctxfuse::classify::viterbi<3, 2>(hmm, x);
    EXPECT_EQ(result.path, decode(best_index, 6)) << "trial " << trial;
  }
}

TEST(GaussianHmm, ForwardFilterMatchesBruteForceMarginals) {
  const Hmm hmm = build(kModel);
  const auto x = test_observations();
  ctxfuse::classify::HmmForwardFilter<3, 2> filter(hmm);
  double previous_evidence = 1.0;  // p(x_1..t-1); 1 before the first step
  for (int t = 0; t < 6; ++t) {
    const ctxfuse::Status st = filter.step(x[t]);
    ASSERT_TRUE(st.accepted());
    const std::vector<Obs> prefix(x.begin(), x.begin() + t + 1);
    std::array<double, 3> marginal{};
    double evidence = 0.0;
    int paths = 1;
    for (int i = 0; i <= t; ++i) paths *= 3;
    for (int i = 0; i < paths; ++i) {
      const auto path = decode(i, t + 1);
      const double p = path_joint(kModel, path, prefix);
      marginal[path[t]] += p;
      evidence += p;
    }
    const auto post = filter.posterior();
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(post[k], marginal[k] / evidence, 1e-12) << "t=" << t;
    EXPECT_NEAR(filter.log_likelihood(), std::log(evidence), 1e-9);
    // The step's Status carries its own evidence log p(x_t | x_1..t-1).
    EXPECT_NEAR(st.log_likelihood, std::log(evidence / previous_evidence), 1e-9) << "t=" << t;
    previous_evidence = evidence;
  }
}

TEST(GaussianHmm, ForwardFilterRejectsNonFiniteObservationAndKeepsState) {
  const Hmm hmm = build(kModel);
  ctxfuse::classify::HmmForwardFilter<3, 2> filter(hmm);
  ASSERT_TRUE(filter.step(test_observations()[0]).accepted());
  const auto before = filter.log_posterior();
  Obs bad;
  bad << std::nan(""), 1.0;
  EXPECT_EQ(filter.step(bad).problem, Problem::non_finite_measurement);
  EXPECT_EQ(filter.log_posterior(), before);
  EXPECT_EQ(filter.steps(), 1u);
  Obs far;  // the squared Mahalanobis distance overflows: no state can have emitted this
  far << 1e200, -1e200;
  const ctxfuse::Status st = filter.step(far);
  EXPECT_EQ(st.outcome, ctxfuse::Outcome::numerical_failure);
  EXPECT_EQ(st.problem, Problem::zero_likelihood);
  EXPECT_EQ(filter.log_posterior(), before);
}

TEST(GaussianHmm, ViterbiRefusesANonFiniteObservation) {
  const Hmm hmm = build(kModel);
  std::vector<Obs> x = test_observations();
  x[3][1] = std::numeric_limits<double>::infinity();
  const auto v = ctxfuse::classify::viterbi<3, 2>(hmm, x);
  EXPECT_EQ(v.status.outcome, ctxfuse::Outcome::invalid_input);
  EXPECT_EQ(v.status.problem, Problem::non_finite_measurement);
  EXPECT_EQ(v.refused_at, 3u);
  EXPECT_TRUE(v.path.empty());
  x[3][1] = 30.0;
  const auto repaired = ctxfuse::classify::viterbi<3, 2>(hmm, x);
  EXPECT_TRUE(repaired.status.accepted());
  EXPECT_EQ(repaired.path.size(), x.size());
}

TEST(GaussianHmm, LogDomainSurvivesLongSequences) {
  const Hmm hmm = build(kModel);
  ctxfuse::classify::HmmForwardFilter<3, 2> filter(hmm);
  Obs x;
  x << 4.0, 25.0;
  for (int t = 0; t < 5000; ++t) ASSERT_TRUE(filter.step(x).accepted());
  EXPECT_GT(filter.posterior()[2], 0.99);
  EXPECT_TRUE(std::isfinite(filter.log_likelihood()));
  EXPECT_LT(filter.log_likelihood(), -1000.0);  // far below what a linear-domain product can hold
  std::vector<Obs> batch(5000, x);
  const auto v = ctxfuse::classify::viterbi<3, 2>(hmm, batch);
  EXPECT_TRUE(std::isfinite(v.log_probability));
  EXPECT_EQ(v.path.back(), 2);
}

// Samples labelled sequences from kModel and checks that supervised estimation recovers it.
TEST(GaussianHmm, SupervisedFitRecoversKnownParameters) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto draw = [&](const auto& probs) {
    double r = u(rng), c = 0.0;
    for (int k = 0; k < 3; ++k) {
      c += probs[k];
      if (r < c) return k;
    }
    return 2;
  };
  const int num_sequences = 400, length = 100;
  std::vector<std::vector<Obs>> obs(num_sequences);
  std::vector<std::vector<int>> labels(num_sequences);
  for (int s = 0; s < num_sequences; ++s) {
    int k = draw(kModel.pi);
    for (int t = 0; t < length; ++t) {
      if (t > 0) k = draw(kModel.a[k]);
      // x = mean + L z with L the closed-form 2x2 Cholesky factor
      const double sxx = kModel.cov[k][0], sxy = kModel.cov[k][1], syy = kModel.cov[k][2];
      const double l11 = std::sqrt(sxx), l21 = sxy / l11, l22 = std::sqrt(syy - l21 * l21);
      const double z1 = n01(rng), z2 = n01(rng);
      Obs x;
      x << kModel.mean[k][0] + l11 * z1, kModel.mean[k][1] + l21 * z1 + l22 * z2;
      obs[s].push_back(x);
      labels[s].push_back(k);
    }
  }
  std::vector<ctxfuse::classify::LabelledSequence<2>> seqs;
  for (int s = 0; s < num_sequences; ++s) seqs.push_back({obs[s], labels[s]});
  ctxfuse::classify::HmmFitOptions opt;
  opt.pseudo_count = 0.0;
  const auto fit = ctxfuse::classify::fit_supervised<3, 2>(seqs, opt);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(std::exp(fit.log_initial[i]), kModel.pi[i], 0.07);
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(std::exp(fit.log_transition(i, j)), kModel.a[i][j], 0.02);
    EXPECT_NEAR(fit.means[i][0], kModel.mean[i][0], 0.1);
    EXPECT_NEAR(fit.means[i][1], kModel.mean[i][1], 0.1);
    EXPECT_NEAR(fit.covariances[i](0, 0), kModel.cov[i][0], 0.1 * kModel.cov[i][0]);
    EXPECT_NEAR(fit.covariances[i](0, 1), kModel.cov[i][1], 0.4);
    EXPECT_NEAR(fit.covariances[i](1, 1), kModel.cov[i][2], 0.1 * kModel.cov[i][2]);
  }
  opt.covariance = ctxfuse::classify::CovarianceKind::diagonal;
  const auto diag = ctxfuse::classify::fit_supervised<3, 2>(seqs, opt);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(diag.covariances[i](0, 1), 0.0);
    EXPECT_NEAR(diag.covariances[i](0, 0), fit.covariances[i](0, 0), 1e-9);
  }
}

TEST(GaussianHmm, SupervisedFitCountsMatchHandComputation) {
  // Two sequences, labels 0 0 0 1 1 | 1 2 2 2:
  // transitions 0->0 (x2), 0->1, 1->1 | 1->2, 2->2 (x2).
  std::vector<Obs> x1(5), x2(4);
  x1[0] << 0, 0; x1[1] << 2, 2; x1[2] << 4, 0; x1[3] << 10, 0; x1[4] << 12, 4;
  x2[0] << 8, 2; x2[1] << 20, 20; x2[2] << 22, 24; x2[3] << 24, 20;
  const std::vector<int> l1{0, 0, 0, 1, 1}, l2{1, 2, 2, 2};
  std::vector<ctxfuse::classify::LabelledSequence<2>> seqs{{x1, l1}, {x2, l2}};
  ctxfuse::classify::HmmFitOptions opt;
  opt.pseudo_count = 1.0;
  opt.variance_floor = 0.0;
  const auto fit = ctxfuse::classify::fit_supervised<3, 2>(seqs, opt);
  // pi: first labels {0, 1} + 1 each -> (2, 2, 1) / 5
  EXPECT_NEAR(std::exp(fit.log_initial[0]), 0.4, 1e-12);
  EXPECT_NEAR(std::exp(fit.log_initial[2]), 0.2, 1e-12);
  // row 0: (2, 1, 0) + 1 -> (3, 2, 1) / 6; row 1: (0, 1, 1) + 1 -> (1, 2, 2) / 5;
  // row 2: (0, 0, 2) + 1 -> (1, 1, 3) / 5
  EXPECT_NEAR(std::exp(fit.log_transition(0, 0)), 0.5, 1e-12);
  EXPECT_NEAR(std::exp(fit.log_transition(0, 2)), 1.0 / 6.0, 1e-12);
  EXPECT_NEAR(std::exp(fit.log_transition(1, 0)), 0.2, 1e-12);
  EXPECT_NEAR(std::exp(fit.log_transition(2, 2)), 0.6, 1e-12);
  // state 1: points (10,0), (12,4), (8,2): mean (10, 2), var x = 8/3, var y = 8/3, cov = 4/3
  EXPECT_NEAR(fit.means[1][0], 10.0, 1e-12);
  EXPECT_NEAR(fit.means[1][1], 2.0, 1e-12);
  EXPECT_NEAR(fit.covariances[1](0, 0), 8.0 / 3.0, 1e-12);
  EXPECT_NEAR(fit.covariances[1](0, 1), 4.0 / 3.0, 1e-12);
}

TEST(GaussianHmm, SupervisedFitRejectsBadInput) {
  std::vector<Obs> x(3, Obs::Zero());
  std::vector<int> bad_label{0, 3, 1}, short_labels{0, 1};
  std::vector<ctxfuse::classify::LabelledSequence<2>> s1{{x, bad_label}}, s2{{x, short_labels}};
  EXPECT_THROW((ctxfuse::classify::fit_supervised<3, 2>(s1)), std::invalid_argument);
  EXPECT_THROW((ctxfuse::classify::fit_supervised<3, 2>(s2)), std::invalid_argument);
  std::vector<int> one_each{0, 1, 2};  // one sample per state: covariance undefined
  std::vector<ctxfuse::classify::LabelledSequence<2>> s3{{x, one_each}};
  EXPECT_THROW((ctxfuse::classify::fit_supervised<3, 2>(s3)), std::invalid_argument);
  Eigen::Vector3d pi(0.5, 0.5, 0.5);  // sums to 1.5
  const std::array<Obs, 3> means{Obs::Zero(), Obs::Zero(), Obs::Zero()};
  EXPECT_THROW((ctxfuse::classify::make_gaussian_hmm<3, 2>(pi, Eigen::Matrix3d::Identity(), means,
                                                           {Cov::Identity(), Cov::Identity(), Cov::Identity()})),
               std::invalid_argument);
}

}  // namespace
