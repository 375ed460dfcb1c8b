// Reading and writing SVM models: libsvm's text model files (as svm-train writes them) and our
// own versioned text format, which adds the input standardisation and one-vs-rest layouts.
// Both are read with io/text.hpp (lines, whitespace-separated fields, numbers). Loading may
// allocate and never yields a half-built model. Each reader comes in two forms:
//  - try_read_libsvm_model, try_read_ctxfuse_svm_model, try_load_svm_model (either format, by
//    its first line), try_save_svm_model: never throw; they return the SvmFileProblem (file,
//    line, field, message) or nothing, and leave the model untouched on a problem. These are
//    the forms for builds without exceptions.
//  - read_libsvm_model, read_ctxfuse_svm_model, load_svm_model, save_svm_model: the same, but
//    a problem throws SvmFileError (an io::ParseError) carrying it.
// The parser works on a run-time dimension: an SvmModel<Eigen::Dynamic> takes the file's
// (ours states it; for libsvm files, whose support vectors are sparse, the largest feature
// index, unless the caller names the dimension), a fixed Dim requires it.
#pragma once

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_file_parse.hpp"
#include "ctxfuse/io/text.hpp"

namespace ctxfuse::classify {

/// A model file could not be used (the throwing readers). what() reads as SvmFileProblem's.
struct SvmFileError : io::ParseError {
  explicit SvmFileError(const SvmFileProblem& p)
      : io::ParseError(p.file, static_cast<std::size_t>(p.line), 0, "", io::cat(p.field, ": ", p.message)),
        file(p.file),
        line(p.line),
        field(p.field) {}
  SvmFileError(std::string file_, int line_, std::string field_, std::string message)
      : SvmFileError(SvmFileProblem{std::move(file_), line_, std::move(field_), std::move(message)}) {}
  // Plain members, for the users of this type; they hide ParseError's file() and line().
  std::string file;
  int line;  // 1-based; 0 when the problem is the file as a whole
  std::string field;
};

namespace svm_io_detail {

/// Parses `in` in `format` into a fresh model, moved into `model` only when the whole file is good.
template <int Dim, int MaxClasses>
std::optional<SvmFileProblem> read_into(std::istream& in, const std::string& source, SvmFileFormat format,
                                        SvmModel<Dim, MaxClasses>& model, int dimension) {
  if (auto problem = requested_dimension_problem<Dim>(source, dimension)) return problem;
  Reader r(in, source);
  SvmModel<Dim, MaxClasses> fresh;
  const bool ok = format == SvmFileFormat::libsvm ? parse_libsvm(r, dimension, fresh) : parse_ctxfuse(r, dimension, fresh);
  if (!ok) return r.take_problem();
  model = std::move(fresh);
  return std::nullopt;
}

/// The throwing readers' way out: SvmFileError (under -fno-exceptions, the message and abort).
[[noreturn]] inline void raise(const SvmFileProblem& problem) { ctxfuse::detail::raise(SvmFileError(problem)); }

template <int Dim>
inline constexpr int kDefaultDimension = Dim == Eigen::Dynamic ? 0 : Dim;

}  // namespace svm_io_detail

/// Format from the first line: "ctxfuse-svm ..." or "svm_type ..."; unknown otherwise.
inline SvmFileFormat detect_svm_file_format(std::string_view first_line) {
  const auto tokens = io::split_fields(first_line, io::Separator::whitespace);
  if (tokens.empty()) return SvmFileFormat::unknown;
  if (tokens[0] == kSvmFileMagic) return SvmFileFormat::ctxfuse;
  if (tokens[0] == "svm_type") return SvmFileFormat::libsvm;
  return SvmFileFormat::unknown;
}

/// Reads a libsvm model (C-SVC, linear or RBF kernel) without throwing: the problem, or nothing
/// when `model` holds the file's model (untouched on a problem). Feature indices above the
/// dimension are a problem; indices absent from a support vector line are zero, as in libsvm's
/// sparse format. libsvm models carry no standardisation, so inputs are used as given.
/// dimension: Dim; for SvmModel<Eigen::Dynamic> 0 (the largest feature index) or the caller's.
template <int Dim, int MaxClasses>
std::optional<SvmFileProblem> try_read_libsvm_model(std::istream& in, const std::string& source, SvmModel<Dim, MaxClasses>& model,
                                                    int dimension = svm_io_detail::kDefaultDimension<Dim>) {
  return svm_io_detail::read_into(in, source, SvmFileFormat::libsvm, model, dimension);
}

/// Reads our own format (docs/formats.md, section "svm") without throwing, as
/// try_read_libsvm_model; for SvmModel<Eigen::Dynamic> dimension 0 takes the file's.
template <int Dim, int MaxClasses>
std::optional<SvmFileProblem> try_read_ctxfuse_svm_model(std::istream& in, const std::string& source,
                                                         SvmModel<Dim, MaxClasses>& model,
                                                         int dimension = svm_io_detail::kDefaultDimension<Dim>) {
  return svm_io_detail::read_into(in, source, SvmFileFormat::ctxfuse, model, dimension);
}

/// Throwing form of try_read_libsvm_model (SvmFileError).
template <int Dim, int MaxClasses = 8>
SvmModel<Dim, MaxClasses> read_libsvm_model(std::istream& in, const std::string& source,
                                            int dimension = svm_io_detail::kDefaultDimension<Dim>) {
  SvmModel<Dim, MaxClasses> model;
  if (auto problem = try_read_libsvm_model(in, source, model, dimension)) svm_io_detail::raise(*problem);
  return model;
}

/// Throwing form of try_read_ctxfuse_svm_model (SvmFileError).
template <int Dim, int MaxClasses = 8>
SvmModel<Dim, MaxClasses> read_ctxfuse_svm_model(std::istream& in, const std::string& source,
                                                 int dimension = svm_io_detail::kDefaultDimension<Dim>) {
  SvmModel<Dim, MaxClasses> model;
  if (auto problem = try_read_ctxfuse_svm_model(in, source, model, dimension)) svm_io_detail::raise(*problem);
  return model;
}

/// Writes our format; numbers with 17 significant digits so that a reload is bit-exact.
template <int Dim, int MaxClasses>
void write_ctxfuse_svm_model(std::ostream& out, const SvmModel<Dim, MaxClasses>& model) {
  using svm_io_detail::format_double;
  const int machines = model.num_machines();
  const int dim = model.dimension();
  out << kSvmFileMagic << ' ' << kSvmFileVersion << '\n';
  out << "dimension " << dim << '\n';
  out << "kernel " << to_string(model.kernel) << '\n';
  out << "gamma " << format_double(model.gamma) << '\n';
  out << "multiclass " << to_string(model.multiclass) << '\n';
  out << "labels";
  for (int i = 0; i < model.num_classes; ++i) out << ' ' << model.labels[static_cast<std::size_t>(i)];
  out << "\ninput_mean";
  for (int f = 0; f < dim; ++f) out << ' ' << format_double(model.input_mean[f]);
  out << "\ninput_std";
  for (int f = 0; f < dim; ++f) out << ' ' << format_double(model.input_std[f]);
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
    for (int f = 0; f < dim; ++f) out << format_double(model.support_vectors(s, f)) << (f + 1 < dim ? ' ' : '\n');
  }
  out << "end\n";
}

