// `ctxfuse classify train`: libsvm C-SVC on a labelled CSV, with validation folds that respect
// sequences (contiguous blocks by default, whole groups with --groups, shuffled stratified on
// request), class weights, and the PSO search over C (and gamma) on those folds. Progress goes
// to stderr, one line per CV fold and per PSO iteration.
#include <chrono>
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "cli/classify_data.hpp"
#include "cli/options.hpp"
#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_io.hpp"
#if CTXFUSE_HAVE_LIBSVM
#include "ctxfuse/classify/svm_train.hpp"
#endif

namespace ctxfuse::cli::classify_cli {

#if CTXFUSE_HAVE_LIBSVM
namespace {

using namespace ctxfuse::classify;

struct TrainSettings {
  std::string data, model;
  ColumnSelection columns;
  std::string kernel = "rbf", multiclass = "ovo", cv = "auto", score = "accuracy", class_weight;
  bool probability = false, no_standardize = false, pso = false, report_cv = false;
  double C = 1.0, gamma = 0.0;
  int folds = 5, pso_swarm = 10, pso_iterations = 10;
  std::size_t pso_samples = 2000;
  std::uint32_t seed = 1;
};

std::string percent(double v) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(2) << 100.0 * v << " %";
  return s.str();
}

/// "auto" (inverse frequency) or "L:W,L:W,...".
std::vector<std::pair<int, double>> parse_class_weights(const std::string& spec, std::span<const int> y) {
  if (spec.empty()) return {};
  if (spec == "auto") return inverse_frequency_weights(y);
  std::vector<std::pair<int, double>> w;
  std::stringstream ss(spec);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto colon = item.find(':');
    int label = 0;
    double weight = 0.0;
    const char* end = item.data() + item.size();
    if (colon == std::string::npos ||
        std::from_chars(item.data(), item.data() + colon, label).ptr != item.data() + colon ||
        std::from_chars(item.data() + colon + 1, end, weight).ptr != end || colon + 1 == item.size() || !(weight > 0) ||
        !std::isfinite(weight))
      throw CLI::ValidationError("--class-weight", "'" + item + "' is not LABEL:WEIGHT with an integer label and a weight > 0");
    w.emplace_back(label, weight);
  }
  return w;
}

CvScore parse_score(const std::string& s) {
  if (s == "balanced-accuracy") return CvScore::balanced_accuracy;
  if (s == "macro-f1") return CvScore::macro_f1;
  return CvScore::accuracy;
}

/// The fold vector the settings ask for, and its one-line description.
std::pair<std::vector<int>, std::string> make_folds(const LabelledCsv& csv, const TrainSettings& s) {
  std::string scheme = s.cv;
  if (scheme == "auto") scheme = csv.groups.empty() ? "blocked" : "groups";
  if (scheme == "groups") {
    if (csv.groups.empty()) throw InputError("--cv groups needs --groups COL");
    const bool logo = s.folds <= 0 || static_cast<std::size_t>(s.folds) >= csv.group_count;
    return {group_folds(csv.groups, s.folds),
            logo ? "leave-one-group-out over " + std::to_string(csv.group_count) + " groups of '" + s.columns.groups + "'"
                 : std::to_string(s.folds) + " folds of whole groups (" + std::to_string(csv.group_count) + " groups of '" +
                       s.columns.groups + "')"};
  }
  if (s.folds < 2) throw InputError("--folds must be >= 2 for " + scheme + " folds");
  if (scheme == "stratified")
    return {stratified_folds(csv.labels, s.folds, s.seed), std::to_string(s.folds) + "-fold stratified (shuffled rows)"};
  return {block_folds(csv.labels.size(), s.folds), std::to_string(s.folds) + " contiguous blocks (row order)"};
}

// Features, training and the model at a run-time dimension (Eigen::Dynamic): one instantiation
// of the training, the search and the model I/O serves every feature count.
constexpr int kAnyDim = Eigen::Dynamic;

