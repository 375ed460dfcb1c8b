// The numbers of the usage examples against references written out by hand on the same data:
// examples/first_filter.hpp's EKF against a textbook EKF, and examples/imm_two_mode.hpp's IMM
// against the IMM of Blom and Bar-Shalom (Bar-Shalom, Li, Kirubarajan, "Estimation with
// Applications to Tracking and Navigation", 11.6.6), to 1e-12 (relative above 1). The
// references use plain Eigen only: no model, step or policy of the library.
// docs/first_filter.md and docs/imm.md quote what the examples print.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstring>
#include <numbers>
#include <ostream>
#include <string>

#include "ctxfuse/testing/jacobians.hpp"
#include "first_filter.hpp"
#include "imm_two_mode.hpp"

namespace {
using Eigen::Matrix2d;
using Eigen::Matrix4d;
using Eigen::Vector2d;
using Eigen::Vector4d;
using Matrix24 = Eigen::Matrix<double, 2, 4>;
namespace ct = ctxfuse::testing;

constexpr double kTol = 1e-12;
const double kLog2Pi = std::log(2.0 * std::numbers::pi);

// Mean and covariance bit for bit (not memcmp of the struct: Eigen may pad it).
template <class B>
bool same_bytes(const B& a, const B& b) {
  return std::memcmp(a.mean.data(), b.mean.data(), sizeof(a.mean)) == 0 &&
         std::memcmp(a.cov.data(), b.cov.data(), sizeof(a.cov)) == 0;
}

// The largest difference between two matrices, relative to the reference's largest entry when
// that is above 1 (positions reach a few hundred metres here, where 1e-12 absolute would be a
// few units in the last place).
template <class A, class B>
double max_rel_diff(const Eigen::MatrixBase<A>& got, const Eigen::MatrixBase<B>& want) {
  return (got - want).cwiseAbs().maxCoeff() / std::max(1.0, want.cwiseAbs().maxCoeff());
}

// ---- a textbook Kalman filter over (x, y, vx, vy) -----------------------------------------

struct Belief {
  Vector4d x;
  Matrix4d P;
};

Matrix4d cv_transition(double dt) {
  Matrix4d F = Matrix4d::Identity();
  F(0, 2) = F(1, 3) = dt;
  return F;
}

// White acceleration of density q, discretised: q dt^3/3, q dt^2/2, q dt.
Matrix4d cv_noise(double q, double dt) {
  Matrix4d Q = Matrix4d::Zero();
  Q(0, 0) = Q(1, 1) = q * dt * dt * dt / 3.0;
  Q(0, 2) = Q(2, 0) = Q(1, 3) = Q(3, 1) = q * dt * dt / 2.0;
  Q(2, 2) = Q(3, 3) = q * dt;
  return Q;
}

void kf_predict(Belief& b, double q, double dt) {
  const Matrix4d F = cv_transition(dt);
  b.x = F * b.x;
  b.P = F * b.P * F.transpose() + cv_noise(q, dt);
}

struct Innovation {
  Vector2d y;
  Matrix24 H;
  Matrix2d R, S;
  double nis = 0.0, log_lik = 0.0;
};

Innovation innovation(const Belief& b, const Vector2d& y, const Matrix24& H, const Matrix2d& R) {
  Innovation in;
  in.y = y;
  in.H = H;
  in.R = R;
  in.S = H * b.P * H.transpose() + R;
  in.nis = y.dot(in.S.inverse() * y);
  in.log_lik = -0.5 * (in.nis + std::log(in.S.determinant()) + 2.0 * kLog2Pi);
  return in;
}

// K = P H' S^-1, x += K y, Joseph form P = (I - K H) P (I - K H)' + K R K'.
void kf_update(Belief& b, const Innovation& in) {
  const Eigen::Matrix<double, 4, 2> K = b.P * in.H.transpose() * in.S.inverse();
  b.x += K * in.y;
  const Matrix4d A = Matrix4d::Identity() - K * in.H;
  b.P = A * b.P * A.transpose() + K * in.R * K.transpose();
}

// Range and bearing from the origin, linearised at the belief's position; bearing wrapped.
Innovation range_bearing(const Belief& b, const Vector2d& z, double sigma_r, double sigma_b) {
  const double px = b.x(0), py = b.x(1), r = std::sqrt(px * px + py * py);
  Matrix24 H;
  H << px / r, py / r, 0.0, 0.0, -py / (r * r), px / (r * r), 0.0, 0.0;
  const Vector2d y(z(0) - r, std::remainder(z(1) - std::atan2(py, px), 2.0 * std::numbers::pi));
  return innovation(b, y, H, Vector2d(sigma_r * sigma_r, sigma_b * sigma_b).asDiagonal());
}

// A position fix.
Innovation position_fix(const Belief& b, const Vector2d& z, double sigma) {
  Matrix24 H = Matrix24::Zero();
  H(0, 0) = H(1, 1) = 1.0;
  return innovation(b, z - H * b.x, H, Matrix2d::Identity() * sigma * sigma);
}

template <class G>
void expect_belief_near(const G& got, const Belief& want, const char* what, double t) {
  EXPECT_LE(max_rel_diff(got.mean, want.x), kTol) << what << " mean at t = " << t;
  EXPECT_LE(max_rel_diff(got.cov, want.P), kTol) << what << " covariance at t = " << t;
}

// ---- examples/first_filter.hpp ---------------------------------------------------------------

TEST(FirstFilterExample, MatchesATextbookEkf) {
  const first_filter::Run run = first_filter::run();
  const first_filter::Settings& s = run.settings;
  ASSERT_EQ(run.steps.size(), static_cast<std::size_t>(s.steps));
  ASSERT_TRUE(run.sensor.sensor.isZero());  // the reference's range and bearing are from the origin
  // The chi-square quantile with 2 degrees of freedom in closed form: -2 ln(1 - p).
  const double threshold = -2.0 * std::log(1.0 - s.gate_probability);

  Belief ref{run.initial.mean, run.initial.cov};
  int gated = 0;
  for (const first_filter::Step& step : run.steps) {
    ASSERT_TRUE(step.predicted.accepted()) << "t = " << step.t;
    kf_predict(ref, run.model.accel_psd, s.dt);
    expect_belief_near(step.prior, ref, "prediction", step.t);

    const Innovation in = range_bearing(ref, step.z, run.sensor.sigma_range, run.sensor.sigma_bearing);
    EXPECT_NEAR(step.scored.nis, in.nis, kTol * std::max(1.0, in.nis)) << "t = " << step.t;
    EXPECT_NEAR(step.scored.log_likelihood, in.log_lik, kTol * std::max(1.0, std::abs(in.log_lik))) << "t = " << step.t;
    EXPECT_NEAR(step.scored.gate_threshold, threshold, 1e-9);
    EXPECT_EQ(step.scored.dof, 2);
    // score() reports what update() does, to the last bit.
    EXPECT_EQ(step.scored.outcome, step.updated.outcome);
    EXPECT_EQ(std::memcmp(&step.scored.nis, &step.updated.nis, sizeof(double)), 0);

    if (in.nis > threshold) {
      ++gated;
      EXPECT_EQ(step.t, s.outlier_step * s.dt) << "gated a measurement that is not the outlier";
      EXPECT_EQ(step.updated.outcome, ctxfuse::Outcome::gated);
      EXPECT_TRUE(same_bytes(step.prior, step.posterior)) << "a gated update changed the belief";
    } else {
      EXPECT_EQ(step.updated.outcome, ctxfuse::Outcome::accepted) << "t = " << step.t;
      kf_update(ref, in);
      expect_belief_near(step.posterior, ref, "update", step.t);
    }
  }
  EXPECT_EQ(gated, 1);
}

TEST(FirstFilterExample, RefusesBadInputAndLeavesTheBeliefAsItWas) {
  using ctxfuse::Problem;
  const first_filter::Run run = first_filter::run();
  ASSERT_EQ(run.refusals.size(), 4u);
  const Problem expected[] = {Problem::measurement_wrong_size, Problem::non_finite_measurement,
                              Problem::measurement_out_of_domain, Problem::non_positive_dt};
  for (std::size_t i = 0; i < 4; ++i) {
    const first_filter::Refusal& r = run.refusals[i];
    EXPECT_EQ(r.status.outcome, ctxfuse::Outcome::invalid_input) << r.what;
    EXPECT_EQ(r.status.problem, expected[i]) << r.what << ": " << ctxfuse::describe(r.status.problem);
    EXPECT_FALSE(r.status.accepted()) << r.what;
    EXPECT_TRUE(same_bytes(r.before, r.after)) << r.what;
    EXPECT_TRUE(same_bytes(r.before, run.steps.back().posterior)) << r.what;
  }
}

TEST(FirstFilterExample, TheModelsJacobiansMatchCentralDifferences) {
  const first_filter::Run run = first_filter::run();
  const ctxfuse::Vector<4> x(20.0, 10.0, 1.0, -0.5);
  const auto f = ct::check_transition(run.model, x, {}, run.settings.dt);
  EXPECT_TRUE(f) << f;
  const auto h = ct::check_measurement(run.sensor, x);
  EXPECT_TRUE(h) << h;
}

// ---- examples/imm_two_mode.hpp ---------------------------------------------------------------

// The IMM of Blom and Bar-Shalom for two constant-velocity modes and position fixes, with the
// probability floor of ctxfuse's IMM added (imm_types.hpp; floor 0 is the textbook).
struct ReferenceImm {
  std::array<Belief, 2> mode;
  Vector2d mu;
  Matrix2d T;  // T(i, j): probability of switching from mode i to mode j in one cycle
  std::array<double, 2> q;
  double fix_sigma, floor;
  int floor_bound = 0;  // cycles at which the floor raised a probability

