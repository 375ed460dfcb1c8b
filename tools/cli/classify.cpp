// `ctxfuse classify train|test`: SVM training (libsvm underneath, optional PSO over C and gamma)
// and evaluation on labelled CSV files. The feature count is known only at run time, so both
// commands dispatch to the fixed-dimension library code compiled for 1..8 features.
//
// Accuracy, per-class precision/recall and the confusion matrix come from
// include/ctxfuse/eval/classification.hpp.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iomanip>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "cli/json.hpp"
#include "cli/registry.hpp"
#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_io.hpp"
#include "ctxfuse/eval/classification.hpp"
#if CTXFUSE_HAVE_LIBSVM
#include "ctxfuse/classify/svm_train.hpp"
#endif

namespace {

using namespace ctxfuse::classify;
using ctxfuse::cli::Args;
using ctxfuse::cli::Json;

constexpr int kMaxCliDim = 8;
constexpr int kMaxCliClasses = 8;

/// A problem with the user's input; main reports it and exits with status 1.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
/// A malformed command line; reported with the usage text and exit status 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// ---------------------------------------------------------------------------------------------
// Labelled CSV: header line, one integer `label` column, every other column a numeric feature.

struct LabelledCsv {
  std::vector<std::string> feature_names;
  std::vector<std::vector<double>> rows;  // features, in header order without the label
  std::vector<int> labels;
};

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split_commas(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    out.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) return out;
    start = comma + 1;
  }
}

LabelledCsv read_labelled_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open for reading");
  LabelledCsv csv;
  std::string line;
  int line_no = 0;
  int label_col = -1;
  std::vector<std::string> names;
  while (std::getline(in, line)) {
    ++line_no;
    if (!trim(line).empty()) break;
  }
  if (trim(line).empty()) throw InputError(path + ": file is empty (expected a header line)");
  for (auto name : split_commas(line)) names.emplace_back(name);
  for (std::size_t c = 0; c < names.size(); ++c) {
    if (names[c].empty()) throw InputError(path + ":" + std::to_string(line_no) + ": column " + std::to_string(c + 1) + ": empty column name");
    if (names[c] == "label") {
      if (label_col >= 0) throw InputError(path + ":" + std::to_string(line_no) + ": column 'label' appears twice");
      label_col = static_cast<int>(c);
    } else {
      csv.feature_names.push_back(names[c]);
    }
  }
  if (label_col < 0) throw InputError(path + ":" + std::to_string(line_no) + ": header has no 'label' column");
  if (csv.feature_names.empty()) throw InputError(path + ":" + std::to_string(line_no) + ": header has no feature columns");
  if (csv.feature_names.size() > static_cast<std::size_t>(kMaxCliDim))
    throw InputError(path + ":" + std::to_string(line_no) + ": " + std::to_string(csv.feature_names.size()) +
                     " feature columns; the CLI supports 1 to " + std::to_string(kMaxCliDim));
  while (std::getline(in, line)) {
    ++line_no;
    if (trim(line).empty()) continue;
    const auto fields = split_commas(line);
    const auto where = [&](std::size_t c) {
      return path + ":" + std::to_string(line_no) + ": column '" + names[c] + "' (" + std::to_string(c + 1) + ")";
    };
    if (fields.size() != names.size())
      throw InputError(path + ":" + std::to_string(line_no) + ": expected " + std::to_string(names.size()) + " fields, got " +
                       std::to_string(fields.size()));
    std::vector<double> row;
    row.reserve(csv.feature_names.size());
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const auto f = fields[c];
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(f.data(), f.data() + f.size(), v);
      if (f.empty() || ec != std::errc() || ptr != f.data() + f.size())
        throw InputError(where(c) + ": expected a number, got '" + std::string(f) + "'");
      if (!std::isfinite(v)) throw InputError(where(c) + ": value is NaN or Inf");
      if (static_cast<int>(c) == label_col) {
        if (v != std::floor(v) || std::fabs(v) > 1e9) throw InputError(where(c) + ": label must be an integer, got '" + std::string(f) + "'");
        csv.labels.push_back(static_cast<int>(v));
      } else {
        row.push_back(v);
      }
    }
    csv.rows.push_back(std::move(row));
  }
  if (csv.rows.empty()) throw InputError(path + ": no data rows after the header");
  return csv;
}

// ---------------------------------------------------------------------------------------------
// Option parsing

