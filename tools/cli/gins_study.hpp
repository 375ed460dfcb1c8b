// The GNSS/INS study (studies/gins_sim_study.hpp) as `ctxfuse gins-study` (gins_study.cpp) and the
// demo's scene_gins / phone_gins sections (gins_demo.cpp) share it: the study of one drive,
// compiled once in gins_study.cpp (its instantiation costs a minute of compile CPU), and the
// JSON of its error statistics.
#pragma once

#include "cli/json.hpp"
#include "ctxfuse/instances/gins_sim_study.hpp"

namespace ctxfuse::cli {

/// ctxfuse::studies::gins_sim_study on `drive` (defined in gins_study.cpp).
ctxfuse::studies::GinsSimStudy gins_study_of(const sim::Drive& drive, const ctxfuse::studies::GinsSimSettings& settings = {});

inline Json gins_errors_json(const ctxfuse::studies::HorizontalErrors& e) {
  Json j;
  j["n"] = static_cast<double>(e.n);
  j["rms_m"] = e.rms;
  j["p67_m"] = e.p67;
  j["p75_m"] = e.p75;
  j["max_m"] = e.max;
  return j;
}

/// One scheme with one noise policy into `j`: the whole drive, the part with GNSS, the garage,
/// the fixes used, gated and released (of those used), the forward filter's odometer scale error at the end.
inline void add_gins_run_json(const ctxfuse::studies::GinsSimRun& r, Json& j) {
  if (r.scheme.smooth) j["smoothed"] = r.smoothed;
  j["speed_scale"] = r.speed_scale;
  j["speed_scale_sigma"] = r.speed_scale_sigma;
  j["all"] = gins_errors_json(r.all);
  j["with_gnss"] = gins_errors_json(r.with_gnss);
  j["indoor"] = gins_errors_json(r.indoor);
  j["fixes_used"] = static_cast<double>(r.fixes_used);
  j["fixes_gated"] = static_cast<double>(r.fixes_gated);
  j["fixes_released"] = static_cast<double>(r.fixes_released);
}

}  // namespace ctxfuse::cli
