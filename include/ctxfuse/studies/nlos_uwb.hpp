// Scoring of the NLOS-robust UWB pipeline on the Hanyang recordings (truth lives here only;
// the authors' RMSE protocol is in studies/hanyang_protocol.hpp):
// - residual labels of the ranges: NLOS when a range exceeds the distance from the reference
//   (tag at reference + tag height) to the anchor by more than label_sigma_multiple sigmas;
// - precision / recall / accuracy of the SVM (p1 > 0.5), consistency (p2 > 0.5) and D-S
//   (R > threshold) decisions against those labels;
// - the SVM's training rows from other recordings (never the one being scored).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string_view>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/core/error.hpp"
#include "ctxfuse/classify/confusion_matrix.hpp"
#include "ctxfuse/studies/hanyang_protocol.hpp"
#include "ctxfuse/io/hanyang_uwb.hpp"
#include "ctxfuse/pipelines/nlos_uwb/calibrated_ekf.hpp"
#include "ctxfuse/pipelines/nlos_uwb/training.hpp"
#include "ctxfuse/pipelines/nlos_uwb/run.hpp"
#include "ctxfuse/pipelines/nlos_uwb/smoother.hpp"

namespace ctxfuse::studies {

inline std::vector<TimedPoint2> timed_points(const pipelines::nlos_uwb::Track& track) {
  std::vector<TimedPoint2> out;
  out.reserve(track.estimates.size());
  for (const auto& e : track.estimates) out.push_back({e.t, e.position});
  return out;
}

/// Reference position at t (linear interpolation); NaN outside the reference's time span.
inline Eigen::Vector3d reference_at(std::span<const io::HanyangReferencePose> ref, double t) {
  if (ref.empty() || t < ref.front().t || t > ref.back().t) return Eigen::Vector3d::Constant(std::nan(""));
  const auto it = std::lower_bound(ref.begin(), ref.end(), t, [](const io::HanyangReferencePose& p, double v) { return p.t < v; });
  if (it == ref.begin()) return it->position;
  const auto& b = *it;
  const auto& a = *(it - 1);
  const double w = (t - a.t) / (b.t - a.t);
  return (1.0 - w) * a.position + w * b.position;
}

/// Range minus the reference distance (tag at reference + (0, 0, tag height)); NaN outside.
inline double range_residual(const messages::UwbRange& r, std::span<const io::HanyangReferencePose> ref, double tag_height_m) {
  Eigen::Vector3d p = reference_at(ref, r.t);
  p.z() += tag_height_m;
  return r.range_m - (p - r.anchor_position).norm();
}

/// -1 unlabelled (outside the reference), else kNlosLabel / kLosLabel.
inline int residual_label(const messages::UwbRange& r, std::span<const io::HanyangReferencePose> ref,
                          const pipelines::nlos_uwb::Settings& s) {
  const double e = range_residual(r, ref, s.tag_height_m);
  if (std::isnan(e)) return -1;
  return e > s.label_sigma_multiple * s.range_sigma_m ? pipelines::nlos_uwb::kNlosLabel : pipelines::nlos_uwb::kLosLabel;
}

struct Identification {
  double precision = std::nan(""), recall = std::nan(""), accuracy = std::nan("");
  std::size_t scored = 0, labelled_nlos = 0;
};

inline Identification identification_of(const classify::ConfusionMatrix& m) {
  return {m.precision(1), m.recall(1), m.accuracy(), m.total(), m.support(1)};
}

struct IdentificationReport {
  Identification svm, consistency, ds;
};

/// Scores the verdicts of a run against residual labels (ranges where a classifier gave no
/// evidence are not scored for it).
template <class = void>
IdentificationReport identification(const pipelines::nlos_uwb::Track& track, std::span<const io::HanyangReferencePose> ref,
                                    const pipelines::nlos_uwb::Settings& s) {
  classify::ConfusionMatrix svm(2), cons(2), ds(2);
  for (const auto& rec : track.ranges) {
    const int y = residual_label(rec.range, ref, s);
    if (y < 0) continue;
    const auto& v = rec.verdict;
    if (!std::isnan(v.p1)) svm.add(y, v.p1 > 0.5);
    if (!std::isnan(v.p2)) cons.add(y, v.p2 > 0.5);
    if (!std::isnan(v.R)) ds.add(y, v.nlos);
  }
  return {identification_of(svm), identification_of(cons), identification_of(ds)};
}

/// The SVM's training rows of one recording: the pipeline's own features (the EKF without NLOS
/// handling supplies v_i, as at run time) with residual labels from that recording's reference.
template <class = void>
void append_svm_rows(const std::filesystem::path& case_dir, const pipelines::nlos_uwb::Settings& s,
                     pipelines::nlos_uwb::LabelledSvmRows& rows) {
  namespace nu = pipelines::nlos_uwb;
  const auto ranges = io::read_hanyang_uwb(case_dir).uwb_ranges();
  const auto ref = io::read_hanyang_reference(case_dir);
  const nu::Track track = nu::run(std::span<const messages::UwbRange>(ranges), nu::RangeEkf<>(s),
                                  nu::NlosPolicyChoice{nu::NlosHandling::none}, nu::NlosClassifier(s), s);
  for (const auto& rec : track.ranges) {
    const int y = residual_label(rec.range, ref, s);
    if (y < 0 || !rec.input.finite()) continue;
    rows.inputs.push_back(rec.input);
    rows.labels.push_back(y);
  }
}

/// The other dynamic cases of the dataset that holds `case_dir` (.../{LOS,NLOS}/Trajectory_*/
/// Case_*): every sibling case folder with a trajectory.csv, `case_dir` itself excluded. Empty
/// when `case_dir` is not laid out so (a Case_* folder in a Trajectory_* folder).
inline std::vector<std::filesystem::path> other_hanyang_cases(const std::filesystem::path& case_dir) {
  namespace fs = std::filesystem;
  const fs::path self = fs::weakly_canonical(case_dir);
  const fs::path root = self.parent_path().parent_path().parent_path();
  std::vector<fs::path> out;
  if (!self.filename().string().starts_with("Case_") || !self.parent_path().filename().string().starts_with("Trajectory_") ||
      !fs::is_directory(root))
    return out;
  for (const auto& cond : fs::directory_iterator(root)) {
    if (!cond.is_directory()) continue;
    for (const auto& traj : fs::directory_iterator(cond.path())) {
      if (!traj.is_directory()) continue;
      for (const auto& c : fs::directory_iterator(traj.path()))
        if (c.is_directory() && fs::exists(c.path() / "trajectory.csv") && fs::weakly_canonical(c.path()) != self)
          out.push_back(c.path());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// The SVM trained on `cases` (none of them the scored one: the caller's split).
template <class = void>
pipelines::nlos_uwb::NlosSvm train_svm_on_cases(std::span<const std::filesystem::path> cases,
                                                const pipelines::nlos_uwb::Settings& s) {
  pipelines::nlos_uwb::LabelledSvmRows rows;
  for (const auto& c : cases) append_svm_rows(c, s, rows);
  return pipelines::nlos_uwb::train_nlos_svm(rows, s);
}

}  // namespace ctxfuse::studies

namespace ctxfuse::studies {

/// One estimator/policy combination run on a case and scored with the authors' protocol.
struct NlosUwbVariant {
  std::string name;
  pipelines::nlos_uwb::Track track;
  ProtocolRmse rmse;
};

struct NlosUwbCaseReport {
  std::vector<std::filesystem::path> training_cases;  // the SVM's (never the scored case)
  bool svm = false;
  double svm_gamma = std::nan("");  // the trained SVM's RBF gamma (standardised features)
  std::vector<NlosUwbVariant> variants;               // see evaluate_nlos_uwb_case
  IdentificationReport identification;                // of the paper's pipeline (first variant)
  std::map<std::string, double> authors;              // RMSD_results.txt, when the case has it

  const NlosUwbVariant& variant(std::string_view name) const {
    for (const auto& v : variants)
      if (v.name == name) return v;
    throw std::invalid_argument("no variant " + std::string(name));
  }
};

inline constexpr std::array<std::string_view, 17> kNlosUwbVariants{
    "ekf_gate_paper_rule",  // the paper's pipeline: EKF + innovation gate + the epoch attach rule
    "ekf_gate_per_range",   // the per-range extension
    "ekf_gate",             // innovation gate only, no NLOS classification in the loop
    // The self-calibrating EKF (pipelines/nlos_uwb/calibrated_ekf.hpp: anchor biases, the
    // averaged report's time), newest state, and its fixed-lag output (smoothed_output_lag_s).
    "calibrated_ekf_gate_paper_rule",
    "calibrated_ekf_gate_per_range",
    "calibrated_ekf_gate",
    "calibrated_ekf_gate_paper_rule_lag",
    "calibrated_ekf_gate_per_range_lag",
    "calibrated_ekf_gate_lag",
    "smoother_gate_paper_rule",  // the fixed-lag smoother (10 states), newest state
    "smoother_gate",             // the same without the NLOS rule
    "smoother_gate_lag9",        // the same, the state 9 epochs back (0.9 s late)
    "smoother_gate_paper_rule_lag9",
    "ekf_paper_rule",       // the epoch rule without the innovation gate
    "ekf",                  // neither: every range enters
    "least_squares",        // snapshot LS per epoch
    "motion_model_only"};   // the "IMU only" baseline: the motion model from the first fix

namespace detail {

/// run_nlos_uwb_variant's body, a template only so that the compiled target ctxfuse::instances
/// can hold its one instance (void; instances/nlos_uwb.hpp): it instantiates every estimator
/// of the variants (the policy is a run-time NlosPolicyChoice).
template <class = void>
pipelines::nlos_uwb::Track run_nlos_uwb_variant(std::size_t index, std::span<const messages::UwbRange> rs,
                                                const pipelines::nlos_uwb::NlosClassifier& classifier,
                                                const pipelines::nlos_uwb::Settings& s) {
  namespace nu = pipelines::nlos_uwb;
  using Calibrated = nu::CalibratedRangeEkf<policies::ChiSquareGate, false, nu::NlosClassifier::kMaxAnchors>;
  using CalibratedLag = nu::CalibratedRangeEkf<policies::ChiSquareGate, true, nu::NlosClassifier::kMaxAnchors>;
  using Lagged = nu::RangeSmoother<10, policies::ChiSquareGate, 9>;
  // The policy is a run-time choice: one run loop per estimator, not per estimator and policy.
  constexpr nu::NlosPolicyChoice paper{nu::NlosHandling::paper_epoch_rule}, per_range{nu::NlosHandling::per_range},
      every{nu::NlosHandling::none};
  switch (index) {
    case 0: return nu::run(rs, nu::RangeEkf<>(s), paper, classifier, s);
    case 1: return nu::run(rs, nu::RangeEkf<>(s), per_range, classifier, s);
    case 2: return nu::run(rs, nu::RangeEkf<>(s), every, classifier, s);
    case 3: return nu::run(rs, Calibrated(s), paper, classifier, s);
    case 4: return nu::run(rs, Calibrated(s), per_range, classifier, s);
    case 5: return nu::run(rs, Calibrated(s), every, classifier, s);
    case 6: return nu::run(rs, CalibratedLag(s), paper, classifier, s);
    case 7: return nu::run(rs, CalibratedLag(s), per_range, classifier, s);
    case 8: return nu::run(rs, CalibratedLag(s), every, classifier, s);
    case 9: return nu::run(rs, nu::RangeSmoother<>(s), paper, classifier, s);
    case 10: return nu::run(rs, nu::RangeSmoother<>(s), every, classifier, s);
    case 11: return nu::run(rs, Lagged(s), every, classifier, s);
    case 12: return nu::run(rs, Lagged(s), paper, classifier, s);
    case 13: return nu::run(rs, nu::RangeEkf<policies::NoGate>(s), paper, classifier, s);
    case 14: return nu::run(rs, nu::RangeEkf<policies::NoGate>(s), every, classifier, s);
    case 15: return nu::least_squares_track(rs, s);
    case 16: return nu::run(rs, nu::MotionModelOnly(s), every, classifier, s);
    default: throw std::invalid_argument("no variant " + std::to_string(index));
  }
}

}  // namespace detail

/// Runs one variant of kNlosUwbVariants (by index) on `rs`. No reference is involved.
template <class = void>
pipelines::nlos_uwb::Track run_nlos_uwb_variant(std::size_t index, std::span<const messages::UwbRange> rs,
                                                const pipelines::nlos_uwb::NlosClassifier& classifier,
                                                const pipelines::nlos_uwb::Settings& s) {
  return detail::run_nlos_uwb_variant<>(index, rs, classifier, s);
}

/// Runs the variants named in `names` (every one of kNlosUwbVariants, in that order, when
/// empty) on `rs` with `classifier`; nothing is scored (rmse NaN). Throws std::invalid_argument
/// for an unknown name or settings that do not validate.
template <class = void>
std::vector<NlosUwbVariant> run_nlos_uwb_variants(std::span<const messages::UwbRange> rs,
                                                  const pipelines::nlos_uwb::NlosClassifier& classifier,
                                                  const pipelines::nlos_uwb::Settings& s,
                                                  std::span<const std::string_view> names = {}) {
  ctxfuse::detail::require_setting(s.check(), "settings");
  std::vector<NlosUwbVariant> out;
  auto add = [&](std::size_t i) { out.push_back({std::string(kNlosUwbVariants[i]), run_nlos_uwb_variant(i, rs, classifier, s), {}}); };
  if (names.empty())
    for (std::size_t i = 0; i < kNlosUwbVariants.size(); ++i) add(i);
  for (std::string_view n : names) {
    const auto it = std::find(kNlosUwbVariants.begin(), kNlosUwbVariants.end(), n);
    if (it == kNlosUwbVariants.end()) throw std::invalid_argument("no variant " + std::string(n));
    add(static_cast<std::size_t>(it - kNlosUwbVariants.begin()));
  }
  return out;
}

/// Scores every variant against `reference` with protocol `p` (fills each one's rmse).
inline void score_nlos_uwb_variants(std::vector<NlosUwbVariant>& variants, std::span<const io::HanyangReferencePose> reference,
                                    const ScoringProtocol& p) {
  for (auto& v : variants) v.rmse = score_2d(timed_points(v.track), reference, p);
}

/// Runs every variant on the case in `case_dir` with the SVM trained on `training_cases`
/// (none: p1 absent, R = p2), and scores each against the case's reference with the authors'
/// protocol on `span`. Throws std::invalid_argument when a training case is the scored one or
/// the reference does not fit the span, io::ParseError on bad files.
template <class = void>
NlosUwbCaseReport evaluate_nlos_uwb_case(const std::filesystem::path& case_dir,
                                         std::span<const std::filesystem::path> training_cases,
                                         const pipelines::nlos_uwb::Settings& s, const HanyangSpan& span) {
  namespace nu = pipelines::nlos_uwb;
  namespace fs = std::filesystem;
  ctxfuse::detail::require_setting(s.check(), "settings");
  NlosUwbCaseReport rep;
  for (const auto& c : training_cases)
    if (fs::weakly_canonical(c) == fs::weakly_canonical(case_dir))
      throw std::invalid_argument("the scored case " + case_dir.string() + " is among the SVM's training cases");
  const auto ranges = io::read_hanyang_uwb(case_dir).uwb_ranges();
  const auto ref = io::read_hanyang_reference(case_dir);
  if (const SpanBounds b = find_span(ref, span); !b.problem.empty()) throw std::invalid_argument("hanyang_rmse_2d: " + b.problem);
  rep.training_cases.assign(training_cases.begin(), training_cases.end());
  std::optional<nu::NlosSvm> svm;
  if (!training_cases.empty()) svm = train_svm_on_cases(training_cases, s);
  rep.svm = svm.has_value();
  if (svm) rep.svm_gamma = svm->gamma;
  rep.variants = run_nlos_uwb_variants(ranges, nu::NlosClassifier(s, svm), s);
  ScoringProtocol p;
  p.name = "custom";
  p.span = span;
  score_nlos_uwb_variants(rep.variants, ref, p);
  rep.identification = identification(rep.variants.front().track, ref, s);
  if (fs::exists(case_dir / "RMSD_results.txt")) rep.authors = read_hanyang_rmsd(case_dir / "RMSD_results.txt");
  return rep;
}

}  // namespace ctxfuse::studies
