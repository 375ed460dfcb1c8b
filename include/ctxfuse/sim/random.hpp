// Portable random numbers for the simulator. std::mt19937_64 is bit-exactly specified by the
// standard, but the std:: distributions are not, so the same seed would give different drives
// on libstdc++ and libc++. The uniform and normal variates below are written out explicitly so
// that a seed reproduces the same bytes with any conforming compiler and library.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace ctxfuse::sim {

/// Independent sub-streams, one per sensor, so that changing one sensor's configuration (and
/// thus how many draws it makes) leaves every other sensor's output unchanged.
enum class Stream : std::uint64_t { imu = 1, gnss = 2, uwb = 3, speed = 4, magnetometer = 5, sky = 6 };

/// SplitMix64 finaliser: spreads nearby seeds (1, 2, 3, ...) over the whole 64-bit space.
constexpr std::uint64_t mix_seed(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  Rng(std::uint64_t seed, Stream stream)
      : engine_(mix_seed(mix_seed(seed) ^ (static_cast<std::uint64_t>(stream) * 0xd1b54a32d192ed03ULL))) {}

  /// Uniform on the open interval (0, 1): 53 random bits, offset by half a step so that the
  /// logarithm in normal() never sees zero.
  double uniform() {
    return (static_cast<double>(engine_() >> 11) + 0.5) * 0x1.0p-53;
  }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  bool bernoulli(double p) { return uniform() < p; }

  /// Standard normal by Box-Muller; always two uniforms per call (no cached second variate),
  /// which keeps the number of draws per call fixed and easy to reason about.
  double normal() {
    const double u1 = uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }
  double normal(double mean, double stddev) { return mean + stddev * normal(); }

  /// N standard normals drawn in index order. Not Vector(normal(), normal(), ...): the order in
  /// which a call's arguments are evaluated is unspecified (g++ goes right to left, clang left
  /// to right), so the same seed would give each compiler another run.
  template <int N>
  Eigen::Matrix<double, N, 1> normals() {
    Eigen::Matrix<double, N, 1> v;
    for (int i = 0; i < N; ++i) v(i) = normal();
    return v;
  }

 private:
  std::mt19937_64 engine_;
};

/// First-order Gauss-Markov process x' = -x/tau + w, discretised exactly:
/// x_{k+1} = phi x_k + sigma sqrt(1 - phi^2) n_k with phi = exp(-dt/tau). Started from its
/// stationary distribution, so its standard deviation is sigma at every step.
struct GaussMarkov {
  double sigma = 0.0;
  double tau_s = 1.0;

  double start(Rng& rng) const { return sigma * rng.normal(); }
  double step(double x, double dt, Rng& rng) const {
    const double phi = std::exp(-dt / tau_s);
    return phi * x + sigma * std::sqrt(1.0 - phi * phi) * rng.normal();
  }
};

}  // namespace ctxfuse::sim
