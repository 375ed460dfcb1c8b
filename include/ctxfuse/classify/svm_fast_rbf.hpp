// RBF SVM prediction whose per-sample cost does not grow with the number of support vectors: a
// fast Gauss transform with a rigorous per-query error bound, and the exact path (svm.hpp)
// whenever the bound cannot guarantee the exact path's answer. Two tiers: inside the support
// vectors' bounding box, the target grid of svm_fast_rbf_local.hpp (one Taylor expansion of the
// whole sum per grid cell: one polynomial per query); elsewhere, or when the build budget allows
// no target grid, the source boxes derived below.
//
// Expansion. The standardised support vectors are binned on a grid of boxes of side h, centre
// c = k h (k integer, nearest). With y = x - c, sigma = s - c, rho = |sigma|, t = 2 gamma y.sigma,
//   K(x, s) = exp(-gamma |y|^2) exp(-gamma rho^2) e^t,  e^t = sum_k t^k / k!,
// and t^k / k! = (2 gamma)^k sum_{|alpha| = k} y^alpha sigma^alpha / alpha!. Truncating at |alpha| < p,
// box b contributes exp(-gamma |y|^2) sum_alpha C_alpha y^alpha to machine m, with
//   C_alpha = sum_{s in b} coef(m, s) exp(-gamma rho^2) sigma^alpha (2 gamma)^|alpha| / alpha!.
// Every box is evaluated (SIMD over boxes); a box whose y has a component with gamma y_f^2 >
// 600 / Dim is cut off (contributes 0). Cost per query: boxes x T(p) x machines multiply-adds,
// T(p) = binom(p - 1 + Dim, Dim), whatever the number of support vectors.
//
// Bound, per machine. |sigma_f| <= h/2 (nearest centre); W_b = sum_{s in b} |coef(m, s)|;
//   G_b = prod_f exp(-gamma max(|y_f| - h/2, 0)^2),  a_b = gamma h sum_f |y_f|.
// (1) Per support vector: -gamma|y|^2 - gamma rho^2 + max(t, 0) <= -gamma |y - sigma|^2 if t >= 0,
//     <= -gamma |y|^2 otherwise; both <= -gamma sum_f max(|y_f| - h/2, 0)^2, so the factor is <= G_b.
// (2) Truncation: |e^t - sum_{k<p} t^k/k!| <= |t|^p / p! e^{max(t,0)} (Lagrange remainder), and
//     |t| <= 2 gamma sum_f |y_f| |sigma_f| <= a_b: error <= W_b G_b a_b^p / p!.
// (3) Cut-off: a skipped box contributes at most W_b G_b by (1).
// (4) Magnitudes for rounding: sum_alpha |C_alpha y^alpha| exp(-gamma|y|^2) <= sum_s |coef|
//     exp(-gamma|y|^2 - gamma rho^2 + 2 gamma sum_f |y_f sigma_f|) <= W_b G_b (same steps as (1)).
// Rounding (u = 2^-53; "n roundings" contribute n u times the magnitudes of (4); kernel
// exponential exp_neg_gamma relative error <= 8u, as tested in svm_predict_test.cpp):
//   - coefficients, built in long double: 10 + gamma Dim^2 h^2/4 + (n_b + 3p + Dim + 4) u_ld / u;
//   - sigma = s - c is exact (h a power of two; checked at build by TwoSum);
//   - y = fl(x - c): |g_b(y^) - g_b(y)| <= W_b G_b gamma u (3|y|^2 + Dim h^2/4) (mean value of
//     e^-a - e^-b <= |a - b| e^-min(a,b), |a - b| <= gamma |y^ - y| (2|y| + 2 rho));
//   - nested Horner 2(p-1) + Dim, box factor prod_f exp(-gamma y_f^2): 9 Dim - 1 + gamma|y|^2,
//     product 1, sum over boxes chunks + 8 (lanes);
//   - the exact path (rbf_sums): kernel 8 + (Dim + 2) max(gamma |x - s|^2, 1) (argument
//     rounding; gamma z^2 e^{-gamma z^2} <= max(gamma m^2, 1) e^{-gamma m^2} for z >= m), plus
//     at most ceil(n / 256) + 257 roundings per term in its blocked sums (any order);
//   - decision value fl(S - rho) in both: + 4u (|S| + |rho|); exact path's clamp: + W 1e-307.
// E(x) sums these over boxes and multiplies by 1 + 1e-6 (second-order terms, rounding of E).
//
// Choice of h and p for the source boxes (efficiency only: E(x) is computed per query whatever
// the choice). h =
// 2^e {1, 5/4, 3/2, 7/4} with h sqrt(2 gamma) in [1/4, 4]; for each h the smallest p whose
// truncation bound (2), summed over boxes (cut-off ones by (3)), is <= truncation_target (1e-10)
// at 128 sample queries (support vectors: queries come from the data); then the (h, p) of least
// cost boxes x (T machines + 24). The paper-sized 2-D model (bench_classify_svm: gamma 0.5,
// 19,080 SVs) gets h = 1.75, p = 31: 16 boxes of T = 496 terms.
//
// Evaluation: kFgtLanes boxes per GNU vector (one AVX-512 register); the innermost Horner
// polynomials run as up to four interleaved chains (the same operations per chain). On the
// paper-sized model the 16 x 496 coefficients (63 KB) are streamed from L2 per query, which
// bounds the speed; the target grid reads one cell's 465 instead (bench_classify_svm).
//
// Use of the fast value: it is accepted only if every E_m <= value_tolerance (1e-9), the label is
// certain (|f_m| > E_m for votes; gaps > E_i + E_j for one-vs-rest), and with probabilities:
// two classes, the Platt error |A| E / 4 + 32u (sigmoid slope <= 1/4, clipping 1-Lipschitz,
// sigmoid rounding) <= probability_tolerance (1e-9) and |p0 - 1/2| beyond it; one-vs-rest with
// more classes, the same per-sigmoid bounds carried through p_m = s_m / sum s (each error <=
// the tolerance, and the largest probability ahead of every other by the sum of their errors).
// One-vs-one probabilities with more classes always run the exact path: the pairwise coupling
// iterates to a stopping test, and a tiny change of its inputs can change its iteration count
// and so its output by much more than the change (no bound is claimed). Otherwise that query
// runs svm_decision / svm_predict: decisions equal the exact path's by construction.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_fast_rbf_kernel.hpp"
#include "ctxfuse/classify/svm_fast_rbf_local.hpp"
#include "ctxfuse/classify/svm_rbf.hpp"