struct Options {
  std::vector<std::pair<std::string, std::string>> values;
  std::vector<std::string> flags;
  bool has_flag(std::string_view f) const { return std::find(flags.begin(), flags.end(), f) != flags.end(); }
  std::optional<std::string> get(std::string_view key) const {
    for (const auto& [k, v] : values)
      if (k == key) return v;
    return std::nullopt;
  }
};

Options parse_options(Args args, const std::vector<std::string_view>& with_value, const std::vector<std::string_view>& flags) {
  Options o;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const auto a = args[i];
    if (std::find(flags.begin(), flags.end(), a) != flags.end()) {
      o.flags.emplace_back(a);
    } else if (std::find(with_value.begin(), with_value.end(), a) != with_value.end()) {
      if (i + 1 >= args.size()) throw UsageError("option " + std::string(a) + " needs a value");
      o.values.emplace_back(std::string(a), std::string(args[++i]));
    } else {
      throw UsageError("unknown option '" + std::string(a) + "'");
    }
  }
  return o;
}

double number_option(const Options& o, std::string_view key, double fallback) {
  const auto v = o.get(key);
  if (!v) return fallback;
  double x = 0.0;
  const auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), x);
  if (ec != std::errc() || ptr != v->data() + v->size() || !std::isfinite(x))
    throw UsageError("option " + std::string(key) + ": expected a number, got '" + *v + "'");
  return x;
}

// ---------------------------------------------------------------------------------------------
// Metrics: ctxfuse::eval::ConfusionMatrix over class indices; labels map to indices in the
// model's label order, then any label seen only in the data.

struct Metrics {
  std::vector<int> classes;  // index -> label
  ctxfuse::eval::ConfusionMatrix confusion{1};
};

Metrics compute_metrics(std::vector<int> classes, const std::vector<int>& truth, const std::vector<int>& predicted) {
  for (int t : truth)
    if (std::find(classes.begin(), classes.end(), t) == classes.end()) classes.push_back(t);
  const auto index = [&](int label) { return static_cast<int>(std::find(classes.begin(), classes.end(), label) - classes.begin()); };
  std::vector<int> t(truth.size()), p(predicted.size());
  std::transform(truth.begin(), truth.end(), t.begin(), index);
  std::transform(predicted.begin(), predicted.end(), p.begin(), index);
  Metrics m;
  m.confusion = ctxfuse::eval::ConfusionMatrix::from_labels(t, p, static_cast<int>(classes.size()));
  m.classes = std::move(classes);
  return m;
}

void print_metrics(const Metrics& m, std::ostream& out, Json& json) {
  const int k = static_cast<int>(m.classes.size());
  const auto& cm = m.confusion;
  out << "samples   " << cm.total() << "\naccuracy  " << std::fixed << std::setprecision(2) << 100.0 * cm.accuracy() << " %\n\n";
  out << "class   precision %   recall %   support\n";
  json["samples"] = static_cast<long long>(cm.total());
  json["accuracy"] = cm.accuracy();
  Json::Array per_class;
  for (int c = 0; c < k; ++c) {
    out << std::setw(5) << m.classes[static_cast<std::size_t>(c)] << "   " << std::setw(11) << 100.0 * cm.precision(c) << "   "
        << std::setw(8) << 100.0 * cm.recall(c) << "   " << std::setw(7) << cm.support(c) << '\n';
    Json entry;
    entry["label"] = m.classes[static_cast<std::size_t>(c)];
    entry["precision"] = cm.precision(c);  // null when nothing was predicted as this class
    entry["recall"] = cm.recall(c);
    entry["support"] = static_cast<long long>(cm.support(c));
    per_class.push_back(std::move(entry));
  }
  json["per_class"] = Json(std::move(per_class));
  out << "\nconfusion matrix (rows: true label, columns: predicted)\n      ";
  for (int c : m.classes) out << std::setw(8) << c;
  out << '\n';
  // Arrays are filled in place: pushing Json temporaries trips a false -Wmaybe-uninitialized in
  // g++ 12's std::variant move.
  Json::Array confusion;
  Json::Array labels;
  for (int r = 0; r < k; ++r) {
    labels.emplace_back(m.classes[static_cast<std::size_t>(r)]);
    out << std::setw(6) << m.classes[static_cast<std::size_t>(r)];
    Json::Array row;
    for (int c = 0; c < k; ++c) {
      out << std::setw(8) << cm.count(r, c);
      row.emplace_back(static_cast<double>(cm.count(r, c)));
    }
    confusion.emplace_back(std::move(row));
    out << '\n';
  }
  json["labels"] = Json(std::move(labels));
  json["confusion"] = Json(std::move(confusion));
  out.unsetf(std::ios::floatfield);
}