int train(const LabelledCsv& csv, const TrainSettings& s, std::ostream& out, std::ostream& err) {
  const auto dim = static_cast<Eigen::Index>(csv.feature_names.size());
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  SvmFeatures<kAnyDim> x(static_cast<Eigen::Index>(csv.rows.size()), dim);
  for (std::size_t i = 0; i < csv.rows.size(); ++i) x.row(static_cast<Eigen::Index>(i)) = row_vector(csv.rows[i]).transpose();

  SvmTrainOptions options;
  options.kernel = s.kernel == "linear" ? SvmKernel::linear : SvmKernel::rbf;
  options.multiclass = s.multiclass == "ovr" ? SvmMulticlass::one_vs_rest : SvmMulticlass::one_vs_one;
  options.probability = s.probability;
  options.standardize = !s.no_standardize;
  options.C = s.C;
  options.gamma = s.gamma;
  options.seed = s.seed;
  options.class_weights = parse_class_weights(s.class_weight, csv.labels);
  const CvScore score = parse_score(s.score);

  const auto classes = labels_sorted(csv.labels);
  out << "training  " << csv.rows.size() << " samples, " << dim << " features (";
  for (std::size_t f = 0; f < csv.feature_names.size(); ++f) out << (f ? "," : "") << csv.feature_names[f];
  out << "), " << classes.size() << " classes, kernel " << s.kernel << ", " << s.multiclass
      << (options.standardize ? ", standardised" : ", raw features") << '\n';
  if (classes.size() < 2 || classes.size() > static_cast<std::size_t>(kMaxCliClasses))
    throw InputError("data has " + std::to_string(classes.size()) + " classes; need 2 to " + std::to_string(kMaxCliClasses));
  out << "classes  ";
  for (int c : classes) out << ' ' << c << " (" << std::count(csv.labels.begin(), csv.labels.end(), c) << ")";
  out << '\n';
  if (!options.class_weights.empty()) {
    out << "weights  ";
    for (const auto& [label, w] : options.class_weights) out << ' ' << label << ":" << std::setprecision(4) << w;
    out << '\n';
  }
  std::vector<int> folds;
  std::string folds_text;
  if (s.pso || s.report_cv) {
    std::tie(folds, folds_text) = make_folds(csv, s);
    out << "folds     " << folds_text << '\n';
  }

  if (s.pso) {
    SvmTuneOptions tune;
    tune.fold_of_sample = folds;
    tune.score = score;
    tune.max_search_samples = s.pso_samples;
    tune.pso.seed = s.seed;
    tune.pso.swarm_size = s.pso_swarm;
    tune.pso.iterations = s.pso_iterations;
    tune.on_progress = [&](const SvmTuneProgress& p) {
      err << "pso: iteration " << p.iteration << "/" << p.iterations << ", " << p.evaluations << " cross-validations, best "
          << to_string(score) << " " << percent(p.best_score) << " at C " << std::setprecision(4) << p.C;
      if (options.kernel == SvmKernel::rbf) err << ", gamma " << p.gamma;
      err << " (" << std::fixed << std::setprecision(1) << elapsed() << " s)\n" << std::defaultfloat << std::flush;
    };
    const auto t = tune_svm_pso<kAnyDim, kMaxCliClasses>(x, csv.labels, options, tune);
    options.C = t.C;
    if (options.kernel == SvmKernel::rbf) options.gamma = t.gamma;
    out << "pso       " << t.evaluations << " cross-validations on " << t.search_samples << " of " << csv.rows.size()
        << " samples, best " << to_string(score) << " " << percent(t.cv_accuracy) << '\n';
  }
  const double gamma = options.gamma > 0 ? options.gamma : 1.0 / static_cast<double>(dim);
  out << "params    C " << std::setprecision(6) << options.C;
  if (options.kernel == SvmKernel::rbf) out << ", gamma " << gamma;
  out << '\n';
  if (s.report_cv) {
    const auto cv = cross_validate_svm<kAnyDim, kMaxCliClasses>(
        x, csv.labels, options, folds, score, [&](int f, int n, std::size_t done, double so_far) {
          err << "cv: fold " << f + 1 << "/" << n << ", " << done << " samples scored, " << to_string(score) << " so far "
              << percent(so_far) << " (" << std::fixed << std::setprecision(1) << elapsed() << " s)\n" << std::defaultfloat << std::flush;
        });
    out << "cv        accuracy " << percent(cv.accuracy) << ", balanced accuracy " << percent(cv.balanced_accuracy)
        << ", macro-F1 " << percent(cv.macro_f1) << " (" << folds_text << ")\n";
  }
  err << "fit: all " << csv.rows.size() << " samples (" << std::fixed << std::setprecision(1) << elapsed() << " s)\n"
      << std::defaultfloat << std::flush;
  const auto model = train_svm<kAnyDim, kMaxCliClasses>(x, csv.labels, options);
  std::vector<int> predicted(csv.rows.size());
  SvmPrediction<kMaxCliClasses> p;
  for (std::size_t i = 0; i < csv.rows.size(); ++i) {
    if (!svm_predict(model, row_vector(csv.rows[i]), p))  // the reader refused non-finite rows
      throw std::logic_error("classify: a checked row was refused by the SVM");
    predicted[i] = p.label;
  }
  const auto m = confusion_over(classes, csv.labels, predicted);
  out << "model     " << model.num_support_vectors() << " support vectors, " << model.num_machines() << " machine(s)"
      << (model.has_probability ? ", probabilities" : "") << "\ntraining  accuracy " << percent(m.accuracy())
      << ", balanced accuracy " << percent(m.balanced_accuracy()) << ", macro-F1 " << percent(m.macro_f1()) << '\n';
  save_svm_model(s.model, model);
  out << "wrote     " << s.model << '\n';
  return 0;
}

}  // namespace

