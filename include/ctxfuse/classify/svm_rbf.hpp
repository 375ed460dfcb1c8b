// RBF kernel values exp(-gamma |x - sv|^2) for a fixed-size block of support vectors.
//
// The loop is plain arithmetic with no library call, so the compiler vectorises it: the
// exponential is evaluated by Cody-Waite range reduction and a degree-11 polynomial
// (approximation error below 2e-17 relative for |r| <= ln2/2, i.e. about libm's accuracy), and
// the power of two is built directly in the exponent bits. Every block has the same compile-time
// length so even -O2's cheapest vectoriser accepts it (no epilogue, no alias checks). On x86-64
// the block is also compiled for AVX2+FMA and chosen at run time when the CPU has them; the
// default build stays baseline x86-64 (no -march flags needed or imposed); an AVX-512 variant is
// picked first where the CPU has it.
#pragma once

#include <array>
#include <bit>
#include <cstdint>

namespace ctxfuse::classify::svm_detail {

inline constexpr int kRbfBlock = 256;

/// exp(t) for -708 <= t <= 0 (callers clamp; see rbf_block).
#if defined(__GNUC__) || defined(__clang__)
[[gnu::always_inline]]
#endif
inline double exp_nonpositive(double t) {
  constexpr double kLog2e = 1.4426950408889634;
  constexpr double kShifter = 0x1.8p52;  // adding it rounds to an integer kept in the low bits
  constexpr double kLn2Hi = 0x1.62e42fefa3800p-1;
  constexpr double kLn2Lo = 0x1.ef35793c76730p-45;
  const double shifted = t * kLog2e + kShifter;
  const double k = shifted - kShifter;
  const double r = (t - k * kLn2Hi) - k * kLn2Lo;
  // Degree-11 polynomial interpolating exp at the Chebyshev points of [-ln2/2, ln2/2] (computed
  // in 60-digit arithmetic, then rounded): relative error below 2e-17 before rounding, two
  // multiply-adds fewer than the Taylor series of the same accuracy.
  double p = 0x1.af631d0059becp-26;
  p = p * r + 0x1.28b4057f44145p-22;
  p = p * r + 0x1.71ddf5749d126p-19;
  p = p * r + 0x1.a01991ac8730ap-16;
  p = p * r + 0x1.a01a01b14378fp-13;
  p = p * r + 0x1.6c16c187fbe02p-10;
  p = p * r + 0x1.111111110f225p-7;
  p = p * r + 0x1.555555554f0cfp-5;
  p = p * r + 0x1.555555555555ap-3;
  p = p * r + 0x1.0000000000011p-1;
  p = p * r + 1.0;
  p = p * r + 1.0;
  // The low 12 bits of `shifted` hold k (two's complement); k + 1023 is the biased exponent.
  const std::uint64_t scale_bits = (std::bit_cast<std::uint64_t>(shifted) + 1023u) << 52;
  return p * std::bit_cast<double>(scale_bits);
}

/// Accumulate = false: out[i] = K_i. Accumulate = true: out[i] += coef[i] * K_i, which for a
/// single machine saves storing and re-reading the kernel values (the per-lane partial sums are
/// added up once at the end, so no floating-point reduction sits inside the loop).
template <int Dim, bool Accumulate>
#if defined(__GNUC__) || defined(__clang__)
[[gnu::always_inline]]
#endif
inline void rbf_block(std::array<const double*, Dim> columns, std::array<double, Dim> x, double neg_gamma,
                      double d2_max, const double* __restrict coef, double* __restrict out) {
  for (int i = 0; i < kRbfBlock; ++i) {
    double d2 = 0.0;
    for (int f = 0; f < Dim; ++f) {
      const double d = columns[static_cast<std::size_t>(f)][i] - x[static_cast<std::size_t>(f)];
      d2 += d * d;
    }
    // Squared distances beyond 708/gamma are clamped there: exp(-708) ~ 3e-308 cannot change a
    // decision value, and it keeps the exponent bits valid. The bound is a run-time value on
    // purpose: with a literal, g++ folds the clamped branch to a constant and stops vectorising.
    d2 = d2 < d2_max ? d2 : d2_max;
    if constexpr (Accumulate) {
      out[i] += coef[i] * exp_nonpositive(neg_gamma * d2);
    } else {
      out[i] = exp_nonpositive(neg_gamma * d2);
    }
  }
}

template <int Dim, bool Accumulate = false>
void rbf_block_baseline(std::array<const double*, Dim> columns, std::array<double, Dim> x, double neg_gamma,
                        double* __restrict out, const double* __restrict coef = nullptr) {
  rbf_block<Dim, Accumulate>(columns, x, neg_gamma, 708.0 / -neg_gamma, coef, out);
}

#if (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__) && !defined(__AVX2__)
#define CTXFUSE_SVM_RUNTIME_AVX2 1
template <int Dim, bool Accumulate = false>
__attribute__((target("avx2,fma"))) void rbf_block_avx2(std::array<const double*, Dim> columns, std::array<double, Dim> x,
                                                        double neg_gamma, double* __restrict out,
                                                        const double* __restrict coef = nullptr) {
  rbf_block<Dim, Accumulate>(columns, x, neg_gamma, 708.0 / -neg_gamma, coef, out);
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
                                                    double neg_gamma, double* __restrict out,
                                                    const double* __restrict coef = nullptr) {
  rbf_block<Dim, Accumulate>(columns, x, neg_gamma, 708.0 / -neg_gamma, coef, out);
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
inline void rbf_block_dispatch(std::array<const double*, Dim> columns, std::array<double, Dim> x, double neg_gamma,
                               double* __restrict out, const double* __restrict coef) {
#ifdef CTXFUSE_SVM_RUNTIME_AVX2
#ifndef CTXFUSE_SVM_NO_AVX512  // define to measure or use the AVX2 path on AVX-512 machines
  if (cpu_has_avx512f()) {
    rbf_block_avx512<Dim, Accumulate>(columns, x, neg_gamma, out, coef);
    return;
  }
#endif
  if (cpu_has_avx2_fma()) {
    rbf_block_avx2<Dim, Accumulate>(columns, x, neg_gamma, out, coef);
    return;
  }
#endif
  rbf_block_baseline<Dim, Accumulate>(columns, x, neg_gamma, out, coef);
}

}  // namespace ctxfuse::classify::svm_detail
