// RBF kernel values exp(-gamma |x - sv|^2) for a fixed-size block of support vectors.
//
// The exponential works on the squared distance d2 directly, with gamma folded into its constants
// (RbfExp, built once per prediction), and a table of the N powers 2^(j/N) (N = 8 or 16):
//   k = round(-gamma d2 N log2 e), u = d2 + k ln2/(N gamma) by Cody-Waite (ln2/(N gamma) split in
//   two so that k times the high part is exact), and
//   exp(-gamma d2) = T + T (u Q(u)),  T = 2^(k div N) 2^((k mod N)/N),
// where 1 + v q(v), v = -gamma u, interpolates exp at the Chebyshev points of [-ln2/(2N), ln2/(2N)]
// (2 % wider; q fitted to expm1(v)/v, 0.03 eps (N = 8) and 0.08 eps (N = 16) relative there) and
// Q(u) = q(-gamma u) (-gamma) has the coefficients c_i (-gamma)^(i+1). The table shortens the
// interval, so the polynomial needs degree 7 (N = 8) or 6 (N = 16) instead of 11 without one.
// Folding gamma saves the multiply -gamma * d2 per support vector (and its rounding). The last
// step is one multiply-add, so the rounded table value (<= 0.37 eps) and the final rounding are
// the only errors of size; u Q(u) is formed first because T u can be subnormal near the clamp,
// and its rounding, multiplied by Q ~ gamma, would cost many ulps.
// T is built with integer arithmetic: `shifted` (d2 k_scale + 1.5 2^52) holds k in its low bits;
// the table stores bits(2^(j/N)) - j 2^(52 - log2 N), so adding shifted << (52 - log2 N) puts
// k div N into the exponent field and takes the low bits of k back out; T stays normal for every
// clamped d2.
//
// Three implementations, one per instruction set, chosen at run time:
// - baseline (any CPU; also the scalar exp_neg_gamma that exp_nonpositive and the tests use):
//   N = 8, plain C++ over a fixed 256-element block;
// - AVX2+FMA (x86-64): N = 8, the same operations with every multiply-add fused; the table lookup
//   is two in-register dword permutes (vpermd of the low and of the high halves of the eight
//   entries) and a blend;
// - AVX-512 (x86-64): N = 16, the lookup is one two-register permute (vpermt2q).
// The vector variants process four (AVX2) or two (AVX-512) vectors in lockstep: each step is
// issued for all of them before the next, so the out-of-order core always has independent
// operations at hand (the chain of dependent operations per vector is about 60 cycles).
// Their accuracy is tested directly (SvmRbfKernel.EveryCompiledVariantMatchesLibmToAFewUlp).
// No -march flags are needed or imposed: the vector variants carry their own target attributes.
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#if (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__)
#include <immintrin.h>
#define CTXFUSE_SVM_RUNTIME_AVX2 1  // the AVX2 and AVX-512 variants exist, chosen at run time
#endif

