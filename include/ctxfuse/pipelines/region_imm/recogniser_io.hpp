// A trained region recogniser saved to a text file and loaded back exactly (every number with
// 17 significant digits, so a loaded recogniser labels every epoch as the one that was saved):
// `ctxfuse run region-imm --recogniser FILE` runs on a log without training data. Layout, one
// record per line, `key values...`:
//   ctxfuse-region-recogniser 1
//   tuned C gamma cv_score
//   validation_accuracy svm_0 svm_1 svm_2 hmm_0 hmm_1 hmm_2
//   vote svm_0 svm_1 svm_2 hmm_0 hmm_1 hmm_2
//   hmm_log_initial x3
//   hmm_log_transition x9 (row-major, rows "from")
//   hmm_state k mean_0 mean_1 cov_00 cov_01 cov_10 cov_11      (k = 0, 1, 2)
//   svm_lines N, then N lines of the SVM in classify/svm_io.hpp's ctxfuse-svm format
// A malformed file throws RecogniserFileError naming the file, the line and the field.
#pragma once

#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <istream>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "ctxfuse/classify/svm_io.hpp"
#include "ctxfuse/io/text.hpp"
#include "ctxfuse/pipelines/region_imm/recogniser.hpp"

namespace ctxfuse::pipelines::region_imm {

class RecogniserFileError : public std::runtime_error {
 public:
  RecogniserFileError(const std::string& file, std::size_t line, const std::string& field, const std::string& what)
      : std::runtime_error(compose(file, line, field, what)) {}

 private:
  static std::string compose(const std::string& file, std::size_t line, const std::string& field, const std::string& what) {
    std::string m = file;
    if (line > 0) m.append(":").append(std::to_string(line));
    if (!field.empty()) m.append(": field '").append(field).append("'");
    return m.append(": ").append(what);
  }
};

inline constexpr std::string_view kRecogniserMagic = "ctxfuse-region-recogniser";

inline void write_recogniser(std::ostream& os, const Recogniser& r) {
  auto num = [&](double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, " %.17g", v);
    os << buf;
  };
  os << kRecogniserMagic << " 1\n";
  os << "tuned";
  for (double v : {r.tuned.C, r.tuned.gamma, r.tuned.cv_accuracy}) num(v);
  os << "\nvalidation_accuracy";
  for (const auto& c : r.validation_accuracy)
    for (double v : c) num(v);
  os << "\nvote";
  for (const auto& c : r.vote.weights)
    for (double v : c) num(v);
  os << "\nhmm_log_initial";
  for (int k = 0; k < kRegions; ++k) num(r.hmm.log_initial(k));
  os << "\nhmm_log_transition";
  for (int i = 0; i < kRegions; ++i)
    for (int j = 0; j < kRegions; ++j) num(r.hmm.log_transition(i, j));
  os << '\n';
  for (std::size_t k = 0; k < static_cast<std::size_t>(kRegions); ++k) {
    os << "hmm_state " << k;
    num(r.hmm.means[k](0));
    num(r.hmm.means[k](1));
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) num(r.hmm.covariances[k](i, j));
    os << '\n';
  }
  std::ostringstream svm;
  classify::write_ctxfuse_svm_model(svm, r.svm);
  const std::string text = svm.str();
  std::size_t lines = 0;
  for (char c : text) lines += c == '\n' ? 1 : 0;
  if (!text.empty() && text.back() != '\n') ++lines;
  os << "svm_lines " << lines << '\n' << text;
  if (!text.empty() && text.back() != '\n') os << '\n';
}

