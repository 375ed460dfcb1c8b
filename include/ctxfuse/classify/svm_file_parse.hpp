// The two SVM model file parsers of svm_io.hpp (libsvm's text models and our own format), on a
// run-time dimension and without exceptions: each reading step returns false once the file is
// found wrong, and the first problem (file, line, field, message) is kept. svm_io.hpp holds the
// entry points, the throwing forms and the writer.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/io/text.hpp"

namespace ctxfuse::classify {

/// Why a model file could not be used.
struct SvmFileProblem {
  std::string file;
  int line = 0;  // 1-based; 0 when the problem is the file as a whole
  std::string field;
  std::string message;

  /// "<file>:<line>: <field>: <message>", without the line when it is 0.
  std::string what() const {
    std::string m = file;
    if (line > 0) m.append(":").append(std::to_string(line));
    return m.append(": ").append(field).append(": ").append(message);
  }
};

enum class SvmFileFormat : std::uint8_t { ctxfuse, libsvm, unknown };

inline constexpr std::string_view kSvmFileMagic = "ctxfuse-svm";
inline constexpr int kSvmFileVersion = 1;

namespace svm_io_detail {

/// Largest dimension and support vector count a file may claim (memory is still only taken
/// for what the file holds).
inline constexpr long long kMaxDimension = 1'000'000;
inline constexpr long long kMaxSupportVectors = 100'000'000;

/// A text file being parsed and the first problem found in it. Every reading step returns
/// false once something is wrong, so the parsers stop at the first problem without exceptions.
class Reader {
 public:
  Reader(std::istream& in, const std::string& source) : file_(in, source) {}

  bool next(std::string_view& line) { return file_.next(line); }
  int line() const { return static_cast<int>(file_.line_number()); }
  const std::string& name() const { return file_.name(); }

  /// Records the problem (at the current line unless `at_line` is given); returns false.
  bool fail(std::string_view field, std::string message, int at_line = -1) {
    if (!problem_) problem_ = SvmFileProblem{file_.name(), at_line < 0 ? line() : at_line, io::printable(field), std::move(message)};
    return false;
  }

  /// A finite number of any magnitude.
  bool real(std::string_view token, std::string_view field, double& v) {
    if (io::parse_real(token, v, io::kAnyFinite) == io::NumberError::none) return true;
    return fail(field, io::cat("expected a finite number, got ", io::quote(token)));
  }

  bool integer(std::string_view token, std::string_view field, long long& v) {
    if (io::parse_integer(token, v) == io::NumberError::none) return true;
    return fail(field, io::cat("expected an integer, got ", io::quote(token)));
  }

  /// libsvm writes labels with %d, yet data files sometimes carry "1.0": any whole value.
  bool label(std::string_view token, std::string_view field, int& v) {
    const auto e = io::parse_whole(token, v, -2'000'000'000, 2'000'000'000);
    if (e == io::NumberError::none) return true;
    const bool number = e == io::NumberError::not_whole || e == io::NumberError::out_of_range || e == io::NumberError::too_large;
    return fail(field, io::cat(number ? "expected an integer label, got " : "expected a finite number, got ", io::quote(token)));
  }

  template <int MaxClasses>
  bool class_count(long long k, std::string_view field) {
    if (k >= 2 && k <= MaxClasses) return true;
    return fail(field, "class count " + std::to_string(k) + " outside [2, " + std::to_string(MaxClasses) +
                           "] supported by this build (MaxClasses)");
  }

  std::optional<SvmFileProblem> take_problem() { return std::move(problem_); }

