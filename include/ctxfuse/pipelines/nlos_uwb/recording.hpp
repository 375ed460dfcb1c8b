// What the pipeline takes from the recording itself rather than from one firmware: the anchors
// (id, position, count), each anchor's report period (the median interval of its own stamps),
// and whether a report is the mean of the last n raw ranges, detected on the recording's
// static start. `settings_for_recording` turns that into the pipeline's Settings:
//   - range_period_s: the median over the anchors of their median report interval;
//   - epoch_window_s: half the shortest anchor period (an epoch takes one range per anchor
//     within half a period of its first range; an anchor that reports again ends it anyway);
//   - range_average_samples: the detected n, or 1 (raw) when the recording does not show it.
// Detection of the averaging: the static start is the time before any anchor's range, smoothed
// over a second, leaves its first second's median by more than kStaticMoveM, less a margin of
// kStaticMarginS (the tag starts to move before its ranges show it). On that span, the first
// differences of each anchor's ranges on its own period grid (a dropped report leaves a hole)
// have an autocorrelation that tells: differences of white noise give -1/2 at lag 1; of an
// n-sample moving average of white noise, -1/2 at lag n and 0 below. n is the first lag whose
// mean autocorrelation over the anchors is below -0.3 with every lower lag within +-0.15 (the
// estimate's standard error with 40 differences is about 0.16 per anchor, less in the mean);
// anchors with fewer than kMinDifferences differences are left out (a slow anchor has few);
// none left, or no such lag: not detected (raw).
// The tag's height: a 3-D fit (multilaterate_3d) of each anchor's median range over the
// static start, with its vertical dilution of precision; settings_for_recording takes it when
// the vertical sigma it implies is small enough (choose_tag_height).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "ctxfuse/filters/multilateration.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/pipelines/nlos_uwb/classifier.hpp"
#include "ctxfuse/pipelines/nlos_uwb/settings.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

struct AnchorFacts {
  int id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // its first range's
  std::size_t ranges = 0;
  double median_interval_s = std::nan("");  // NaN with fewer than two ranges
  bool moves = false;                       // its position differs between ranges
};

struct RecordingFacts {
  std::vector<AnchorFacts> anchors;  // by id
  double t_begin = std::nan(""), t_end = std::nan("");
  double range_period_s = std::nan(""), shortest_period_s = std::nan("");
  double static_start_s = 0.0;  // the span the averaging was tested on (0: none)
  static constexpr int kMaxLag = 10;
  std::array<double, kMaxLag> autocorrelation{};  // lags 1..kMaxLag of the range differences
  std::size_t differences = 0;                    // most differences of one anchor on the span
  int range_average_samples = 1;
  bool averaging_detected = false;
  std::string averaging_note;  // how range_average_samples was decided
  // The static start's 3-D fit: the tag's height, the vertical sigma per metre of range sigma
  // (VDOP) and the fit's RMS residual; NaN when the start is under a second or the fit fails.
  double tag_height_m = std::nan(""), tag_height_vdop = std::nan(""), tag_height_rms_m = std::nan("");
  std::string tag_height_note;
};

inline constexpr double kStaticMoveM = 0.3;
inline constexpr double kStaticMarginS = 2.0;
inline constexpr std::size_t kMinDifferences = 40;

namespace detail {

inline double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  if (v.size() % 2 == 1) return *mid;
  return 0.5 * (*mid + *std::max_element(v.begin(), mid));
}

/// Mean autocorrelation of first differences over the anchors' grids, lags 1..kMaxLag, of the
/// anchors with at least kMinDifferences differences (NaN when none has).
inline void difference_autocorrelation(const std::map<int, std::map<long, double>>& grids, RecordingFacts& f) {
  f.autocorrelation.fill(0.0);
  f.differences = 0;
  int used = 0;
  for (const auto& [id, grid] : grids) {
    std::map<long, double> d;
    for (const auto& [k, r] : grid)
      if (const auto next = grid.find(k + 1); next != grid.end()) d[k] = next->second - r;
    f.differences = std::max(f.differences, d.size());
    if (d.size() < kMinDifferences) continue;
    double mean = 0.0;
    for (const auto& [k, e] : d) mean += e;
    mean /= static_cast<double>(d.size());
    double var = 0.0;
    for (auto& [k, e] : d) {
      e -= mean;
      var += e * e;
    }
    var /= static_cast<double>(d.size());
    if (!(var > 0.0)) continue;
    for (long lag = 1; lag <= RecordingFacts::kMaxLag; ++lag) {
      double c = 0.0;
      int pairs = 0;
      for (const auto& [k, e] : d)
        if (const auto other = d.find(k + lag); other != d.end()) {
          c += e * other->second;
          ++pairs;
        }
      f.autocorrelation[static_cast<std::size_t>(lag - 1)] += pairs > 0 ? (c / pairs) / var : 0.0;
    }
    ++used;
  }
  if (used == 0) {
    f.autocorrelation.fill(std::nan(""));
    return;
  }
  for (double& a : f.autocorrelation) a /= used;
}