template <class = void>
Recogniser read_recogniser(std::istream& in, const std::string& file) {
  std::size_t line_no = 0;
  std::string line;
  auto next = [&](const char* key) {
    if (!std::getline(in, line)) throw RecogniserFileError(file, line_no + 1, key, "file ends before this record");
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
  };
  // The values of the next line, which must start with `key` and hold `n` numbers.
  auto values = [&](const char* key, std::size_t n) {
    next(key);
    std::istringstream ss(line);
    std::string head;
    ss >> head;
    if (head != key) throw RecogniserFileError(file, line_no, key, io::cat("expected record '", key, "', found ", io::quote(head)));
    std::vector<double> v;
    std::string tok;
    while (ss >> tok) {
      double x = 0.0;
      const auto res = std::from_chars(tok.data(), tok.data() + tok.size(), x);
      if (res.ec != std::errc() || res.ptr != tok.data() + tok.size())
        throw RecogniserFileError(file, line_no, key, io::cat(io::quote(tok), " is not a number"));
      v.push_back(x);
    }
    if (v.size() != n)
      throw RecogniserFileError(file, line_no, key, "expected " + std::to_string(n) + " numbers, found " + std::to_string(v.size()));
    return v;
  };
  next("magic");
  if (line != std::string(kRecogniserMagic) + " 1")
    throw RecogniserFileError(file, line_no, "", "not a region recogniser file (expected '" + std::string(kRecogniserMagic) + " 1')");
  Recogniser r;
  const auto tuned = values("tuned", 3);
  r.tuned.C = tuned[0];
  r.tuned.gamma = tuned[1];
  r.tuned.cv_accuracy = tuned[2];
  const auto acc = values("validation_accuracy", 6);
  const auto vote = values("vote", 6);
  for (std::size_t c = 0; c < 2; ++c)
    for (std::size_t k = 0; k < 3; ++k) {
      r.validation_accuracy[c][k] = acc[3 * c + k];
      r.vote.weights[c][k] = vote[3 * c + k];
    }
  const auto init = values("hmm_log_initial", 3);
  const auto trans = values("hmm_log_transition", 9);
  for (int i = 0; i < kRegions; ++i) {
    r.hmm.log_initial(i) = init[static_cast<std::size_t>(i)];
    for (int j = 0; j < kRegions; ++j) r.hmm.log_transition(i, j) = trans[static_cast<std::size_t>(3 * i + j)];
  }
  for (std::size_t k = 0; k < static_cast<std::size_t>(kRegions); ++k) {
    const auto st = values("hmm_state", 7);
    if (st[0] != static_cast<double>(k)) throw RecogniserFileError(file, line_no, "hmm_state", "states must be listed 0, 1, 2 in order");
    r.hmm.means[k] = Eigen::Vector2d(st[1], st[2]);
    r.hmm.covariances[k] << st[3], st[4], st[5], st[6];
  }
  try {
    r.hmm.finalize();
  } catch (const std::invalid_argument& e) {
    throw RecogniserFileError(file, line_no, "hmm_state", e.what());
  }
  const auto n = values("svm_lines", 1);
  if (!(n[0] >= 1.0 && n[0] <= 1e7)) throw RecogniserFileError(file, line_no, "svm_lines", "line count out of range");
  std::string svm_text;
  const std::size_t svm_first = line_no + 1;
  for (std::size_t i = 0; i < static_cast<std::size_t>(n[0]); ++i) {
    next("svm");
    svm_text.append(line).push_back('\n');
  }
  std::istringstream svm(svm_text);
  try {
    r.svm = classify::read_ctxfuse_svm_model<2, 3>(svm, file + " (SVM from line " + std::to_string(svm_first) + ")");
  } catch (const std::exception& e) {
    throw RecogniserFileError(file, svm_first, "svm", e.what());
  }
  return r;
}

/// Throws std::runtime_error naming the file when it cannot be written.
inline void save_recogniser(const std::filesystem::path& path, const Recogniser& r) {
  std::ofstream os(path, std::ios::binary);
  if (!os) throw std::runtime_error(path.string() + ": cannot open for writing");
  write_recogniser(os, r);
  os.flush();
  if (!os) throw std::runtime_error(path.string() + ": write failed");
}

template <class = void>
Recogniser load_recogniser(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RecogniserFileError(path.string(), 0, "", "cannot open for reading");
  return read_recogniser(in, path.string());
}

}  // namespace ctxfuse::pipelines::region_imm