  // What one cycle leaves to compare.
  Vector2d c;
  Belief prior_c, prior_mu, combined;

  static Belief combine(const std::array<Belief, 2>& b, const Vector2d& w) {
    Belief out{w(0) * b[0].x + w(1) * b[1].x, Matrix4d::Zero()};
    for (int i = 0; i < 2; ++i) {
      const Vector4d d = b[i].x - out.x;
      out.P += w(i) * (b[i].P + d * d.transpose());
    }
    return out;
  }

  void cycle(const Vector2d& z, double dt) {
    // Interaction: c_j = sum_i p_ij mu_i, mu_{i|j} = p_ij mu_i / c_j, mixed priors.
    c = T.transpose() * mu;
    std::array<Belief, 2> mixed;
    for (int j = 0; j < 2; ++j) {
      Vector2d w;
      for (int i = 0; i < 2; ++i) w(i) = T(i, j) * mu(i) / c(j);
      mixed[j] = combine(mode, w);
    }
    // Mode-matched filtering, with each mode's likelihood Lambda_j = N(y_j; 0, S_j).
    Vector2d lambda;
    for (int j = 0; j < 2; ++j) {
      mode[j] = mixed[j];
      kf_predict(mode[j], q[j], dt);
    }
    prior_c = combine(mode, c);
    prior_mu = combine(mode, mu);
    for (int j = 0; j < 2; ++j) {
      const Innovation in = position_fix(mode[j], z, fix_sigma);
      lambda(j) = std::exp(-0.5 * in.nis) / std::sqrt(in.S.determinant() * std::pow(2.0 * std::numbers::pi, 2));
      kf_update(mode[j], in);
    }
    // Mode probabilities mu_j = Lambda_j c_j / sum_k Lambda_k c_k, then the floor: a
    // probability below it is raised to it and the other one takes the rest.
    mu = lambda.cwiseProduct(c) / lambda.dot(c);
    for (int j = 0; j < 2; ++j)
      if (mu(j) < floor) {
        mu(j) = floor;
        mu(1 - j) = 1.0 - floor;
        ++floor_bound;
      }
    combined = combine(mode, mu);
  }
};

struct ImmCase {
  const char* name;
  double probability_floor;
  ctxfuse::imm::PriorWeights prior_weights;
  double p_stay;
};

// What gtest (and the test names ctest discovers) show for a case: its name, not its bytes.
void PrintTo(const ImmCase& c, std::ostream* os) { *os << c.name; }

class ImmTwoModeExample : public ::testing::TestWithParam<ImmCase> {};

TEST_P(ImmTwoModeExample, MatchesATextbookImm) {
  imm_two_mode::Settings s;
  s.options.probability_floor = GetParam().probability_floor;
  s.options.prior_weights = GetParam().prior_weights;
  s.p_stay = GetParam().p_stay;
  const imm_two_mode::Run run = imm_two_mode::run(s);
  ASSERT_EQ(run.cycles.size(), static_cast<std::size_t>(s.steps));

  ReferenceImm ref;
  ref.mode = {Belief{run.initial.mean, run.initial.cov}, Belief{run.initial.mean, run.initial.cov}};
  ref.mu = run.mu0 / run.mu0.sum();
  ref.T << s.p_stay, 1.0 - s.p_stay, 1.0 - s.p_stay, s.p_stay;
  ref.q = {s.q_quiet, s.q_manoeuvre};
  ref.fix_sigma = s.fix_sigma;
  ref.floor = s.options.probability_floor;

  int turning = 0;
  for (const imm_two_mode::Cycle& c : run.cycles) {
    ASSERT_TRUE(c.mixed.accepted() && c.predicted.accepted()) << "t = " << c.t;
    ASSERT_EQ(c.update.accepted_count, 2) << "t = " << c.t;
    ref.cycle(c.z, s.dt);
    EXPECT_LE(max_rel_diff(c.c, ref.c), kTol) << "t = " << c.t;
    // combined() inside the cycle follows options.prior_weights; combined(predicted) is the textbook's.
    const bool textbook = s.options.prior_weights == ctxfuse::imm::PriorWeights::predicted;
    expect_belief_near(c.prior, textbook ? ref.prior_c : ref.prior_mu, "combined() after predict", c.t);
    expect_belief_near(c.prior_predicted, ref.prior_c, "prior weighted with c_j", c.t);
    expect_belief_near(c.mode[0], ref.mode[0], "mode 0", c.t);
    expect_belief_near(c.mode[1], ref.mode[1], "mode 1", c.t);
    EXPECT_LE(max_rel_diff(c.mu, ref.mu), kTol) << "t = " << c.t;
    expect_belief_near(c.combined, ref.combined, "combined", c.t);
    turning += c.turning;
  }
  EXPECT_EQ(turning, s.turn_last - s.turn_first + 1);
  // The floor of the case with a high one binds, so that its arithmetic is checked too.
  if (s.options.probability_floor >= 0.01) {
    EXPECT_GT(ref.floor_bound, 0);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ImmTwoModeExample,
    ::testing::Values(
        // The example as it runs: the defaults of ImmOptions.
        ImmCase{"defaults", ctxfuse::imm::ImmOptions<2>{}.probability_floor,
                ctxfuse::imm::ImmOptions<2>{}.prior_weights, 0.95},
        // A floor that binds, and the textbook prior weights.
        ImmCase{"floor_0_05_predicted", 0.05, ctxfuse::imm::PriorWeights::predicted, 0.95},
        // No mixing: each mode a Kalman filter of its own (what the example's last lines print).
        ImmCase{"modes_alone", ctxfuse::imm::ImmOptions<2>{}.probability_floor,
                ctxfuse::imm::ImmOptions<2>{}.prior_weights, 1.0}),
    [](const ::testing::TestParamInfo<ImmCase>& info) { return std::string(info.param.name); });

TEST(ImmTwoModeExample, DefaultsAreTheOnesDocsImmMdStates) {
  const ctxfuse::imm::ImmOptions<2> defaults;
  EXPECT_EQ(defaults.probability_floor, 1e-6);
  EXPECT_EQ(defaults.prior_weights, ctxfuse::imm::PriorWeights::previous_posterior);
  EXPECT_EQ(imm_two_mode::Settings{}.options.probability_floor, 1e-6);
  EXPECT_EQ(imm_two_mode::Settings{}.options.prior_weights, ctxfuse::imm::PriorWeights::previous_posterior);
}

}  // namespace
