// The scene-detection paper's eight GNSS features per epoch (digest section B), from
// per-satellite elevation, azimuth and C/N0.
//
// Conventions (the paper leaves these open):
// - A satellite counts when its C/N0 is finite (it is tracked); satellites listed in view
//   without C/N0 are ignored by every feature.
// - Unknown geometry: a tracked satellite whose elevation or azimuth is NaN (receivers report
//   -91 or leave the field empty before the almanac is known; readers map that to NaN) counts in
//   the satellite count and the C/N0 features (3, 4, 6) and is left out of the mean elevation,
//   the azimuth vacancy and the PDOP computed from geometry (7, 8, 2 without receiver PDOP).
// - PDOP: the receiver's value when given (finite); otherwise computed from the counted
//   satellites' elevation/azimuth with one common receiver clock (rows [cos e sin a,
//   cos e cos a, sin e, 1]); needs >= 4 satellites and a well-conditioned geometry, else fill.
// - Every window is in seconds, so receivers at 1 Hz and 5 Hz get comparable features; the
//   defaults (4 s) are the paper's 4 epochs at 1 Hz. Window statistics (features 4, 5) are
//   population standard deviations (1/n) over the epochs with time in (t - window_s, t], the
//   current epoch included; at most WindowCapacity epochs (the oldest are dropped beyond that).
// - Feature 6: for every counted satellite of the current epoch, the population std of its C/N0
//   over the epochs with time in (t - cn0_window_s, t] in which it was tracked; satellites with
//   fewer than 2 values are skipped; the mean over the rest.
// - Feature 8 (azimuth vacancy): largest azimuth gap [deg] between consecutive satellites with
//   elevation in [10, 60] deg, the gap across 0/360 included. 0 or 1 such satellites: 360.
// - An epoch with no tracked satellite (indoors, or a missing epoch given as empty) gets count 0
//   and fill_value for every other feature; a feature that cannot be computed (e.g. PDOP with
//   3 satellites) gets fill_value too. The paper fills with negative values before
//   standardisation; fill_value defaults to -1.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ctxfuse/core/error.hpp"
#include "ctxfuse/core/status.hpp"

namespace ctxfuse::features {

struct SatelliteObservation {
  int id = 0;                 // stable across epochs (e.g. system * 1000 + PRN)
  double elevation_deg = 0.0;  // NaN: unknown (no geometry)
  double azimuth_deg = 0.0;    // NaN: unknown (no geometry)
  double cn0_dbhz = std::numeric_limits<double>::quiet_NaN();  // NaN: in view, not tracked
};

struct GnssEpoch {
  double time_s = 0.0;
  std::span<const SatelliteObservation> satellites;
  double pdop = std::numeric_limits<double>::quiet_NaN();  // NaN: compute from geometry
};

/// Column of each feature in GnssSceneFeatures.
struct GnssSceneFeature {
  static constexpr int satellite_count = 0;
  static constexpr int pdop = 1;
  static constexpr int mean_cn0 = 2;
  static constexpr int count_std = 3;
  static constexpr int pdop_std = 4;
  static constexpr int mean_cn0_std = 5;
  static constexpr int mean_elevation = 6;
  static constexpr int azimuth_vacancy = 7;
};
inline constexpr int kGnssSceneFeatureCount = 8;
inline constexpr std::array<std::string_view, kGnssSceneFeatureCount> kGnssSceneFeatureNames{
    "satellite_count", "pdop",           "mean_cn0_dbhz",  "count_std",
    "pdop_std",        "mean_cn0_std_db", "mean_elevation_deg", "azimuth_vacancy_deg"};
using GnssSceneFeatures = std::array<double, kGnssSceneFeatureCount>;

struct GnssSceneConfig {
  double window_s = 4.0;      // features 4, 5
  double cn0_window_s = 4.0;  // feature 6
  double vacancy_min_elevation_deg = 10.0;
  double vacancy_max_elevation_deg = 60.0;
  double fill_value = -1.0;
  /// Above this PDOP the geometry is called degenerate and PDOP is filled.
  double max_pdop = 100.0;