// ---------------------------------------------------------------------------------------------
// Commands, per compiled dimension

template <int Dim>
Eigen::Matrix<double, Dim, 1> row_vector(const std::vector<double>& row) {
  Eigen::Matrix<double, Dim, 1> x;
  for (int f = 0; f < Dim; ++f) x[f] = row[static_cast<std::size_t>(f)];
  return x;
}

#if CTXFUSE_HAVE_LIBSVM
template <int Dim>
int train_dim(const LabelledCsv& csv, const Options& o, std::ostream& out) {
  using Model = SvmModel<Dim, kMaxCliClasses>;
  SvmFeatures<Dim> x(static_cast<Eigen::Index>(csv.rows.size()), Dim);
  for (std::size_t i = 0; i < csv.rows.size(); ++i) x.row(static_cast<Eigen::Index>(i)) = row_vector<Dim>(csv.rows[i]).transpose();

  SvmTrainOptions options;
  const auto kernel = o.get("--kernel").value_or("rbf");
  if (kernel == "linear") options.kernel = SvmKernel::linear;
  else if (kernel == "rbf") options.kernel = SvmKernel::rbf;
  else throw UsageError("--kernel: expected linear or rbf, got '" + kernel + "'");
  const auto multiclass = o.get("--multiclass").value_or("ovo");
  if (multiclass == "ovo") options.multiclass = SvmMulticlass::one_vs_one;
  else if (multiclass == "ovr") options.multiclass = SvmMulticlass::one_vs_rest;
  else throw UsageError("--multiclass: expected ovo or ovr, got '" + multiclass + "'");
  options.probability = o.has_flag("--probability");
  options.standardize = !o.has_flag("--no-standardize");
  options.C = number_option(o, "--C", 1.0);
  options.gamma = number_option(o, "--gamma", 0.0);
  const double seed = number_option(o, "--seed", 1.0);
  if (seed < 0 || seed != std::floor(seed) || seed > 4294967295.0) throw UsageError("--seed: expected a non-negative integer");
  options.seed = static_cast<std::uint32_t>(seed);
  const double folds_value = number_option(o, "--folds", 5.0);
  if (folds_value < 2 || folds_value != std::floor(folds_value) || folds_value > 100)
    throw UsageError("--folds: expected an integer in [2, 100]");
  const int folds = static_cast<int>(folds_value);
  if (!(options.C > 0)) throw UsageError("--C must be > 0");
  if (options.gamma < 0) throw UsageError("--gamma must be > 0");

  const auto classes = labels_in_order(csv.labels);
  out << "training  " << csv.rows.size() << " samples, " << Dim << " features, " << classes.size() << " classes, kernel "
      << kernel << ", " << multiclass << (options.standardize ? ", standardised" : ", raw features") << '\n';
  if (classes.size() < 2 || classes.size() > static_cast<std::size_t>(kMaxCliClasses))
    throw InputError("data has " + std::to_string(classes.size()) + " classes; need 2 to " + std::to_string(kMaxCliClasses));
  if (o.has_flag("--pso")) {
    SvmTuneOptions tune;
    tune.folds = folds;
    tune.fold_seed = options.seed;
    tune.pso.seed = options.seed;
    tune.pso.swarm_size = static_cast<int>(number_option(o, "--pso-swarm", 10));
    tune.pso.iterations = static_cast<int>(number_option(o, "--pso-iterations", 10));
    const auto t = tune_svm_pso<Dim, kMaxCliClasses>(x, csv.labels, options, tune);
    options.C = t.C;
    if (options.kernel == SvmKernel::rbf) options.gamma = t.gamma;
    out << "pso       " << t.evaluations << " cross-validations, best " << folds << "-fold accuracy " << std::fixed
        << std::setprecision(2) << 100.0 * t.cv_accuracy << " %" << '\n';
    out.unsetf(std::ios::floatfield);
  }
  const double gamma = options.gamma > 0 ? options.gamma : 1.0 / Dim;
  out << "params    C " << std::setprecision(6) << options.C << (options.kernel == SvmKernel::rbf ? ", gamma " + std::to_string(gamma) : "") << '\n';
  if (o.get("--folds")) {
    const auto cv = cross_validate_svm<Dim, kMaxCliClasses>(x, csv.labels, options, folds, options.seed);
    out << "cv        " << folds << "-fold stratified accuracy " << std::fixed << std::setprecision(2) << 100.0 * cv.accuracy
        << " %\n";
    out.unsetf(std::ios::floatfield);
  }
  const Model model = train_svm<Dim, kMaxCliClasses>(x, csv.labels, options);
  std::size_t correct = 0;
  SvmPrediction<kMaxCliClasses> p;
  for (std::size_t i = 0; i < csv.rows.size(); ++i) {
    svm_predict(model, row_vector<Dim>(csv.rows[i]), p);
    correct += p.label == csv.labels[i] ? 1 : 0;
  }
  out << "model     " << model.num_support_vectors() << " support vectors, " << model.num_machines() << " machine(s)"
      << (model.has_probability ? ", probabilities" : "") << "\ntraining  accuracy " << std::fixed << std::setprecision(2)
      << 100.0 * static_cast<double>(correct) / static_cast<double>(csv.rows.size()) << " %\n";
  out.unsetf(std::ios::floatfield);
  const auto path = *o.get("--model");
  save_svm_model(path, model);
  out << "wrote     " << path << '\n';
  return 0;
}
#endif

