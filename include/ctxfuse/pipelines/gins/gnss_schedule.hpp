// Which GNSS fixes the filter may use: decimation to a rate and simulated outages (windows in
// which every fix is withheld). Both are decided from the fixes' stamps alone; a withheld fix
// still marks an epoch of the forward pass (a trajectory row), it just updates nothing.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace ctxfuse::pipelines::gins {

struct OutageWindow {
  double start = 0.0;  // fixes with start <= t < end are withheld
  double end = 0.0;
  bool contains(double t) const { return t >= start && t < end; }
};

/// `length` s of outage every `period` s, the first `start_offset` s after the first GNSS
/// epoch, as long as a window ends at least `end_margin` s before the last epoch.
struct OutageSchedule {
  double length = 0.0;
  double period = 0.0;
  double start_offset = 0.0;
  double end_margin = 30.0;
  bool enabled() const { return length > 0.0 && period > 0.0; }
};

inline std::vector<OutageWindow> outage_windows(const OutageSchedule& s, double first_t, double last_t) {
  std::vector<OutageWindow> out;
  if (!s.enabled() || !std::isfinite(first_t) || !std::isfinite(last_t)) return out;
  for (int k = 0;; ++k) {
    const double start = first_t + s.start_offset + k * s.period;
    const double end = start + s.length;
    if (end > last_t - s.end_margin + 1e-9) break;
    out.push_back({start, end});
  }
  return out;
}

inline bool in_any(const std::vector<OutageWindow>& w, double t) {
  for (const auto& o : w)
    if (o.contains(t)) return true;
  return false;
}

/// Decimation to `rate_hz` (0 or less: every fix), online over the fixes in time order: the
/// first fix is kept, then each fix at least one period (less 10 %, for stamp jitter) after
/// the last kept one. Run over all fixes before outages are applied, so that an outage does not
/// shift the kept epochs after it.
class Decimator {
 public:
  explicit Decimator(double rate_hz = 0.0) : min_gap_(rate_hz > 0.0 ? 0.9 / rate_hz : 0.0) {}
  bool keep(double t) {
    if (min_gap_ > 0.0 && t - last_ < min_gap_) return false;
    last_ = t;
    return true;
  }

 private:
  double min_gap_ = 0.0;
  double last_ = -INFINITY;
};

}  // namespace ctxfuse::pipelines::gins
