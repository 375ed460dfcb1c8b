// The target-side tier of the fast Gauss transform SVM evaluator (svm_fast_rbf.hpp): one Taylor
// expansion of the whole support-vector sum per grid cell of the query space, so that a query
// inside the grid costs one polynomial (T(p) terms per machine) whatever the number of support
// vectors or source boxes. Queries outside the grid use the source boxes of svm_fast_rbf.hpp.
//
// Expansion. Cells of side h cover the support vectors' bounding box (standardised units); cell
// t has centre c. With y = x - c (|y_f| <= r = h/2), d = s - c, t = 2 gamma y.d,
//   K(x, s) = exp(-gamma |y|^2) exp(-gamma |d|^2) e^t,
// and, truncating e^t at total degree < p (the same multi-index algebra as the source boxes),
//   f(x) ~ exp(-gamma |y|^2) sum_{|alpha| < p} D_alpha y^alpha,
//   D_alpha = sum_s coef(m, s) exp(-gamma |d|^2) (2 gamma)^|alpha| d^alpha / alpha!.
// Here y is small and d is not: the roles of svm_fast_rbf.hpp's y and sigma are swapped, and so
// are its bound's arguments.
//
// Bound, per cell and machine (every step of svm_fast_rbf.hpp's derivation with y and d swapped;
// r_b = r (1 + 1e-9) covers both the computed and the exact offset):
//   G_s = exp(-gamma sum_f max(|d_f| - r_b, 0)^2), a_s = 2 gamma r_b sum_f |d_f|,
//   m_s^2 = sum_f max(|d_f| - r_b, 0)^2 (so |x - s| >= m_s anywhere in the cell),
//   W_t = sum_s |coef| G_s, W2_t = sum_s |coef| max(gamma m_s^2, 1) G_s.
// (1) truncation: sum_s |coef| G_s a_s^p / p! (Lagrange remainder of e^t; |t| <= a_s and
//     exp(-gamma|y|^2 - gamma|d|^2 + max(t, 0)) <= G_s);
// (2) magnitudes: sum_alpha |D_alpha y^alpha| exp(-gamma |y|^2) <= W_t (as (4) of the source
//     boxes), so every rounding below is a count of u = 2^-53 times W_t:
//     the coefficients (per block of 64 support vectors: per-feature factors
//     exp(-gamma d_f^2) (2 gamma d_f)^j / j! formed in long double and rounded once, their
//     product with coef in double, a double sum over the block, the block sums added in long
//     double, the total rounded once: 2 Dim + 66 + (n / 64 + 2 Dim p + 8 + gamma rho^2_max
//     (Dim + 2)) u_ld / u), the nested Horner (2 (p - 1) + 2 Dim), the factor
//     prod_f exp(-gamma y_f^2) (9 Dim + 2 gamma Dim r^2 + 1), the exact path's blocked sums
//     (ceil(n / 256) + 257 + 8);
// (3) in W2_t units: the exact path's kernel argument (Dim + 2; max(gamma z^2, 1) e^{-gamma z^2}
//     decreases in z and z >= m_s) and the computed offset y^ = fl(x - c) (|y^ - y| <= u r per
//     feature, gradient 2 gamma z e^{-gamma z^2} <= 2 sqrt(gamma) max(gamma z^2, 1) e^{-gamma z^2}:
//     2 sqrt(gamma Dim) r);
// (4) underflow, absolute: W (Dim + 4 p) e^(gamma Dim) max(1, r)^(p - 1) 2^-1074 (W the
//     machine's sum of |coef|; a value below DBL_MIN is off by at most 2^-1075, the other factors
//     of its term are at most e^gamma per feature).
// B_t = ((1) + u (2) W_t + u (3) W2_t)(1 + 1e-6) + (4), rounded up, is stored per cell and
// machine; the caller adds the decision value's own rounding (4u (|S| + |rho|)) as for the
// source boxes. The bound's own sums (W_t, W2_t, (1)) run in double and long double: their
// relative rounding, far below 1e-9, is covered by a factor 1 + 1e-9.
//
// Choice of (h, p) (efficiency only: B_t is computed for the grid built): h = 2^e {1, 5/4, 3/2,
// 7/4} with h sqrt(2 gamma) in [1/8, 4]; for each h the smallest p whose truncation bound (1)
// at up to 64 cells holding support vectors (up to 512 support vectors sampled, weights scaled)
// is <= the target; then the least T(p) among grids within the cell and build budgets
// (svm_fast_rbf.hpp sets the build budget from the model's size).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include "ctxfuse/classify/svm_fast_rbf_kernel.hpp"
#include "ctxfuse/classify/svm_rbf.hpp"

