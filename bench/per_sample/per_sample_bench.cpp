// The NLOS paper's per-sample timing table (digest section C, Table 5), ours against libsvm and
// Ceres in one binary and one run. A sample is one UWB range; an epoch is the 4 ranges (one per
// anchor) that one fixed-lag smoother step fuses. Run with
//   bench_per_sample --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
//                    --benchmark_report_aggregates_only=true
//                    --benchmark_out=out/bench/bench_per_sample.json --benchmark_out_format=json
//   python3 bench/per_sample/table.py out/bench/bench_per_sample.json   (table beside the paper's)
//
// Per range: PerSample/SVM (our RBF SVM with probabilities, the paper-sized model of
//   bench/classify_svm/nlos_svm_model.hpp, through the evaluator the NLOS classifier builds:
//   classify::SvmFastRbf with its automatic choice, here the fast Gauss transform),
//   PerSample/SVM/Exact (the exact kernel sum of svm.hpp), PerSample/LibSVM (libsvm on the same
//   model file and inputs), PerSample/Consistency (p2, eq. 3-6), PerSample/DS (Dempster's rule on
//   p1, p2).
// Per epoch of 4 ranges (the counter s_per_range is the CPU time divided by 4):
//   PerSample/Fusion/SameWindow, PerSample/Ceres, PerSample/TinySolver: the paper's fusion, the
//   UWB/IMU factor graph of imu_window.hpp (10 planar IMU states, IMU factors of the epoch's
//   10 samples preintegrated, 4 ranges per state), one step of it (preintegration and solve)
//   by our smoother, and the same window solved by Ceres' fastest solver there (sparse normal
//   Cholesky) and by Ceres' TinySolver (dense, given our analytic Jacobians), to the same
//   solution; PerSample/Fusion/Stream (steady state);
//   PerSample/CvFusion/SameWindow, PerSample/CvCeres: the constant-velocity window of
//   bench/fixed_lag/fixed_lag_window.hpp (10 planar position-velocity states), our step and
//   Ceres';
//   PerSample/Total/Epoch4: each of the epoch's 4 ranges through the NLOS pipeline's classifier
//   (pipelines/nlos_uwb/classifier.hpp: features, SVM + consistency + D-S + the eq. 8
//   decision), its paper attach rule for the epoch (policies.hpp), and the IMU graph's step.
// Every benchmark checks its result before timing and reports an error instead of a time when
// the check fails.
#include <benchmark/benchmark.h>
#include <svm.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <string>
#include <vector>

#include "ctxfuse/classify/consistency.hpp"
#include "ctxfuse/classify/dempster_shafer.hpp"
#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_fast_rbf.hpp"
#include "ctxfuse/pipelines/nlos_uwb/classifier.hpp"
#include "ctxfuse/pipelines/nlos_uwb/policies.hpp"
#include "fixed_lag_window.hpp"
#include "imu_window.hpp"
#include "nlos_svm_model.hpp"