  /// Usable, or which window is out of range (GnssSceneExtractor's constructor refuses it).
  SettingCheck check() const {
    if (!(window_s > 0.0 && std::isfinite(window_s))) return SettingCheck::refuse("window_s must be finite and > 0");
    if (!(cn0_window_s > 0.0 && std::isfinite(cn0_window_s)))
      return SettingCheck::refuse("cn0_window_s must be finite and > 0");
    return {};
  }
};

/// True when the satellite's elevation and azimuth are both known.
inline bool has_geometry(const SatelliteObservation& s) { return std::isfinite(s.elevation_deg) && std::isfinite(s.azimuth_deg); }

/// PDOP from elevation/azimuth of the tracked satellites with known geometry (single receiver
/// clock); NaN when fewer than 4 such satellites or the geometry matrix is singular.
inline double pdop_from_geometry(std::span<const SatelliteObservation> sats) {
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  int n = 0;
  for (const auto& s : sats) {
    if (!std::isfinite(s.cn0_dbhz) || !has_geometry(s)) continue;
    const double e = s.elevation_deg * std::numbers::pi / 180.0;
    const double a = s.azimuth_deg * std::numbers::pi / 180.0;
    const Eigen::Vector4d row(std::cos(e) * std::sin(a), std::cos(e) * std::cos(a), std::sin(e), 1.0);
    normal += row * row.transpose();
    ++n;
  }
  if (n < 4) return std::numeric_limits<double>::quiet_NaN();
  Eigen::LDLT<Eigen::Matrix4d> ldlt(normal);
  if (ldlt.info() != Eigen::Success || (ldlt.vectorD().array() <= 1e-12 * normal.trace()).any())
    return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Matrix4d q = ldlt.solve(Eigen::Matrix4d::Identity());
  const double p2 = q(0, 0) + q(1, 1) + q(2, 2);
  return p2 > 0.0 ? std::sqrt(p2) : std::numeric_limits<double>::quiet_NaN();
}

/// Largest empty azimuth sector [deg] among satellites with elevation in [min_el, max_el];
/// 360 with fewer than 2 such satellites. `scratch` must hold sats.size() values.
inline double azimuth_vacancy(std::span<const SatelliteObservation> sats, double min_el, double max_el,
                              std::span<double> scratch) {
  std::size_t n = 0;
  for (const auto& s : sats) {
    if (!std::isfinite(s.cn0_dbhz) || !has_geometry(s) || s.elevation_deg < min_el || s.elevation_deg > max_el) continue;
    double a = std::fmod(s.azimuth_deg, 360.0);
    if (a < 0.0) a += 360.0;
    scratch[n++] = a;
  }
  if (n < 2) return 360.0;
  std::sort(scratch.begin(), scratch.begin() + static_cast<std::ptrdiff_t>(n));
  double gap = 360.0 - (scratch[n - 1] - scratch[0]);  // across 0/360
  for (std::size_t i = 1; i < n; ++i) gap = std::max(gap, scratch[i] - scratch[i - 1]);
  return gap;
}

/// Streaming extractor: fixed-capacity ring buffers, no allocation per epoch.
template <int MaxSatellites = 128, int WindowCapacity = 32>
class GnssSceneExtractor {
  static_assert(MaxSatellites >= 1 && WindowCapacity >= 2);

 public:
  explicit GnssSceneExtractor(GnssSceneConfig config = {}) : config_(config) {
    ctxfuse::detail::require_setting(config_.check(), "GnssSceneExtractor");
  }

  void reset() {
    size_ = 0;
    head_ = 0;
  }