/// The static start's 3-D fit of each anchor's median range (fills facts' tag_height_*).
template <class = void>
void fit_tag_height(const std::map<int, std::vector<const messages::UwbRange*>>& by_anchor, double t0, double t1,
                    RecordingFacts& f) {
  if (!(t1 - t0 >= 1.0)) {
    f.tag_height_note = "static start under 1 s: no height fit";
    return;
  }
  std::vector<messages::UwbRange> medians;
  for (const auto& [id, list] : by_anchor) {
    std::vector<double> r;
    for (const auto* x : list)
      if (x->t < t1) r.push_back(x->range_m);
    if (r.empty()) continue;
    messages::UwbRange m = *list.front();
    m.range_m = median(std::move(r));
    medians.push_back(m);
  }
  MultilaterationOptions o;
  o.sigma_m = 1.0;  // the covariance is then the dilution of precision squared
  const auto fit = multilaterate_3d(medians, o);
  if (!fit.ok()) {
    f.tag_height_note = std::string("no 3-D fit of the static start: ") + std::string(describe(fit.status.problem));
    return;
  }
  f.tag_height_m = fit.position.z();
  f.tag_height_vdop = std::sqrt(fit.cov(2, 2));
  f.tag_height_rms_m = fit.rms_m;
  f.tag_height_note = "3-D fit of " + std::to_string(medians.size()) + " anchors' median ranges over the static start";
}

}  // namespace detail

/// The recording's facts from its time-ordered ranges (see the header comment).
template <class = void>
RecordingFacts describe_recording(std::span<const messages::UwbRange> ranges) {
  RecordingFacts f;
  if (ranges.empty()) {
    f.averaging_note = "no ranges: raw assumed";
    return f;
  }
  f.t_begin = ranges.front().t;
  f.t_end = ranges.back().t;
  std::map<int, std::vector<const messages::UwbRange*>> by_anchor;
  for (const auto& r : ranges) by_anchor[r.anchor_id].push_back(&r);
  std::vector<double> periods;
  for (const auto& [id, list] : by_anchor) {
    AnchorFacts a;
    a.id = id;
    a.position = list.front()->anchor_position;
    a.ranges = list.size();
    std::vector<double> dt;
    for (std::size_t i = 1; i < list.size(); ++i) {
      dt.push_back(list[i]->t - list[i - 1]->t);
      a.moves = a.moves || list[i]->anchor_position != a.position;
    }
    a.median_interval_s = detail::median(std::move(dt));
    if (std::isfinite(a.median_interval_s) && a.median_interval_s > 0.0) periods.push_back(a.median_interval_s);
    f.anchors.push_back(a);
  }
  if (periods.empty()) {
    f.averaging_note = "no anchor with two ranges: raw assumed";
    return f;
  }
  f.range_period_s = detail::median(periods);
  f.shortest_period_s = *std::min_element(periods.begin(), periods.end());

  // The static start: no anchor's range, as the median of the last second, more than
  // kStaticMoveM from its first second's median.
  double moves = f.t_end;
  for (const auto& [id, list] : by_anchor) {
    std::vector<double> first;
    for (const auto* r : list)
      if (r->t <= f.t_begin + 1.0) first.push_back(r->range_m);
    const double m0 = detail::median(first);
    std::size_t lo = 0;
    for (std::size_t i = 0; i < list.size() && list[i]->t < moves; ++i) {
      while (list[lo]->t < list[i]->t - 1.0) ++lo;
      std::vector<double> window;
      for (std::size_t k = lo; k <= i; ++k) window.push_back(list[k]->range_m);
      if (std::abs(detail::median(std::move(window)) - m0) > kStaticMoveM) {
        moves = list[i]->t;
        break;
      }
    }
  }
  const double static_end = moves - kStaticMarginS;
  f.static_start_s = std::max(0.0, static_end - f.t_begin);
  detail::fit_tag_height(by_anchor, f.t_begin, static_end, f);
  std::map<int, std::map<long, double>> grids;
  for (const auto& [id, list] : by_anchor) {
    const double period = f.anchors[static_cast<std::size_t>(std::distance(by_anchor.begin(), by_anchor.find(id)))].median_interval_s;
    if (!(period > 0.0)) continue;
    for (const auto* r : list)
      if (r->t < static_end) grids[id][std::lround((r->t - f.t_begin) / period)] = r->range_m;
  }
  detail::difference_autocorrelation(grids, f);
  const auto& acf = f.autocorrelation;
  if (std::isnan(acf[0])) {
    f.averaging_note = "static start too short (" + std::to_string(f.differences) + " range differences on the best anchor, " +
                       std::to_string(kMinDifferences) + " needed): raw assumed";
    return f;
  }
  for (int lag = 1; lag <= RecordingFacts::kMaxLag; ++lag) {
    if (acf[static_cast<std::size_t>(lag - 1)] < -0.3) {
      f.range_average_samples = lag;
      f.averaging_detected = true;
      f.averaging_note = lag == 1 ? "raw reports (difference autocorrelation -0.5 at lag 1)"
                                  : "mean of " + std::to_string(lag) + " raw ranges (difference autocorrelation below -0.3 at lag " +
                                        std::to_string(lag) + ", within 0.15 of 0 below)";
      return f;
    }
    if (std::abs(acf[static_cast<std::size_t>(lag - 1)]) > 0.15) break;
  }
  f.averaging_note = "no moving-average signature in the range differences: raw assumed";
  return f;
}

