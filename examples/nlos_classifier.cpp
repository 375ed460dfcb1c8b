// The UWB paper's per-range NLOS decision from a libsvm model file: SVM probability p1, the
// consistency check's p2, their Dempster-Shafer combination R and the decision R > 0.8.
// docs/classifiers.md explains it.
//   build/release/examples/example_nlos_classifier
#include <cstdio>

#include "nlos_classifier.hpp"

int main() {
  const auto verdicts = nlos_classifier::run();
  std::printf("%-18s %6s %6s %7s %9s %6s %6s %6s %9s  %s\n", "range", "v_u", "v_i", "e [m]", "decision", "p1", "p2",
              "R", "conflict", "verdict");
  for (const auto& v : verdicts) {
    const double e = ctxfuse::classify::ConsistencyModel::consistency_error(v.range.range_change, v.range.travelled);
    std::printf("%-18s %6.2f %6.2f %7.2f %9.4f %6.3f %6.3f %6.3f %9.3f  %s\n", v.range.what, v.range.range_rate,
                v.range.speed, e, v.svm.decision_values[0], v.p1, v.p2, v.ds.nlos_belief(), v.ds.conflict,
                v.nlos ? "NLOS" : "LOS");
  }
  return 0;
}