namespace ctxfuse::classify::svm_detail {

/// What the target grid holds (cells = 0: none built).
struct FgtLocalPlan {
  double h = 0.0;
  int order = 0, terms = 0;
  long cells = 0;
};

/// Scalar nested Horner over features F..Dim-1 of total degree <= k (svm_fast_rbf_kernel.hpp's
/// horner() for one point; the same coefficient order, horner_order()).
template <int Dim, int F>
inline double local_horner(int k, const double*& c, const double (&y)[Dim]) {
  if constexpr (F == Dim - 1) {
    double out = *c++;
    for (int j = 0; j < k; ++j) out = out * y[F] + *c++;
    return out;
  } else {
    double out = local_horner<Dim, F + 1>(0, c, y);
    for (int e = k - 1; e >= 0; --e) {
      const double q = local_horner<Dim, F + 1>(k - e, c, y);
      out = out * y[F] + q;
    }
    return out;
  }
}

template <int Dim, int MaxM>
class FgtLocalGrid {
 public:
  struct Limits {
    double truncation_target = 1e-10;
    int max_order = 40, max_terms = 4096;
    long max_cells = 4096;
    double max_build_terms = 2.5e8;  // cells x support vectors x T(p) x machines
  };

  const FgtLocalPlan& plan() const { return plan_; }

  /// Builds the grid for the model's standardised support vectors sv (n x Dim) and coefficients
  /// (M x n), w_total[m] >= sum_s |coef(m, s)| (the caller's, rounded up); leaves it empty when
  /// no grid fits the limits.
  template <class Sv, class Coef>
  void build(const Sv& sv, const Coef& coef, const std::array<double, MaxM>& w_total, double gamma, const RbfExp& exp,
             const Limits& lim);

  /// Sums (without rho) and bounds of every machine for the standardised query xs; false (and
  /// nothing written) when xs is outside the grid. No allocation.
  template <class X>
  bool evaluate(const X& xs, double* sums, double* bounds) const {
    if (plan_.cells == 0) return false;
    long cell = 0;
    double y[Dim];
    double factor = 1.0;
    for (int f = 0; f < Dim; ++f) {  // cell index: the last feature varies fastest
      const auto fi = static_cast<std::size_t>(f);
      const double k = std::floor((xs[f] - lo_[fi]) / plan_.h);
      if (!(k >= 0.0 && k < static_cast<double>(count_[fi]))) return false;
      y[f] = xs[f] - centre(f, static_cast<long>(k));
      if (!(std::abs(y[f]) <= r_)) return false;
      factor *= exp_neg_gamma(y[f] * y[f], exp_);
      cell = cell * count_[fi] + static_cast<long>(k);
    }
    const auto cm = static_cast<std::size_t>(cell * machines_);
    const double* c = coef_.data() + cm * static_cast<std::size_t>(plan_.terms);
    for (int m = 0; m < machines_; ++m) {
      sums[m] = factor * local_horner<Dim, 0>(plan_.order - 1, c, y);
      bounds[m] = bound_[cm + static_cast<std::size_t>(m)];
    }
    return true;
  }

 private:
  static constexpr int kBlock = 64;  // support vectors per block of the build
  static constexpr long kMaxColumns = 256;

  /// Per block of support vectors, per feature f, grid column i and degree j < p:
  /// A(f, i, j)[b] = exp(-gamma d^2) (2 gamma d)^j / j!, d = s_f - c_f(i), rounded once from long
  /// double; and for the bound, |d|, max(|d| - r_b, 0)^2 and exp(-gamma max(|d| - r_b, 0)^2).
  struct BlockTables {
    int p = 0;
    std::array<long, Dim> offset{};  // first column of feature f in the per-column arrays
    std::vector<double> a, ad, m2, g;
    double* A(long col, int j) { return a.data() + static_cast<std::size_t>((col * p + j) * kBlock); }
  };

