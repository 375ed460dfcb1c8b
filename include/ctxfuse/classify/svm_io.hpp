// Reading and writing SVM models: libsvm's text model files (as svm-train writes them) and our
// own versioned text format, which adds the input standardisation and one-vs-rest layouts.
// Both are read with io/text.hpp (lines, whitespace-separated fields, numbers). Loading may
// allocate; a malformed file throws SvmFileError (an io::ParseError) naming file, line and
// field, and never yields a half-built model.
#pragma once

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/io/text.hpp"

namespace ctxfuse::classify {

/// A model file could not be used. what() reads "<file>:<line>: <field>: <message>" (without
/// the line when the problem is the file as a whole).
struct SvmFileError : io::ParseError {
  SvmFileError(std::string file_, int line_, std::string field_, const std::string& message)
      : io::ParseError(file_, static_cast<std::size_t>(line_), 0, "", io::cat(field_, ": ", message)),
        file(std::move(file_)),
        line(line_),
        field(std::move(field_)) {}
  // Plain members, for the users of this type; they hide ParseError's file() and line().
  std::string file;
  int line;  // 1-based; 0 when the problem is the file as a whole
  std::string field;
};

enum class SvmFileFormat : std::uint8_t { ctxfuse, libsvm, unknown };

inline constexpr std::string_view kSvmFileMagic = "ctxfuse-svm";
inline constexpr int kSvmFileVersion = 1;

namespace svm_io_detail {

inline int line_number(const io::TextFile& file) { return static_cast<int>(file.line_number()); }

/// Throws SvmFileError at the current line of `file`.
[[noreturn]] inline void fail(const io::TextFile& file, std::string field, const std::string& message) {
  throw SvmFileError(file.name(), line_number(file), std::move(field), message);
}

/// A finite number of any magnitude.
inline double real_field(const io::TextFile& file, std::string_view token, const std::string& field) {
  double v = 0.0;
  if (io::parse_real(token, v, io::kAnyFinite) != io::NumberError::none)
    fail(file, field, io::cat("expected a finite number, got ", io::quote(token)));
  return v;
}

inline long long integer_field(const io::TextFile& file, std::string_view token, const std::string& field) {
  long long v = 0;
  if (io::parse_integer(token, v) != io::NumberError::none)
    fail(file, field, io::cat("expected an integer, got ", io::quote(token)));
  return v;
}

/// libsvm writes labels with %d, yet data files sometimes carry "1.0": any whole value.
inline int label_field(const io::TextFile& file, std::string_view token, const std::string& field) {
  int v = 0;
  const auto e = io::parse_whole(token, v, -2'000'000'000, 2'000'000'000);
  if (e == io::NumberError::none) return v;
  const bool number = e == io::NumberError::not_whole || e == io::NumberError::out_of_range || e == io::NumberError::too_large;
  fail(file, field, io::cat(number ? "expected an integer label, got " : "expected a finite number, got ", io::quote(token)));
}

inline std::string format_double(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

template <int MaxClasses>
void check_class_count(const io::TextFile& r, long long k, const std::string& field) {
  if (k < 2 || k > MaxClasses)
    fail(r, field, "class count " + std::to_string(k) + " outside [2, " + std::to_string(MaxClasses) +
                       "] supported by this build (MaxClasses)");
}

template <int Dim, int MaxClasses>
void finalize_or_fail(SvmModel<Dim, MaxClasses>& model, const io::TextFile& r) {
  if (auto problem = svm_model_problem(model); !problem.empty()) throw SvmFileError(r.name(), 0, "model", problem);
  finalize_svm_model(model);
}

}  // namespace svm_io_detail

/// Format from the first line: "ctxfuse-svm ..." or "svm_type ..."; unknown otherwise.
inline SvmFileFormat detect_svm_file_format(std::string_view first_line) {
  const auto tokens = io::split_fields(first_line, io::Separator::whitespace);
  if (tokens.empty()) return SvmFileFormat::unknown;
  if (tokens[0] == kSvmFileMagic) return SvmFileFormat::ctxfuse;
  if (tokens[0] == "svm_type") return SvmFileFormat::libsvm;
  return SvmFileFormat::unknown;
}

/// Reads a libsvm model (C-SVC, linear or RBF kernel). Features with index > Dim are an error;
/// indices absent from a support vector line are zero, as in libsvm's sparse format. libsvm
/// models carry no standardisation, so inputs are used as given.
template <int Dim, int MaxClasses = 8>
SvmModel<Dim, MaxClasses> read_libsvm_model(std::istream& in, const std::string& source) {
  using namespace svm_io_detail;
  io::TextFile r(in, source);
  std::string_view line;
  SvmModel<Dim, MaxClasses> model;
  model.multiclass = SvmMulticlass::one_vs_one;
  long long nr_class = -1, total_sv = -1;
  bool have_kernel = false, have_gamma = false, have_rho = false, have_label = false, have_nr_sv = false;
  bool have_prob_a = false, have_prob_b = false, have_sv = false;
  std::vector<double> rho, prob_a, prob_b;
  std::vector<int> labels;
  std::vector<long long> nr_sv;
  int nr_sv_line = 0;
  const auto expect_count = [&](const std::vector<std::string_view>& t, std::size_t n, const std::string& field) {
    if (nr_class < 0) fail(r, field, "appears before nr_class");
    if (t.size() != n + 1)
      fail(r, field, "expected " + std::to_string(n) + " values, got " + std::to_string(t.size() - 1));
  };
  while (r.next(line)) {
    const auto t = io::split_fields(line, io::Separator::whitespace);
    if (t.empty()) continue;
    const std::string key(t[0]);
    if (key == "SV") {
      have_sv = true;
      break;
    }
    if (key == "svm_type") {
      if (t.size() != 2 || t[1] != "c_svc")
        fail(r, key, "only c_svc models are supported, got '" + (t.size() > 1 ? std::string(t[1]) : std::string()) + "'");
    } else if (key == "kernel_type") {
      if (t.size() != 2) fail(r, key, "expected one value");
      if (t[1] == "linear") model.kernel = SvmKernel::linear;
      else if (t[1] == "rbf") model.kernel = SvmKernel::rbf;
      else fail(r, key, "only linear and rbf kernels are supported, got '" + std::string(t[1]) + "'");
      have_kernel = true;
    } else if (key == "gamma") {
      if (t.size() != 2) fail(r, key, "expected one value");
      model.gamma = real_field(r, t[1], key);
      have_gamma = true;
    } else if (key == "degree" || key == "coef0") {
      // Only meaningful for polynomial and sigmoid kernels, which were rejected above.
    } else if (key == "nr_class") {
      if (t.size() != 2) fail(r, key, "expected one value");
      nr_class = integer_field(r, t[1], key);
      check_class_count<MaxClasses>(r, nr_class, key);
    } else if (key == "total_sv") {
      if (t.size() != 2) fail(r, key, "expected one value");
      total_sv = integer_field(r, t[1], key);
      if (total_sv < 1 || total_sv > 100'000'000) fail(r, key, "implausible support vector count " + std::string(t[1]));
    } else if (key == "rho") {
      expect_count(t, static_cast<std::size_t>(nr_class * (nr_class - 1) / 2), key);
      for (std::size_t i = 1; i < t.size(); ++i) rho.push_back(real_field(r, t[i], key));
      have_rho = true;
    } else if (key == "label") {
      expect_count(t, static_cast<std::size_t>(nr_class), key);
      for (std::size_t i = 1; i < t.size(); ++i) labels.push_back(label_field(r, t[i], key));
      have_label = true;
    } else if (key == "probA" || key == "probB") {
      expect_count(t, static_cast<std::size_t>(nr_class * (nr_class - 1) / 2), key);
      auto& dst = key == "probA" ? prob_a : prob_b;
      for (std::size_t i = 1; i < t.size(); ++i) dst.push_back(real_field(r, t[i], key));
      (key == "probA" ? have_prob_a : have_prob_b) = true;
    } else if (key == "nr_sv") {
      expect_count(t, static_cast<std::size_t>(nr_class), key);
      for (std::size_t i = 1; i < t.size(); ++i) {
        nr_sv.push_back(integer_field(r, t[i], key));
        if (nr_sv.back() < 0) fail(r, key, "negative count");
      }
      have_nr_sv = true;
      nr_sv_line = line_number(r);
    } else {
      fail(r, key, "unknown header field");
    }
  }
  const auto missing = [&](bool have, const char* field) {
    if (!have) throw SvmFileError(source, line_number(r), field, "missing from the header");
  };
  missing(have_sv, "SV");
  missing(have_kernel, "kernel_type");
  missing(nr_class >= 0, "nr_class");
  missing(total_sv >= 0, "total_sv");
  missing(have_rho, "rho");
  missing(have_label, "label");
  missing(have_nr_sv, "nr_sv");
  if (model.kernel == SvmKernel::rbf) missing(have_gamma, "gamma");
  if (have_prob_a != have_prob_b) fail(r, have_prob_a ? "probB" : "probA", "probA and probB must come together");
  long long nr_sv_total = 0;
  for (auto n : nr_sv) nr_sv_total += n;
  if (nr_sv_total != total_sv)
    throw SvmFileError(source, nr_sv_line, "nr_sv", "counts sum to " + std::to_string(nr_sv_total) + ", total_sv says " + std::to_string(total_sv));

  const int k = static_cast<int>(nr_class);
  const auto l = static_cast<Eigen::Index>(total_sv);
  const int machines = svm_machine_count(SvmMulticlass::one_vs_one, k);
  model.num_classes = k;
  for (int i = 0; i < k; ++i) model.labels[static_cast<std::size_t>(i)] = labels[static_cast<std::size_t>(i)];
  for (int p = 0; p < machines; ++p) model.rho[static_cast<std::size_t>(p)] = rho[static_cast<std::size_t>(p)];
  model.has_probability = have_prob_a;
  if (have_prob_a)
    for (int p = 0; p < machines; ++p) {
      model.prob_a[static_cast<std::size_t>(p)] = prob_a[static_cast<std::size_t>(p)];
      model.prob_b[static_cast<std::size_t>(p)] = prob_b[static_cast<std::size_t>(p)];
    }

  // libsvm keeps k-1 coefficient rows; the SVs of class c serve the pairs (c, o): for o > c the
  // coefficient sits in row o-1, for o < c in row o. Rows are collected as they are read, so
  // memory follows the file's real content, not the count its header claims.
  std::vector<double> coef_values, feature_values;
  for (Eigen::Index s = 0; s < l; ++s) {
    if (!r.next(line))
      throw SvmFileError(source, line_number(r) + 1, "SV", "file ends after " + std::to_string(s) + " of " +
                                                              std::to_string(l) + " support vectors");
    const auto t = io::split_fields(line, io::Separator::whitespace);
    if (static_cast<int>(t.size()) < k - 1) fail(r, "SV", "expected " + std::to_string(k - 1) + " coefficients");
    for (int c = 0; c < k - 1; ++c) coef_values.push_back(real_field(r, t[static_cast<std::size_t>(c)], "SV coefficient " + std::to_string(c + 1)));
    std::array<double, Dim> row{};
    long long previous_index = 0;
    for (std::size_t i = static_cast<std::size_t>(k - 1); i < t.size(); ++i) {
      const auto colon = t[i].find(':');
      if (colon == std::string_view::npos) fail(r, "SV feature", "expected index:value, got '" + std::string(t[i]) + "'");
      const long long index = integer_field(r, t[i].substr(0, colon), "SV feature index");
      if (index <= previous_index) fail(r, "SV feature index", "indices must increase, got " + std::to_string(index));
      if (index > Dim)
        fail(r, "SV feature index", "index " + std::to_string(index) + " exceeds the model dimension " + std::to_string(Dim));
      previous_index = index;
      row[static_cast<std::size_t>(index - 1)] = real_field(r, t[i].substr(colon + 1), "SV feature " + std::to_string(index));
    }
    feature_values.insert(feature_values.end(), row.begin(), row.end());
  }
  while (r.next(line))
    if (!io::split_fields(line, io::Separator::whitespace).empty()) fail(r, "SV", "more support vector lines than total_sv");

  const auto sv_coef = [&](int row, Eigen::Index s) { return coef_values[static_cast<std::size_t>(s * (k - 1) + row)]; };
  model.support_vectors.resize(l, Dim);
  for (Eigen::Index s = 0; s < l; ++s)
    for (int f = 0; f < Dim; ++f) model.support_vectors(s, f) = feature_values[static_cast<std::size_t>(s * Dim + f)];
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
  finalize_or_fail(model, r);
  return model;
}

/// Reads our own format (see docs/formats.md, section "svm").
template <int Dim, int MaxClasses = 8>
SvmModel<Dim, MaxClasses> read_ctxfuse_svm_model(std::istream& in, const std::string& source) {
  using namespace svm_io_detail;
  io::TextFile r(in, source);
  std::string_view line;
  SvmModel<Dim, MaxClasses> model;
  // Reads the next non-empty line, which must start with `key`, and returns its values.
  const auto field = [&](const std::string& key, int expected_values) {
    do {
      if (!r.next(line)) throw SvmFileError(source, line_number(r) + 1, key, "file ends before this field");
    } while (io::split_fields(line, io::Separator::whitespace).empty());
    auto t = io::split_fields(line, io::Separator::whitespace);
    if (t[0] != key) fail(r, key, "expected field '" + key + "', found '" + std::string(t[0]) + "'");
    t.erase(t.begin());
    if (expected_values >= 0 && static_cast<int>(t.size()) != expected_values)
      fail(r, key, "expected " + std::to_string(expected_values) + " values, got " + std::to_string(t.size()));
    return t;
  };
  {
    const auto t = field(std::string(kSvmFileMagic), 1);
    const auto version = integer_field(r, t[0], "version");
    if (version != kSvmFileVersion)
      fail(r, "version", "unsupported version " + std::to_string(version) + " (this build reads " + std::to_string(kSvmFileVersion) + ")");
  }
  {
    const auto t = field("dimension", 1);
    const auto d = integer_field(r, t[0], "dimension");
    if (d != Dim) fail(r, "dimension", "model has dimension " + std::to_string(d) + ", expected " + std::to_string(Dim));
  }
  {
    const auto t = field("kernel", 1);
    if (t[0] == "linear") model.kernel = SvmKernel::linear;
    else if (t[0] == "rbf") model.kernel = SvmKernel::rbf;
    else fail(r, "kernel", "expected linear or rbf, got '" + std::string(t[0]) + "'");
  }
  model.gamma = real_field(r, field("gamma", 1)[0], "gamma");
  {
    const auto t = field("multiclass", 1);
    if (t[0] == "ovo") model.multiclass = SvmMulticlass::one_vs_one;
    else if (t[0] == "ovr") model.multiclass = SvmMulticlass::one_vs_rest;
    else fail(r, "multiclass", "expected ovo or ovr, got '" + std::string(t[0]) + "'");
  }
  {
    const auto t = field("labels", -1);
    check_class_count<MaxClasses>(r, static_cast<long long>(t.size()), "labels");
    model.num_classes = static_cast<int>(t.size());
    for (std::size_t i = 0; i < t.size(); ++i) model.labels[i] = label_field(r, t[i], "labels");
  }
  const auto read_feature_vector = [&](const std::string& key, auto& dst) {
    const auto t = field(key, Dim);
    for (int f = 0; f < Dim; ++f) dst[f] = real_field(r, t[static_cast<std::size_t>(f)], key);
  };
  read_feature_vector("input_mean", model.input_mean);
  read_feature_vector("input_std", model.input_std);
  for (int f = 0; f < Dim; ++f)
    if (model.input_std[f] <= 0.0) fail(r, "input_std", "must be > 0");
  const int machines = model.num_machines();
  const auto read_machine_values = [&](const std::string& key, auto& dst) {
    const auto t = field(key, machines);
    for (int m = 0; m < machines; ++m) dst[static_cast<std::size_t>(m)] = real_field(r, t[static_cast<std::size_t>(m)], key);
  };
  read_machine_values("rho", model.rho);
  {
    const auto t = field("probability", 1);
    const auto flag = integer_field(r, t[0], "probability");
    if (flag != 0 && flag != 1) fail(r, "probability", "expected 0 or 1");
    model.has_probability = flag == 1;
  }
  if (model.has_probability) {
    read_machine_values("prob_a", model.prob_a);
    read_machine_values("prob_b", model.prob_b);
  }
  const auto n = integer_field(r, field("support_vectors", 1)[0], "support_vectors");
  if (n < 1 || n > 100'000'000) fail(r, "support_vectors", "implausible count " + std::to_string(n));
  const auto l = static_cast<Eigen::Index>(n);
  std::vector<double> coef_values, feature_values;  // grown as read, see read_libsvm_model
  for (Eigen::Index s = 0; s < l; ++s) {
    if (!r.next(line))
      throw SvmFileError(source, line_number(r) + 1, "support vector", "file ends after " + std::to_string(s) + " of " + std::to_string(l));
    const auto t = io::split_fields(line, io::Separator::whitespace);
    if (static_cast<int>(t.size()) != machines + Dim)
      fail(r, "support vector", "expected " + std::to_string(machines) + " coefficients and " + std::to_string(Dim) +
                                    " features, got " + std::to_string(t.size()) + " values");
    for (int m = 0; m < machines; ++m) coef_values.push_back(real_field(r, t[static_cast<std::size_t>(m)], "coefficient " + std::to_string(m + 1)));
    for (int f = 0; f < Dim; ++f)
      feature_values.push_back(real_field(r, t[static_cast<std::size_t>(machines + f)], "feature " + std::to_string(f + 1)));
  }
  model.support_vectors.resize(l, Dim);
  model.coefficients.resize(machines, l);
  for (Eigen::Index s = 0; s < l; ++s) {
    for (int m = 0; m < machines; ++m) model.coefficients(m, s) = coef_values[static_cast<std::size_t>(s * machines + m)];
    for (int f = 0; f < Dim; ++f) model.support_vectors(s, f) = feature_values[static_cast<std::size_t>(s * Dim + f)];
  }
  field("end", 0);
  while (r.next(line))
    if (!io::split_fields(line, io::Separator::whitespace).empty()) fail(r, "end", "unexpected content after 'end'");
  finalize_or_fail(model, r);
  return model;
}

/// Writes our format; numbers with 17 significant digits so that a reload is bit-exact.
template <int Dim, int MaxClasses>
void write_ctxfuse_svm_model(std::ostream& out, const SvmModel<Dim, MaxClasses>& model) {
  using svm_io_detail::format_double;
  const int machines = model.num_machines();
  out << kSvmFileMagic << ' ' << kSvmFileVersion << '\n';
  out << "dimension " << Dim << '\n';
  out << "kernel " << to_string(model.kernel) << '\n';
  out << "gamma " << format_double(model.gamma) << '\n';
  out << "multiclass " << to_string(model.multiclass) << '\n';
  out << "labels";
  for (int i = 0; i < model.num_classes; ++i) out << ' ' << model.labels[static_cast<std::size_t>(i)];
  out << "\ninput_mean";
  for (int f = 0; f < Dim; ++f) out << ' ' << format_double(model.input_mean[f]);
  out << "\ninput_std";
  for (int f = 0; f < Dim; ++f) out << ' ' << format_double(model.input_std[f]);
  const auto machine_line = [&](const char* key, const auto& values) {
    out << '\n' << key;
    for (int m = 0; m < machines; ++m) out << ' ' << format_double(values[static_cast<std::size_t>(m)]);
  };
  machine_line("rho", model.rho);
  out << "\nprobability " << (model.has_probability ? 1 : 0);
  if (model.has_probability) {
    machine_line("prob_a", model.prob_a);
    machine_line("prob_b", model.prob_b);
  }
  out << "\nsupport_vectors " << model.support_vectors.rows() << '\n';
  for (Eigen::Index s = 0; s < model.support_vectors.rows(); ++s) {
    for (int m = 0; m < machines; ++m) out << format_double(model.coefficients(m, s)) << ' ';
    for (int f = 0; f < Dim; ++f) out << format_double(model.support_vectors(s, f)) << (f + 1 < Dim ? ' ' : '\n');
  }
  out << "end\n";
}

namespace svm_io_detail {
inline std::ifstream open_model(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw SvmFileError(path.string(), 0, "file", "cannot open for reading");
  return in;
}
}  // namespace svm_io_detail

/// Format of a model file from its first line.
inline SvmFileFormat detect_svm_file_format(const std::filesystem::path& path) {
  auto in = svm_io_detail::open_model(path);
  io::TextFile file(in, path.string());
  std::string_view first;  // stays empty for an empty file
  file.next(first);
  return detect_svm_file_format(first);
}

/// Loads either format, chosen by the first line.
template <int Dim, int MaxClasses = 8>
SvmModel<Dim, MaxClasses> load_svm_model(const std::filesystem::path& path) {
  const auto format = detect_svm_file_format(path);
  auto in = svm_io_detail::open_model(path);
  switch (format) {
    case SvmFileFormat::ctxfuse: return read_ctxfuse_svm_model<Dim, MaxClasses>(in, path.string());
    case SvmFileFormat::libsvm: return read_libsvm_model<Dim, MaxClasses>(in, path.string());
    case SvmFileFormat::unknown: break;
  }
  throw SvmFileError(path.string(), 1, "format",
                     "neither a ctxfuse-svm file nor a libsvm model (first line must start with '" +
                         std::string(kSvmFileMagic) + "' or 'svm_type')");
}

/// Feature dimension stated by our format's header (0 for libsvm files, which do not state it).
inline int svm_file_dimension(const std::filesystem::path& path) {
  auto in = svm_io_detail::open_model(path);
  io::TextFile file(in, path.string());
  std::string_view line;
  bool ours = false;
  while (file.line_number() < 3 && file.next(line)) {
    const auto t = io::split_fields(line, io::Separator::whitespace);
    if (file.line_number() == 1) ours = !t.empty() && t[0] == kSvmFileMagic;
    if (!ours) return 0;
    if (t.size() == 2 && t[0] == "dimension") {
      int d = 0;
      if (io::parse_integer(t[1], d, 1, std::numeric_limits<int>::max()) != io::NumberError::none)
        svm_io_detail::fail(file, "dimension", io::cat("expected a positive integer, got ", io::quote(t[1])));
      return d;
    }
  }
  throw SvmFileError(path.string(), svm_io_detail::line_number(file), "dimension", "missing from the header");
}

template <int Dim, int MaxClasses>
void save_svm_model(const std::filesystem::path& path, const SvmModel<Dim, MaxClasses>& model) {
  std::ofstream out(path);
  if (!out) throw SvmFileError(path.string(), 0, "file", "cannot open for writing");
  write_ctxfuse_svm_model(out, model);
  out.flush();
  if (!out) throw SvmFileError(path.string(), 0, "file", "write failed");
}

}  // namespace ctxfuse::classify
