// The IMU-driven estimators of the region paper as Cores of the aided-filter wrapper
// (aided.hpp): one sub-model alone (EKF-ODR / EKF-I-OTR / EKF-IDR), the federated Kalman
// filter, and the IMM over the three sub-models, plain or region-aware.
//
// Sub-models (paper's EKF-ODR, EKF-I-OTR, EKF-IDR): ODR takes GNSS; I-OTR takes GNSS and UWB,
// each with its noise inflated by `iotr_noise_factor` (the "weighted" mode) and a larger
// process noise; IDR takes UWB. Region-aware routing (proposed method): when the recognised
// region is outdoor no sub-model takes UWB; when it is indoor no sub-model takes GNSS; in the
// transition region every sub-model takes what its sensors provide. The plain IMM takes
// everything everywhere, with the same sub-models and the same fixed transition matrix as the
// prior of the region-adaptive one. IMM cycles run from one receiver epoch to the next (1 s),
// the rate of the recognised labels, so the transition matrices are per cycle.
#pragma once

#include <boost/hana.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "ctxfuse/core/retraction.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/federated.hpp"
#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/pipelines/region_imm/aided.hpp"
#include "ctxfuse/policies/gating.hpp"
#include "ctxfuse/policies/mixing.hpp"

namespace ctxfuse::pipelines::region_imm {

struct GnssTag {};
struct UwbTag {};
struct SpeedTag {};

namespace detail {
inline bool accepted(const Status& s) { return s.accepted(); }
template <int R>
bool accepted(const imm::UpdateResult<R>& r) {
  return r.any_accepted();
}

// The vehicle constraint at each speed-sample time, with every taker's share of its noise.
// True when the taker accepted it or there was nothing to apply; a refused constraint (a
// non-finite speed under the speed update) or a gated one leaves the belief as it was, and
// Aided counts it (Track::rejected_speed). The constraint feeds no health count: it is no
// sensor whose lock-out a recovery could mend.
template <class UpdateFn>
bool apply_constraint(const Settings& s, const messages::SpeedSample& v, double share, UpdateFn&& update) {
  if (s.use_speed) return accepted(update(speed_meas(s, share), Vector<2>(v.speed_mps, 0.0)));
  if (s.use_nhc) return accepted(update(nhc_meas(s, share), Vector<1>(0.0)));
  return true;
}
}  // namespace detail

/// One sub-model alone.
template <class = void>
struct SingleCoreT {
  static constexpr int kTakers = 1;
  static constexpr bool kWhole = false;
  using Filter = Ekf<models::PlanarImuModel, policies::ChiSquareGate>;
  const Settings* s;
  bool gnss_taker, uwb_taker;
  double process_factor, meas_factor;
  std::optional<Filter> f{};

  void start(double, const Gaussian<L::size>& b0) {
    f.emplace(process_model(*s, process_factor), b0, FilterOptions{}, policies::ChiSquareGate(s->gate_probability));
  }
  Status predict(const models::PlanarImu& u, double dt) { return f->predict(u, dt); }
  bool speed(const messages::SpeedSample& v) {
    return detail::apply_constraint(*s, v, 1.0, [&](const auto& m, const auto& z) { return f->update(m, z); });
  }
  const Gaussian<L::size>& integrity_view() const { return f->belief(); }
  void reanchor(const UwbIntegrity::Fault& fault) {
    auto b = f->belief();
    region_imm::reanchor(b, fault, *s);
    (void)f->reset(b);  // a re-anchored belief is finite and positive definite by construction
  }
  bool takes_gnss() const { return gnss_taker; }
  bool takes_uwb() const { return uwb_taker; }
  bool watches_uwb() const { return uwb_taker; }
  Takes<1> gnss(const messages::GnssFix& e) { return {f->update(gnss_meas(e, *s, meas_factor), Vector<2>(e.position.head<2>()))}; }
  Takes<1> uwb(const messages::UwbRange& r) { return {f->update(uwb_meas(r, *s, meas_factor), Vector<1>(r.range_m))}; }
  void close_cycle(double) {}
  Eigen::Vector2d position() const { return L::get<"p">(f->belief().mean); }
  int dominant_mode() const { return -1; }
  Eigen::Vector2d taker_position(int) const { return position(); }
  void widen(int, double reach) {
    auto b = f->belief();
    region_imm::widen(b.cov, *s, reach);
    (void)f->reset(b);  // widening adds a positive semi-definite term: still a covariance
  }
  void open_cycle(double) {}
};
using SingleCore = SingleCoreT<>;

/// Federated filter: local filter 0 takes GNSS, local filter 1 takes UWB; both take the
/// vehicle constraint with R / beta_i (its share); fusion and reset at every receiver epoch.
/// The integrity check watches the UWB local filter. With `static_weights` the master
/// combines the locals with the fixed weights beta_i instead of their information:
/// x = sum beta_i x_i (on the manifold, about local 0), P = sum beta_i^2 P_i (the covariance of
/// that fixed combination of independent estimates), then resets the locals as usual.
template <class = void>
struct FederatedCoreT {
  static constexpr int kTakers = 1;
  static constexpr bool kWhole = false;
  using Filter = fkf::FederatedFilter<models::PlanarImuModel, 2, policies::ChiSquareGate>;
  const Settings* s;
  bool static_weights = false;
  std::array<double, 2> beta{0.5, 0.5};
  std::optional<Filter> f{};