namespace ctxfuse::classify {

struct SvmFastRbfOptions {
  enum class Mode : std::uint8_t { automatic, fast, exact } mode = Mode::automatic;
  double value_tolerance = 1e-9;        // accept f_fast only when E(x) <= this
  double probability_tolerance = 1e-9;  // and the Platt bound <= this
  double truncation_target = 1e-10;     // worst-case truncation bound used to choose (h, p)
  int max_order = 40;
  int max_terms = 4096;  // T(p) per box and machine
  int instruction_set = -1;  // -1: the widest available; 0 baseline, 1 AVX2, 2 AVX-512 if available (tests)
  bool target_grid = true;   // the per-cell expansions of svm_fast_rbf_local.hpp for queries inside the data
  double max_build_terms = 2.5e8;  // the target grid's build budget (cells x SVs x terms x machines)
};

/// What the build chose. eligible: the fast structure exists; fast: predictions use it.
struct SvmFastRbfPlan {
  bool eligible = false, fast = false;
  double h = 0.0, worst_truncation = 0.0;
  int order = 0, terms = 0, boxes = 0, slots = 0;
  double fast_cost = 0.0, exact_cost = 0.0;  // the automatic choice's estimates (ns-like units)
  svm_detail::FgtLocalPlan target;  // the target grid (cells = 0: none; queries use the boxes)
};

/// Per query: whether the fast value was used, or the fast path ran and fell back to exact;
/// target: the value came from the target grid (else from the source boxes).
struct SvmFastReport {
  bool fast = false, fallback = false, target = false;
  double bound = 0.0;  // max_m E_m(x) when the fast path ran
};


/// An RBF model with its fast Gauss transform. Holds a copy of the model (model()), which the
/// exact path uses; build allocates, prediction never does. Thread-safe for concurrent queries.
template <int Dim, int MaxClasses = 8>
class SvmFastRbf {
  static_assert(Dim != Eigen::Dynamic, "SvmFastRbf needs the feature dimension at compile time (its expansion is built for it)");
 public:
  using Model = SvmModel<Dim, MaxClasses>;
  using Feature = typename Model::Feature;
  using Values = std::array<double, Model::kMaxMachines>;