  /// acc[i] += sum_b v[b] prod_{f >= F} A(f, column_f, alpha_f)[b] for the multi-indices of
  /// total degree <= k over features F..Dim-1, in horner_order(); each block sum is a double
  /// dot product (its own rounding allowance), added to acc in long double.
  template <int F>
  static void accumulate(const double* v, int k, long double*& out, BlockTables& tab, const std::array<long, Dim>& col,
                         int nb) {
    for (int e = k; e >= 0; --e) {
      const double* a = tab.A(tab.offset[F] + col[F], e);
      if constexpr (F == Dim - 1) {
        double sum = 0.0;
        for (int b = 0; b < nb; ++b) sum += v[b] * a[b];
        *out++ += sum;
      } else {
        double w[kBlock];
        for (int b = 0; b < nb; ++b) w[b] = v[b] * a[b];
        accumulate<F + 1>(w, k - e, out, tab, col, nb);
      }
    }
  }

  double centre(int f, long k) const { return lo_[static_cast<std::size_t>(f)] + (static_cast<double>(k) + 0.5) * plan_.h; }

  /// The cells' layout for side h over [lo, hi] per feature; false beyond max_cells.
  bool lay_out(double h, const std::array<double, Dim>& lo, const std::array<double, Dim>& hi, long max_cells) {
    long cells = 1;
    for (int f = 0; f < Dim; ++f) {
      const auto fi = static_cast<std::size_t>(f);
      const double n = std::floor((hi[fi] - lo[fi]) / h) + 1.0;
      if (!(n <= kMaxColumns && n * static_cast<double>(cells) <= static_cast<double>(max_cells))) return false;
      count_[fi] = static_cast<long>(n);
      cells *= count_[fi];
      lo_[fi] = lo[fi];
    }
    plan_.h = h;
    plan_.cells = cells;
    return true;
  }

