// Shared by `ctxfuse classify train|test` (classify_train.cpp, classify_test.cpp): the labelled
// CSV reader with column selection, the metrics report, and the feature-dimension dispatch.
#pragma once

#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iomanip>
#include <map>
#include <ostream>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "cli/json.hpp"
#include "cli/registry.hpp"
#include "ctxfuse/classify/svm_folds.hpp"
#include "ctxfuse/classify/confusion_matrix.hpp"
#include "ctxfuse/io/text.hpp"

namespace ctxfuse::cli::classify_cli {

inline constexpr int kMaxCliClasses = 8;

/// A problem with the user's input: exit status 1.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Which CSV columns are the label, the features and the groups.
struct ColumnSelection {
  std::string label = "label";
  std::vector<std::string> features;                // empty: every column not otherwise used
  std::vector<std::string> ignore{"time_s"};        // never features (missing names are fine)
  std::string groups;                               // empty: none
};

/// Declares --label, --features, --ignore (and --groups when `with_groups`) on `app`.
inline void add_column_options(CLI::App& app, ColumnSelection& c, bool with_groups) {
  app.add_option("--label", c.label, "name of the integer label column");
  app.add_option("--features", c.features, "feature columns, in this order (comma-separated; default: all others)")
      ->delimiter(',');
  app.add_option("--ignore", c.ignore, "columns that are never features (comma-separated)")->delimiter(',');
  if (with_groups)
    app.add_option("--groups", c.groups, "column of group ids (recording, height, ...): folds keep groups whole; not a feature");
}

struct LabelledCsv {
  std::vector<std::string> feature_names;
  std::vector<std::vector<double>> rows;  // selected features, in selection order
  std::vector<int> labels;
  std::vector<int> groups;  // group index per row (first appearance order) when a group column is selected
  std::size_t group_count = 0;
};

/// Reads a CSV with a header line (its first non-blank line). Only the selected columns are
/// parsed (others may hold text). Throws io::ParseError naming file, line and column.
inline LabelledCsv read_labelled_csv(io::TextFile& file, const ColumnSelection& sel) {
  std::string_view line;
  do {
    if (!file.next(line)) throw io::ParseError(file.name(), 0, 0, "", "file is empty (expected a header line)");
  } while (io::trim(line).empty());
  const io::Header header(io::split_fields(line, io::Separator::comma));
  std::map<std::string, int> column;
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (header.name(c).empty()) throw io::ParseError(file.name(), file.line_number(), c + 1, "", "empty column name");
    if (!column.emplace(header.name(c), static_cast<int>(c)).second)
      throw io::ParseError(file.name(), file.line_number(), c + 1, header.name(c), "appears twice in the header");
  }
  const auto find = [&](const std::string& name, const char* role) {
    const auto it = column.find(name);
    if (it == column.end()) file.fail(io::cat("header has no ", io::quote(name), " column (", role, ")"));
    return it->second;
  };
  const int label_col = find(sel.label, "--label");
  const int group_col = sel.groups.empty() ? -1 : find(sel.groups, "--groups");
  if (group_col == label_col) throw InputError("--groups and --label name the same column '" + sel.label + "'");
  std::vector<int> feature_cols;
  if (!sel.features.empty()) {
    for (const auto& f : sel.features) {
      const int c = find(f, "--features");
      if (c == label_col || c == group_col) throw InputError("--features: '" + f + "' is the label or group column");
      if (std::find(feature_cols.begin(), feature_cols.end(), c) != feature_cols.end())
        throw InputError("--features: '" + f + "' listed twice");
      feature_cols.push_back(c);
    }
  } else {
    for (std::size_t c = 0; c < header.size(); ++c) {
      const int ci = static_cast<int>(c);
      if (ci == label_col || ci == group_col ||
          std::find(sel.ignore.begin(), sel.ignore.end(), header.name(c)) != sel.ignore.end())
        continue;
      feature_cols.push_back(ci);
    }
  }
  LabelledCsv csv;
  for (int c : feature_cols) csv.feature_names.push_back(header.name(static_cast<std::size_t>(c)));
  if (csv.feature_names.empty()) file.fail("no feature columns selected");
  std::map<double, int> group_index;
  const auto at = [](int c) { return static_cast<std::size_t>(c); };
  io::Fields f(file.name(), &header);
  while (io::next_fields(file, f, io::Separator::comma)) {
    f.expect_count(header.size());
    csv.labels.push_back(f.whole<int>(at(label_col), -1'000'000'000, 1'000'000'000));
    if (group_col >= 0) {
      const auto [it, added] = group_index.emplace(f.real(at(group_col), io::kAnyFinite), static_cast<int>(group_index.size()));
      csv.groups.push_back(it->second);
    }
    std::vector<double> row;
    row.reserve(feature_cols.size());
    for (int c : feature_cols) row.push_back(f.real(at(c), io::kAnyFinite));
    csv.rows.push_back(std::move(row));
  }
  if (csv.rows.empty()) throw io::ParseError(file.name(), 0, 0, "", "no data rows after the header");
  csv.group_count = group_index.size();
  return csv;
}

