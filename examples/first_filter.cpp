// A first filter: a target moving at constant velocity in the plane, tracked by an EKF from
// range and bearing measurements of a sensor at the origin. The models, the filter and the
// simulated measurements are in first_filter.hpp; this program prints what happened.
// One measurement is an outlier (its range is 12 m off) and the chi-square gate refuses it;
// at the end, four bad inputs are refused and leave the belief untouched.
//   build/release/examples/example_first_filter [seed]
// docs/first_filter.md explains every line of the output.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include "first_filter.hpp"

int main(int argc, char** argv) {
  using namespace first_filter;
  Settings settings;
  if (argc > 1) settings.seed = std::strtoull(argv[1], nullptr, 10);
  const Run run = first_filter::run(settings);
  const double deg = 180.0 / std::numbers::pi;

  std::printf("# first_filter, seed %llu: range-bearing EKF, chi-square gate p = %.2f (threshold %.3f for 2 dof)\n",
              static_cast<unsigned long long>(settings.seed), settings.gate_probability,
              run.steps.front().scored.gate_threshold);
  std::printf("# t_s range_m bearing_deg nis log_lik outcome x_m y_m vx_m_s vy_m_s sigma_x_m sigma_y_m\n");
  for (const Step& s : run.steps) {
    if (!s.predicted) {
      std::fprintf(stderr, "t = %.0f s: prediction refused: %s\n", s.t, describe(s.predicted.problem).data());
      return 1;
    }
    const Gaussian<4>& b = s.posterior;
    std::printf("%4.1f %7.3f %8.3f %7.3f %7.3f %-8s %7.3f %7.3f %6.3f %6.3f %5.3f %5.3f\n", s.t, s.z(0),
                s.z(1) * deg, s.scored.nis, s.scored.log_likelihood, describe(s.updated.outcome).data(), b.mean(0),
                b.mean(1), b.mean(2), b.mean(3), std::sqrt(b.cov(0, 0)), std::sqrt(b.cov(1, 1)));
  }

  const Step& last = run.steps.back();
  std::printf("# final position error %.3f m (truth %.3f %.3f)\n",
              (last.posterior.mean.head<2>() - last.truth.head<2>()).norm(), last.truth(0), last.truth(1));
  std::printf("# refused inputs (outcome, problem, belief unchanged?)\n");
  int changed = 0;
  for (const Refusal& r : run.refusals) {
    const bool same = r.before.mean == r.after.mean && r.before.cov == r.after.cov;
    changed += !same;
    std::printf("# %-16s %s: %s; belief unchanged: %s\n", r.what, describe(r.status.outcome).data(),
                describe(r.status.problem).data(), same ? "yes" : "NO");
  }
  return changed == 0 ? 0 : 1;
}