  void start(double, const Gaussian<L::size>& b0) {
    process_model_ = process_model(*s, 1.0);
    f.emplace(process_model_, b0, beta, FilterOptions{}, policies::ChiSquareGate(s->gate_probability));
  }
  Status predict(const models::PlanarImu& u, double dt) { return f->predict(u, dt); }
  bool speed(const messages::SpeedSample& v) {  // accepted by either local filter
    bool any = false;
    for (int i = 0; i < 2; ++i)
      any = detail::apply_constraint(*s, v, 1.0 / beta[static_cast<std::size_t>(i)],
                                     [&](const auto& m, const auto& z) { return f->update(i, m, z); }) ||
            any;
    return any;
  }
  const Gaussian<L::size>& integrity_view() const { return f->local(1); }
  void reanchor(const UwbIntegrity::Fault& fault) {
    auto g = f->global();
    region_imm::reanchor(g, fault, *s);
    (void)f->reset(g);  // finite and positive definite by construction
  }
  bool takes_gnss() const { return true; }
  bool takes_uwb() const { return true; }
  bool watches_uwb() const { return true; }
  Takes<1> gnss(const messages::GnssFix& e) { return {f->update(0, gnss_meas(e, *s), Vector<2>(e.position.head<2>()))}; }
  Takes<1> uwb(const messages::UwbRange& r) { return {f->update(1, uwb_meas(r, *s), Vector<1>(r.range_m))}; }
  // A refused fusion (the locals' information not positive definite) keeps the last global
  // estimate and the locals as they are; the next epoch fuses again.
  void close_cycle(double) {
    if (!static_weights) {
      (void)f->fuse_and_reset();
      return;
    }
    const models::PlanarImuModel& m = process_model_;
    Gaussian<L::size> g;
    Vector<L::size> dx = Vector<L::size>::Zero();
    g.cov.setZero();
    for (int i = 0; i < 2; ++i) {
      const auto bi = beta[static_cast<std::size_t>(i)];
      dx += bi * state_difference(m, f->local(i).mean, f->local(0).mean);
      g.cov += bi * bi * f->local(i).cov;
    }
    g.mean = state_inject(m, f->local(0).mean, dx);
    (void)f->reset(g);  // a positive combination of the locals' covariances: still one
  }
  Eigen::Vector2d position() const { return L::get<"p">(f->global().mean); }
  int dominant_mode() const { return -1; }
  Eigen::Vector2d taker_position(int) const { return position(); }
  void widen(int, double reach) {
    auto g = f->global();
    region_imm::widen(g.cov, *s, reach);
    (void)f->reset(g);  // still a covariance
  }
  void open_cycle(double) {}
  models::PlanarImuModel process_model_{};
};
using FederatedCore = FederatedCoreT<>;

using OdrMode = imm::Mode<models::PlanarImuModel, imm::Accepts<GnssTag, SpeedTag>, policies::ChiSquareGate>;
using IotrMode = imm::Mode<models::PlanarImuModel, imm::Accepts<GnssTag, UwbTag, SpeedTag>, policies::ChiSquareGate>;
using IdrMode = imm::Mode<models::PlanarImuModel, imm::Accepts<UwbTag, SpeedTag>, policies::ChiSquareGate>;

template <class Mixing>
using RegionImm = imm::Imm<Mixing, OdrMode, IotrMode, IdrMode>;

inline auto make_modes(const Settings& s) {
  const policies::ChiSquareGate gate(s.gate_probability);
  return boost::hana::make_tuple(OdrMode{process_model(s, s.mode_process_noise_factor[0]), gate},
                                 IotrMode{process_model(s, s.mode_process_noise_factor[1]), gate},
                                 IdrMode{process_model(s, s.mode_process_noise_factor[2]), gate});
}

/// Plain IMM (no regions: fixed matrix, no routing) or the region-aware one (recognised
/// labels: routing masks and the region-adaptive matrix). Each mode is a taker with its own
/// health; the IMM as a whole is one more (kWhole), because recovering only the modes that
/// gated a source is not enough when the dominant mode does not take it: the next mixing
/// re-centres them on it (leaving a garage whose anchors are all inside, scenario "paper",
/// EKF-IDR stayed dominant, ODR and I-OTR gated every fix and the estimate drifted to 135 m).
/// The integrity check watches the combined estimate, and a fault re-anchors every mode (the
/// next mixing would re-centre a re-anchored mode on the others).
template <class Mixing>
struct ImmCore {
  static constexpr int kTakers = 3;
  static constexpr bool kWhole = true;
  const Settings* s;
  Mixing mixing;
  const RegionTrack* regions = nullptr;  // null: plain IMM
  std::optional<RegionImm<Mixing>> f{};
  int region = -1;
  Gaussian<L::size> view{};
  double opened_at = std::numeric_limits<double>::quiet_NaN();  // when the open cycle began

