// The core of examples/nlos_classifier.cpp: the per-range NLOS decision of the UWB paper built
// from the library's classifier parts: an RBF SVM read from a libsvm model file (p1), the
// consistency check of a range's change against the distance travelled (p2), their
// Dempster-Shafer combination R and the decision R > 0.8. tests/examples/
// nlos_classifier_example_test.cpp checks every number against libsvm itself and the paper's
// formulas written out by hand. docs/classifiers.md walks through this file.
#pragma once

#include <Eigen/Core>

#include <array>
#include <sstream>
#include <string>
#include <vector>

#include "ctxfuse/classify/consistency.hpp"
#include "ctxfuse/classify/dempster_shafer.hpp"
#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_io.hpp"

namespace nlos_classifier {
using namespace ctxfuse;

// A small two-class RBF model in libsvm's text format, written by hand for this example (it is
// not trained: a trained one comes from libsvm's svm-train, or from `ctxfuse classify train`).
// Features: the range rate v_u [m/s] and the vehicle speed v_i [m/s]; label 1 is NLOS, 0 LOS.
// Its support vectors say what the paper's SVM learns: a range that changes faster than the
// vehicle moves is NLOS.
inline constexpr const char* kModel =
    "svm_type c_svc\n"
    "kernel_type rbf\n"
    "gamma 0.5\n"
    "nr_class 2\n"
    "total_sv 6\n"
    "rho 0.12\n"
    "label 1 0\n"
    "probA -2.1\n"
    "probB 0.05\n"
    "nr_sv 3 3\n"
    "SV\n"
    "1 1:2.5 2:0.5 \n"
    "1 1:-2.0 2:1.0 \n"
    "0.6 1:3.0 2:2.0 \n"
    "-1 1:0.2 2:1.5 \n"
    "-1 1:-0.3 2:0.4 \n"
    "-0.6 1:0.5 2:3.0 \n";

inline constexpr int kNlos = 1;

using Model = classify::SvmModel<2, 2>;  // 2 features, at most 2 classes

struct Range {
  const char* what;
  double range_rate;      // v_u [m/s]
  double speed;           // v_i [m/s]
  double range_change;    // d_rho since the anchor's previous range [m]
  double travelled;       // d_d, the vehicle's distance in that time [m]
};

struct Verdict {
  Range range;
  classify::SvmPrediction<2> svm;  // decision value and both class probabilities
  double p1 = 0.0;                 // SVM: P(NLOS)
  double p2 = 0.0;                 // consistency check: P(NLOS)
  classify::DsResult ds;           // R = ds.nlos_belief()
  bool nlos = false;
};

/// Reads kModel as a file would be read (the source name appears in any error).
inline Model load_model() {
  std::istringstream in(kModel);
  return classify::read_libsvm_model<2, 2>(in, "nlos_classifier example model");
}

/// Ranges of one anchor a second apart, each with the SVM's features and the consistency
/// check's inputs.
inline std::vector<Range> ranges() {
  return {
      {"steady approach", -0.9, 1.0, -0.92, 1.0},
      {"standing still", 0.02, 0.0, 0.03, 0.0},
      {"jump of 2.4 m", 2.4, 0.5, 2.4, 0.5},
      {"slow drift", 0.35, 0.2, 0.37, 0.2},
      {"fast, consistent", 2.8, 3.0, 2.8, 3.0},
      {"back from a jump", -2.3, 0.5, -2.3, 0.5},
  };
}

inline std::vector<Verdict> run() {
  const Model model = load_model();  // throws classify::SvmFileError on a malformed file
  const classify::ConsistencyModel consistency;  // the paper's steps: sigma 0.10 m, p 0.35..0.90
  const classify::NlosDecisionRule decide;       // NLOS when R > 0.8
  const int nlos_index = model.labels[0] == kNlos ? 0 : 1;  // probabilities are in label order
  std::vector<Verdict> out;
  for (const Range& r : ranges()) {
    Verdict v;
    v.range = r;
    // Non-finite features are refused with a status, nothing computed.
    if (!classify::svm_predict(model, Eigen::Vector2d(r.range_rate, r.speed), v.svm)) continue;
    v.p1 = v.svm.probabilities[static_cast<std::size_t>(nlos_index)];
    v.p2 = consistency.nlos_probability(r.range_change, r.travelled);
    v.ds = classify::combine_probabilities(v.p1, v.p2);
    v.nlos = v.ds.status.accepted() && decide(v.ds.nlos_belief());
    out.push_back(v);
  }
  return out;
}

}  // namespace nlos_classifier
