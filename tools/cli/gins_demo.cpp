// `ctxfuse demo` sections "scene_gins" (paper B) and "phone_gins" (paper D): the GNSS/INS study
// of studies/gins_sim_study.hpp on the demo's drive, beside the papers' figures. One study serves
// both sections: scheme (a) with fixed, scene-adaptive (classifier) and true-scene R is paper
// B's comparison; schemes (a)-(d), and the ZIHR variants, are paper D's. docs/results.md
// (section gins_sim) explains the rows; `ctxfuse gins-study` prints the same study per seed.
#include <memory>
#include <ostream>
#include <string>
#include <string_view>

#include "cli/formatted.hpp"
#include "cli/gins_study.hpp"
#include "cli/registry.hpp"

namespace ctxfuse::cli {
namespace {

/// The study of the drive the demo runs (both sections see the same drive object).
const ctxfuse::studies::GinsSimStudy& study_for(const sim::Drive& d) {
  static const sim::Drive* cached_for = nullptr;
  static std::unique_ptr<ctxfuse::studies::GinsSimStudy> cached;
  if (!cached || cached_for != &d) {
    cached = std::make_unique<ctxfuse::studies::GinsSimStudy>(gins_study_of(d));
    cached_for = &d;
  }
  return *cached;
}

const ctxfuse::studies::GinsSimRun* find_run(const ctxfuse::studies::GinsSimStudy& st, std::string_view scheme_prefix, std::string_view noise) {
  for (const auto& r : st.runs)
    if (r.scheme.name.starts_with(scheme_prefix) && r.noise == noise) return &r;
  return nullptr;
}

struct NoiseRow {
  const char* noise;  // the study's name
  const char* key;    // JSON
};
constexpr NoiseRow kNoises[] = {{"fixed", "fixed"}, {"scene (classifier)", "scene_classifier"}, {"scene (true)", "scene_true"}};

// Paper B: the scene-adaptive R of eq. 20-21 against a fixed R, horizontal error at 67 %.
void scene_gins_section(const DemoContext& ctx, Json& j, std::ostream& out) {
  const ctxfuse::studies::GinsSimStudy& st = study_for(*ctx.drive);
  out << formatted("  GNSS/INS (simplified strapdown, 15 states + the odometer's scale error, fixes at 1 Hz, 99.9 %% gate),\n"
                   "  forward filter; horizontal error at the 1 Hz truth epochs of the whole drive (the garage has no fix).\n"
                   "  Scene classifier (linear SVM, 8 features, Platt, trained on seeds N+101..N+103): %.2f %% of the epochs\n"
                   "  right (paper: 90.3 %%)\n",
                   100.0 * st.scene_accuracy);
  out << "  R                      | 67 % [m]  RMS [m]   max [m]   | RMS GNSS  RMS garage | fixes used/gated/released | paper 67 % [m]\n";
  j["scene_accuracy"] = st.scene_accuracy;
  j["paper_scene_accuracy"] = 0.903;
  const double paper[] = {11.23, 8.59, -1.0};
  for (std::size_t i = 0; i < std::size(kNoises); ++i) {
    const ctxfuse::studies::GinsSimRun* r = find_run(st, "(a)", kNoises[i].noise);
    if (!r) continue;
    out << formatted("  %-22s | %-9.2f %-9.2f %-9.2f | %-9.2f %-10.2f | %5d/%d/%-14d | %s\n", kNoises[i].noise, r->all.p67, r->all.rms,
                     r->all.max, r->with_gnss.rms, r->indoor.rms, r->fixes_used, r->fixes_gated, r->fixes_released,
                     paper[i] > 0 ? formatted("%.2f", paper[i]).c_str() : "(oracle)");
    Json& row = j["gnss_ins"][kNoises[i].key];
    add_gins_run_json(*r, row);
    if (paper[i] > 0) row["paper_p67_m"] = paper[i];
  }
}

struct PaperScheme {
  const char* prefix;  // the study's scheme name starts with it
  const char* key;
  double p75, rms;     // paper D, horizontal [m]; negative: not in the paper
};
constexpr PaperScheme kPaperSchemes[] = {{"(a)", "a_gnss_ins", 131.52, 669.86},
                                         {"(b)", "b_rts", 24.21, 42.90},
                                         {"(c)", "c_constraints", 16.76, 17.44},
                                         {"(d)", "d_constraints_rts", 7.09, 11.34},
                                         {"(c')", "c_constraints_zihr", -1.0, -1.0},
                                         {"(d')", "d_constraints_zihr_rts", -1.0, -1.0}};

// Paper D: (a) GNSS/INS, (b) + RTS, (c) + ZUPT/NHC with the odometer's speed, (d) + both.
void phone_gins_section(const DemoContext& ctx, Json& j, std::ostream& out) {
  const ctxfuse::studies::GinsSimStudy& st = study_for(*ctx.drive);
  out << formatted("  The same filter with ZUPT while static, NHC + odometer speed (scale error estimated) while moving (10 Hz),\n"
                   "  RTS over 10 Hz records.\n"
                   "  Static while moving: raw-IMU detector %.2f %%, with the odometer (the decision used) %.2f %% of the samples\n",
                   100.0 * st.false_static_share, 100.0 * st.false_static_share_odometer);
  out << "  scheme                              | R                  | 75 % [m]  RMS [m]   max [m]   | RMS garage | paper 75 % / RMS [m]\n";
  j["false_static_share"] = st.false_static_share;
  j["false_static_share_odometer"] = st.false_static_share_odometer;
  for (const auto& p : kPaperSchemes) {
    for (std::size_t i = 0; i < 2; ++i) {  // fixed and the classifier's scene R
      const ctxfuse::studies::GinsSimRun* r = find_run(st, p.prefix, kNoises[i].noise);
      if (!r) continue;
      out << formatted("  %-35s | %-18s | %-9.2f %-9.2f %-9.2f | %-10.2f | %s\n", r->scheme.name.c_str(), kNoises[i].noise, r->all.p75,
                       r->all.rms, r->all.max, r->indoor.rms,
                       p.p75 > 0 && i == 0 ? formatted("%.2f / %.2f", p.p75, p.rms).c_str() : "");
      Json& row = j["schemes"][p.key][kNoises[i].key];
      add_gins_run_json(*r, row);
    }
    if (p.p75 > 0) {
      j["schemes"][p.key]["paper_p75_m"] = p.p75;
      j["schemes"][p.key]["paper_rms_m"] = p.rms;
    }
  }
}

const RegisterDemoSection reg_scene{{"scene_gins", "Scene-adaptive GNSS/INS (paper B)", scene_gins_section}};
const RegisterDemoSection reg_phone{{"phone_gins", "Smartphone GNSS/INS with vehicle constraints (paper D)", phone_gins_section}};

}  // namespace
}  // namespace ctxfuse::cli