  explicit SvmFastRbf(const Model& model, SvmFastRbfOptions options = {}) : model_(model), options_(options) {
    if (model_.kernel == SvmKernel::rbf && svm_model_problem(model_).empty() && Dim <= 8) build();
    // Not in exact mode, which never reads it.
    if (plan_.eligible && options_.target_grid && options_.mode != SvmFastRbfOptions::Mode::exact) {
      typename svm_detail::FgtLocalGrid<Dim, Model::kMaxMachines>::Limits lim;
      lim.truncation_target = options_.truncation_target;
      lim.max_order = options_.max_order;
      lim.max_terms = options_.max_terms;
      // The build costs at most about what 10^4 exact predictions cost (a build term costs
      // about twice an exact one, svm_bench.cpp), and the budget.
      lim.max_build_terms = std::min(options_.max_build_terms,
                                     2e4 * double(model_.num_support_vectors()) * model_.num_machines());
      target_.build(model_.support_vectors, model_.coefficients, weight_total_, model_.gamma, exp_, lim);
      plan_.target = target_.plan();
      // Per query inside the grid (svm_bench.cpp): ~0.5 ns per term and machine + 60 ns.
      if (plan_.target.cells > 0) plan_.fast_cost = std::min(plan_.fast_cost, 0.5 * plan_.target.terms * model_.num_machines() + 60.0);
    }
    const auto mode = options_.mode;
    plan_.fast = plan_.eligible && (mode == SvmFastRbfOptions::Mode::fast ||
                                    (mode == SvmFastRbfOptions::Mode::automatic && plan_.fast_cost < 0.5 * plan_.exact_cost));
  }

  const Model& model() const { return model_; }
  const SvmFastRbfPlan& plan() const { return plan_; }

  /// As svm_decision (same Status, `out` untouched on bad input).
  Status decision(const Feature& x, SvmPrediction<MaxClasses>& out, SvmFastReport* report = nullptr) const {
    return run(x, out, report, false);
  }
  /// As svm_predict.
  Status predict(const Feature& x, SvmPrediction<MaxClasses>& out, SvmFastReport* report = nullptr) const {
    return run(x, out, report, true);
  }

  /// The raw fast decision values f_m and bounds E_m(x) >= |f_m - svm_decision's f_m| (needs
  /// plan().eligible; no fallback, no acceptance test).
  Status fast_values(const Feature& x, Values& values, Values& bounds) const {
    if (const Status st = svm_detail::input_status(x); !st) return st;
    evaluate(svm_standardize(model_, x), values, bounds);
    for (int m = 0; m < model_.num_machines(); ++m) values[idx(m)] -= model_.rho[idx(m)];  // as finish_decision
    return {};
  }

 private:
  static constexpr int L = svm_detail::kFgtLanes;
  static std::size_t idx(long i) { return static_cast<std::size_t>(i); }

  Status run(const Feature& x, SvmPrediction<MaxClasses>& out, SvmFastReport* report, bool probabilities) const {
    if (const Status st = svm_detail::input_status(x); !st) return st;
    SvmFastReport r;
    // Probabilities of one-vs-one models with more than two classes: always the exact path
    // (accept() explains why).
    const bool coupled = probabilities && model_.has_probability && model_.num_classes > 2 &&
                         model_.multiclass == SvmMulticlass::one_vs_one;
    if (plan_.fast && coupled) r.fallback = true;
    if (plan_.fast && !coupled) {
      Values sums{}, bounds{};
      r.target = evaluate(svm_standardize(model_, x), sums, bounds);
      for (int m = 0; m < model_.num_machines(); ++m) r.bound = std::max(r.bound, bounds[idx(m)]);
      r.fast = accept(sums, bounds, probabilities && model_.has_probability, out);
      r.fallback = !r.fast;
    }
    if (!r.fast) {
      // The input passed the same checks above, so the exact path accepts it too.
      const Status exact = probabilities ? svm_predict(model_, x, out) : svm_decision(model_, x, out);
      if (!exact) return exact;
    }
    if (report) *report = r;
    return {};
  }