/// Records the fixed-lag output's window needs to hold settings.smoothed_output_lag_s of the
/// recording (calibrated_ekf.hpp: one per accepted range, one per epoch's end): every anchor's
/// reports over the lag plus the epochs over it. A window with fewer records smooths over less
/// than the lag (its output is then less far behind).
inline double lag_records_needed(const RecordingFacts& facts, const Settings& s) {
  double per_second = 1.0 / s.range_period_s;  // epochs
  for (const auto& a : facts.anchors)
    if (a.median_interval_s > 0.0) per_second += 1.0 / a.median_interval_s;
  return per_second * s.smoothed_output_lag_s;
}

/// The window's size: the records needed with a quarter to spare (reports come early or late
/// by their jitter, and a missed report's neighbours do not close up), at least 8.
inline int lag_window_records(const RecordingFacts& facts, const Settings& s) {
  const double needed = lag_records_needed(facts, s);
  if (!std::isfinite(needed)) return s.lag_records;
  return std::max(8, static_cast<int>(std::ceil(1.25 * needed)) + 2);
}

/// The tag's height into s: `option_m` when finite ("option"); else the static start's fit
/// when its vertical sigma, VDOP x range_sigma_m, is at most tag_height_max_sigma_m ("static
/// start"); else s's own (default). Returns which, with the figures.
inline std::string choose_tag_height(const RecordingFacts& facts, Settings& s, double option_m) {
  if (std::isfinite(option_m)) {
    s.tag_height_m = option_m;
    return "option";
  }
  const double sigma = facts.tag_height_vdop * s.range_sigma_m;
  if (std::isfinite(facts.tag_height_m) && sigma <= s.tag_height_max_sigma_m) {
    s.tag_height_m = facts.tag_height_m;
    return "static start (vertical sigma " + std::to_string(sigma) + " m)";
  }
  if (std::isfinite(sigma))
    return "default: the static start's height fit (" + std::to_string(facts.tag_height_m) + " m) has a vertical sigma of " +
           std::to_string(sigma) + " m, above tag_height_max_sigma_m";
  return "default: " + facts.tag_height_note;
}

/// The pipeline's settings for a recording: `base` with the period, the epoch window and the
/// averaging from `facts` (range_average_samples from `average_override` when it is >= 1).
/// `problem` says why the recording cannot be run ("" when it can): fewer than 3 or more than
/// NlosClassifier::kMaxAnchors anchors, an anchor that moves, no report period. The tag's height
/// by choose_tag_height (tag_height_option_m: NaN for auto); `tag_height_source` gets its answer.
inline Settings settings_for_recording(const RecordingFacts& facts, Settings base, int average_override, std::string& problem,
                                       double tag_height_option_m = std::nan(""), std::string* tag_height_source = nullptr) {
  problem.clear();
  const int n = static_cast<int>(facts.anchors.size());
  if (n < 3 || n > NlosClassifier::kMaxAnchors)
    problem = "the recording has " + std::to_string(n) + " anchors; the pipeline takes 3 to " + std::to_string(NlosClassifier::kMaxAnchors);
  for (const auto& a : facts.anchors)
    if (a.moves && problem.empty()) problem = "anchor " + std::to_string(a.id) + " changes position during the recording";
  if (!(facts.range_period_s > 0.0) && problem.empty()) problem = "no anchor has two ranges: no report period";
  if (!problem.empty()) return base;
  base.range_period_s = facts.range_period_s;
  base.epoch_window_s = 0.5 * facts.shortest_period_s;
  base.range_average_samples = average_override >= 1 ? average_override : facts.range_average_samples;
  base.lag_records = lag_window_records(facts, base);
  const std::string source = choose_tag_height(facts, base, tag_height_option_m);
  if (tag_height_source) *tag_height_source = source;
  if (const SettingCheck c = base.check(); !c) problem = "settings: " + std::string(c.what);
  return base;
}

}  // namespace ctxfuse::pipelines::nlos_uwb
