// The paper-sized NLOS SVM of the benchmarks (bench_classify_svm, bench_per_sample): the NLOS
// paper's protocol (digest section C): UWB ranges to 4 anchors along a simulated drive, half of
// each anchor's sequence made NLOS by adding positive noise with mean 1-2 m, features (v_u range
// rate, v_i vehicle speed), RBF C-SVC with probabilities. The heavy LOS/NLOS overlap of range
// rates leaves >10,000 SVs.
//
// The model is trained once by libsvm and cached in a file; both predictors (libsvm's and ours)
// load that file, and before anything is timed they must agree on every benchmark input
// (decision value to 1e-9, probabilities to 1e-6), so comparisons are between equal computations.
#pragma once

#include <svm.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_io.hpp"

namespace ctxfuse::bench {

struct NlosSample {
  double range_rate;  // v_u [m/s]
  double speed;       // v_i [m/s]
  int nlos;
};

/// A drive around a 120 m x 70 m loop at 1-9 m/s, UWB at 10 Hz to 4 anchors with 0.1 m
/// ranging noise. Each anchor's sequence alternates LOS and NLOS blocks of 2-10 s (half NLOS);
/// in an NLOS block every range gets a positive error mu * g, g ~ Gamma(40, 1/40) (mean 1),
/// with mu ~ U(1, 2) m drawn per block.
inline std::vector<NlosSample> simulate_nlos_drive(int samples_per_anchor, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::gamma_distribution<double> excess(40.0, 1.0 / 40.0);
  const double dt = 0.1;
  const std::array<Eigen::Vector2d, 4> anchors = {Eigen::Vector2d(-10, -8), Eigen::Vector2d(130, -6),
                                                  Eigen::Vector2d(128, 78), Eigen::Vector2d(-8, 80)};
  const double perimeter = 2 * (120.0 + 70.0);
  const auto position = [&](double s) {
    s = std::fmod(s, perimeter);
    if (s < 120) return Eigen::Vector2d(s, 0);
    if (s < 190) return Eigen::Vector2d(120, s - 120);
    if (s < 310) return Eigen::Vector2d(310 - s, 70);
    return Eigen::Vector2d(0, perimeter - s);
  };
  std::vector<NlosSample> out;
  for (std::size_t a = 0; a < anchors.size(); ++a) {
    double travelled = 0.0, previous_range = 0.0;
    int block_left = 0;
    bool nlos = false;
    double mu = 0.0;
    for (int k = 0; k <= samples_per_anchor; ++k) {
      const double t = k * dt;
      const double speed = 5.0 + 4.0 * std::sin(0.031 * t + static_cast<double>(a)) * std::cos(0.007 * t);
      travelled += speed * dt;
      if (block_left-- <= 0) {
        block_left = 20 + static_cast<int>(u01(rng) * 80);
        nlos = u01(rng) < 0.5;
        mu = 1.0 + u01(rng);
      }
      double range = (position(travelled) - anchors[a]).norm() + 0.1 * n01(rng);
      if (nlos) range += mu * excess(rng);
      if (k > 0) out.push_back({(range - previous_range) / dt, speed + 0.05 * n01(rng), nlos ? 1 : 0});
      previous_range = range;
    }
  }
  return out;
}

/// The model loaded by both predictors, the training set's standardisation, and 1024 benchmark
/// inputs (drive seed 2) in both input forms, checked to agree.
struct NlosSvmBenchModel {
  svm_model* libsvm = nullptr;
  classify::SvmModel<2, 2> ours;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Vector2d stdev = Eigen::Vector2d::Ones();
  std::vector<NlosSample> raw;  // the benchmark inputs before standardisation
  std::vector<Eigen::Vector2d> inputs;
  std::vector<std::array<svm_node, 3>> nodes;

