// A two-mode IMM: constant velocity with little process noise (mode 0, quiet) and with much
// (mode 1, manoeuvring), over the same state (p, v), tracking a target from 2-D position fixes.
// The target drives straight east at 10 m/s, turns left through 90 degrees in 10 s and drives
// straight north. The models, the IMM and the simulated fixes are in imm_two_mode.hpp; this
// program prints, for each fix, the mode probabilities and the combined estimate's error.
//   build/release/examples/example_imm_two_mode [seed]
// Output: lines starting with '#' are comments; the others are
//   t_s turning c_quiet mu_quiet mu_manoeuvre error_m prior_gap_m
// c_quiet is the predicted probability of mode 0 (after mixing), mu_* the posterior ones,
// error_m the distance of the combined position from the truth, prior_gap_m the distance
// between the combined prediction that combined() gives between predict() and update() (its
// default weights, the last cycle's mu_j) and the textbook's (weights c_j): docs/imm.md.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "imm_two_mode.hpp"

int main(int argc, char** argv) {
  using namespace imm_two_mode;
  Settings settings;
  if (argc > 1) settings.seed = std::strtoull(argv[1], nullptr, 10);
  const Run run = imm_two_mode::run(settings);

  std::printf("# imm_two_mode, seed %llu: q %.2f and %.2f m^2/s^3, p_stay %.2f, fixes %.1f m, floor %g\n",
              static_cast<unsigned long long>(settings.seed), settings.q_quiet, settings.q_manoeuvre,
              settings.p_stay, settings.fix_sigma, settings.options.probability_floor);
  std::printf("# t_s turning c_quiet mu_quiet mu_manoeuvre error_m prior_gap_m\n");
  double sq[2] = {0.0, 0.0};
  int n[2] = {0, 0};
  for (const Cycle& c : run.cycles) {
    if (!c.mixed || !c.predicted) {
      const Status& bad = c.mixed ? c.predicted : c.mixed;
      std::fprintf(stderr, "t = %.0f s: refused: %s\n", c.t, describe(bad.problem).data());
      return 1;
    }
    const double err = (c.combined.mean.head<2>() - c.truth.head<2>()).norm();
    const double gap = (c.prior_predicted.mean.head<2>() - c.prior.mean.head<2>()).norm();
    sq[c.turning] += err * err;
    ++n[c.turning];
    std::printf("%4.0f %d %.6f %.6f %.6f %6.3f %6.3f\n", c.t, c.turning ? 1 : 0, c.c(0), c.mu(0), c.mu(1), err, gap);
  }
  std::printf("# RMS position error, IMM: straight %.3f m, turning %.3f m\n", std::sqrt(sq[0] / n[0]),
              std::sqrt(sq[1] / n[1]));

  // The same fixes through each mode alone: with p_stay = 1 the modes never mix, so each mode
  // is a plain Kalman filter with its own process noise.
  Settings alone = settings;
  alone.p_stay = 1.0;
  const Run single = imm_two_mode::run(alone);
  for (int j = 0; j < 2; ++j) {
    double sq_j[2] = {0.0, 0.0};
    for (const Cycle& c : single.cycles)
      sq_j[c.turning] += (c.mode[j].mean.head<2>() - c.truth.head<2>()).squaredNorm();
    std::printf("# RMS position error, mode %d alone: straight %.3f m, turning %.3f m\n", j, std::sqrt(sq_j[0] / n[0]),
                std::sqrt(sq_j[1] / n[1]));
  }
  return 0;
}