  /// Computes the features of `epoch` into `out` (accepted). Refused (invalid input, with the
  /// Problem naming the field): `out` and the extractor's history are left unchanged.
  Status push(const GnssEpoch& epoch, GnssSceneFeatures& out) {
    if (const Status s = validate(epoch); !s) return s;
    const double fill = config_.fill_value;

    // Store the epoch in the ring first: window statistics include it.
    Record& rec = ring_[head_];
    rec.time = epoch.time_s;
    rec.num_sats = 0;
    double cn0_sum = 0.0, el_sum = 0.0;
    int with_elevation = 0;
    for (const auto& s : epoch.satellites) {
      if (!std::isfinite(s.cn0_dbhz)) continue;
      rec.ids[rec.num_sats] = s.id;
      rec.cn0[rec.num_sats] = s.cn0_dbhz;
      ++rec.num_sats;
      cn0_sum += s.cn0_dbhz;
      if (has_geometry(s)) {
        el_sum += s.elevation_deg;
        ++with_elevation;
      }
    }
    const int count = rec.num_sats;
    double pdop = std::isfinite(epoch.pdop) ? epoch.pdop : pdop_from_geometry(epoch.satellites);
    if (!(pdop <= config_.max_pdop)) pdop = std::numeric_limits<double>::quiet_NaN();
    if (count == 0) pdop = std::numeric_limits<double>::quiet_NaN();
    rec.pdop = pdop;
    head_ = (head_ + 1) % WindowCapacity;
    size_ = std::min(size_ + 1, WindowCapacity);

    using F = GnssSceneFeature;
    GnssSceneFeatures f;
    f.fill(fill);
    f[F::satellite_count] = count;
    if (count > 0) {
      f[F::pdop] = std::isfinite(pdop) ? pdop : fill;
      f[F::mean_cn0] = cn0_sum / count;
      if (with_elevation > 0) f[F::mean_elevation] = el_sum / with_elevation;
      f[F::azimuth_vacancy] = azimuth_vacancy_of(epoch.satellites);
      f[F::count_std] = window_std([](const Record& r) { return double(r.num_sats); }, epoch.time_s);
      const double ps = window_std([](const Record& r) { return r.pdop; }, epoch.time_s);
      f[F::pdop_std] = std::isfinite(ps) ? ps : fill;
      const double cs = cn0_std_mean(rec);
      f[F::mean_cn0_std] = std::isfinite(cs) ? cs : fill;
    }
    out = f;
    return Status{};
  }

  const GnssSceneConfig& config() const { return config_; }

 private:
  struct Record {
    double time = 0.0;
    double pdop = 0.0;
    int num_sats = 0;
    std::array<int, MaxSatellites> ids{};
    std::array<double, MaxSatellites> cn0{};
  };

  Status validate(const GnssEpoch& epoch) const {
    if (!std::isfinite(epoch.time_s)) return Status::invalid(Problem::non_finite_time);
    if (size_ > 0 && !(epoch.time_s > newest().time)) return Status::invalid(Problem::out_of_order_time);
    if (epoch.satellites.size() > static_cast<std::size_t>(MaxSatellites))
      return Status::invalid(Problem::measurement_count_above_capacity);
    if (!std::isnan(epoch.pdop) && !(epoch.pdop > 0.0 && std::isfinite(epoch.pdop)))
      return Status::invalid(Problem::invalid_dop);
    for (std::size_t i = 0; i < epoch.satellites.size(); ++i) {
      const auto& s = epoch.satellites[i];
      if (!std::isnan(s.elevation_deg) && !(std::abs(s.elevation_deg) <= 90.0)) return Status::invalid(Problem::invalid_elevation);
      if (std::isinf(s.azimuth_deg)) return Status::invalid(Problem::invalid_azimuth);
      if (!std::isnan(s.cn0_dbhz) && !(s.cn0_dbhz >= 0.0 && s.cn0_dbhz <= 100.0))
        return Status::invalid(Problem::invalid_cn0);
      // Quadratic, but epochs hold a few dozen satellites and this keeps the step allocation-free.
      for (std::size_t j = 0; j < i; ++j)
        if (epoch.satellites[j].id == s.id) return Status::invalid(Problem::duplicate_satellite);
    }
    return Status{};
  }

