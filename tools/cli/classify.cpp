// `ctxfuse classify train|test`: SVM training (libsvm underneath, optional PSO over C and gamma,
// validation folds that respect sequences) and evaluation on labelled CSV files. The commands
// live in classify_train.cpp and classify_test.cpp; classify_data.hpp holds what they share.
#include <ostream>
#include <string_view>

#include "cli/classify_data.hpp"
#include "cli/registry.hpp"

namespace {

using ctxfuse::cli::Args;

constexpr std::string_view kUsage =
    "usage: ctxfuse classify train|test [options]   (`ctxfuse classify train --help` lists the options)\n"
    "  train  fits an SVM on a labelled CSV (cross-validation by blocks, groups or stratified; PSO)\n"
    "  test   scores a model on a labelled CSV (accuracy, balanced accuracy, macro-F1, confusion)\n";

int classify_command(Args args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    (args.empty() ? err : out) << kUsage;
    return args.empty() ? 2 : 0;
  }
  if (args[0] == "train") return ctxfuse::cli::classify_cli::classify_train(args.subspan(1), out, err);
  if (args[0] == "test") return ctxfuse::cli::classify_cli::classify_test(args.subspan(1), out, err);
  err << "ctxfuse classify: unknown sub-command '" << args[0] << "'\n\n" << kUsage;
  return 2;
}

const ctxfuse::cli::RegisterCommand register_classify{
    {"classify", "train / test SVM classifiers on labelled CSV files", &classify_command}};

}  // namespace
