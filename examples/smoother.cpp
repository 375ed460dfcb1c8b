// The first filter's target, smoothed: a fixed-lag smoother of 5 states with the same
// constant-velocity and range-bearing models, beside the EKF. docs/smoother.md explains it.
//   build/release/examples/example_smoother [seed]
#include <cstdio>
#include <cstdlib>

#include "smoother.hpp"

int main(int argc, char** argv) {
  smoother_example::Settings s;
  if (argc > 1) s.seed = std::strtoull(argv[1], nullptr, 10);
  const smoother_example::Run r = smoother_example::run(s);

  std::printf("fixed-lag smoother, window %d, %d epochs of range and bearing (seed %llu)\n", smoother_example::kLag,
              s.steps, static_cast<unsigned long long>(s.seed));
  std::printf("   t   status    iter  EKF x y [m]          smoother newest x y  oldest in window (t, x, y)\n");
  for (const auto& st : r.steps) {
    std::printf("%4.0f  %-9s %3d   %8.3f %8.3f   %8.3f %8.3f      %4.0f %8.3f %8.3f\n", st.t,
                ctxfuse::describe(st.smoothed.outcome).data(), st.iterations, st.ekf.mean(0), st.ekf.mean(1),
                st.newest.mean(0), st.newest.mean(1), st.times[0], st.window[0](0), st.window[0](1));
  }
  std::printf("horizontal RMS error over the epochs with a lagged estimate:\n");
  std::printf("  EKF                          %.3f m\n", r.rms_ekf);
  std::printf("  smoother, newest state       %.3f m\n", r.rms_newest);
  std::printf("  smoother, %d epochs later     %.3f m\n", smoother_example::kLag - 1, r.rms_lagged);
  return 0;
}