  FgtLocalPlan plan_;
  RbfExp exp_{};
  std::array<double, Dim> lo_{};
  std::array<long, Dim> count_{};
  double r_ = 0.0;
  int machines_ = 0;
  std::vector<double> coef_;   // [cell][machine][term], terms in horner_order()
  std::vector<double> bound_;  // [cell][machine]: B_t
};

template <int Dim, int MaxM>
template <class Sv, class Coef>
void FgtLocalGrid<Dim, MaxM>::build(const Sv& sv, const Coef& coef, const std::array<double, MaxM>& w_total, double gamma,
                                    const RbfExp& exp, const Limits& lim) {
  using LD = long double;
  const auto ix = [](long i) { return static_cast<std::size_t>(i); };
  plan_ = {};
  exp_ = exp;
  const long n = sv.rows();
  const int M = static_cast<int>(coef.rows());
  if (n == 0 || M > MaxM) return;
  machines_ = M;
  std::array<double, Dim> lo{}, hi{};
  for (int f = 0; f < Dim; ++f) {
    lo[ix(f)] = sv.col(f).minCoeff();
    hi[ix(f)] = sv.col(f).maxCoeff();
  }
  std::vector<double> weight(ix(n));
  for (long s = 0; s < n; ++s) weight[ix(s)] = coef.col(s).cwiseAbs().maxCoeff();
  // Sum over support vectors (every stride-th, up to 512, weights scaled) of |coef| G_s a_s^p / p!
  // at the centres of up to 64 of the cells that hold support vectors (queries come from the
  // data; evenly spaced in cell order), for p = 1..P: the largest (an estimate for the choice).
  std::vector<long> held;
  const int P = lim.max_order;
  std::vector<LD> total(ix(P + 1));
  const auto sampled_truncation = [&](double h, std::vector<LD>& worst) {
    const double rb = h / 2 * (1.0 + 1e-9);
    const long stride = std::max(1L, n / 512);
    std::fill(worst.begin(), worst.end(), 0.0L);
    held.clear();
    for (long s = 0; s < n; ++s) {
      long t = 0;
      for (int f = 0; f < Dim; ++f)
        t = t * count_[ix(f)] + std::min(static_cast<long>((sv(s, f) - lo[ix(f)]) / h), count_[ix(f)] - 1);
      held.push_back(t);
    }
    std::sort(held.begin(), held.end());
    held.erase(std::unique(held.begin(), held.end()), held.end());
    const auto step = std::max<std::size_t>(1, held.size() / 64);
    for (std::size_t k = 0; k < held.size(); k += step) {
      const long t = held[k];
      std::array<double, Dim> c{};
      for (long rest = t, f = Dim - 1; f >= 0; --f) {
        c[ix(f)] = centre(static_cast<int>(f), rest % count_[ix(f)]);
        rest /= count_[ix(f)];
      }
      std::fill(total.begin(), total.end(), 0.0L);
      for (long s = 0; s < n; s += stride) {
        double a = 0.0, g = 0.0;
        for (int f = 0; f < Dim; ++f) {
          const double d = std::abs(sv(s, f) - c[ix(f)]), m = std::max(d - rb, 0.0);
          a += 2 * gamma * rb * d;
          g += m * m;
        }
        LD term = static_cast<LD>(weight[ix(s)] * static_cast<double>(stride) * std::exp(-gamma * g));
        for (int p = 1; p <= P; ++p) total[ix(p)] += (term *= a / p);
      }
      for (int p = 1; p <= P; ++p) worst[ix(p)] = std::max(worst[ix(p)], total[ix(p)]);
    }
  };
  struct Choice { double h = 0.0; int p = 0, terms = 0; long cells = 0; } best;
  std::vector<LD> worst(ix(P + 1));
  const int e_lo = static_cast<int>(std::floor(std::log2(0.125 / std::sqrt(2 * gamma))));
  for (int e = e_lo; e <= e_lo + 6; ++e)
    for (const double mult : {1.0, 1.25, 1.5, 1.75}) {
      const double h = std::ldexp(mult, e), hs = h * std::sqrt(2 * gamma);
      if (hs < 0.125 || hs > 4.0 || !lay_out(h, lo, hi, lim.max_cells) ||
          double(plan_.cells) * double(n) * M > lim.max_build_terms)
        continue;
      sampled_truncation(h, worst);
      double terms = 1.0;
      for (int p = 1; p <= P; ++p) {
        terms = p == 1 ? 1.0 : terms * (p - 1 + Dim) / (p - 1);  // T(p) = binom(p - 1 + Dim, Dim)
        if (terms > lim.max_terms) break;
        if (worst[ix(p)] > lim.truncation_target) continue;
        const double build_terms = double(plan_.cells) * double(n) * terms * M;
        if (build_terms <= lim.max_build_terms && (best.p == 0 || terms < best.terms || (terms == best.terms && plan_.cells < best.cells)))
          best = {h, p, static_cast<int>(terms), plan_.cells};
        break;
      }
    }
  plan_ = {};
  if (best.p == 0) return;
  lay_out(best.h, lo, hi, lim.max_cells);
  const int p = best.p;
  plan_.order = p;
  plan_.terms = best.terms;
  const double h = best.h, rb = h / 2 * (1.0 + 1e-9);
  r_ = h / 2 * (1.0 + 1e-12);
  const int T = best.terms;
  const long cells = plan_.cells;
  const auto zero = [](double v) { return std::max(v, 0.0); };
  BlockTables tab;
  tab.p = p;
  long columns = 0;
  for (int f = 0; f < Dim; ++f) tab.offset[ix(f)] = columns, columns += count_[ix(f)];
  tab.a.assign(ix(columns * p * kBlock), 0.0);
  tab.ad.assign(ix(columns * kBlock), 0.0), tab.m2.assign(ix(columns * kBlock), 0.0), tab.g.assign(ix(columns * kBlock), 0.0);
  std::vector<LD> acc(ix(cells * M * T), 0.0L), w_t(ix(cells * M), 0.0L), w2_t(ix(cells * M), 0.0L), trunc(ix(cells * M), 0.0L);
  double inv_p_factorial = 1.0;
  for (int j = 2; j <= p; ++j) inv_p_factorial /= j;
  LD rho2_max = 0.0L;
  for (long s0 = 0; s0 < n; s0 += kBlock) {
    const int nb = static_cast<int>(std::min<long>(kBlock, n - s0));
    for (int f = 0; f < Dim; ++f)
      for (long i = 0; i < count_[ix(f)]; ++i) {
        const long col = tab.offset[ix(f)] + i;
        const double c = centre(f, i);
        for (int b = 0; b < nb; ++b) {
          const LD d = static_cast<LD>(sv(s0 + b, f)) - c, ad = std::abs(d);
          LD v = std::exp(-gamma * d * d);
          for (int j = 0; j < p; ++j, v = v * (2 * gamma * d) / j) tab.A(col, j)[b] = static_cast<double>(v);
          const double m = zero(static_cast<double>(ad) - rb);
          tab.ad[ix(col * kBlock + b)] = static_cast<double>(ad);
          tab.m2[ix(col * kBlock + b)] = m * m;
          tab.g[ix(col * kBlock + b)] = std::exp(-gamma * m * m);
          rho2_max = std::max(rho2_max, d * d * Dim);
        }
      }
    std::array<long, Dim> col{};
    for (long t = 0; t < cells; ++t) {
      for (long rest = t, f = Dim - 1; f >= 0; --f) {  // cell index: the last feature varies fastest
        col[ix(f)] = rest % count_[ix(f)];
        rest /= count_[ix(f)];
      }
      double g[kBlock], g2[kBlock], tr[kBlock];
      for (int b = 0; b < nb; ++b) {
        double gg = 1.0, m2 = 0.0, a = 0.0;
        for (int f = 0; f < Dim; ++f) {
          const auto k = ix((tab.offset[ix(f)] + col[ix(f)]) * kBlock + b);
          gg *= tab.g[k], m2 += tab.m2[k], a += tab.ad[k];
        }
        a *= 2 * gamma * rb;
        double ap = 1.0;
        for (int j = 0; j < p; ++j) ap *= a;
        g[b] = gg, g2[b] = std::max(gamma * m2, 1.0) * gg, tr[b] = ap * inv_p_factorial * gg;
      }
      for (int m = 0; m < M; ++m) {
        const auto tm = ix(t * M + m);
        double w[kBlock], sw = 0.0, sw2 = 0.0, st = 0.0;
        for (int b = 0; b < nb; ++b) {
          w[b] = coef(m, s0 + b);
          sw += std::abs(w[b]) * g[b], sw2 += std::abs(w[b]) * g2[b], st += std::abs(w[b]) * tr[b];
        }
        w_t[tm] += sw, w2_t[tm] += sw2, trunc[tm] += st;
        LD* out = acc.data() + tm * ix(T);
        accumulate<0>(w, p - 1, out, tab, col, nb);
      }
    }
  }
  // Rounding allowances (header comment), in units of u.
  const double u = kFgtUnit, u_ld = std::numeric_limits<LD>::epsilon() / 2;
  const double k_build = 2 * Dim + kBlock + 2 + (double(n) / kBlock + 2 * Dim * p + 8 + gamma * double(rho2_max) * (Dim + 2)) * u_ld / u;
  // Underflow: a table entry or a Horner step that lands below DBL_MIN is off by up to 2^-1075
  // absolutely; the other factors of its term are at most e^gamma each (sum_j |A(f, i, j)| <=
  // exp(-gamma d^2 + 2 gamma |d|)) and |y^alpha| <= max(1, r)^(p - 1), so per machine at most
  // W (Dim + 4 p) e^(gamma Dim) max(1, r)^(p - 1) 2^-1074 (W: the machine's sum of |coef|).
  const double underflow_scale = (Dim + 4.0 * p) * std::exp(std::min(gamma * Dim, 700.0)) *
                                 std::pow(std::max(1.0, r_), p - 1) * 0x1p-1074;
  const double k_w = k_build + 2 * (p - 1) + 2 * Dim + 9 * Dim + 2 * gamma * Dim * r_ * r_ + 1 +
                     std::ceil(double(n) / kRbfBlock) + kRbfBlock + 1 + 8;
  const double k_w2 = Dim + 2 + 2 * std::sqrt(gamma * Dim) * r_;
  coef_.resize(acc.size());
  for (std::size_t i = 0; i < acc.size(); ++i) coef_[i] = static_cast<double>(acc[i]);
  bound_.resize(w_t.size());
  // The bound's own sums ran in double: a few hundred roundings of relative size u at most,
  // covered by the factor 1 + 1e-9.
  for (std::size_t i = 0; i < w_t.size(); ++i)
    bound_[i] = static_cast<double>((trunc[i] + u * (k_w * w_t[i] + k_w2 * w2_t[i])) * (1.0L + 1e-6L)) * (1.0 + 1e-9) +
                w_total[i % ix(M)] * underflow_scale;
}

}  // namespace ctxfuse::classify::svm_detail