  /// Fills `out` from the fast sums; true when the result is guaranteed (see the header).
  bool accept(const Values& sums, const Values& e, bool probabilities, SvmPrediction<MaxClasses>& out) const {
    const int k = model_.num_classes, M = model_.num_machines();
    for (int m = 0; m < M; ++m)
      if (!(e[idx(m)] <= options_.value_tolerance)) return false;
    svm_detail::finish_decision(model_, sums.data(), out);
    const auto& f = out.decision_values;
    if (!probabilities) {
      if (k == 2 || model_.multiclass == SvmMulticlass::one_vs_one) {
        for (int m = 0; m < M; ++m)
          if (!(std::abs(f[idx(m)]) > e[idx(m)])) return false;
        return true;
      }
      const auto w = idx(out.class_index);
      for (int i = 0; i < M; ++i)
        if (idx(i) != w && !(f[w] - f[idx(i)] > e[w] + e[idx(i)])) return false;
      return true;
    }
    if (k == 2) {
      const double dp = std::abs(model_.prob_a[0]) * e[0] / 4 * (1.0 + 1e-9) + 32 * svm_detail::kFgtUnit;
      if (!(dp <= options_.probability_tolerance)) return false;
      svm_detail::add_probabilities(model_, out);
      return std::abs(out.probabilities[0] - 0.5) > dp;
    }
    // One-vs-one: the pairwise coupling iterates to a stopping test, so a perturbation of its
    // inputs can change its iteration count and its output by far more than the perturbation;
    // no bound is claimed, and run() never gets here for such models.
    if (model_.multiclass == SvmMulticlass::one_vs_one) return false;
    // One-vs-rest: p_m = s_m / S with s_m the clipped sigmoids; |s_m - s_m'| <= d_m (as above),
    // |S - S'| <= sum d_m + k u S (its summation), and the divisions round once in each path.
    std::array<double, MaxClasses> d{};
    double dsum = 0.0, total = 0.0;
    for (int m = 0; m < M; ++m) {
      d[idx(m)] = std::abs(model_.prob_a[idx(m)]) * e[idx(m)] / 4 * (1.0 + 1e-9) + 32 * svm_detail::kFgtUnit;
      dsum += d[idx(m)];
    }
    svm_detail::add_probabilities(model_, out);
    for (int m = 0; m < M; ++m) {  // the sum of the sigmoids, recovered up to rounding
      const double dv = out.decision_values[idx(m)];
      total += std::min(std::max(svm_detail::platt_probability(dv, model_.prob_a[idx(m)], model_.prob_b[idx(m)]),
                                 svm_detail::kMinPairProbability),
                        1.0 - svm_detail::kMinPairProbability);
    }
    const double ds = (dsum + (2 * k + 4) * svm_detail::kFgtUnit * total) * (1.0 + 1e-9);
    if (!(total - ds > 0.5 * total)) return false;
    std::array<double, MaxClasses> err{};
    for (int m = 0; m < M; ++m) {
      err[idx(m)] = ((d[idx(m)] + out.probabilities[idx(m)] * ds) / (total - ds) + 4 * svm_detail::kFgtUnit) * (1.0 + 1e-9);
      if (!(err[idx(m)] <= options_.probability_tolerance)) return false;
    }
    const auto w = idx(out.class_index);
    for (int i = 0; i < k; ++i)
      if (idx(i) != w && !(out.probabilities[w] - out.probabilities[idx(i)] > err[w] + err[idx(i)])) return false;
    return true;
  }

  /// Sums and bounds from the target grid (true) or the source boxes (false).
  bool evaluate(const Feature& xs, Values& sums, Values& bounds) const {
    using namespace svm_detail;
    const bool target = target_.evaluate(xs, sums.data(), bounds.data());
    if (!target) box_sums(xs, sums, bounds);
    for (int m = 0; m < model_.num_machines(); ++m) {
      const auto i = idx(m);
      bounds[i] = bounds[i] * (1.0 + 1e-6) + 4 * kFgtUnit * (std::abs(sums[i]) + std::abs(model_.rho[i])) +
                  weight_total_[i] * 1e-307;
    }
    return target;
  }