namespace svm_io_detail {
inline SvmFileProblem cannot_open(const std::filesystem::path& path) {
  return {path.string(), 0, "file", "cannot open for reading"};
}

/// The format of an open file from its first line (CR stripped); the stream is rewound.
inline SvmFileFormat format_of(std::istream& in) {
  std::string first;  // stays empty for an empty file
  std::getline(in, first);
  if (!first.empty() && first.back() == '\r') first.pop_back();
  in.clear();
  in.seekg(0);
  return detect_svm_file_format(first);
}
}  // namespace svm_io_detail

/// Format of a model file from its first line (throws SvmFileError when it cannot be opened).
inline SvmFileFormat detect_svm_file_format(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) svm_io_detail::raise(svm_io_detail::cannot_open(path));
  return svm_io_detail::format_of(in);
}

/// Feature dimension stated by our format's header (0 for libsvm files, which do not state it).
/// Throws SvmFileError when the file cannot be opened or our header has no usable dimension.
inline int svm_file_dimension(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) svm_io_detail::raise(svm_io_detail::cannot_open(path));
  svm_io_detail::Reader r(in, path.string());
  std::string_view line;
  bool ours = false;
  while (r.line() < 3 && r.next(line)) {
    const auto t = io::split_fields(line, io::Separator::whitespace);
    if (r.line() == 1) ours = !t.empty() && t[0] == kSvmFileMagic;
    if (!ours) return 0;
    if (t.size() == 2 && t[0] == "dimension") {
      int d = 0;
      if (io::parse_integer(t[1], d, 1, std::numeric_limits<int>::max()) != io::NumberError::none)
        r.fail("dimension", io::cat("expected a positive integer, got ", io::quote(t[1])));
      else
        return d;
      break;
    }
  }
  r.fail("dimension", "missing from the header");
  svm_io_detail::raise(*r.take_problem());
}

/// Loads either format, chosen by the first line, without throwing: the problem, or nothing
/// when `model` holds the file's model (untouched on a problem). dimension as try_read_*.
template <int Dim, int MaxClasses>
std::optional<SvmFileProblem> try_load_svm_model(const std::filesystem::path& path, SvmModel<Dim, MaxClasses>& model,
                                                 int dimension = svm_io_detail::kDefaultDimension<Dim>) {
  std::ifstream in(path);
  if (!in) return svm_io_detail::cannot_open(path);
  const auto format = svm_io_detail::format_of(in);
  if (format == SvmFileFormat::unknown)
    return SvmFileProblem{path.string(), 1, "format",
                          "neither a ctxfuse-svm file nor a libsvm model (first line must start with '" +
                              std::string(kSvmFileMagic) + "' or 'svm_type')"};
  return svm_io_detail::read_into(in, path.string(), format, model, dimension);
}

/// Throwing form of try_load_svm_model (SvmFileError).
template <int Dim, int MaxClasses = 8>
SvmModel<Dim, MaxClasses> load_svm_model(const std::filesystem::path& path, int dimension = svm_io_detail::kDefaultDimension<Dim>) {
  SvmModel<Dim, MaxClasses> model;
  if (auto problem = try_load_svm_model(path, model, dimension)) svm_io_detail::raise(*problem);
  return model;
}

/// Writes our format to `path` without throwing: the problem, or nothing when written.
template <int Dim, int MaxClasses>
std::optional<SvmFileProblem> try_save_svm_model(const std::filesystem::path& path, const SvmModel<Dim, MaxClasses>& model) {
  std::ofstream out(path);
  if (!out) return SvmFileProblem{path.string(), 0, "file", "cannot open for writing"};
  write_ctxfuse_svm_model(out, model);
  out.flush();
  if (!out) return SvmFileProblem{path.string(), 0, "file", "write failed"};
  return std::nullopt;
}

/// Throwing form of try_save_svm_model (SvmFileError).
template <int Dim, int MaxClasses>
void save_svm_model(const std::filesystem::path& path, const SvmModel<Dim, MaxClasses>& model) {
  if (auto problem = try_save_svm_model(path, model)) svm_io_detail::raise(*problem);
}

}  // namespace ctxfuse::classify