template <int Dim>
int test_dim(const LabelledCsv& csv, const Options& o, std::ostream& out) {
  const auto model_path = *o.get("--model");
  const auto model = load_svm_model<Dim, kMaxCliClasses>(model_path);
  std::vector<int> predicted(csv.rows.size());
  std::ofstream predictions;
  if (const auto p = o.get("--predictions")) {
    predictions.open(*p);
    if (!predictions) throw InputError(*p + ": cannot open for writing");
    predictions << "row,label,predicted";
    for (int c = 0; c < model.num_classes; ++c)
      predictions << (model.has_probability ? ",p_" : ",decision_") << model.labels[static_cast<std::size_t>(c)];
    predictions << '\n' << std::setprecision(10);
  }
  SvmPrediction<kMaxCliClasses> p;
  for (std::size_t i = 0; i < csv.rows.size(); ++i) {
    svm_predict(model, row_vector<Dim>(csv.rows[i]), p);  // rows were checked finite when read
    predicted[i] = p.label;
    if (predictions.is_open()) {
      predictions << i + 1 << ',' << csv.labels[i] << ',' << p.label;
      if (model.has_probability) {
        for (int c = 0; c < model.num_classes; ++c) predictions << ',' << p.probabilities[static_cast<std::size_t>(c)];
      } else if (model.num_classes == 2) {
        predictions << ',' << p.decision_values[0] << ',' << -p.decision_values[0];
      } else if (model.multiclass == SvmMulticlass::one_vs_rest) {
        for (int c = 0; c < model.num_classes; ++c) predictions << ',' << p.decision_values[static_cast<std::size_t>(c)];
      } else {
        // One-vs-one has no per-class decision value; write each class's vote count instead.
        std::vector<int> votes(static_cast<std::size_t>(model.num_classes), 0);
        int m = 0;
        for (int a = 0; a < model.num_classes; ++a)
          for (int b = a + 1; b < model.num_classes; ++b, ++m) ++votes[static_cast<std::size_t>(p.decision_values[static_cast<std::size_t>(m)] > 0 ? a : b)];
        for (int v : votes) predictions << ',' << v;
      }
      predictions << '\n';
    }
  }
  std::vector<int> classes(model.labels.begin(), model.labels.begin() + model.num_classes);
  const auto metrics = compute_metrics(classes, csv.labels, predicted);
  Json json;
  json["model"] = model_path;
  json["data"] = *o.get("--data");
  out << "model     " << model_path << " (" << to_string(model.kernel) << ", " << to_string(model.multiclass) << ", "
      << model.num_support_vectors() << " support vectors)\n";
  print_metrics(metrics, out, json);
  if (const auto j = o.get("--json")) {
    std::ofstream js(*j);
    if (!js) throw InputError(*j + ": cannot open for writing");
    json.dump(js);
    js << '\n';
  }
  return 0;
}