  void box_sums(const Feature& xs, Values& sums, Values& bounds) const {
    using namespace svm_detail;
    FgtColumns<Dim> col;
    const double far = 600.0 / (Dim * model_.gamma);
    for (int f = 0; f < Dim; ++f) {
      const auto fi = idx(f);
      for (int k = 0; k < columns_[fi]; ++k) {
        const auto ki = idx(k);
        const double y = xs[f] - static_cast<double>(first_[fi] + k) * plan_.h, y2 = y * y;
        const bool near = y2 <= far;
        const double m = std::max(std::abs(y) * (1.0 - 4 * kFgtUnit) - half_, 0.0);
        col.y[fi][ki] = near ? y : 0.0;
        col.e[fi][ki] = near ? exp_neg_gamma(y2, exp_) : 0.0;
        col.g[fi][ki] = exp_neg_gamma(std::min(m * m, exp_.d2_max), exp_);
        col.a[fi][ki] = near ? std::abs(y) : 0.0;
        col.q[fi][ki] = y2;
      }
    }
    FgtLayout lay = layout_;  // the pointers refreshed: copies of this object stay valid
    lay.coef = coef_.data(), lay.weight = weight_.data(), lay.column = column_.data();
    fgt_sums_dispatch<Dim, Model::kMaxMachines>(options_.instruction_set, lay, col, sums.data(), bounds.data());
  }

  using Keyed = std::vector<std::pair<std::array<long long, Dim>, long>>;
  bool bin(double h, Keyed& keyed, std::vector<long>& starts, double& half);
  void build();

