// RBF kernel values exp(-gamma |x - sv|^2) for a fixed-size block of support vectors.
//
// The loop is plain arithmetic with no library call, so the compiler vectorises it. The
// exponential works on the squared distance d2 directly, with gamma folded into its constants
// (RbfExp, built once per prediction): k = round(-gamma d2 log2 e), then u = d2 + k ln2/gamma by
// Cody-Waite (ln2/gamma split in two so that k times the high part is exact), and
// exp(-gamma d2) = 2^k P(u) with P(u) = p(-gamma u), p the degree-11 polynomial interpolating exp
// at the Chebyshev points of [-ln2/2, ln2/2] (below 2e-17 relative there). Folding gamma saves
// the multiply -gamma * d2 per support vector (and its rounding). P is evaluated as six linear
// pairs a_2j + a_2j+1 u combined by Horner in u^2: one multiply more than plain Horner but half
// its chain of dependent multiply-adds, and measured faster on every compiled variant.
// 2^k is added into P's exponent bits as an integer (P lies in [0.7, 1.42], so the result stays
// normal for k >= -1021), a multiply fewer. Every block has the same compile-time length so even
// -O2's cheapest vectoriser accepts it (no epilogue, no alias checks). On x86-64 the block is also
// compiled for AVX2+FMA and chosen at run time when the CPU has them; the default build stays
// baseline x86-64 (no -march flags needed or imposed); an AVX-512 variant is picked first where
// the CPU has it.
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