namespace ctxfuse::classify::svm_detail {

inline constexpr int kRbfBlock = 256;

/// 2^(j/16) for j = 0..15, rounded to nearest (80-digit arithmetic); the 8-entry table takes the
/// even j. Largest rounding error 0.37 eps relative (j = 1).
inline constexpr std::array<double, 16> kExp2Sixteenths = {
    0x1.0000000000000p+0, 0x1.0b5586cf9890fp+0, 0x1.172b83c7d517bp+0, 0x1.2387a6e756238p+0,
    0x1.306fe0a31b715p+0, 0x1.3dea64c123422p+0, 0x1.4bfdad5362a27p+0, 0x1.5ab07dd485429p+0,
    0x1.6a09e667f3bcdp+0, 0x1.7a11473eb0187p+0, 0x1.8ace5422aa0dbp+0, 0x1.9c49182a3f090p+0,
    0x1.ae89f995ad3adp+0, 0x1.c199bdd85529cp+0, 0x1.d5818dcfba487p+0, 0x1.ea4afa2a490dap+0};

/// exp(-gamma d2) constants for one gamma and table size N (8 or 16).
template <int N>
struct RbfReduction {
  static_assert(N == 8 || N == 16);
  static constexpr int kLog2N = N == 8 ? 3 : 4;
  static constexpr int kTerms = N == 8 ? 7 : 6;  // coefficients of Q
  /// bits(2^(j/N)) - j 2^(52 - log2 N): adding shifted << (52 - log2 N) gives bits(2^(k/N)).
  static constexpr std::array<std::uint64_t, N> kTable = [] {
    std::array<std::uint64_t, N> t{};
    for (int j = 0; j < N; ++j)
      t[static_cast<std::size_t>(j)] = std::bit_cast<std::uint64_t>(kExp2Sixteenths[static_cast<std::size_t>(j * (16 / N))]) -
                                       (static_cast<std::uint64_t>(j) << (52 - kLog2N));
    return t;
  }();
  double k_scale = 0.0;  // -gamma N log2(e)
  double step_hi = 0.0;  // ln2 / (N gamma) = step_hi + step_lo; step_hi has 39 significant bits
  double step_lo = 0.0;
  std::array<double, kTerms> q{};  // c_i (-gamma)^(i+1)
};

/// Constants of exp(-gamma d2) for one gamma (rbf_exp_constants).
struct RbfExp {
  double d2_max = 0.0;  // 708 / gamma: larger squared distances are clamped here
  RbfReduction<8> r8;   // baseline and AVX2
  RbfReduction<16> r16;  // AVX-512
};

template <int N>
RbfReduction<N> rbf_reduction(double gamma) {
  // expm1(v)/v at the Chebyshev points of 1.02 [-ln2/(2N), ln2/(2N)] (80-digit arithmetic, then
  // rounded); the interpolation error of 1 + v q(v) against exp is 0.026 eps (N = 8) and 0.079 eps
  // (N = 16) relative.
  constexpr std::array<double, 7> c8 = {0x1.0000000000000p+0,  0x1.00000000000b6p-1,  0x1.55555555555a6p-3,
                                        0x1.55555549f61cap-5,  0x1.1111110c0332ep-7,  0x1.6c1c716b4cd42p-10,
                                        0x1.a01f0fd6a7da1p-13};
  constexpr std::array<double, 6> c16 = {0x1.0000000000003p+0, 0x1.0000000000001p-1, 0x1.555555546b66ep-3,
                                         0x1.55555554e05e3p-5, 0x1.1112490f573e0p-7, 0x1.6c17f96a3dbd8p-10};
  constexpr double kLn2Hi = 0x1.62e42fefa3800p-1;  // ln2 = kLn2Hi + kLn2Lo to ~1e-32
  constexpr double kLn2Lo = 0x1.ef35793c76730p-45;
  using R = RbfReduction<N>;
  R r;
  const double ln2_hi = kLn2Hi / N;  // exact: N is a power of two
  const double ln2_lo = kLn2Lo / N;
  r.k_scale = -gamma * N * 1.4426950408889634;
  // 39 significant bits: k * step_hi is exact for |k| < 2^14 (|k| <= 708 N / ln2 + 1/2 < 16,344),
  // and d2 + k * step_hi is exact (Sterbenz) since k is the nearest integer to d2 / step.
  r.step_hi = std::bit_cast<double>(std::bit_cast<std::uint64_t>(ln2_hi / gamma) & ~std::uint64_t{0x3fff});
  r.step_lo = (std::fma(-r.step_hi, gamma, ln2_hi) + ln2_lo) / gamma;
  double power = -gamma;
  for (std::size_t i = 0; i < r.q.size(); ++i, power *= -gamma) {
    if constexpr (N == 8) {
      r.q[i] = c8[i] * power;
    } else {
      r.q[i] = c16[i] * power;
    }
  }
  return r;
}

inline RbfExp rbf_exp_constants(double gamma) {
  RbfExp e;
  e.d2_max = 708.0 / gamma;
  e.r8 = rbf_reduction<8>(gamma);
  e.r16 = rbf_reduction<16>(gamma);
  return e;
}

inline constexpr double kRbfShifter = 0x1.8p52;  // adding it rounds to an integer kept in the low bits

/// exp(-gamma d2) for 0 <= d2 <= e.d2_max with an N-entry table (the formula every variant uses).
template <int N>
#if defined(__GNUC__) || defined(__clang__)
[[gnu::always_inline]]
#endif
inline double exp_neg_gamma_table(double d2, const RbfReduction<N>& r) {
  using R = RbfReduction<N>;
  const double shifted = d2 * r.k_scale + kRbfShifter;
  const double k = shifted - kRbfShifter;
  const double u = (d2 + k * r.step_hi) + k * r.step_lo;
  double q = r.q[R::kTerms - 1];
  for (int i = R::kTerms - 2; i >= 0; --i) q = q * u + r.q[static_cast<std::size_t>(i)];
  // The low bits of `shifted` hold k (two's complement).
  const auto bits = std::bit_cast<std::uint64_t>(shifted);
  const double t = std::bit_cast<double>(R::kTable[bits & (N - 1)] + (bits << (52 - R::kLog2N)));
  return t + t * (u * q);
}

/// exp(-gamma d2) for 0 <= d2 <= e.d2_max (the baseline variant's formula, N = 8).
#if defined(__GNUC__) || defined(__clang__)
[[gnu::always_inline]]
#endif
inline double exp_neg_gamma(double d2, const RbfExp& e) {
  return exp_neg_gamma_table<8>(d2, e.r8);
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
  for (int i = 0; i < kRbfBlock; ++i) {
    double d2 = 0.0;
    for (int f = 0; f < Dim; ++f) {
      const double d = columns[static_cast<std::size_t>(f)][i] - x[static_cast<std::size_t>(f)];
      d2 += d * d;
    }
    // Squared distances beyond 708/gamma are clamped there: exp(-708) ~ 3e-308 cannot change a
    // decision value, and it keeps the exponent bits valid.
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

#ifdef CTXFUSE_SVM_RUNTIME_AVX2

#if defined(__clang__)
#define CTXFUSE_SVM_UNROLL _Pragma("unroll")
#else
#define CTXFUSE_SVM_UNROLL _Pragma("GCC unroll 16")
#endif

// The vector variants: the same operations as exp_neg_gamma_table (each multiply-add fused, as
// the compiler contracts them in the scalar formula) on L vectors at a time, in lockstep. After
// each polynomial step an empty asm statement takes and returns the L partial results: it costs
// nothing, but keeps clang from regrouping the steps into one chain per vector (10 % slower).

/// The 8-entry table's low and high 32-bit halves, one register each for the AVX2 lookup (vpermd
/// selects by the index's low three bits).
inline constexpr std::array<std::uint32_t, 16> kRbfTableHalves = [] {
  std::array<std::uint32_t, 16> h{};
  for (std::size_t j = 0; j < 8; ++j) {
    h[j] = static_cast<std::uint32_t>(RbfReduction<8>::kTable[j]);
    h[j + 8] = static_cast<std::uint32_t>(RbfReduction<8>::kTable[j] >> 32);
  }
  return h;
}();

template <int Dim, bool Accumulate = false>
__attribute__((target("avx2,fma"))) void rbf_block_avx2(std::array<const double*, Dim> columns, std::array<double, Dim> x,
                                                        const RbfExp& e, double* __restrict out,
                                                        const double* __restrict coef = nullptr) {
  using R = RbfReduction<8>;
  constexpr int W = 4;
  constexpr int L = 4;  // measured best for AVX2 (16 registers)
  static_assert(kRbfBlock % (W * L) == 0);
  const __m256i table_low = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(kRbfTableHalves.data()));
  const __m256i table_high = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(kRbfTableHalves.data() + 8));
  __m256d xs[Dim];
  for (std::size_t f = 0; f < Dim; ++f) xs[f] = _mm256_set1_pd(x[f]);
  const R& r = e.r8;
  const __m256d d2_max = _mm256_set1_pd(e.d2_max);
  const __m256d k_scale = _mm256_set1_pd(r.k_scale);
  const __m256d shifter = _mm256_set1_pd(kRbfShifter);
  const __m256d step_hi = _mm256_set1_pd(r.step_hi);
  const __m256d step_lo = _mm256_set1_pd(r.step_lo);
  __m256d q[R::kTerms];
  for (std::size_t i = 0; i < r.q.size(); ++i) q[i] = _mm256_set1_pd(r.q[i]);
  for (int i = 0; i < kRbfBlock; i += W * L) {
    __m256d d2[L], s[L], u[L], t[L], p[L];
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) {
      const int at = i + W * v;
      __m256d d = _mm256_sub_pd(_mm256_loadu_pd(columns[0] + at), xs[0]);
      d2[v] = _mm256_mul_pd(d, d);
      for (std::size_t f = 1; f < Dim; ++f) {
        d = _mm256_sub_pd(_mm256_loadu_pd(columns[f] + at), xs[f]);
        d2[v] = _mm256_fmadd_pd(d, d, d2[v]);
      }
    }
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) d2[v] = _mm256_min_pd(d2[v], d2_max);
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) s[v] = _mm256_fmadd_pd(d2[v], k_scale, shifter);
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) {
      const __m256d k = _mm256_sub_pd(s[v], shifter);
      u[v] = _mm256_fmadd_pd(k, step_lo, _mm256_fmadd_pd(k, step_hi, d2[v]));
    }
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) {
      // k's low 32 bits in both halves of each lane, then the two halves of table[k mod 8].
      const __m256i bits = _mm256_castpd_si256(s[v]);
      const __m256i index = _mm256_shuffle_epi32(bits, 0xA0);
      const __m256i entry = _mm256_blend_epi32(_mm256_permutevar8x32_epi32(table_low, index),
                                               _mm256_permutevar8x32_epi32(table_high, index), 0xAA);
      t[v] = _mm256_castsi256_pd(_mm256_add_epi64(entry, _mm256_slli_epi64(bits, 52 - R::kLog2N)));
    }
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) p[v] = q[R::kTerms - 1];
    CTXFUSE_SVM_UNROLL for (int j = R::kTerms - 2; j >= 0; --j) {
      CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) p[v] = _mm256_fmadd_pd(p[v], u[v], q[static_cast<std::size_t>(j)]);
      __asm__("" : "+x"(p[0]), "+x"(p[1]), "+x"(p[2]), "+x"(p[3]));
    }
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) {
      const int at = i + W * v;
      const __m256d kernel = _mm256_fmadd_pd(t[v], _mm256_mul_pd(u[v], p[v]), t[v]);
      if constexpr (Accumulate) {
        _mm256_storeu_pd(out + at, _mm256_fmadd_pd(_mm256_loadu_pd(coef + at), kernel, _mm256_loadu_pd(out + at)));
      } else {
        _mm256_storeu_pd(out + at, kernel);
      }
    }
  }
}

