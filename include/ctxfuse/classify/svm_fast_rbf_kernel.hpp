// The evaluation kernels of the fast Gauss transform SVM evaluator (svm_fast_rbf.hpp, whose
// header comment derives the expansion and the error bound they compute): the per-query
// column values, the box coefficients' layout, the vectorised Horner evaluation of every box
// with its bound, the run-time choice of instruction set (none of these allocates), and the
// multi-index order in which the build stores the coefficients. No Eigen.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "ctxfuse/classify/svm_rbf.hpp"

#if defined(__GNUC__) || defined(__clang__)
#define CTXFUSE_FGT_INLINE [[gnu::always_inline]] inline
#else
#define CTXFUSE_FGT_INLINE inline
#endif

namespace ctxfuse::classify {

namespace svm_detail {

inline constexpr int kFgtLanes = 8;       // boxes per SIMD chunk
inline constexpr int kFgtMaxColumns = 64;  // grid columns per feature (else: exact path only)
inline constexpr double kFgtUnit = 0x1p-53;

template <int Dim>
struct FgtColumns {  // per query and grid column: y_f, exp(-gamma y_f^2), G factor, |y_f|, y_f^2
  std::array<std::array<double, kFgtMaxColumns>, Dim> y, e, g, a, q;
};

struct FgtLayout {
  const double* coef;           // [chunk][machine][term][lane], terms in horner() order
  const double* weight;         // [chunk][machine][lane]: W_b
  const std::int32_t* column;   // [chunk][feature][lane]
  int chunks, machines, terms, order;
  double gamma, trunc_scale, inv_factorial, k_fixed, k_radius;  // k_radius: gamma Dim h^2 / 4
};

/// kFgtLanes boxes' worth of doubles (a GNU vector: one AVX-512 register, two AVX2 ones, four
/// SSE2 ones). Only ever passed by reference (no vector ABI at function boundaries). a * b + c
/// is contracted to a fused multiply-add where the target has one (g++ and clang defaults); the
/// rounding allowances count two roundings per step either way.
typedef double FgtVec __attribute__((vector_size(kFgtLanes * sizeof(double))));

CTXFUSE_FGT_INLINE void fgt_load(FgtVec& v, const double* p) { std::memcpy(&v, p, sizeof v); }

/// G one-variable Horner chains of degrees d, ..., d + G - 1 in y (coefficients consecutive
/// from c, highest degree first, c advanced past them), each then folded into out = out x + q.
template <int G>
CTXFUSE_FGT_INLINE void horner_chains(int d, const double*& c, const FgtVec& y, const FgtVec& x, FgtVec& out) {
  constexpr int L = kFgtLanes;
  const double* ci[G];
  FgtVec q[G];
  ci[0] = c;
  for (int i = 1; i < G; ++i) ci[i] = ci[i - 1] + (d + i) * L;  // chain i - 1 has d + i coefficients
  for (int i = 0; i < G; ++i) fgt_load(q[i], ci[i]);
  for (int t = 1; t < G; ++t)  // chain i first takes i steps alone (indices 1..i)
    for (int i = t; i < G; ++i) {
      FgtVec v;
      fgt_load(v, ci[i] + t * L);
      q[i] = q[i] * y + v;
    }
  for (int j = 1; j <= d; ++j)  // then d steps together (chain i: indices i + 1..i + d)
    for (int i = 0; i < G; ++i) {
      FgtVec v;
      fgt_load(v, ci[i] + (i + j) * L);
      q[i] = q[i] * y + v;
    }
  for (int i = 0; i < G; ++i) out = out * x + q[i];
  c = ci[G - 1] + (d + G) * L;
}

/// Nested Horner over features F..Dim-1, total degree <= k, for kFgtLanes boxes at once.
template <int Dim, int F>
CTXFUSE_FGT_INLINE void horner(int k, const double*& c, const FgtVec (&y)[Dim], FgtVec& out) {
  constexpr int L = kFgtLanes;
  if constexpr (F == Dim - 1) {
    fgt_load(out, c);
    c += L;
    for (int j = 0; j < k; ++j, c += L) {
      FgtVec v;
      fgt_load(v, c);
      out = out * y[F] + v;
    }
  } else if constexpr (F + 1 == Dim - 1) {
    // As the general case below, but the innermost polynomials of degrees d, ..., d + G - 1
    // (stored one after the other) run as G interleaved chains: the same operations per chain,
    // so the same roundings, with G times the independent work in flight.
    fgt_load(out, c);
    c += L;
    int d = 1;
    for (; d + 3 <= k; d += 4) horner_chains<4>(d, c, y[Dim - 1], y[F], out);
    for (; d + 1 <= k; d += 2) horner_chains<2>(d, c, y[Dim - 1], y[F], out);
    if (d == k) horner_chains<1>(d, c, y[Dim - 1], y[F], out);
  } else {
    horner<Dim, F + 1>(0, c, y, out);
    for (int e = k - 1; e >= 0; --e) {
      FgtVec q;
      horner<Dim, F + 1>(k - e, c, y, q);
      out = out * y[F] + q;
    }
  }
}

/// The multi-indices in the order horner() reads their coefficients.
template <int Dim>
void horner_order(int f, int k, std::array<int, Dim>& a, std::vector<std::array<int, Dim>>& out) {
  for (int e = k; e >= 0; --e) {
    a[static_cast<std::size_t>(f)] = e;
    if (f == Dim - 1) out.push_back(a);
    else horner_order<Dim>(f + 1, k - e, a, out);
  }
  a[static_cast<std::size_t>(f)] = 0;
}

/// Sums (without rho) and error bounds E_m of every machine; no allocation.
template <int Dim, int MaxM>
CTXFUSE_FGT_INLINE void fgt_sums(const FgtLayout& lay, const FgtColumns<Dim>& col, double* sums, double* bounds) {
  constexpr int L = kFgtLanes;
  FgtVec acc[MaxM], err[MaxM];
  const int M = lay.machines;
  for (int m = 0; m < M; ++m) acc[m] = FgtVec{} , err[m] = FgtVec{};
  for (int c = 0; c < lay.chunks; ++c) {
    double yl[Dim][L], fac[L], base[L], s[L], dd[L], gg[L];
    const std::int32_t* ix = lay.column + c * Dim * L;
    for (int l = 0; l < L; ++l) fac[l] = gg[l] = 1.0, s[l] = dd[l] = 0.0;
    for (int f = 0; f < Dim; ++f)
      for (int l = 0; l < L; ++l) {
        const auto k = static_cast<std::size_t>(ix[f * L + l]);
        const auto fi = static_cast<std::size_t>(f);
        yl[f][l] = col.y[fi][k];
        fac[l] *= col.e[fi][k];
        gg[l] *= col.g[fi][k];
        s[l] += col.a[fi][k];
        dd[l] += col.q[fi][k];
      }
    double trunc[L], sq[L];
    for (int l = 0; l < L; ++l) trunc[l] = 1.0, sq[l] = s[l] * lay.trunc_scale * (1.0 + 4 * kFgtUnit);
    for (int e = lay.order; e > 0; e >>= 1) {
      if (e & 1)
        for (int l = 0; l < L; ++l) trunc[l] *= sq[l];
      for (int l = 0; l < L; ++l) sq[l] *= sq[l];
    }
    for (int l = 0; l < L; ++l) {
      // gg == 0: below the W 1e-307 allowance; gd capped so that the product stays finite.
      const double gd = std::min(lay.gamma * dd[l], 1e300);
      const double cut = fac[l] == 0.0 ? 1.0 : trunc[l] * lay.inv_factorial;
      const double rounding = lay.k_fixed + lay.k_radius + 4 * gd + 2 * (Dim + 2) * (gd + lay.k_radius);
      base[l] = gg[l] == 0.0 ? 0.0 : gg[l] * (cut + kFgtUnit * rounding);
    }
    FgtVec y[Dim], facv, basev;
    for (int f = 0; f < Dim; ++f) fgt_load(y[f], yl[f]);
    fgt_load(facv, fac);
    fgt_load(basev, base);
    const double* cf = lay.coef + static_cast<std::size_t>(c) * M * lay.terms * L;
    const double* w = lay.weight + static_cast<std::size_t>(c) * M * L;
    for (int m = 0; m < M; ++m, w += L) {
      FgtVec p, wv;
      horner<Dim, 0>(lay.order - 1, cf, y, p);
      fgt_load(wv, w);
      acc[m] += facv * p;
      err[m] += wv * basev;
    }
  }
  for (int m = 0; m < M; ++m) {
    double total = 0.0, bound = 0.0;
    for (int l = 0; l < L; ++l) total += acc[m][l], bound += err[m][l];
    sums[m] = total;
    bounds[m] = bound;
  }
}

// The same code compiled for AVX2+FMA and AVX-512 (no Eigen inside), chosen at run time.
#ifdef CTXFUSE_SVM_RUNTIME_AVX2
template <int Dim, int MaxM>
__attribute__((target("avx2,fma"))) void fgt_sums_avx2(const FgtLayout& l, const FgtColumns<Dim>& c, double* s, double* b) {
  fgt_sums<Dim, MaxM>(l, c, s, b);
}
template <int Dim, int MaxM>
__attribute__((target("avx512f,fma"))) void fgt_sums_avx512(const FgtLayout& l, const FgtColumns<Dim>& c, double* s,
                                                            double* b) {
  fgt_sums<Dim, MaxM>(l, c, s, b);
}
#endif

/// isa: -1 the widest available; 0 baseline, 1 AVX2, 2 AVX-512 when available (tests).
template <int Dim, int MaxM>
void fgt_sums_dispatch(int isa, const FgtLayout& l, const FgtColumns<Dim>& c, double* s, double* b) {
#ifdef CTXFUSE_SVM_RUNTIME_AVX2
#ifndef CTXFUSE_SVM_NO_AVX512
  if ((isa < 0 || isa == 2) && cpu_has_avx512f()) return fgt_sums_avx512<Dim, MaxM>(l, c, s, b);
#endif
  if ((isa < 0 || isa >= 1) && cpu_has_avx2_fma()) return fgt_sums_avx2<Dim, MaxM>(l, c, s, b);
#endif
  fgt_sums<Dim, MaxM>(l, c, s, b);
}

}  // namespace svm_detail

}  // namespace ctxfuse::classify