  Model model_;
  SvmFastRbfOptions options_;
  SvmFastRbfPlan plan_;
  svm_detail::RbfExp exp_{};
  std::array<long long, Dim> first_{};
  std::array<int, Dim> columns_{};
  Values weight_total_{};
  double half_ = 0.0;  // max |s_f - c_f| over support vectors and features (<= h/2 + rounding)
  std::vector<double> coef_, weight_;
  std::vector<std::int32_t> column_;
  svm_detail::FgtLayout layout_{};
  svm_detail::FgtLocalGrid<Dim, Model::kMaxMachines> target_;
};

/// Bins the support vectors on the grid of side h (centres k h, k = nearbyint(s / h)): keyed
/// sorted by box, box starts, per-feature first index and column count, half = max |s_f - c_f|.
/// False when a subtraction s_f - c_f is inexact (TwoSum) or a feature needs too many columns.
template <int Dim, int MaxClasses>
bool SvmFastRbf<Dim, MaxClasses>::bin(double h, Keyed& keyed, std::vector<long>& starts, double& half) {
  const long n = model_.num_support_vectors();
  half = 0.0;
  for (long s = 0; s < n; ++s) {
    for (int f = 0; f < Dim; ++f) {
      const double v = model_.support_vectors(s, f), kd = std::nearbyint(v / h), c = -kd * h, d = v + c, cc = d - v;
      if (!(std::abs(kd) < 0x1p40) || (v - (d - cc)) + (c - cc) != 0.0) return false;
      keyed[idx(s)].first[idx(f)] = static_cast<long long>(kd);
      half = std::max(half, std::abs(d));
    }
    keyed[idx(s)].second = s;
  }
  std::sort(keyed.begin(), keyed.end());
  starts.clear();
  for (long s = 0; s < n; ++s)
    if (s == 0 || keyed[idx(s)].first != keyed[idx(s - 1)].first) starts.push_back(s);
  starts.push_back(n);
  for (int f = 0; f < Dim; ++f) {
    long long lo = keyed[0].first[idx(f)], hi = lo;
    for (const auto& [key, s] : keyed) lo = std::min(lo, key[idx(f)]), hi = std::max(hi, key[idx(f)]);
    if (hi - lo >= svm_detail::kFgtMaxColumns) return false;
    first_[idx(f)] = lo;
    columns_[idx(f)] = static_cast<int>(hi - lo + 1);
  }
  return true;
}

template <int Dim, int MaxClasses>
void SvmFastRbf<Dim, MaxClasses>::build() {
  using namespace svm_detail;
  const double gamma = model_.gamma, u = kFgtUnit;
  const long n = model_.num_support_vectors();
  const int M = model_.num_machines();
  for (int m = 0; m < M; ++m) weight_total_[idx(m)] = model_.coefficients.row(m).cwiseAbs().sum() * (1.0 + 1e-9);
  exp_ = rbf_exp_constants(gamma);
  Keyed keyed(idx(n));
  std::vector<long> starts;
  double half = 0.0;
  // Choice of (h, p): h = 2^e {1, 5/4, 3/2, 7/4} with h sqrt(2 gamma) in [1/4, 4]; for each, the
  // truncation bound (2) summed over boxes at sample queries (128 support vectors: queries come
  // from the data), and the smallest p whose largest sampled bound is <= truncation_target.
  struct Choice { double h = 0.0, cost = 0.0, worst = 0.0; int p = 0; } best;
  const int e_lo = static_cast<int>(std::floor(std::log2(0.25 / std::sqrt(2 * gamma))));
  const int P = options_.max_order;
  for (int e = e_lo; e <= e_lo + 4; ++e)
    for (const double mult : {1.0, 1.25, 1.5, 1.75}) {
      const double h = std::ldexp(mult, e), hs = h * std::sqrt(2 * gamma);
      if (hs < 0.25 || hs > 4.0 || !bin(h, keyed, starts, half)) continue;
      const long boxes = static_cast<long>(starts.size()) - 1;
      std::vector<double> worst(idx(P + 1), 0.0), total(idx(P + 1)), wb(idx(boxes), 0.0);
      for (int m = 0; m < M; ++m)
        for (long b = 0; b < boxes; ++b) {
          double w = 0.0;
          for (long i = starts[idx(b)]; i < starts[idx(b + 1)]; ++i) w += std::abs(model_.coefficients(m, keyed[idx(i)].second));
          wb[idx(b)] = std::max(wb[idx(b)], w);
        }
      for (long q = 0; q < n; q += std::max(1L, n / 128)) {
        std::fill(total.begin(), total.end(), 0.0);
        for (long b = 0; b < boxes; ++b) {
          double a = 0.0, gm = 0.0;
          bool masked = false;
          const auto& key = keyed[idx(starts[idx(b)])].first;
          for (int f = 0; f < Dim; ++f) {
            const double y = std::abs(model_.support_vectors(q, f) - static_cast<double>(key[idx(f)]) * h);
            masked = masked || gamma * y * y > 600.0 / Dim;
            a += 2 * gamma * half * y;
            gm += std::pow(std::max(y - half, 0.0), 2);
          }
          const double cut = wb[idx(b)] * std::exp(-gamma * gm);
          double term = cut;
          for (int p = 1; p <= P; ++p) total[idx(p)] += masked ? cut : (term *= a / p);
        }
        for (int p = 1; p <= P; ++p) worst[idx(p)] = std::max(worst[idx(p)], total[idx(p)]);
      }
      double terms = 1.0;
      for (int p = 1; p <= P; ++p) {
        terms = p == 1 ? 1.0 : terms * (p - 1 + Dim) / (p - 1);  // T(p) = binom(p - 1 + Dim, Dim)
        if (terms > options_.max_terms) break;
        if (worst[idx(p)] > options_.truncation_target) continue;
        const double cost = std::ceil(double(boxes) / L) * L * (terms * M + 24);
        if (best.p == 0 || cost < best.cost) best = {h, cost, worst[idx(p)], p};
        break;
      }
    }
  if (best.p == 0) return;
  // The chosen grid: boxes in key order, kFgtLanes to a chunk.
  const double h = best.h;
  const int p = best.p;
  bin(h, keyed, starts, half);
  std::vector<std::array<int, Dim>> alphas;
  std::array<int, Dim> alpha{};
  horner_order<Dim>(0, p - 1, alpha, alphas);
  const int T = static_cast<int>(alphas.size());
  std::vector<long double> factor(idx(T)), mono(idx(T)), acc(idx(T) * idx(M));
  for (int t = 0; t < T; ++t) {  // (2 gamma)^|alpha| / alpha!
    long double v = 1.0L;
    for (int f = 0; f < Dim; ++f)
      for (int j = 1; j <= alphas[idx(t)][idx(f)]; ++j) v = v * (2.0L * gamma) / j;
    factor[idx(t)] = v;
  }
  const long boxes = static_cast<long>(starts.size()) - 1, chunks = (boxes + L - 1) / L;
  coef_.assign(idx(chunks * M * T * L), 0.0);
  weight_.assign(idx(chunks * M * L), 0.0);
  column_.assign(idx(chunks * Dim * L), 0);
  long n_max = 0;
  std::vector<std::array<long double, Dim>> powers(idx(p));
  for (long b = 0; b < boxes; ++b) {
    const long c = b / L, l = b % L;
    const auto& key = keyed[idx(starts[idx(b)])].first;
    for (int f = 0; f < Dim; ++f) column_[idx((c * Dim + f) * L + l)] = static_cast<std::int32_t>(key[idx(f)] - first_[idx(f)]);
    std::fill(acc.begin(), acc.end(), 0.0L);
    n_max = std::max(n_max, starts[idx(b + 1)] - starts[idx(b)]);
    for (long i = starts[idx(b)]; i < starts[idx(b + 1)]; ++i) {
      const long s = keyed[idx(i)].second;
      double rho2 = 0.0;
      for (int f = 0; f < Dim; ++f) {
        const double sigma = model_.support_vectors(s, f) - static_cast<double>(key[idx(f)]) * h;  // exact
        rho2 += sigma * sigma;
        powers[0][idx(f)] = 1.0L;
        for (int j = 1; j < p; ++j) powers[idx(j)][idx(f)] = powers[idx(j - 1)][idx(f)] * sigma;
      }
      const long double k0 = exp_neg_gamma(std::min(rho2, exp_.d2_max), exp_);
      for (int t = 0; t < T; ++t) {
        long double v = factor[idx(t)] * k0;
        for (int f = 0; f < Dim; ++f) v *= powers[idx(alphas[idx(t)][idx(f)])][idx(f)];
        mono[idx(t)] = v;
      }
      for (int m = 0; m < M; ++m) {
        const long double w = model_.coefficients(m, s);
        for (int t = 0; t < T; ++t) acc[idx(m * T + t)] += w * mono[idx(t)];
        weight_[idx((c * M + m) * L + l)] += std::abs(model_.coefficients(m, s));
      }
    }
    for (int m = 0; m < M; ++m)
      for (int t = 0; t < T; ++t) coef_[idx(((c * M + m) * T + t) * L + l)] = static_cast<double>(acc[idx(m * T + t)]);
  }
  for (double& w : weight_) w *= 1.0 + 1e-9;  // round the box sums up
  // Rounding allowances (header comment), in units of u.
  const double u_ld = std::numeric_limits<long double>::epsilon() / 2;
  const double k_build = 10.0 + gamma * Dim * Dim * half * half + (double(n_max) + 3 * p + Dim + 4) * u_ld / u;
  // The exact path: its blocked sums, and its kernel's 8 + (Dim + 2) max(gamma |x - s|^2, 1)
  // (the part above Dim + 2 is in evaluate's 2 (Dim + 2) (gamma |y|^2 + k_radius)).
  const double exact_depth = std::ceil(double(n) / kRbfBlock) + kRbfBlock + 1 + 8 + (Dim + 2);
  const double k_fixed = k_build + 2 * (p - 1) + Dim + 9 * Dim + 1 + double(chunks) + L + exact_depth;
  double inv_factorial = 1.0;
  for (int j = 2; j <= p; ++j) inv_factorial /= j;
  half_ = half;
  layout_ = {coef_.data(), weight_.data(), column_.data(), static_cast<int>(chunks), M, T, p, gamma, 2 * gamma * half,
             inv_factorial * (1.0 + 1e-12), k_fixed, gamma * Dim * half * half};
  plan_ = {true, false, h, best.worst, p, T, static_cast<int>(boxes), static_cast<int>(chunks * L), 0.0, 0.0, {}};
  // Automatic choice, per query (bench/classify_svm/svm_bench.cpp, AVX-512): exact ~0.45 ns per
  // support vector (+45 % per further machine); fast ~0.06 ns per slot term + 150 ns.
  plan_.exact_cost = 0.45 * double(n) * (1 + 0.45 * (M - 1));
  plan_.fast_cost = 0.06 * best.cost + 150.0;
}

}  // namespace ctxfuse::classify