inline bool cpu_has_avx2_fma() {
  static const bool available = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return available;
}

// 512-bit variant. Only this intrinsics loop is compiled for AVX-512 (no Eigen code), which keeps
// clear of the g++ 12 miscompilation of small fixed-size Eigen code under -march=native.
template <int Dim, bool Accumulate = false>
__attribute__((target("avx512f,fma"))) void rbf_block_avx512(std::array<const double*, Dim> columns,
                                                             std::array<double, Dim> x, const RbfExp& e,
                                                             double* __restrict out,
                                                             const double* __restrict coef = nullptr) {
  using R = RbfReduction<16>;
  constexpr int W = 8;
  constexpr int L = 2;  // measured 2 % faster than 4
  static_assert(kRbfBlock % (W * L) == 0);
  // vpermt2q selects from the two registers by the index's low four bits.
  const __m512i table_a = _mm512_loadu_si512(R::kTable.data());
  const __m512i table_b = _mm512_loadu_si512(R::kTable.data() + 8);
  __m512d xs[Dim];
  for (std::size_t f = 0; f < Dim; ++f) xs[f] = _mm512_set1_pd(x[f]);
  const R& r = e.r16;
  const __mmask8 all = 0xFF;
  const __m512d d2_max = _mm512_set1_pd(e.d2_max);
  const __m512d k_scale = _mm512_set1_pd(r.k_scale);
  const __m512d shifter = _mm512_set1_pd(kRbfShifter);
  const __m512d step_hi = _mm512_set1_pd(r.step_hi);
  const __m512d step_lo = _mm512_set1_pd(r.step_lo);
  __m512d q[R::kTerms];
  for (std::size_t i = 0; i < r.q.size(); ++i) q[i] = _mm512_set1_pd(r.q[i]);
  for (int i = 0; i < kRbfBlock; i += W * L) {
    __m512d d2[L], s[L], u[L], t[L], p[L];
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) {
      const int at = i + W * v;
      __m512d d = _mm512_sub_pd(_mm512_loadu_pd(columns[0] + at), xs[0]);
      d2[v] = _mm512_mul_pd(d, d);
      for (std::size_t f = 1; f < Dim; ++f) {
        d = _mm512_sub_pd(_mm512_loadu_pd(columns[f] + at), xs[f]);
        d2[v] = _mm512_fmadd_pd(d, d, d2[v]);
      }
    }
    // The full-mask forms of min and shift: g++ 12's unmasked ones start from an undefined
    // register and warn (-Wuninitialized); the code is the same.
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) d2[v] = _mm512_mask_min_pd(d2_max, all, d2[v], d2_max);
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) s[v] = _mm512_fmadd_pd(d2[v], k_scale, shifter);
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) {
      const __m512d k = _mm512_sub_pd(s[v], shifter);
      u[v] = _mm512_fmadd_pd(k, step_lo, _mm512_fmadd_pd(k, step_hi, d2[v]));
    }
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) {
      const __m512i bits = _mm512_castpd_si512(s[v]);
      const __m512i entry = _mm512_permutex2var_epi64(table_a, bits, table_b);
      t[v] = _mm512_castsi512_pd(_mm512_add_epi64(entry, _mm512_mask_slli_epi64(bits, all, bits, 52 - R::kLog2N)));
    }
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) p[v] = q[R::kTerms - 1];
    CTXFUSE_SVM_UNROLL for (int j = R::kTerms - 2; j >= 0; --j) {
      CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) p[v] = _mm512_fmadd_pd(p[v], u[v], q[static_cast<std::size_t>(j)]);
      __asm__("" : "+v"(p[0]), "+v"(p[1]));
    }
    CTXFUSE_SVM_UNROLL for (int v = 0; v < L; ++v) {
      const int at = i + W * v;
      const __m512d kernel = _mm512_fmadd_pd(t[v], _mm512_mul_pd(u[v], p[v]), t[v]);
      if constexpr (Accumulate) {
        _mm512_storeu_pd(out + at, _mm512_fmadd_pd(_mm512_loadu_pd(coef + at), kernel, _mm512_loadu_pd(out + at)));
      } else {
        _mm512_storeu_pd(out + at, kernel);
      }
    }
  }
}
#undef CTXFUSE_SVM_UNROLL

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
