// JSON of the GNSS/INS study's error statistics (eval/gins_sim_study.hpp), shared by
// `ctxfuse gins-study` and the demo's scene_gins / phone_gins sections.
#pragma once

#include "cli/json.hpp"
#include "ctxfuse/eval/gins_sim_study.hpp"

namespace ctxfuse::cli {

inline Json gins_errors_json(const eval::HorizontalErrors& e) {
  Json j;
  j["n"] = static_cast<double>(e.n);
  j["rms_m"] = e.rms;
  j["p67_m"] = e.p67;
  j["p75_m"] = e.p75;
  j["max_m"] = e.max;
  return j;
}

/// One scheme with one noise policy into `j`: the whole drive, the part with GNSS, the garage,
/// the fixes used and gated.
inline void add_gins_run_json(const eval::GinsSimRun& r, Json& j) {
  j["all"] = gins_errors_json(r.all);
  j["with_gnss"] = gins_errors_json(r.with_gnss);
  j["indoor"] = gins_errors_json(r.indoor);
  j["fixes_used"] = static_cast<double>(r.fixes_used);
  j["fixes_gated"] = static_cast<double>(r.fixes_gated);
}

}  // namespace ctxfuse::cli