template <template <int> class Fn, class... A>
int dispatch_dim(int dim, A&&... a) {
  switch (dim) {
    case 1: return Fn<1>::run(a...);
    case 2: return Fn<2>::run(a...);
    case 3: return Fn<3>::run(a...);
    case 4: return Fn<4>::run(a...);
    case 5: return Fn<5>::run(a...);
    case 6: return Fn<6>::run(a...);
    case 7: return Fn<7>::run(a...);
    case 8: return Fn<8>::run(a...);
    default: throw InputError("feature dimension " + std::to_string(dim) + " outside 1..8");
  }
}

#if CTXFUSE_HAVE_LIBSVM
template <int Dim>
struct TrainFn {
  static int run(const LabelledCsv& csv, const Options& o, std::ostream& out) { return train_dim<Dim>(csv, o, out); }
};
#endif
template <int Dim>
struct TestFn {
  static int run(const LabelledCsv& csv, const Options& o, std::ostream& out) { return test_dim<Dim>(csv, o, out); }
};

constexpr std::string_view kUsage =
    "usage:\n"
    "  ctxfuse classify train --data CSV --model OUT [--kernel linear|rbf] [--multiclass ovo|ovr]\n"
    "                         [--probability] [--C x] [--gamma g] [--pso] [--folds k] [--seed n]\n"
    "                         [--pso-swarm n] [--pso-iterations n] [--no-standardize]\n"
    "  ctxfuse classify test  --model MODEL --data CSV [--json FILE] [--predictions FILE]\n"
    "\n"
    "CSV: a header line, an integer 'label' column and 1..8 numeric feature columns.\n"
    "train: defaults rbf, ovo, C 1, gamma 1/features, inputs standardised (mean/std stored in the\n"
    "  model). --pso searches log2 C in [-5, 15] and log2 gamma in [-15, 3] for the best stratified\n"
    "  k-fold accuracy (k = --folds, default 5); --folds alone also reports that accuracy.\n"
    "test: MODEL is a ctxfuse-svm file or a libsvm model file (used on the features as given);\n"
    "  prints accuracy, per-class precision/recall and the confusion matrix.\n";

int classify_command(Args args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    (args.empty() ? err : out) << kUsage;
    return args.empty() ? 2 : 0;
  }
  const auto sub = args[0];
  try {
    if (sub == "train") {
#if CTXFUSE_HAVE_LIBSVM
      const auto o = parse_options(args.subspan(1),
                                   {"--data", "--model", "--kernel", "--multiclass", "--C", "--gamma", "--folds", "--seed",
                                    "--pso-swarm", "--pso-iterations"},
                                   {"--pso", "--probability", "--no-standardize"});
      if (!o.get("--data") || !o.get("--model")) throw UsageError("train needs --data and --model");
      const auto csv = read_labelled_csv(*o.get("--data"));
      return dispatch_dim<TrainFn>(static_cast<int>(csv.feature_names.size()), csv, o, out);
#else
      err << "ctxfuse classify train: this build has no libsvm\n";
      return 1;
#endif
    }
    if (sub == "test") {
      const auto o = parse_options(args.subspan(1), {"--data", "--model", "--json", "--predictions"}, {});
      if (!o.get("--data") || !o.get("--model")) throw UsageError("test needs --data and --model");
      const auto csv = read_labelled_csv(*o.get("--data"));
      const int dim = static_cast<int>(csv.feature_names.size());
      const int model_dim = svm_file_dimension(*o.get("--model"));
      if (model_dim != 0 && model_dim != dim)
        throw InputError(*o.get("--model") + ": model expects " + std::to_string(model_dim) + " features, " + *o.get("--data") +
                         " has " + std::to_string(dim));
      return dispatch_dim<TestFn>(dim, csv, o, out);
    }
    err << "ctxfuse classify: unknown sub-command '" << sub << "'\n\n" << kUsage;
    return 2;
  } catch (const UsageError& e) {
    err << "ctxfuse classify " << sub << ": " << e.what() << "\n\n" << kUsage;
    return 2;
  } catch (const std::invalid_argument& e) {  // training rejected the data or parameters
    err << "ctxfuse classify " << sub << ": error: " << e.what() << '\n';
    return 1;
  } catch (const SvmFileError& e) {
    err << "ctxfuse classify " << sub << ": error: " << e.what() << '\n';
    return 1;
  } catch (const InputError& e) {
    err << "ctxfuse classify " << sub << ": error: " << e.what() << '\n';
    return 1;
  }
}

const ctxfuse::cli::RegisterCommand register_classify{
    {"classify", "train / test SVM classifiers on labelled CSV files", &classify_command}};

}  // namespace
