// `ctxfuse context joint`: the region paper's joint classifier (SVM + HMM, weighted vote,
// eq. 18-28) on a time-ordered labelled feature CSV such as `features nmea` writes, with the
// region transition matrix (eq. 36-37) of the joint labels.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <ctxfuse/classify/hmm.hpp>
#include <ctxfuse/classify/joint.hpp>
#include <ctxfuse/classify/region_transition.hpp>
#include <ctxfuse/classify/svm.hpp>
#include <ctxfuse/classify/svm_train.hpp>
#include <ctxfuse/classify/confusion_matrix.hpp>
#include <ctxfuse/io/text.hpp>

#include "cli/options.hpp"
#include "cli/registry.hpp"

namespace {

using ctxfuse::cli::Args;
namespace cls = ctxfuse::classify;
namespace io = ctxfuse::io;

constexpr std::string_view kHelp =
    "The region paper's joint classifier (SVM + HMM, weighted vote, eq. 18-28). CSVs: header, integer\n"
    "`label` column with regions 0..N-1 (N = 2 or 3), 2 or 8 numeric feature columns, rows in time order\n"
    "(one sequence). The first 1-F of --train fits an SVM and a Gaussian HMM; the last F is the\n"
    "validation set that gives the per-region accuracies P_S,k, P_H,k and so the vote weights\n"
    "w = P / (P_S + P_H). --test is then classified by the SVM, the HMM (Viterbi over the whole test\n"
    "sequence, or the online forward filter's most probable region) and the weighted vote; prints\n"
    "accuracy, precision/recall and confusion matrix of each, and the transition matrix of the joint\n"
    "labels (rows without transitions: identity).";

struct Table {
  std::vector<int> labels;
  std::vector<std::vector<double>> rows;
  int features = 0;
};

/// Every column but `label` is a feature; every field must be a finite number.
Table read_table(const std::string& path) {
  io::TextFile file(path);
  Table t;
  std::string_view line;
  do {
    if (!file.next(line)) throw io::ParseError(file.name(), 0, 0, "", "no data rows");
  } while (io::trim(line).empty());
  const io::Header header(io::split_fields(line, io::Separator::comma));
  std::size_t label_col = io::require_column(file, header, "label");
  for (std::size_t i = label_col + 1; i < header.size(); ++i)  // of several, the last; the others are features
    if (header.name(i) == "label") label_col = i;
  t.features = static_cast<int>(header.size()) - 1;
  io::Fields f(file.name(), &header);
  while (io::next_fields(file, f, io::Separator::comma)) {
    f.expect_count(header.size());
    std::vector<double> row;
    for (std::size_t i = 0; i < f.size(); ++i)
      if (i == label_col) t.labels.push_back(f.whole<int>(i, 0, 2));  // a region 0, 1 or 2
      else row.push_back(f.real(i, io::kAnyFinite));
    t.rows.push_back(std::move(row));
  }
  if (t.rows.empty()) throw io::ParseError(file.name(), 0, 0, "", "no data rows");
  return t;
}

std::string pct(double v) {
  if (!std::isfinite(v)) return "   nan";
  char b[16];
  std::snprintf(b, sizeof b, "%6.2f", 100.0 * v);
  return b;
}

void report(std::ostream& out, std::string_view name, std::span<const int> truth, std::span<const int> pred, int n) {
  const auto m = ctxfuse::classify::ConfusionMatrix::from_labels(truth, pred, n);
  out << name << ": accuracy " << pct(m.accuracy()) << " %, balanced accuracy " << pct(m.balanced_accuracy())
      << " %, macro-F1 " << pct(m.macro_f1()) << " %\n  region  precision %  recall %  support\n";
  for (int k = 0; k < n; ++k)
    out << "  " << k << "       " << pct(m.precision(k)) << "     " << pct(m.recall(k)) << "   " << m.support(k) << '\n';
  out << "  confusion (rows: true region, columns: predicted region)\n  true\\pred";
  for (int p = 0; p < n; ++p) out << ' ' << std::setw(6) << p;
  for (int t = 0; t < n; ++t) {
    out << "\n  " << std::setw(9) << t;
    for (int p = 0; p < n; ++p) out << ' ' << std::setw(6) << m.count(t, p);
  }
  out << '\n';
}

struct Settings {
  double validation_fraction = 0.25;
  cls::SvmTrainOptions svm;
  cls::HmmFitOptions hmm;
  bool viterbi = true;
};

template <int N, int D>
int run_joint(const Table& train, const Table& test, const Settings& s, std::ostream& out) {
  using Vec = Eigen::Matrix<double, D, 1>;
  auto to_vecs = [](const Table& t, std::size_t b, std::size_t e) {
    std::vector<Vec> v;
    for (std::size_t i = b; i < e; ++i) v.push_back(Eigen::Map<const Vec>(t.rows[i].data()));
    return v;
  };
  const std::size_t cut =
      static_cast<std::size_t>(std::llround((1.0 - s.validation_fraction) * double(train.rows.size())));
  if (cut < 4 || cut >= train.rows.size()) throw std::runtime_error("--validation-fraction leaves no fit or no validation rows");
  const auto fit_x = to_vecs(train, 0, cut), val_x = to_vecs(train, cut, train.rows.size()),
             test_x = to_vecs(test, 0, test.rows.size());
  const std::span<const int> fit_y(train.labels.data(), cut), val_y(train.labels.data() + cut, train.rows.size() - cut);

  cls::SvmFeatures<D> fx(static_cast<Eigen::Index>(fit_x.size()), D);
  for (std::size_t i = 0; i < fit_x.size(); ++i) fx.row(static_cast<Eigen::Index>(i)) = fit_x[i].transpose();
  const auto svm = cls::train_svm<D>(fx, fit_y, s.svm);
  const cls::LabelledSequence<D> seq{fit_x, fit_y};
  const auto hmm = cls::fit_supervised<N, D>(std::span<const cls::LabelledSequence<D>>(&seq, 1), s.hmm);

  auto svm_labels = [&](const std::vector<Vec>& x) {
    std::vector<int> y;
    for (const auto& v : x) {
      cls::SvmPrediction<8> p;
      if (const ctxfuse::Status st = cls::svm_predict(svm, v, p); !st)
        throw std::runtime_error("SVM prediction failed: " + std::string(ctxfuse::describe(st.problem)));
      y.push_back(p.label);
    }
    return y;
  };
  auto hmm_labels = [&](const std::vector<Vec>& x) {
    if (s.viterbi) {
      auto v = cls::viterbi<N, D>(hmm, x);
      if (!v.status) throw std::runtime_error("HMM: row " + std::to_string(v.refused_at + 1) + " is not finite");
      return std::move(v.path);
    }
    cls::HmmForwardFilter<N, D> filter(hmm);
    std::vector<int> y;
    for (const auto& v : x) {
      // A refused epoch keeps the previous posterior: its argmax is reused.
      static_cast<void>(filter.step(v));
      y.push_back(filter.most_probable());
    }
    return y;
  };

  const auto val_svm = svm_labels(val_x), val_hmm = hmm_labels(val_x);
  const auto p_svm = cls::per_region_accuracy<N>(val_y, val_svm), p_hmm = cls::per_region_accuracy<N>(val_y, val_hmm);
  const auto vote = cls::WeightedVote<N, 2>::from_accuracies({p_svm, p_hmm});
  out << "fit " << cut << " rows, validation " << val_y.size() << " rows, test " << test.rows.size() << " rows; "
      << N << " regions, " << D << " features\n";
  out << "validation accuracy per region (SVM / HMM) and weights w_s / w_h:\n";
  for (int k = 0; k < N; ++k)
    out << "  region " << k << " (" << std::count(val_y.begin(), val_y.end(), k) << " rows): " << pct(p_svm[k]) << " / "
        << pct(p_hmm[k]) << " %   w " << vote.weights[0][k] << " / " << vote.weights[1][k] << '\n';

  const auto t_svm = svm_labels(test_x), t_hmm = hmm_labels(test_x);
  std::vector<int> t_joint(t_svm.size());
  for (std::size_t i = 0; i < t_svm.size(); ++i) t_joint[i] = vote({t_svm[i], t_hmm[i]});
  report(out, "SVM", test.labels, t_svm, N);
  report(out, s.viterbi ? "HMM (Viterbi)" : "HMM (forward filter)", test.labels, t_hmm, N);
  report(out, "joint vote", test.labels, t_joint, N);
  const auto m = cls::region_transition_matrix<N>(t_joint);
  out << "transition matrix of the joint labels (eq. 36-37):\n";
  for (int i = 0; i < N; ++i) {
    out << " ";
    for (int j = 0; j < N; ++j) {
      char b[16];
      std::snprintf(b, sizeof b, " %.4f", m(i, j));
      out << b;
    }
    out << '\n';
  }
  return 0;
}

int run_context(Args args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    (args.empty() ? err : out) << "usage: ctxfuse context joint [options]   (`ctxfuse context joint --help` lists them)\n";
    return args.empty() ? 2 : 0;
  }
  if (args[0] != "joint") {
    err << "ctxfuse context: unknown sub-command '" << args[0] << "' (joint)\n";
    return 2;
  }
  auto app = ctxfuse::cli::make_app("context joint", std::string(kHelp));
  std::string train_path, test_path, kernel = "linear", covariance = "diagonal", decoder = "viterbi";
  Settings s;
  s.svm.C = 1.0;
  s.svm.gamma = 0.0;
  app.add_option("--train", train_path, "labelled CSV: fit (first 1-F) and validation (last F) rows")->required();
  app.add_option("--test", test_path, "labelled CSV to classify")->required();
  app.add_option("--validation-fraction", s.validation_fraction, "F: the last F of --train validate")->check(CLI::Range(0.0, 1.0));
  app.add_option("--kernel", kernel, "SVM kernel: linear or rbf")->check(CLI::IsMember({"linear", "rbf"}));
  app.add_option("--C", s.svm.C, "SVM C")->check(ctxfuse::cli::kPositiveNumber);
  app.add_option("--gamma", s.svm.gamma, "RBF gamma; 0 = 1 / features")->check(ctxfuse::cli::kNonNegativeNumber);
  app.add_option("--covariance", covariance, "HMM emission covariance: full or diagonal")->check(CLI::IsMember({"full", "diagonal"}));
  app.add_option("--decoder", decoder, "HMM decoding: viterbi or filter")->check(CLI::IsMember({"viterbi", "filter"}));
  if (const auto status = ctxfuse::cli::parse_options(app, args.subspan(1), out, err)) return *status;
  if (!(s.validation_fraction > 0.0 && s.validation_fraction < 1.0)) {
    err << "ctxfuse context joint: --validation-fraction must be in (0, 1)\n";
    return 2;
  }
  s.svm.kernel = kernel == "rbf" ? cls::SvmKernel::rbf : cls::SvmKernel::linear;
  s.hmm.covariance = covariance == "full" ? cls::CovarianceKind::full : cls::CovarianceKind::diagonal;
  s.viterbi = decoder == "viterbi";
  try {
    const Table train = read_table(train_path), test = read_table(test_path);
    if (train.features != test.features) throw std::runtime_error("--train and --test have different feature counts");
    const int regions = 1 + std::max(*std::max_element(train.labels.begin(), train.labels.end()),
                                     *std::max_element(test.labels.begin(), test.labels.end()));
    const int n = std::max(regions, 2);
    if (train.features == 8 && n == 2) return run_joint<2, 8>(train, test, s, out);
    if (train.features == 8 && n == 3) return run_joint<3, 8>(train, test, s, out);
    if (train.features == 2 && n == 2) return run_joint<2, 2>(train, test, s, out);
    if (train.features == 2 && n == 3) return run_joint<3, 2>(train, test, s, out);
    err << "ctxfuse context joint: " << train.features << " features are not supported (2 or 8)\n";
    return 2;
  } catch (const std::exception& e) {
    err << "ctxfuse context joint: error: " << e.what() << '\n';
    return 1;
  }
}

const ctxfuse::cli::RegisterCommand reg_context_data{
    {"context", "joint SVM + HMM region recognition on labelled feature sequences", run_context}};

}  // namespace
