// One fixed-lag smoother step (window of 10 planar position-velocity states, 4 UWB ranges per
// epoch, constant-velocity motion) against Ceres 2.1 solving the same window from the same
// starting point to the same solution. Run with
//   bench_fixed_lag --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//                   --benchmark_out=fixed_lag.json --benchmark_out_format=json
//
// FixedLag/Stream: steps along a periodic drive, the steady state a user pays per epoch.
// FixedLag/SameWindow: the step that produced the snapshot window Ceres solves, on copies of
//   the smoother taken before it (the copies made outside the timing, step_snapshot_copies).
// FixedLag/Ceres/*: that window built as a ceres::Problem (autodiff costs from the same
//   factors, problem construction timed) and solved with tolerances that reproduce the
//   smoother's solution to 1e-6; checked before anything is timed.
#include <benchmark/benchmark.h>

#include "fixed_lag_window.hpp"

namespace {
using namespace ctxfuse;
using namespace ctxfuse::bench::fixed_lag_window;

void FixedLag_Stream(benchmark::State& state) {
  DriveStream stream;
  for (auto _ : state) {
    stream.step();
    benchmark::DoNotOptimize(stream.smoother->newest().data());
  }
  if (stream.refused > 0) state.SkipWithError("a step was refused");
  state.counters["iterations_last"] = stream.smoother->report().iterations;
}

void FixedLag_SameWindow(benchmark::State& state) {
  const Snapshot& snap = snapshot();
  const std::unique_ptr<Smoother> stepped = step_snapshot_copies(state);
  const Smoother& s = *stepped;
  double gap = 0.0;
  for (int i = 0; i < K; ++i)
    gap = std::max(gap, (s.window().epochs[static_cast<std::size_t>(i)].x - snap.after->window().epochs[static_cast<std::size_t>(i)].x)
                            .cwiseAbs().maxCoeff());
  state.counters["gauss_newton_iterations"] = s.report().iterations;
  state.counters["gap_to_snapshot"] = gap;
}

void FixedLag_Ceres(benchmark::State& state, ceres::LinearSolverType solver) {
  const ceres::Solver::Options options = ceres_options(solver);
  ceres::Solver::Summary summary;
  const double gap = solve_with_ceres(options, summary);
  if (!(gap <= 1e-6)) {
    state.SkipWithError("Ceres does not reach the smoother's solution to 1e-6 with these options");
    return;
  }
  for (auto _ : state) {
    benchmark::DoNotOptimize(solve_with_ceres(options, summary));
  }
  state.counters["gap_to_smoother"] = gap;
  state.counters["ceres_iterations"] = static_cast<double>(summary.iterations.size());
}

}  // namespace

BENCHMARK(FixedLag_Stream)->Name("FixedLag/Stream");
BENCHMARK(FixedLag_SameWindow)->Name("FixedLag/SameWindow");
BENCHMARK_CAPTURE(FixedLag_Ceres, dense_normal_cholesky, ceres::DENSE_NORMAL_CHOLESKY)->Name("FixedLag/Ceres/DenseNormalCholesky");
BENCHMARK_CAPTURE(FixedLag_Ceres, dense_qr, ceres::DENSE_QR)->Name("FixedLag/Ceres/DenseQR");
BENCHMARK_CAPTURE(FixedLag_Ceres, sparse_normal_cholesky, ceres::SPARSE_NORMAL_CHOLESKY)->Name("FixedLag/Ceres/SparseNormalCholesky");
BENCHMARK_MAIN();