namespace {
using namespace ctxfuse;
namespace cv = ctxfuse::bench::fixed_lag_window;
namespace iw = ctxfuse::bench::imu_window;
using iw::dt;
using ctxfuse::bench::NlosSvmBenchModel;
namespace nu = ctxfuse::pipelines::nlos_uwb;
constexpr int kRangesPerEpoch = 4;

/// The model, or why there is none (training/loading failed, or ours and libsvm disagree).
struct LoadedModel {
  NlosSvmBenchModel model;
  std::string error;
  LoadedModel() {
    try {
      model = ctxfuse::bench::build_nlos_svm_bench_model(CTXFUSE_SVM_BENCH_CACHE);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
};

const LoadedModel& loaded() {
  static const LoadedModel m;
  return m;
}
const NlosSvmBenchModel& model() { return loaded().model; }

/// False (and the benchmark reports the error instead of a time) when there is no checked model.
bool have_model(benchmark::State& state) {
  if (loaded().error.empty()) return true;
  state.SkipWithError(loaded().error.c_str());
  return false;
}

/// CPU seconds per range of an epoch benchmark (Google Benchmark divides rates by CPU time).
void per_range_counter(benchmark::State& state) {
  state.counters["s_per_range"] = benchmark::Counter(static_cast<double>(state.iterations() * kRangesPerEpoch),
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

/// p2 of eq. 6 written out plainly (paper thresholds 1, 2, 3 sigma, probabilities 0.35, 0.55,
/// 0.70, 0.90), the reference the consistency model is checked against.
double consistency_reference(double range_change, double travelled, double sigma) {
  const double e = std::abs(range_change) - travelled;
  if (e <= sigma) return 0.35;
  if (e <= 2 * sigma) return 0.55;
  if (e <= 3 * sigma) return 0.70;
  return 0.90;
}

/// The benchmark inputs' NLOS probabilities from both classifiers, checked once.
struct Probabilities {
  std::vector<double> p1, p2;
  bool ok = true;
  Probabilities() {
    const auto& m = model();
    const classify::ConsistencyModel consistency{};
    classify::SvmPrediction<2> out;
    for (std::size_t i = 0; i < m.raw.size(); ++i) {
      ok = ok && classify::svm_predict(m.ours, m.inputs[i], out).accepted();
      p1.push_back(out.probabilities[static_cast<std::size_t>(m.nlos_class())]);
      const double change = m.raw[i].range_rate * dt, travelled = m.raw[i].speed * dt;
      p2.push_back(consistency.nlos_probability(change, travelled));
      ok = ok && p2.back() == consistency_reference(change, travelled, consistency.sigma_uwb);
    }
  }
};

const Probabilities& probabilities() {
  static const Probabilities p;
  return p;
}

/// The evaluator the pipeline's classifier builds (automatic choice), checked once against the
/// exact path on every input (probabilities to 1e-9, labels equal).
struct Evaluator {
  nu::NlosSvmEvaluator fast{model().ours};
  bool ok = true;
  Evaluator() {
    const auto& m = model();
    classify::SvmPrediction<2> exact, out;
    for (const auto& x : m.inputs) {
      ok = ok && classify::svm_predict(m.ours, x, exact).accepted() && fast.predict(x, out).accepted() &&
           out.label == exact.label && std::abs(out.probabilities[0] - exact.probabilities[0]) <= 1e-9;
    }
  }
};

const Evaluator& evaluator() {
  static const Evaluator e;
  return e;
}

void PerSample_SVM(benchmark::State& state) {
  if (!have_model(state)) return;
  if (!evaluator().ok) {
    state.SkipWithError("the fast evaluator and the exact path disagree");
    return;
  }
  const auto& m = model();
  const auto& fast = evaluator().fast;
  classify::SvmPrediction<2> out;
  std::size_t i = 0;
  for (auto _ : state) {
    static_cast<void>(fast.predict(m.inputs[i], out));  // inputs checked by the fixture
    benchmark::DoNotOptimize(out.probabilities[0]);
    i = (i + 1) % m.inputs.size();
  }
  state.counters["support_vectors"] = static_cast<double>(m.ours.num_support_vectors());
  state.counters["fast"] = fast.plan().fast;
  state.counters["target_cells"] = static_cast<double>(fast.plan().target.cells);
}

void PerSample_SVM_Exact(benchmark::State& state) {
  if (!have_model(state)) return;
  const auto& m = model();
  classify::SvmPrediction<2> out;
  std::size_t i = 0;
  for (auto _ : state) {
    static_cast<void>(classify::svm_predict(m.ours, m.inputs[i], out));  // inputs checked by the fixture
    benchmark::DoNotOptimize(out.probabilities[0]);
    i = (i + 1) % m.inputs.size();
  }
  state.counters["support_vectors"] = static_cast<double>(m.ours.num_support_vectors());
}

void PerSample_LibSVM(benchmark::State& state) {
  if (!have_model(state)) return;
  const auto& m = model();
  double prob[2];
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(svm_predict_probability(m.libsvm, m.nodes[i].data(), prob));
    benchmark::DoNotOptimize(prob[0]);
    i = (i + 1) % m.nodes.size();
  }
  state.counters["support_vectors"] = static_cast<double>(m.libsvm->l);
}

void PerSample_Consistency(benchmark::State& state) {
  if (!have_model(state)) return;
  const auto& m = model();
  if (!probabilities().ok) {
    state.SkipWithError("consistency probabilities differ from eq. 6 written out");
    return;
  }
  const classify::ConsistencyModel consistency{};
  std::size_t i = 0;
  for (auto _ : state) {
    const double change = m.raw[i].range_rate * dt, travelled = m.raw[i].speed * dt;
    benchmark::DoNotOptimize(consistency.nlos_probability(change, travelled));
    i = (i + 1) % m.raw.size();
  }
}

void PerSample_DS(benchmark::State& state) {
  if (!have_model(state)) return;
  const auto& p = probabilities();
  for (std::size_t i = 0; i < p.p1.size(); ++i) {
    const double q = p.p1[i] * p.p2[i], r = q / (q + (1 - p.p1[i]) * (1 - p.p2[i]));
    const auto ds = classify::combine_probabilities(p.p1[i], p.p2[i]);
    if (!ds.status || !(std::abs(ds.nlos_belief() - r) <= 1e-12)) {
      state.SkipWithError("D-S belief differs from p1 p2 / (p1 p2 + q1 q2)");
      return;
    }
  }
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(classify::combine_probabilities(p.p1[i], p.p2[i]).mass.nlos);
    i = (i + 1) % p.p1.size();
  }
}

/// Largest state difference between two windows of the same size.
template <class Window>
double window_gap(const Window& a, const Window& b) {
  double gap = 0.0;
  for (std::size_t i = 0; i < a.epochs.size(); ++i) gap = std::max(gap, (a.epochs[i].x - b.epochs[i].x).cwiseAbs().maxCoeff());
  return gap;
}

void PerSample_Fusion_SameWindow(benchmark::State& state) {
  const iw::Snapshot& snap = iw::snapshot();
  auto s = std::make_unique<iw::Smoother>(*snap.before);
  models::PlanarPreintegrated pre;
  if (!iw::step(*s, snap.k, snap.meas, pre) || !(window_gap(s->window(), snap.after->window()) <= 1e-12)) {
    state.SkipWithError("the step does not reproduce the snapshot window");
    return;
  }
  const auto last = iw::step_snapshot_copies(state);
  per_range_counter(state);
  state.counters["iterations"] = last->report().iterations;
}

void PerSample_Fusion_Stream(benchmark::State& state) {
  iw::DriveStream stream;
  for (auto _ : state) {
    stream.step();
    benchmark::DoNotOptimize(stream.smoother->newest().data());
  }
  if (stream.refused > 0) state.SkipWithError("a step was refused");
  per_range_counter(state);
}

/// Ceres on a snapshot window: Solve is the IMU graph's (iw::) or the constant-velocity
/// window's (cv::) solve_with_ceres.
template <double (*Solve)(const ceres::Solver::Options&, ceres::Solver::Summary&)>
void PerSample_Ceres(benchmark::State& state) {
  const ceres::Solver::Options options = cv::ceres_options(ceres::SPARSE_NORMAL_CHOLESKY);
  ceres::Solver::Summary summary;
  const double gap = Solve(options, summary);
  if (!(gap <= 1e-6)) {
    state.SkipWithError("Ceres does not reach the smoother's solution to 1e-6");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(Solve(options, summary));
  state.counters["gap_to_smoother"] = gap;
  state.counters["iterations"] = static_cast<double>(summary.iterations.size());
  per_range_counter(state);
}

void PerSample_TinySolver(benchmark::State& state) {
  auto solver = std::make_unique<iw::TinySolver>();  // its fixed-size workspace is ~0.2 MB
  iw::tiny_options(*solver);
  const double gap = iw::solve_with_tiny(*solver);
  if (!(gap <= 1e-6)) {
    state.SkipWithError("TinySolver does not reach the smoother's solution to 1e-6");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(iw::solve_with_tiny(*solver));
  state.counters["gap_to_smoother"] = gap;
  state.counters["iterations"] = solver->summary.iterations;
  per_range_counter(state);
}

// The constant-velocity window (10 planar position-velocity states); Ceres on it is
// PerSample_Ceres<cv::solve_with_ceres>.
void PerSample_CvFusion_SameWindow(benchmark::State& state) {
  const cv::Snapshot& snap = cv::snapshot();
  auto s = std::make_unique<cv::Smoother>(*snap.before);
  if (!s->step(snap.t, {}, snap.meas) || !(window_gap(s->window(), snap.after->window()) <= 1e-12)) {
    state.SkipWithError("the step does not reproduce the snapshot window");
    return;
  }
  (void)cv::step_snapshot_copies(state);
  per_range_counter(state);
}

/// One epoch of the whole chain, through the NLOS pipeline's own pieces: each range through
/// `pipelines::nlos_uwb::NlosClassifier` (its feature extractor: v_u = (r_k - r_{k-1}) / dt
/// from the drive's own ranges, v_i = the drive's speed; SVM p1, consistency p2, D-S R, the
/// eq. 8 decision) with the paper-sized model (the benchmark's standardisation as the model's
/// input scaling), then `PaperEpochRule::select` for the epoch, as `pipelines::nlos_uwb::run`
/// calls them.
struct EpochChain {
  nu::Settings settings{};
  nu::NlosClassifier classifier{settings, pipeline_svm()};
  nu::PaperEpochRule rule{classify::FactorAttachPolicy{settings.mixed_epoch_belief}};
  double speed = iw::Drive::speed;
  std::array<nu::RangeVerdict, kRangesPerEpoch> verdicts{};
  std::array<bool, kRangesPerEpoch> attach{};

  static nu::NlosSvm pipeline_svm() {
    nu::NlosSvm svm = model().ours;
    svm.input_mean = model().mean;
    svm.input_std = model().stdev;
    return svm;
  }

  /// The epoch's measurements, attached as the rule says (or all, with attach_all: the
  /// classifiers still run, the step always fuses 4 ranges). Epochs come in time order.
  iw::Smoother::Measurements classify(long k, bool attach_all = false) {
    const auto& now = iw::drive().ranges[static_cast<std::size_t>(k % iw::Drive::period)];
    for (std::size_t a = 0; a < kRangesPerEpoch; ++a) {
      messages::UwbRange r;
      r.t = static_cast<double>(k) * dt;
      r.anchor_id = static_cast<int>(a);
      r.range_m = now[a];
      verdicts[a] = classifier.classify(r, speed);
    }
    rule.select(verdicts, attach);
    iw::Smoother::Measurements meas = iw::drive().measurements(k);
    if (!attach_all)
      for (std::size_t a = 0; a < kRangesPerEpoch; ++a) meas.attached[a] = attach[a];
    return meas;
  }
};

void PerSample_Total_Epoch4(benchmark::State& state, bool attach_all) {
  if (!have_model(state)) return;
  {
    // Check: over one period of the drive, p1 equals libsvm's probability and R the closed
    // form p1 p2 / (p1 p2 + q1 q2) with p2 of eq. 6 written out.
    EpochChain chain;
    (void)chain.classify(0);  // each anchor's first range: no range rate yet
    for (long k = 1; k <= iw::Drive::period; ++k) {
      (void)chain.classify(k);
      const auto& now = iw::drive().ranges[static_cast<std::size_t>(k % iw::Drive::period)];
      const auto& before = iw::drive().ranges[static_cast<std::size_t>(k - 1)];
      for (std::size_t a = 0; a < kRangesPerEpoch; ++a) {
        const double change = now[a] - before[a];
        double prob[2];
        const auto node = NlosSvmBenchModel::node(model().standardise(change / dt, chain.speed));
        svm_predict_probability(model().libsvm, node.data(), prob);
        const double p1 = prob[model().nlos_class()], p2 = consistency_reference(change, chain.speed * dt, 0.1);
        const double r = p1 * p2 / (p1 * p2 + (1 - p1) * (1 - p2));
        if (!(std::abs(chain.verdicts[a].p1 - p1) <= 1e-6) || !(std::abs(chain.verdicts[a].R - r) <= 1e-6)) {
          state.SkipWithError("the pipeline's p1 or R differs from libsvm and the closed form");
          return;
        }
      }
    }
  }
  EpochChain chain;
  iw::DriveStream stream;
  (void)chain.classify(stream.k);
  long attached = 0;
  for (auto _ : state) {
    const iw::Smoother::Measurements meas = chain.classify(stream.k + 1, attach_all);
    attached += meas.attached_count() > 0;
    stream.step(meas);
    benchmark::DoNotOptimize(stream.smoother->newest().data());
  }
  if (stream.refused > 0) state.SkipWithError("a step was refused");
  per_range_counter(state);
  state.counters["attached_epochs"] = static_cast<double>(attached) / static_cast<double>(std::max(1L, stream.k));
}

}  // namespace

BENCHMARK(PerSample_SVM)->Name("PerSample/SVM")->Unit(benchmark::kMicrosecond);
BENCHMARK(PerSample_SVM_Exact)->Name("PerSample/SVM/Exact")->Unit(benchmark::kMicrosecond);
BENCHMARK(PerSample_LibSVM)->Name("PerSample/LibSVM")->Unit(benchmark::kMicrosecond);
BENCHMARK(PerSample_Consistency)->Name("PerSample/Consistency");
BENCHMARK(PerSample_DS)->Name("PerSample/DS");
BENCHMARK(PerSample_Fusion_SameWindow)->Name("PerSample/Fusion/SameWindow")->Unit(benchmark::kMicrosecond);
BENCHMARK(PerSample_Fusion_Stream)->Name("PerSample/Fusion/Stream")->Unit(benchmark::kMicrosecond);
BENCHMARK(PerSample_Ceres<iw::solve_with_ceres>)->Name("PerSample/Ceres")->Unit(benchmark::kMicrosecond);
BENCHMARK(PerSample_TinySolver)->Name("PerSample/TinySolver")->Unit(benchmark::kMicrosecond);
BENCHMARK(PerSample_CvFusion_SameWindow)->Name("PerSample/CvFusion/SameWindow")->Unit(benchmark::kMicrosecond);
BENCHMARK(PerSample_Ceres<cv::solve_with_ceres>)->Name("PerSample/CvCeres")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(PerSample_Total_Epoch4, paper_rule, false)->Name("PerSample/Total/Epoch4")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(PerSample_Total_Epoch4, all_attached, true)->Name("PerSample/Total/Epoch4/AllAttached")->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