  const Record& at_age(int age) const {  // age 0 = newest
    return ring_[(head_ - 1 - age + 2 * WindowCapacity) % WindowCapacity];
  }
  const Record& newest() const { return at_age(0); }

  // Two passes (mean, then squared deviations): the one-pass sum-of-squares form leaves
  // 1e-8-sized residue for constant PDOP, which would read as "PDOP varies".
  template <typename Get>
  double window_std(Get get, double now) const {
    double sum = 0.0;
    int n = 0;
    int depth = 0;
    for (; depth < size_; ++depth) {
      const Record& r = at_age(depth);
      if (!(r.time > now - config_.window_s)) break;
      const double v = get(r);
      if (!std::isfinite(v)) continue;
      sum += v;
      ++n;
    }
    if (n == 0) return std::numeric_limits<double>::quiet_NaN();
    const double mean = sum / n;
    double sq = 0.0;
    for (int age = 0; age < depth; ++age) {
      const double v = get(at_age(age));
      if (std::isfinite(v)) sq += (v - mean) * (v - mean);
    }
    return std::sqrt(sq / n);
  }

  double cn0_std_mean(const Record& current) const {
    double total = 0.0;
    int sats = 0;
    int depth = 0;
    while (depth < size_ && at_age(depth).time > current.time - config_.cn0_window_s) ++depth;
    std::array<double, WindowCapacity> values{};
    for (int i = 0; i < current.num_sats; ++i) {
      int n = 0;
      for (int age = 0; age < depth; ++age) {
        const Record& r = at_age(age);
        for (int j = 0; j < r.num_sats; ++j)
          if (r.ids[j] == current.ids[i]) {
            values[n++] = r.cn0[j];
            break;
          }
      }
      if (n < 2) continue;
      double mean = 0.0;
      for (int k = 0; k < n; ++k) mean += values[k];
      mean /= n;
      double sq = 0.0;
      for (int k = 0; k < n; ++k) sq += (values[k] - mean) * (values[k] - mean);
      total += std::sqrt(sq / n);
      ++sats;
    }
    return sats > 0 ? total / sats : std::numeric_limits<double>::quiet_NaN();
  }

  double azimuth_vacancy_of(std::span<const SatelliteObservation> sats) {
    return features::azimuth_vacancy(sats, config_.vacancy_min_elevation_deg,
                                     config_.vacancy_max_elevation_deg,
                                     std::span<double>(scratch_.data(), sats.size()));
  }

  GnssSceneConfig config_;
  std::array<Record, WindowCapacity> ring_{};
  std::array<double, MaxSatellites> scratch_{};
  int size_ = 0;
  int head_ = 0;
};

/// Features of a whole batch of epochs, or why not.
struct GnssSceneBatch {
  std::vector<GnssSceneFeatures> features;  // one per epoch when accepted; empty when refused
  Status status{};                          // the first refused epoch's Status
  std::size_t refused_at = 0;               // that epoch's index
};

/// Batch form: features of every epoch in order; the first invalid epoch refuses the batch.
template <int MaxSatellites = 128, int WindowCapacity = 32>
GnssSceneBatch gnss_scene_features(std::span<const GnssEpoch> epochs, const GnssSceneConfig& config = {}) {
  GnssSceneExtractor<MaxSatellites, WindowCapacity> extractor(config);
  GnssSceneBatch out;
  out.features.resize(epochs.size());
  for (std::size_t i = 0; i < epochs.size(); ++i) {
    if (const Status status = extractor.push(epochs[i], out.features[i]); !status) {
      out.features.clear();
      out.status = status;
      out.refused_at = i;
      return out;
    }
  }
  return out;
}

}  // namespace ctxfuse::features
