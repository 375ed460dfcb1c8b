// `ctxfuse classify test`: scores a ctxfuse-svm or libsvm model on a labelled CSV: accuracy,
// balanced accuracy, macro-F1, per-class precision / recall / F1 and the labelled confusion
// matrix, classes in ascending label order (ctxfuse/classify/confusion_matrix.hpp).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/classify_data.hpp"
#include "cli/options.hpp"
#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_io.hpp"

namespace ctxfuse::cli::classify_cli {
namespace {

using namespace ctxfuse::classify;

struct TestSettings {
  std::string data, model, json, predictions;
  ColumnSelection columns;
};

// The model's dimension is a run-time value (SvmModel<Eigen::Dynamic>): one instantiation
// serves every feature count.
using TestModel = SvmModel<Eigen::Dynamic, kMaxCliClasses>;

int test_model(const TestModel& model, const LabelledCsv& csv, const TestSettings& s, std::ostream& out) {
  const std::vector<int> model_labels(model.labels.begin(), model.labels.begin() + model.num_classes);
  // Classes in ascending order: the model's and any seen only in the data.
  std::vector<int> all = model_labels;
  all.insert(all.end(), csv.labels.begin(), csv.labels.end());
  const auto classes = labels_sorted(all);
  // Model class index of each sorted model label, for the per-class columns.
  std::vector<int> order;
  for (int c : labels_sorted(model_labels))
    order.push_back(static_cast<int>(std::find(model_labels.begin(), model_labels.end(), c) - model_labels.begin()));
  std::ofstream predictions;
  if (!s.predictions.empty()) {
    predictions.open(s.predictions);
    if (!predictions) throw InputError(s.predictions + ": cannot open for writing");
    predictions << "row,label,predicted";
    for (int c : order) predictions << (model.has_probability ? ",p_" : ",decision_") << model_labels[static_cast<std::size_t>(c)];
    predictions << '\n' << std::setprecision(10);
  }
  std::vector<int> predicted(csv.rows.size());
  SvmPrediction<kMaxCliClasses> p;
  for (std::size_t i = 0; i < csv.rows.size(); ++i) {
    if (!svm_predict(model, row_vector(csv.rows[i]), p))  // the reader refused non-finite rows
      throw std::logic_error("classify: a checked row was refused by the SVM");
    predicted[i] = p.label;
    if (!predictions.is_open()) continue;
    predictions << i + 1 << ',' << csv.labels[i] << ',' << p.label;
    std::vector<double> per_class(static_cast<std::size_t>(model.num_classes), 0.0);
    if (model.has_probability) {
      for (int c = 0; c < model.num_classes; ++c) per_class[static_cast<std::size_t>(c)] = p.probabilities[static_cast<std::size_t>(c)];
    } else if (model.num_classes == 2) {
      per_class = {p.decision_values[0], -p.decision_values[0]};
    } else if (model.multiclass == SvmMulticlass::one_vs_rest) {
      for (int c = 0; c < model.num_classes; ++c) per_class[static_cast<std::size_t>(c)] = p.decision_values[static_cast<std::size_t>(c)];
    } else {
      // One-vs-one has no per-class decision value; write each class's vote count instead.
      int m = 0;
      for (int a = 0; a < model.num_classes; ++a)
        for (int b = a + 1; b < model.num_classes; ++b, ++m)
          per_class[static_cast<std::size_t>(p.decision_values[static_cast<std::size_t>(m)] > 0 ? a : b)] += 1.0;
    }
    for (int c : order) predictions << ',' << per_class[static_cast<std::size_t>(c)];
    predictions << '\n';
  }
  Json json;
  json["model"] = s.model;
  json["data"] = s.data;
  out << "model     " << s.model << " (" << to_string(model.kernel) << ", " << to_string(model.multiclass) << ", "
      << model.num_support_vectors() << " support vectors)\nfeatures ";
  for (const auto& n : csv.feature_names) out << ' ' << n;
  out << '\n';
  print_metrics(classes, confusion_over(classes, csv.labels, predicted), out, json);
  if (!s.json.empty()) {
    std::ofstream js(s.json);
    if (!js) throw InputError(s.json + ": cannot open for writing");
    json.dump(js);
    js << '\n';
  }
  return 0;
}

}  // namespace

int classify_test(Args args, std::ostream& out, std::ostream& err) {
  auto app = make_app("classify test",
                      "Scores a model (ctxfuse-svm file, or a libsvm model used on the features as given) on a labelled CSV:\n"
                      "accuracy, balanced accuracy, macro-F1, per-class precision/recall/F1, labelled confusion matrix.\n"
                      "Select the same feature columns as in training.");
  TestSettings s;
  app.add_option("--model", s.model, "model file")->required();
  app.add_option("--data", s.data, "labelled CSV (header line)")->required();
  app.add_option("--json", s.json, "also write the scores as JSON to this file");
  app.add_option("--predictions", s.predictions, "write row, label, prediction and per-class values (ascending labels)");
  add_column_options(app, s.columns, true);
  if (const auto status = parse_options(app, args, out, err)) return *status;
  try {
    const auto csv = read_labelled_csv(s.data, s.columns);
    const int dim = static_cast<int>(csv.feature_names.size());
    // Our files state their dimension; a libsvm model is used on the selected features as given.
    const bool libsvm = detect_svm_file_format(std::filesystem::path(s.model)) == SvmFileFormat::libsvm;
    const auto model = load_svm_model<Eigen::Dynamic, kMaxCliClasses>(s.model, libsvm ? dim : 0);
    if (model.dimension() != dim)
      throw InputError(s.model + ": model expects " + std::to_string(model.dimension()) + " features, " + s.data + " has " +
                       std::to_string(dim) + " selected");
    return test_model(model, csv, s, out);
  } catch (const SvmFileError& e) {
    err << "ctxfuse classify test: error: " << e.what() << '\n';
    return 1;
  } catch (const InputError& e) {
    err << "ctxfuse classify test: error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace ctxfuse::cli::classify_cli