namespace ctxfuse::classify::svm_detail {

inline constexpr int kRbfBlock = 256;

/// Constants of exp(-gamma d2) for one gamma (rbf_exp_constants).
struct RbfExp {
  double d2_max = 0.0;   // 708 / gamma: larger squared distances are clamped here
  double k_scale = 0.0;  // -gamma log2(e)
  double step_hi = 0.0;  // ln2 / gamma = step_hi + step_lo; step_hi has 40 significant bits
  double step_lo = 0.0;
  std::array<double, 12> poly{};  // a_i = c_i (-gamma)^i
};

inline RbfExp rbf_exp_constants(double gamma) {
  // exp at the Chebyshev points of [-ln2/2, ln2/2], degree 11 (60-digit arithmetic, then rounded).
  constexpr std::array<double, 12> c = {1.0,
                                        1.0,
                                        0x1.0000000000011p-1,
                                        0x1.555555555555ap-3,
                                        0x1.555555554f0cfp-5,
                                        0x1.111111110f225p-7,
                                        0x1.6c16c187fbe02p-10,
                                        0x1.a01a01b14378fp-13,
                                        0x1.a01991ac8730ap-16,
                                        0x1.71ddf5749d126p-19,
                                        0x1.28b4057f44145p-22,
                                        0x1.af631d0059becp-26};
  constexpr double kLn2Hi = 0x1.62e42fefa3800p-1;  // ln2 = kLn2Hi + kLn2Lo to ~1e-32
  constexpr double kLn2Lo = 0x1.ef35793c76730p-45;
  RbfExp e;
  e.d2_max = 708.0 / gamma;
  e.k_scale = -gamma * 1.4426950408889634;
  // 40 significant bits: k * step_hi is exact for |k| < 2^13, and d2 + k * step_hi is exact
  // (Sterbenz) since k is the nearest integer to d2 / step.
  e.step_hi = std::bit_cast<double>(std::bit_cast<std::uint64_t>(kLn2Hi / gamma) & ~std::uint64_t{0x1fff});
  e.step_lo = (std::fma(-e.step_hi, gamma, kLn2Hi) + kLn2Lo) / gamma;
  double power = 1.0;
  for (std::size_t i = 0; i < c.size(); ++i, power *= -gamma) e.poly[i] = c[i] * power;
  return e;
}

/// exp(-gamma d2) for 0 <= d2 <= e.d2_max.
#if defined(__GNUC__) || defined(__clang__)
[[gnu::always_inline]]
#endif
inline double exp_neg_gamma(double d2, const RbfExp& e) {
  constexpr double kShifter = 0x1.8p52;  // adding it rounds to an integer kept in the low bits
  const double shifted = d2 * e.k_scale + kShifter;
  const double k = shifted - kShifter;
  const double u = (d2 + k * e.step_hi) + k * e.step_lo;
  const double u2 = u * u;
  const auto& a = e.poly;
  double p = a[10] + a[11] * u;
  p = p * u2 + (a[8] + a[9] * u);
  p = p * u2 + (a[6] + a[7] * u);
  p = p * u2 + (a[4] + a[5] * u);
  p = p * u2 + (a[2] + a[3] * u);
  p = p * u2 + (a[0] + a[1] * u);
  // The low 12 bits of `shifted` hold k (two's complement); shifted left by 52 they add k to
  // P's biased exponent.
  return std::bit_cast<double>(std::bit_cast<std::uint64_t>(p) + (std::bit_cast<std::uint64_t>(shifted) << 52));
}

/// exp(t) for -708 <= t <= 0: the kernel's exponential with gamma = 1.
inline double exp_nonpositive(double t) {
  static const RbfExp unit = rbf_exp_constants(1.0);
  return exp_neg_gamma(-t, unit);
}

/// Accumulate = false: out[i] = K_i. Accumulate = true: out[i] += coef[i] * K_i, which for a
/// single machine saves storing and re-reading the kernel values (the per-lane partial sums are
/// added up once at the end, so no floating-point reduction sits inside the loop).
template <int Dim, bool Accumulate>
#if defined(__GNUC__) || defined(__clang__)
[[gnu::always_inline]]
#endif
inline void rbf_block(std::array<const double*, Dim> columns, std::array<double, Dim> x, const RbfExp& constants,
                      const double* __restrict coef, double* __restrict out) {
  const RbfExp e = constants;  // a local copy: the stores to out cannot alias it
  // Two vectors per iteration put two independent dependency chains side by side, which the
  // out-of-order core overlaps better than consecutive iterations.
#if defined(__clang__)
#pragma clang loop interleave_count(2)
#elif defined(__GNUC__)
#pragma GCC unroll 2
#endif
  for (int i = 0; i < kRbfBlock; ++i) {
    double d2 = 0.0;
    for (int f = 0; f < Dim; ++f) {
      const double d = columns[static_cast<std::size_t>(f)][i] - x[static_cast<std::size_t>(f)];
      d2 += d * d;
    }
    // Squared distances beyond 708/gamma are clamped there: exp(-708) ~ 3e-308 cannot change a
    // decision value, and it keeps the exponent bits valid. The bound is a run-time value on
    // purpose: with a literal, g++ folds the clamped branch to a constant and stops vectorising.
    d2 = d2 < e.d2_max ? d2 : e.d2_max;
    if constexpr (Accumulate) {
      out[i] += coef[i] * exp_neg_gamma(d2, e);
    } else {
      out[i] = exp_neg_gamma(d2, e);
    }
  }
}

template <int Dim, bool Accumulate = false>
void rbf_block_baseline(std::array<const double*, Dim> columns, std::array<double, Dim> x, const RbfExp& e,
                        double* __restrict out, const double* __restrict coef = nullptr) {
  rbf_block<Dim, Accumulate>(columns, x, e, coef, out);
}

#if (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__) && !defined(__AVX2__)
#define CTXFUSE_SVM_RUNTIME_AVX2 1
template <int Dim, bool Accumulate = false>
__attribute__((target("avx2,fma"))) void rbf_block_avx2(std::array<const double*, Dim> columns, std::array<double, Dim> x,
                                                        const RbfExp& e, double* __restrict out,
                                                        const double* __restrict coef = nullptr) {
  rbf_block<Dim, Accumulate>(columns, x, e, coef, out);
}

inline bool cpu_has_avx2_fma() {
  static const bool available = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return available;
}

// 512-bit variant. Only this plain loop is compiled for AVX-512 (no Eigen code), which keeps clear
// of the g++ 12 miscompilation of small fixed-size Eigen code under -march=native.
#if defined(__clang__)
#define CTXFUSE_SVM_AVX512_ATTRIBUTES __attribute__((target("avx512f,fma"), min_vector_width(512)))
#else
#define CTXFUSE_SVM_AVX512_ATTRIBUTES __attribute__((target("avx512f,fma,prefer-vector-width=512")))
#endif
template <int Dim, bool Accumulate = false>
CTXFUSE_SVM_AVX512_ATTRIBUTES void rbf_block_avx512(std::array<const double*, Dim> columns, std::array<double, Dim> x,
                                                    const RbfExp& e, double* __restrict out,
                                                    const double* __restrict coef = nullptr) {
  rbf_block<Dim, Accumulate>(columns, x, e, coef, out);
}
#undef CTXFUSE_SVM_AVX512_ATTRIBUTES

inline bool cpu_has_avx512f() {
  static const bool available = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("fma");
  return available;
}
#endif

/// One full block (kernel values, or their coefficient-weighted accumulation) on the widest
/// instruction set available.
template <int Dim, bool Accumulate>
inline void rbf_block_dispatch(std::array<const double*, Dim> columns, std::array<double, Dim> x, const RbfExp& e,
                               double* __restrict out, const double* __restrict coef) {
#ifdef CTXFUSE_SVM_RUNTIME_AVX2
#ifndef CTXFUSE_SVM_NO_AVX512  // define to measure or use the AVX2 path on AVX-512 machines
  if (cpu_has_avx512f()) {
    rbf_block_avx512<Dim, Accumulate>(columns, x, e, out, coef);
    return;
  }
#endif
  if (cpu_has_avx2_fma()) {
    rbf_block_avx2<Dim, Accumulate>(columns, x, e, out, coef);
    return;
  }
#endif
  rbf_block_baseline<Dim, Accumulate>(columns, x, e, out, coef);
}

}  // namespace ctxfuse::classify::svm_detail