 private:
  io::TextFile file_;
  std::optional<SvmFileProblem> problem_;
};

inline std::string format_double(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

/// The dimension a reader is asked for: a fixed Dim, or for a run-time dimension 0 (the
/// file's) or the caller's. Out of range: a problem of the file as a whole.
template <int Dim>
std::optional<SvmFileProblem> requested_dimension_problem(const std::string& source, int dimension) {
  if constexpr (Dim == Eigen::Dynamic) {
    if (dimension >= 0 && dimension <= kMaxDimension) return std::nullopt;
  } else {
    if (dimension == Dim) return std::nullopt;
  }
  return SvmFileProblem{source, 0, "dimension", "requested dimension " + std::to_string(dimension) + " is not usable for this model type"};
}

/// The model's own check and its derived fields; a model the check refuses is the file's problem.
template <int Dim, int MaxClasses>
bool finalize(SvmModel<Dim, MaxClasses>& model, Reader& r) {
  if (auto problem = svm_model_problem(model); !problem.empty()) return r.fail("model", std::move(problem), 0);
  finalize_svm_model(model);
  return true;
}

/// One support vector feature of a libsvm file (sparse: absent features are zero).
struct SparseFeature {
  Eigen::Index sv;
  int index;  // 1-based
  double value;
};

/// libsvm's format into a fresh `model`. dim: the dimension asked for, 0 for the largest feature
/// index of the support vectors.
template <int Dim, int MaxClasses>
bool parse_libsvm(Reader& r, int dim, SvmModel<Dim, MaxClasses>& model) {
  std::string_view line;
  model.multiclass = SvmMulticlass::one_vs_one;
  long long nr_class = -1, total_sv = -1;
  bool have_kernel = false, have_gamma = false, have_rho = false, have_label = false, have_nr_sv = false;
  bool have_prob_a = false, have_prob_b = false, have_sv = false;
  std::vector<double> rho, prob_a, prob_b;
  std::vector<int> labels;
  std::vector<long long> nr_sv;
  int nr_sv_line = 0;
  const auto expect_count = [&](const std::vector<std::string_view>& t, long long n, std::string_view field) {
    if (nr_class < 0) return r.fail(field, "appears before nr_class");
    if (static_cast<long long>(t.size()) != n + 1)
      return r.fail(field, "expected " + std::to_string(n) + " values, got " + std::to_string(t.size() - 1));
    return true;
  };
  const auto reals = [&](const std::vector<std::string_view>& t, std::string_view field, std::vector<double>& dst) {
    for (std::size_t i = 1; i < t.size(); ++i) {
      double v = 0.0;
      if (!r.real(t[i], field, v)) return false;
      dst.push_back(v);
    }
    return true;
  };
  while (r.next(line)) {
    const auto t = io::split_fields(line, io::Separator::whitespace);
    if (t.empty()) continue;
    const std::string_view key = t[0];
    if (key == "SV") {
      have_sv = true;
      break;
    }
    if (key == "svm_type") {
      if (t.size() != 2 || t[1] != "c_svc")
        return r.fail(key, io::cat("only c_svc models are supported, got ", io::quote(t.size() > 1 ? t[1] : std::string_view())));
    } else if (key == "kernel_type") {
      if (t.size() != 2) return r.fail(key, "expected one value");
      if (t[1] == "linear") model.kernel = SvmKernel::linear;
      else if (t[1] == "rbf") model.kernel = SvmKernel::rbf;
      else return r.fail(key, io::cat("only linear and rbf kernels are supported, got ", io::quote(t[1])));
      have_kernel = true;
    } else if (key == "gamma") {
      if (t.size() != 2) return r.fail(key, "expected one value");
      if (!r.real(t[1], key, model.gamma)) return false;
      have_gamma = true;
    } else if (key == "degree" || key == "coef0") {
      // Only meaningful for polynomial and sigmoid kernels, which were rejected above.
    } else if (key == "nr_class") {
      if (t.size() != 2) return r.fail(key, "expected one value");
      if (!r.integer(t[1], key, nr_class) || !r.class_count<MaxClasses>(nr_class, key)) return false;
    } else if (key == "total_sv") {
      if (t.size() != 2) return r.fail(key, "expected one value");
      if (!r.integer(t[1], key, total_sv)) return false;
      if (total_sv < 1 || total_sv > kMaxSupportVectors)
        return r.fail(key, "implausible support vector count " + std::string(t[1]));
    } else if (key == "rho") {
      if (!expect_count(t, nr_class * (nr_class - 1) / 2, key) || !reals(t, key, rho)) return false;
      have_rho = true;
    } else if (key == "label") {
      if (!expect_count(t, nr_class, key)) return false;
      for (std::size_t i = 1; i < t.size(); ++i) {
        int v = 0;
        if (!r.label(t[i], key, v)) return false;
        labels.push_back(v);
      }
      have_label = true;
    } else if (key == "probA" || key == "probB") {
      if (!expect_count(t, nr_class * (nr_class - 1) / 2, key) || !reals(t, key, key == "probA" ? prob_a : prob_b))
        return false;
      (key == "probA" ? have_prob_a : have_prob_b) = true;
    } else if (key == "nr_sv") {
      if (!expect_count(t, nr_class, key)) return false;
      for (std::size_t i = 1; i < t.size(); ++i) {
        long long v = 0;
        if (!r.integer(t[i], key, v)) return false;
        if (v < 0) return r.fail(key, "negative count");
        nr_sv.push_back(v);
      }
      have_nr_sv = true;
      nr_sv_line = r.line();
    } else {
      return r.fail(key, "unknown header field");
    }
  }
  const std::pair<bool, const char*> required[] = {{have_sv, "SV"},           {have_kernel, "kernel_type"},
                                                   {nr_class >= 0, "nr_class"}, {total_sv >= 0, "total_sv"},
                                                   {have_rho, "rho"},          {have_label, "label"},
                                                   {have_nr_sv, "nr_sv"},
                                                   {have_gamma || model.kernel != SvmKernel::rbf, "gamma"}};
  for (const auto& [have, field] : required)
    if (!have) return r.fail(field, "missing from the header");
  if (have_prob_a != have_prob_b) return r.fail(have_prob_a ? "probB" : "probA", "probA and probB must come together");
  long long nr_sv_total = 0;
  for (auto n : nr_sv) nr_sv_total += n;
  if (nr_sv_total != total_sv)
    return r.fail("nr_sv", "counts sum to " + std::to_string(nr_sv_total) + ", total_sv says " + std::to_string(total_sv), nr_sv_line);

  const int k = static_cast<int>(nr_class);
  const auto l = static_cast<Eigen::Index>(total_sv);
  const int machines = svm_machine_count(SvmMulticlass::one_vs_one, k);
  // libsvm keeps k-1 coefficient rows; the SVs of class c serve the pairs (c, o): for o > c the
  // coefficient sits in row o-1, for o < c in row o. Rows are collected as they are read, so
  // memory follows the file's real content, not the count its header claims.
  std::vector<double> coef_values;
  std::vector<SparseFeature> features;
  int max_index = 0;
  for (Eigen::Index s = 0; s < l; ++s) {
    if (!r.next(line))
      return r.fail("SV", "file ends after " + std::to_string(s) + " of " + std::to_string(l) + " support vectors", r.line() + 1);
    const auto t = io::split_fields(line, io::Separator::whitespace);
    if (static_cast<int>(t.size()) < k - 1) return r.fail("SV", "expected " + std::to_string(k - 1) + " coefficients");
    for (int c = 0; c < k - 1; ++c) {
      double v = 0.0;
      if (!r.real(t[static_cast<std::size_t>(c)], "SV coefficient " + std::to_string(c + 1), v)) return false;
      coef_values.push_back(v);
    }
    long long previous_index = 0;
    for (std::size_t i = static_cast<std::size_t>(k - 1); i < t.size(); ++i) {
      const auto colon = t[i].find(':');
      if (colon == std::string_view::npos) return r.fail("SV feature", io::cat("expected index:value, got ", io::quote(t[i])));
      long long index = 0;
      if (!r.integer(t[i].substr(0, colon), "SV feature index", index)) return false;
      if (index <= previous_index) return r.fail("SV feature index", "indices must increase, got " + std::to_string(index));
      if (dim > 0 && index > dim)
        return r.fail("SV feature index", "index " + std::to_string(index) + " exceeds the model dimension " + std::to_string(dim));
      if (index > kMaxDimension)
        return r.fail("SV feature index", "index " + std::to_string(index) + " exceeds the largest dimension " + std::to_string(kMaxDimension));
      previous_index = index;
      double v = 0.0;
      if (!r.real(t[i].substr(colon + 1), "SV feature " + std::to_string(index), v)) return false;
      features.push_back({s, static_cast<int>(index), v});
      max_index = std::max(max_index, static_cast<int>(index));
    }
  }
  while (r.next(line))
    if (!io::split_fields(line, io::Separator::whitespace).empty()) return r.fail("SV", "more support vector lines than total_sv");
  if (dim == 0) dim = std::max(max_index, 1);

  model.num_classes = k;
  for (int i = 0; i < k; ++i) model.labels[static_cast<std::size_t>(i)] = labels[static_cast<std::size_t>(i)];
  for (int p = 0; p < machines; ++p) model.rho[static_cast<std::size_t>(p)] = rho[static_cast<std::size_t>(p)];
  model.has_probability = have_prob_a;
  if (have_prob_a)
    for (int p = 0; p < machines; ++p) {
      model.prob_a[static_cast<std::size_t>(p)] = prob_a[static_cast<std::size_t>(p)];
      model.prob_b[static_cast<std::size_t>(p)] = prob_b[static_cast<std::size_t>(p)];
    }
  if (!have_gamma) model.gamma = 1.0 / dim;  // unused by the linear kernel; as a fixed Dim's default
  model.input_mean.setZero(dim);  // libsvm models carry no standardisation
  model.input_std.setOnes(dim);
  model.support_vectors.setZero(l, dim);
  for (const auto& f : features) model.support_vectors(f.sv, f.index - 1) = f.value;
  const auto sv_coef = [&](int row, Eigen::Index s) { return coef_values[static_cast<std::size_t>(s * (k - 1) + row)]; };
  model.coefficients.setZero(machines, l);
  std::vector<Eigen::Index> start(static_cast<std::size_t>(k), 0);
  for (int c = 1; c < k; ++c) start[static_cast<std::size_t>(c)] = start[static_cast<std::size_t>(c - 1)] + nr_sv[static_cast<std::size_t>(c - 1)];
  int p = 0;
  for (int i = 0; i < k; ++i)
    for (int j = i + 1; j < k; ++j, ++p) {
      const auto si = start[static_cast<std::size_t>(i)], sj = start[static_cast<std::size_t>(j)];
      const auto ni = static_cast<Eigen::Index>(nr_sv[static_cast<std::size_t>(i)]);
      const auto nj = static_cast<Eigen::Index>(nr_sv[static_cast<std::size_t>(j)]);
      for (Eigen::Index s = si; s < si + ni; ++s) model.coefficients(p, s) = sv_coef(j - 1, s);
      for (Eigen::Index s = sj; s < sj + nj; ++s) model.coefficients(p, s) = sv_coef(i, s);
    }
  return finalize(model, r);
}

/// Our own format (docs/formats.md, section "svm") into a fresh `model`. dim: the dimension
/// asked for, 0 for the file's.
template <int Dim, int MaxClasses>
bool parse_ctxfuse(Reader& r, int dim, SvmModel<Dim, MaxClasses>& model) {
  std::string_view line;
  std::vector<std::string_view> t;
  // The next non-empty line, which must start with `key` and hold `expected` values (-1: any
  // number), into t without its key.
  const auto field = [&](std::string_view key, long long expected) {
    do {
      if (!r.next(line)) return r.fail(key, "file ends before this field", r.line() + 1);
    } while (io::split_fields(line, io::Separator::whitespace).empty());
    t = io::split_fields(line, io::Separator::whitespace);
    if (t[0] != key) return r.fail(key, io::cat("expected field '", key, "', found ", io::quote(t[0])));
    t.erase(t.begin());
    if (expected >= 0 && static_cast<long long>(t.size()) != expected)
      return r.fail(key, "expected " + std::to_string(expected) + " values, got " + std::to_string(t.size()));
    return true;
  };
  long long version = 0;
  if (!field(kSvmFileMagic, 1) || !r.integer(t[0], "version", version)) return false;
  if (version != kSvmFileVersion)
    return r.fail("version", "unsupported version " + std::to_string(version) + " (this build reads " + std::to_string(kSvmFileVersion) + ")");
  long long d = 0;
  if (!field("dimension", 1) || !r.integer(t[0], "dimension", d)) return false;
  if (dim > 0 && d != dim)
    return r.fail("dimension", "model has dimension " + std::to_string(d) + ", expected " + std::to_string(dim));
  if (d < 1 || d > kMaxDimension) return r.fail("dimension", "implausible dimension " + std::to_string(d));
  dim = static_cast<int>(d);
  if (!field("kernel", 1)) return false;
  if (t[0] == "linear") model.kernel = SvmKernel::linear;
  else if (t[0] == "rbf") model.kernel = SvmKernel::rbf;
  else return r.fail("kernel", io::cat("expected linear or rbf, got ", io::quote(t[0])));
  if (!field("gamma", 1) || !r.real(t[0], "gamma", model.gamma)) return false;
  if (!field("multiclass", 1)) return false;
  if (t[0] == "ovo") model.multiclass = SvmMulticlass::one_vs_one;
  else if (t[0] == "ovr") model.multiclass = SvmMulticlass::one_vs_rest;
  else return r.fail("multiclass", io::cat("expected ovo or ovr, got ", io::quote(t[0])));
  if (!field("labels", -1) || !r.class_count<MaxClasses>(static_cast<long long>(t.size()), "labels")) return false;
  model.num_classes = static_cast<int>(t.size());
  for (std::size_t i = 0; i < t.size(); ++i)
    if (!r.label(t[i], "labels", model.labels[i])) return false;
  const auto read_feature_vector = [&](std::string_view key, auto& dst) {
    if (!field(key, dim)) return false;
    dst.resize(dim);
    for (int f = 0; f < dim; ++f)
      if (!r.real(t[static_cast<std::size_t>(f)], key, dst[f])) return false;
    return true;
  };
  if (!read_feature_vector("input_mean", model.input_mean) || !read_feature_vector("input_std", model.input_std)) return false;
  for (int f = 0; f < dim; ++f)
    if (model.input_std[f] <= 0.0) return r.fail("input_std", "must be > 0");
  const int machines = model.num_machines();
  const auto read_machine_values = [&](std::string_view key, auto& dst) {
    if (!field(key, machines)) return false;
    for (int m = 0; m < machines; ++m)
      if (!r.real(t[static_cast<std::size_t>(m)], key, dst[static_cast<std::size_t>(m)])) return false;
    return true;
  };
  if (!read_machine_values("rho", model.rho)) return false;
  long long flag = 0;
  if (!field("probability", 1) || !r.integer(t[0], "probability", flag)) return false;
  if (flag != 0 && flag != 1) return r.fail("probability", "expected 0 or 1");
  model.has_probability = flag == 1;
  if (model.has_probability && (!read_machine_values("prob_a", model.prob_a) || !read_machine_values("prob_b", model.prob_b)))
    return false;
  long long n = 0;
  if (!field("support_vectors", 1) || !r.integer(t[0], "support_vectors", n)) return false;
  if (n < 1 || n > kMaxSupportVectors) return r.fail("support_vectors", "implausible count " + std::to_string(n));
  const auto l = static_cast<Eigen::Index>(n);
  std::vector<double> coef_values, feature_values;  // grown as read, see parse_libsvm
  for (Eigen::Index s = 0; s < l; ++s) {
    if (!r.next(line))
      return r.fail("support vector", "file ends after " + std::to_string(s) + " of " + std::to_string(l), r.line() + 1);
    t = io::split_fields(line, io::Separator::whitespace);
    if (static_cast<int>(t.size()) != machines + dim)
      return r.fail("support vector", "expected " + std::to_string(machines) + " coefficients and " + std::to_string(dim) +
                                          " features, got " + std::to_string(t.size()) + " values");
    for (int m = 0; m < machines; ++m) {
      double v = 0.0;
      if (!r.real(t[static_cast<std::size_t>(m)], "coefficient " + std::to_string(m + 1), v)) return false;
      coef_values.push_back(v);
    }
    for (int f = 0; f < dim; ++f) {
      double v = 0.0;
      if (!r.real(t[static_cast<std::size_t>(machines + f)], "feature " + std::to_string(f + 1), v)) return false;
      feature_values.push_back(v);
    }
  }
  model.support_vectors.resize(l, dim);
  model.coefficients.resize(machines, l);
  for (Eigen::Index s = 0; s < l; ++s) {
    for (int m = 0; m < machines; ++m) model.coefficients(m, s) = coef_values[static_cast<std::size_t>(s * machines + m)];
    for (int f = 0; f < dim; ++f) model.support_vectors(s, f) = feature_values[static_cast<std::size_t>(s * dim + f)];
  }
  if (!field("end", 0)) return false;
  while (r.next(line))
    if (!io::split_fields(line, io::Separator::whitespace).empty()) return r.fail("end", "unexpected content after 'end'");
  return finalize(model, r);
}

}  // namespace svm_io_detail

}  // namespace ctxfuse::classify