int classify_train(Args args, std::ostream& out, std::ostream& err) {
  auto app = make_app("classify train",
                      "Trains a libsvm C-SVC on a labelled CSV (header line, integer label column, feature columns) and\n"
                      "writes a ctxfuse-svm model (inputs standardised on the training data, mean/std stored in the model).\n"
                      "Validation folds (for --pso and the cross-validation report): --cv auto = whole groups with --groups,\n"
                      "else contiguous blocks in row order (time-ordered data); stratified = shuffled rows.");
  TrainSettings s;
  app.add_option("--data", s.data, "labelled CSV")->required();
  app.add_option("--model", s.model, "model file to write")->required();
  add_column_options(app, s.columns, true);
  app.add_option("--kernel", s.kernel, "linear or rbf")->check(CLI::IsMember({"linear", "rbf"}));
  app.add_option("--multiclass", s.multiclass, "ovo (libsvm's one-vs-one) or ovr (one-vs-rest)")->check(CLI::IsMember({"ovo", "ovr"}));
  app.add_flag("--probability", s.probability, "fit Platt probabilities");
  app.add_flag("--no-standardize", s.no_standardize, "train on the raw features");
  app.add_option("--C", s.C, "C (ignored with --pso)")->check(ctxfuse::cli::kPositiveNumber);
  app.add_option("--gamma", s.gamma, "RBF gamma; 0 = 1 / features (ignored with --pso)")->check(ctxfuse::cli::kNonNegativeNumber);
  app.add_option("--class-weight", s.class_weight,
                 "C multipliers per class: auto (n / (classes * n_class)) or LABEL:W,LABEL:W,... (default: none)");
  app.add_option("--cv", s.cv, "folds: auto, blocked, groups or stratified")->check(CLI::IsMember({"auto", "blocked", "groups", "stratified"}));
  const auto* folds = app.add_option("--folds", s.folds, "number of folds; with groups, 0 or >= groups = leave-one-group-out")
                          ->check(CLI::Range(0, 100));
  app.add_option("--score", s.score, "what --pso maximises: accuracy, balanced-accuracy or macro-f1")
      ->check(CLI::IsMember({"accuracy", "balanced-accuracy", "macro-f1"}));
  app.add_flag("--pso", s.pso, "search log2 C in [-5, 15] (and log2 gamma in [-15, 3]) by PSO on the folds");
  app.add_option("--pso-swarm", s.pso_swarm, "PSO particles")->check(CLI::Range(1, 1000));
  app.add_option("--pso-iterations", s.pso_iterations, "PSO iterations")->check(CLI::Range(0, 1000));
  app.add_option("--pso-samples", s.pso_samples, "search on every m-th row so that at most this many remain (0 = all)");
  app.add_option("--seed", s.seed, "seed of libsvm, PSO and stratified folds");
  if (const auto status = parse_options(app, args, out, err)) return *status;
  s.report_cv = folds->count() > 0 || app.get_option("--cv")->count() > 0 || app.get_option("--groups")->count() > 0;
  try {
    const auto csv = read_labelled_csv(s.data, s.columns);
    return train(csv, s, out, err);
  } catch (const CLI::ValidationError& e) {
    err << "ctxfuse classify train: " << e.what() << '\n';
    return 2;
  } catch (const std::invalid_argument& e) {  // training rejected the data or parameters
    err << "ctxfuse classify train: error: " << e.what() << '\n';
    return 1;
  } catch (const InputError& e) {
    err << "ctxfuse classify train: error: " << e.what() << '\n';
    return 1;
  }
}

#else
int classify_train(Args, std::ostream&, std::ostream& err) {
  err << "ctxfuse classify train: this build has no libsvm\n";
  return 1;
}
#endif

}  // namespace ctxfuse::cli::classify_cli