  // The first cycle opens at the start; the receiver epoch at the start time (the fix the
  // filters start on is one) then neither closes it nor opens another, so that the start's
  // region is observed once (no self-transition counted into M) and the matrix is applied once.
  void start(double t0, const Gaussian<L::size>& b0) {
    imm::ImmOptions<3> o;
    o.probability_floor = s->probability_floor;
    f.emplace(mixing, make_modes(*s), b0, Vector<3>::Constant(1.0 / 3.0), o);
    open_cycle(t0);
  }
  Status predict(const models::PlanarImu& u, double dt) { return f->predict(u, dt); }
  bool speed(const messages::SpeedSample& v) {
    return detail::apply_constraint(*s, v, 1.0,
                                    [&](const auto& m, const auto& z) { return f->update(SpeedTag{}, m, z); });
  }
  const Gaussian<L::size>& integrity_view() {
    view = f->combined();
    return view;
  }
  void reanchor(const UwbIntegrity::Fault& fault) {
    for_each_mode([&](auto j) { region_imm::reanchor(f->template mode_belief<j.value>(), fault, *s); });
  }
  bool takes_gnss() const { return true; }
  bool takes_uwb() const { return true; }
  bool watches_uwb() const { return mask(false) != 0u; }
  Takes<3> gnss(const messages::GnssFix& e) {
    const auto m = boost::hana::make_tuple(gnss_meas(e, *s), gnss_meas(e, *s, s->iotr_noise_factor), gnss_meas(e, *s));
    return takes_of(f->update(GnssTag{}, m, Vector<2>(e.position.head<2>()), mask(true)));
  }
  Takes<3> uwb(const messages::UwbRange& r) {
    const auto m = boost::hana::make_tuple(uwb_meas(r, *s), uwb_meas(r, *s, s->iotr_noise_factor), uwb_meas(r, *s));
    return takes_of(f->update(UwbTag{}, m, Vector<1>(r.range_m), mask(false)));
  }
  void close_cycle(double t) {
    if (t != opened_at) f->update_mode_probabilities();
  }
  Eigen::Vector2d position() const { return L::get<"p">(f->combined().mean); }
  int dominant_mode() const { return f->most_probable(); }
  Eigen::Vector2d taker_position(int j) const {
    Eigen::Vector2d p = Eigen::Vector2d::Zero();
    for_each_mode([&](auto k) {
      if (k.value == j) p = L::get<"p">(f->template mode_belief<k.value>().mean);
    });
    return p;
  }
  void widen(int j, double reach) {
    for_each_mode([&](auto k) {
      if (k.value == j) region_imm::widen(f->template mode_belief<k.value>().cov, *s, reach);
    });
  }
  /// Next cycle: the region recognised at this epoch (the latest known) routes the
  /// measurements until the next epoch.
  void open_cycle(double t) {
    if (t == opened_at) return;
    observe_region(t);
    (void)f->mix();  // the previous cycle was closed by close_cycle(): nothing to refuse
    opened_at = t;
  }

  /// Which modes take a source now: bit j for mode j.
  std::uint32_t mask(bool gnss) const {
    if (!regions || region < 0 || region == 1) return 0b111u;
    if (region == 0) return gnss ? 0b111u : 0u;  // outdoor: nobody takes UWB
    return gnss ? 0u : 0b111u;                   // indoor: nobody takes GNSS
  }

 private:
  void observe_region(double t) {
    if (!regions) return;
    const long k = regions->at(t);
    region = k >= 0 ? regions->label[static_cast<std::size_t>(k)] : -1;
    f->mixing().observe_region(region);
    if constexpr (requires(Mixing& m) { m.observe_posterior(Vector<3>{}); })
      if (k >= 0 && static_cast<std::size_t>(k) < regions->posterior.size())
        f->mixing().observe_posterior(regions->posterior[static_cast<std::size_t>(k)]);
  }
  /// Calls fn(j) with j = hana::int_c<0>, <1>, <2>: one call per mode.
  template <class Fn>
  static void for_each_mode(Fn&& fn) {
    boost::hana::for_each(boost::hana::make_tuple(boost::hana::int_c<0>, boost::hana::int_c<1>, boost::hana::int_c<2>), fn);
  }
  static Takes<3> takes_of(const imm::UpdateResult<3>& r) {
    Takes<3> t;
    for (std::size_t j = 0; j < 3; ++j)
      if (r.taken[j]) t[j] = r.mode[j];
    return t;
  }
};

}  // namespace ctxfuse::pipelines::region_imm