/// The same from a path; problems with the file throw InputError, with the ParseError's message.
inline LabelledCsv read_labelled_csv(const std::string& path, const ColumnSelection& sel) {
  try {
    io::TextFile file(path);
    return read_labelled_csv(file, sel);
  } catch (const io::ParseError& e) {
    throw InputError(e.what());
  }
}

/// Accuracy, balanced accuracy, macro-F1, per-class precision / recall / F1 and the labelled
/// confusion matrix, classes in ascending label order; the same figures into `json`.
inline void print_metrics(std::span<const int> classes, const classify::ConfusionMatrix& cm, std::ostream& out, Json& json) {
  const int k = static_cast<int>(classes.size());
  const auto pct = [](double v) {
    std::ostringstream s;
    if (std::isnan(v)) s << "-";
    else s << std::fixed << std::setprecision(2) << 100.0 * v;
    return s.str();
  };
  out << "samples            " << cm.total() << "\naccuracy           " << pct(cm.accuracy()) << " %\nbalanced accuracy  "
      << pct(cm.balanced_accuracy()) << " %\nmacro-F1           " << pct(cm.macro_f1()) << " %\n\n";
  out << "class   precision %   recall %       F1 %   support\n";
  json["samples"] = static_cast<long long>(cm.total());
  json["accuracy"] = cm.accuracy();
  json["balanced_accuracy"] = cm.balanced_accuracy();
  json["macro_f1"] = cm.macro_f1();
  Json::Array per_class;
  for (int c = 0; c < k; ++c) {
    out << std::setw(5) << classes[static_cast<std::size_t>(c)] << "   " << std::setw(11) << pct(cm.precision(c)) << "   "
        << std::setw(8) << pct(cm.recall(c)) << "   " << std::setw(8) << pct(cm.f1(c)) << "   " << std::setw(7) << cm.support(c) << '\n';
    Json entry;
    entry["label"] = classes[static_cast<std::size_t>(c)];
    entry["precision"] = cm.precision(c);  // null when nothing was predicted as this class
    entry["recall"] = cm.recall(c);
    entry["f1"] = cm.f1(c);
    entry["support"] = static_cast<long long>(cm.support(c));
    per_class.push_back(std::move(entry));
  }
  json["per_class"] = Json(std::move(per_class));
  out << "\nconfusion matrix (rows: true label, columns: predicted label)\ntrue\\pred";
  for (int c : classes) out << std::setw(8) << c;
  out << '\n';
  // Arrays are filled in place: pushing Json temporaries trips a false -Wmaybe-uninitialized in
  // g++ 12's std::variant move.
  Json::Array confusion;
  Json::Array labels;
  for (int r = 0; r < k; ++r) {
    labels.emplace_back(classes[static_cast<std::size_t>(r)]);
    out << std::setw(9) << classes[static_cast<std::size_t>(r)];
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
}

/// One CSV row's features as the run-time sized vector of an SvmModel<Eigen::Dynamic>.
inline Eigen::VectorXd row_vector(const std::vector<double>& row) {
  return Eigen::Map<const Eigen::VectorXd>(row.data(), static_cast<Eigen::Index>(row.size()));
}

int classify_train(Args args, std::ostream& out, std::ostream& err);
int classify_test(Args args, std::ostream& out, std::ostream& err);

}  // namespace ctxfuse::cli::classify_cli
