// `ctxfuse score --estimate TRAJ.csv --reference trajectory.csv [--span a|b|auto|none|START/END]
// [--json FILE]`: scores any trajectory CSV against a Hanyang reference, as trajectory
// evaluation tools do. The estimate is ours (`run uwb --out`: time_ns,x,y,z) or another tool's
// with a `timestamp` [ns] column (the dataset authors' LS.csv, ESKF.csv); the protocol is the
// authors' on a span (studies/hanyang_protocol.hpp) or the plain whole-run 2-D RMSE. A span the
// reference does not fit is a warning and the whole run is scored. Parsing and formatting only.
#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include "cli/formatted.hpp"
#include "cli/json.hpp"
#include "cli/options.hpp"
#include "cli/registry.hpp"
#include "ctxfuse/studies/hanyang_protocol.hpp"

namespace ctxfuse::cli {
namespace {

int score_command(Args args, std::ostream& out, std::ostream& err) {
  auto app = make_app("score",
                      "Scores a trajectory CSV (time_ns or timestamp [ns], x, y [m]) against a reference (Hanyang trajectory.csv):\n"
                      "the 2-D RMSE with the dataset authors' protocol on a span (reference samples with |z| >= 0.5 m dropped,\n"
                      "the rest interpolated to each estimate's time), or over the whole run.");
  std::string estimate, reference, span = "auto", json;
  app.add_option("--estimate", estimate, "trajectory to score (ctxfuse run uwb --out, or LS.csv / ESKF.csv)")->required()->check(CLI::ExistingFile);
  app.add_option("--reference", reference, "the reference (Hanyang trajectory.csv: timestamp,x,y,z,heading_degrees)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--span", span,
                 "a or b (the authors' span of trajectory A or B), auto (the one whose gates the reference passes, else the "
                 "whole run), none (whole run), or START/END gates like x>49.3,y>-5/x<=12,y>3.4")
      ->check(CLI::Validator(
          [](std::string& s) {
            if (s == "a" || s == "b" || s == "auto" || s == "none") return std::string();
            ctxfuse::studies::HanyangSpan parsed;
            return ctxfuse::studies::parse_hanyang_span(s, parsed);
          },
          "SPAN", "span"));
  app.add_option("--json", json, "write the score as JSON");
  if (const auto rc = parse_options(app, args, out, err)) return *rc;
  std::vector<ctxfuse::studies::TimedPoint2> est;
  std::vector<io::HanyangReferencePose> ref;
  ctxfuse::studies::ScoringProtocol p;
  ctxfuse::studies::ProtocolRmse r;
  std::vector<double> errors;
  try {
    est = ctxfuse::studies::read_hanyang_estimates(estimate);
    ref = io::read_hanyang_reference_file(reference);
    p = ctxfuse::studies::choose_protocol(span, ref);
    r = ctxfuse::studies::score_2d(est, ref, p, &errors);
  } catch (const std::exception& e) {
    err << "ctxfuse score: " << e.what() << '\n';
    return 1;
  }
  if (!p.warning.empty()) err << "ctxfuse score: warning: " << p.warning << '\n';
  std::erase_if(errors, [](double e) { return std::isnan(e); });
  const double max_error = errors.empty() ? std::nan("") : *std::max_element(errors.begin(), errors.end());
  double mean = 0.0;
  for (double e : errors) mean += e / static_cast<double>(errors.size());
  out << "score of " << estimate << " against " << reference << ": "
      << (p.span ? "authors' protocol, span " + p.name + " (" + ctxfuse::studies::describe(p.span->start) + " to " + ctxfuse::studies::describe(p.span->end) + ")"
                 : std::string("whole run"))
      << '\n'
      << formatted("  2-D RMSE %.4f m, mean %.4f m, max %.4f m over %zu of %zu estimates (%.3f s to %.3f s of the reference)\n",
                   r.rmse_2d, errors.empty() ? std::nan("") : mean, max_error, r.scored, est.size(), r.t_begin - ref.front().t,
                   r.t_end - ref.front().t);
  if (!json.empty()) {
    Json doc;
    doc["estimate"] = estimate;
    doc["reference"] = reference;
    doc["protocol"] = p.name;
    if (p.span) doc["span"] = ctxfuse::studies::describe(p.span->start) + "/" + ctxfuse::studies::describe(p.span->end);
    doc["warning"] = p.warning;
    doc["rmse_2d_m"] = r.rmse_2d;
    doc["mean_2d_m"] = errors.empty() ? std::nan("") : mean;
    doc["max_2d_m"] = max_error;
    doc["scored"] = static_cast<double>(r.scored);
    doc["estimates"] = static_cast<double>(est.size());
    doc["t_begin"] = r.t_begin;
    doc["t_end"] = r.t_end;
    if (!write_json_file(doc, json, "score", err)) return 1;
  }
  return 0;
}

const RegisterCommand reg_score{{"score", "score a trajectory CSV against a reference (authors' span protocol or whole run)", score_command}};

}  // namespace
}  // namespace ctxfuse::cli