  /// Features in the model's units (the model file carries no scaling).
  Eigen::Vector2d standardise(double range_rate, double speed) const {
    return {(range_rate - mean[0]) / stdev[0], (speed - mean[1]) / stdev[1]};
  }
  static std::array<svm_node, 3> node(const Eigen::Vector2d& x) { return {svm_node{1, x[0]}, svm_node{2, x[1]}, svm_node{-1, 0.0}}; }
  /// Index of the NLOS label (1) in the model's class order.
  int nlos_class() const { return ours.labels[0] == 1 ? 0 : 1; }
};

/// libsvm's C-SVC as the benchmark model trains it: RBF, gamma 0.5, C 1, Platt probabilities
/// (cache_mb changes only the training's speed).
inline svm_parameter nlos_bench_svm_parameters(double cache_mb) {
  svm_parameter p{};
  p.svm_type = C_SVC;
  p.kernel_type = RBF;
  p.gamma = 0.5;
  p.C = 1.0;
  p.cache_size = cache_mb;
  p.eps = 1e-3;
  p.shrinking = 1;
  p.probability = 1;
  return p;
}

namespace nlos_svm_detail {
inline void quiet(const char*) {}
}  // namespace nlos_svm_detail

/// Trains (first run, a few minutes) or loads the model cached at `cache`. With
/// CTXFUSE_BENCH_SMOKE set (scripts/bench_smoke.sh in CI) a small model with its own cache file,
/// which only shows that the binary runs. Throws when the two predictors disagree.
inline NlosSvmBenchModel build_nlos_svm_bench_model(const std::string& cache_path) {
  NlosSvmBenchModel fx;
  svm_set_print_string_function(&nlos_svm_detail::quiet);
  const bool smoke = std::getenv("CTXFUSE_BENCH_SMOKE") != nullptr;
  const auto train = simulate_nlos_drive(smoke ? 250 : 6250, 1);
  Eigen::Vector2d sq = Eigen::Vector2d::Zero();
  for (const auto& s : train) fx.mean += Eigen::Vector2d(s.range_rate, s.speed);
  fx.mean /= static_cast<double>(train.size());
  for (const auto& s : train) sq += (Eigen::Vector2d(s.range_rate, s.speed) - fx.mean).cwiseAbs2();
  fx.stdev = (sq / static_cast<double>(train.size())).cwiseSqrt();
  const std::string cache = cache_path + (smoke ? ".smoke" : "");
  if (!std::filesystem::exists(cache)) {
    std::fprintf(stderr, "training the benchmark model with libsvm on %zu samples (cached in %s) ...\n", train.size(), cache.c_str());
    std::vector<std::array<svm_node, 3>> rows(train.size());
    std::vector<svm_node*> ptrs(train.size());
    std::vector<double> y(train.size());
    for (std::size_t i = 0; i < train.size(); ++i) {
      rows[i] = NlosSvmBenchModel::node(fx.standardise(train[i].range_rate, train[i].speed));
      ptrs[i] = rows[i].data();
      y[i] = train[i].nlos;
    }
    svm_problem prob{static_cast<int>(train.size()), y.data(), ptrs.data()};
    const svm_parameter p = nlos_bench_svm_parameters(500);
    std::srand(1);
    svm_model* trained = svm_train(&prob, &p);
    const auto tmp = cache + ".tmp";
    if (svm_save_model(tmp.c_str(), trained) != 0) throw std::runtime_error("cannot write " + tmp);
    std::filesystem::rename(tmp, cache);
    svm_free_and_destroy_model(&trained);
  }
  fx.libsvm = svm_load_model(cache.c_str());
  if (!fx.libsvm) throw std::runtime_error("libsvm cannot load " + cache);
  fx.ours = classify::load_svm_model<2, 2>(cache);
  fx.raw = simulate_nlos_drive(256, 2);
  for (const auto& s : fx.raw) {
    fx.inputs.push_back(fx.standardise(s.range_rate, s.speed));
    fx.nodes.push_back(NlosSvmBenchModel::node(fx.inputs.back()));
  }
  classify::SvmPrediction<2> out;
  for (std::size_t i = 0; i < fx.inputs.size(); ++i) {
    double dec = 0.0, prob[2];
    svm_predict_values(fx.libsvm, fx.nodes[i].data(), &dec);
    svm_predict_probability(fx.libsvm, fx.nodes[i].data(), prob);
    if (!classify::svm_predict(fx.ours, fx.inputs[i], out))
      throw std::runtime_error("ours refused benchmark input " + std::to_string(i));
    if (std::abs(out.decision_values[0] - dec) > 1e-9 * std::max(1.0, std::abs(dec)) || std::abs(out.probabilities[0] - prob[0]) > 1e-6)
      throw std::runtime_error("ours and libsvm disagree on benchmark input " + std::to_string(i));
  }
  return fx;
}

}  // namespace ctxfuse::bench
