// Model files: our format round-trips bit-exactly; a hand-written libsvm file gives the decision
// values of its closed form; malformed files raise SvmFileError naming file, line and field (the
// try_ forms return the same problem and keep the model); no truncation or corruption of a valid
// file crashes the loaders; a model at a run-time dimension (Eigen::Dynamic) reads, writes and
// predicts as the fixed-size one.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "classify_svm/svm_test_data.hpp"
#include "ctxfuse/classify/svm_io.hpp"

namespace {

using namespace ctxfuse::classify;

std::filesystem::path temp_file(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("ctxfuse_svm_io_" + std::to_string(::getpid()) + "_" + name);
}

template <int Dim, int MaxClasses>
void expect_identical(const SvmModel<Dim, MaxClasses>& a, const SvmModel<Dim, MaxClasses>& b) {
  EXPECT_EQ(a.kernel, b.kernel);
  EXPECT_EQ(a.multiclass, b.multiclass);
  EXPECT_EQ(a.gamma, b.gamma);
  EXPECT_EQ(a.num_classes, b.num_classes);
  EXPECT_EQ(a.labels, b.labels);
  EXPECT_EQ(a.input_mean, b.input_mean);
  EXPECT_EQ(a.input_std, b.input_std);
  EXPECT_EQ(a.support_vectors, b.support_vectors);
  EXPECT_EQ(a.coefficients, b.coefficients);
  EXPECT_EQ(a.rho, b.rho);
  EXPECT_EQ(a.has_probability, b.has_probability);
  if (a.has_probability) {
    EXPECT_EQ(a.prob_a, b.prob_a);
    EXPECT_EQ(a.prob_b, b.prob_b);
  }
}

TEST(SvmIo, OwnFormatRoundTripsBitExactly) {
  for (auto layout : {SvmMulticlass::one_vs_one, SvmMulticlass::one_vs_rest})
    for (auto kernel : {SvmKernel::linear, SvmKernel::rbf})
      for (int classes : {2, 3, 5}) {
        const auto m = ctxfuse::test::random_model<3>(kernel, layout, classes, 40, classes != 5, 3 + classes);
        const auto path = temp_file("roundtrip.model");
        save_svm_model(path, m);
        EXPECT_EQ(detect_svm_file_format(path), SvmFileFormat::ctxfuse);
        EXPECT_EQ(svm_file_dimension(path), 3);
        const auto back = load_svm_model<3>(path);
        expect_identical(m, back);
        std::filesystem::remove(path);
      }
}

// libsvm-format text written by hand: 2 classes (labels 1, -1), RBF gamma 0.5, three SVs, one of
// them sparse (feature 1 absent = 0).
constexpr const char* kHandLibsvm =
    "svm_type c_svc\nkernel_type rbf\ngamma 0.5\nnr_class 2\ntotal_sv 3\nrho 0.25\nlabel 1 -1\n"
    "probA -1.5\nprobB 0.1\nnr_sv 2 1\nSV\n0.5 1:1 2:2 \n0.25 2:-1 \n-0.75 1:-1 2:0.5 \n";

TEST(SvmIo, HandWrittenLibsvmFileGivesClosedFormDecision) {
  std::istringstream in(kHandLibsvm);
  const auto m = read_libsvm_model<2>(in, "hand.model");
  const Eigen::Vector2d x(0.2, 0.1);
  const auto k = [&](double a, double b) { return std::exp(-0.5 * ((x[0] - a) * (x[0] - a) + (x[1] - b) * (x[1] - b))); };
  const double f = 0.5 * k(1, 2) + 0.25 * k(0, -1) - 0.75 * k(-1, 0.5) - 0.25;
  SvmPrediction<8> out;
  ASSERT_TRUE(svm_predict(m, x, out).accepted());
  EXPECT_NEAR(out.decision_values[0], f, 1e-15);
  const double p1 = 1.0 / (1.0 + std::exp(-1.5 * f + 0.1));
  EXPECT_NEAR(out.probabilities[0], p1, 1e-15);
  EXPECT_NEAR(out.probabilities[1], 1.0 - p1, 1e-15);
  EXPECT_EQ(out.label, p1 > 0.5 ? 1 : -1);
}

struct BadCase {
  std::string what;
  std::string from, to;  // text replacement applied to kHandLibsvm
  int line;
  std::string field;
};

std::vector<BadCase> bad_libsvm_cases() {
  return {
      {"bad gamma", "gamma 0.5", "gamma abc", 3, "gamma"},
      {"unknown kernel", "kernel_type rbf", "kernel_type sigmoid", 2, "kernel_type"},
      {"rho count", "rho 0.25", "rho 0.25 0.5", 6, "rho"},
      {"nr_sv sum", "nr_sv 2 1", "nr_sv 2 2", 10, "nr_sv"},
      {"bad coefficient", "0.25 2:-1", "x0.25 2:-1", 13, "SV coefficient 1"},
      {"index beyond dim", "-0.75 1:-1 2:0.5", "-0.75 1:-1 3:0.5", 14, "SV feature index"},
      {"decreasing index", "0.5 1:1 2:2", "0.5 2:1 1:2", 12, "SV feature index"},
      {"missing colon", "0.25 2:-1", "0.25 2-1", 13, "SV feature"},
      {"nan value", "1:-1 2:0.5", "1:-1 2:nan", 14, "SV feature 2"},
      {"truncated", "-0.75 1:-1 2:0.5 \n", "", 14, "SV"},
      {"unknown field", "label 1 -1", "lable 1 -1", 7, "lable"},
      {"one class", "nr_class 2", "nr_class 1", 4, "nr_class"},
      {"huge label", "label 1 -1", "label 1 1e12", 7, "label"},
      // Bytes that a message must not carry raw (a NUL cut the exception's what() short).
      {"NUL in a value", "1:-1 2:0.5", std::string("1:-1 2:0\0.5", 11), 14, "SV feature 2"},
      {"control byte in a kernel name", "kernel_type rbf", "kernel_type r\x01" "bf", 2, "kernel_type"},
      {"NUL in a field name", "probA -1.5", std::string("pro\0bA -1.5", 11), 8, "pro\\x00bA"},
  };
}

TEST(SvmIo, MalformedLibsvmFilesNameLineAndField) {
  for (const auto& c : bad_libsvm_cases()) {
    std::string text = kHandLibsvm;
    const auto at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.what;
    text.replace(at, c.from.size(), c.to);
    const auto path = temp_file("bad.model");
    std::ofstream(path) << text;
    try {
      (void)load_svm_model<2>(path);
      ADD_FAILURE() << c.what << ": no error";
    } catch (const SvmFileError& e) {
      EXPECT_EQ(e.line, c.line) << c.what << ": " << e.what();
      EXPECT_EQ(e.field, c.field) << c.what << ": " << e.what();
      EXPECT_EQ(e.file, path.string());
      EXPECT_NE(std::string(e.what()).find(path.string() + ":" + std::to_string(c.line) + ": " + c.field), std::string::npos);
    }
    std::filesystem::remove(path);
  }
}

TEST(SvmIo, MessagesEscapeUnprintableBytes) {
  std::string text = kHandLibsvm;
  text.replace(text.find("1:-1 2:0.5"), 10, std::string("1:-1 2:0\0.5", 11));
  std::istringstream in(text);
  SvmModel<2> model;
  const auto problem = try_read_libsvm_model(in, "nul.model", model);
  ASSERT_TRUE(problem.has_value());
  EXPECT_EQ(problem->what(), "nul.model:14: SV feature 2: expected a finite number, got '0\\x00.5'");
  std::istringstream again(text);
  try {
    (void)read_libsvm_model<2>(again, "nul.model");
    ADD_FAILURE() << "no error";
  } catch (const SvmFileError& e) {
    EXPECT_EQ(std::string(e.what()), problem->what());
  }
}

TEST(SvmIo, MalformedOwnFilesNameLineAndField) {
  const auto m = ctxfuse::test::random_model<2>(SvmKernel::rbf, SvmMulticlass::one_vs_rest, 3, 5, true, 1);
  std::ostringstream os;
  write_ctxfuse_svm_model(os, m);
  const std::string good = os.str();
  std::vector<std::string> lines;
  {
    std::istringstream is(good);
    for (std::string l; std::getline(is, l);) lines.push_back(l);
  }
  struct OwnCase {
    int line;  // 1-based line to replace
    std::string replacement;
    std::string field;
  };
  const std::vector<OwnCase> cases = {
      {1, "ctxfuse-svm 2", "version"},     {2, "dimension 3", "dimension"},  {3, "kernel poly", "kernel"},
      {4, "gamma inf", "gamma"},           {5, "multiclass both", "multiclass"}, {6, "labels 1", "labels"},
      {8, "input_std 1 0", "input_std"},   {9, "rho 1 2", "rho"},            {10, "probability 2", "probability"},
      {13, "support_vectors -4", "support_vectors"}, {14, "1 2 3", "support vector"}, {15, "1 2 3 x 5", "feature 1"},
  };
  for (const auto& c : cases) {
    auto copy = lines;
    copy[static_cast<std::size_t>(c.line - 1)] = c.replacement;
    std::string text;
    for (const auto& l : copy) text += l + "\n";
    std::istringstream in(text);
    try {
      (void)read_ctxfuse_svm_model<2>(in, "own.model");
      ADD_FAILURE() << "line " << c.line << ": no error";
    } catch (const SvmFileError& e) {
      EXPECT_EQ(e.line, c.line) << e.what();
      EXPECT_EQ(e.field, c.field) << e.what();
      EXPECT_EQ(e.file, "own.model");
    }
  }
}

// The non-throwing forms return the problem the throwing forms throw, and leave the model that
// was passed in as it was.
TEST(SvmIo, TryFormsReturnTheProblemAndKeepTheModel) {
  std::istringstream good_in(kHandLibsvm);
  const auto good = read_libsvm_model<2>(good_in, "hand.model");
  for (const auto& c : bad_libsvm_cases()) {
    std::string text = kHandLibsvm;
    text.replace(text.find(c.from), c.from.size(), c.to);
    const auto path = temp_file("try.model");
    std::ofstream(path) << text;
    SvmModel<2> model = good;
    const auto problem = try_load_svm_model(path, model);
    ASSERT_TRUE(problem.has_value()) << c.what;
    EXPECT_EQ(problem->line, c.line) << c.what;
    EXPECT_EQ(problem->field, c.field) << c.what;
    EXPECT_EQ(problem->file, path.string());
    expect_identical(model, good);
    try {
      (void)load_svm_model<2>(path);
      ADD_FAILURE() << c.what << ": no error";
    } catch (const SvmFileError& e) {
      EXPECT_EQ(problem->what(), e.what());
    }
    std::filesystem::remove(path);
  }
  SvmModel<2> model = good;
  const auto missing = try_load_svm_model(temp_file("does_not_exist.model"), model);
  ASSERT_TRUE(missing.has_value());
  EXPECT_EQ(missing->line, 0);
  EXPECT_EQ(missing->field, "file");
  const auto unwritable = try_save_svm_model(temp_file("no_such_folder") / "m.model", good);
  ASSERT_TRUE(unwritable.has_value());
  EXPECT_EQ(unwritable->message, "cannot open for writing");
  expect_identical(model, good);
}

// decision value of machine m by the model's definition, with std::exp.
template <int Dim, int MaxClasses>
double closed_form_decision(const SvmModel<Dim, MaxClasses>& m, const Eigen::VectorXd& x, int machine) {
  const Eigen::VectorXd xs = (x - Eigen::VectorXd(m.input_mean)).cwiseQuotient(Eigen::VectorXd(m.input_std));
  double f = -m.rho[static_cast<std::size_t>(machine)];
  for (Eigen::Index s = 0; s < m.support_vectors.rows(); ++s) {
    const Eigen::VectorXd sv = m.support_vectors.row(s).transpose();
    const double k = m.kernel == SvmKernel::linear ? sv.dot(xs) : std::exp(-m.gamma * (xs - sv).squaredNorm());
    f += m.coefficients(machine, s) * k;
  }
  return f;
}

// SvmModel<Eigen::Dynamic>: read back from our format at the file's dimension, it predicts the
// closed form and what the fixed-size model predicts, over several kernel blocks (300 support
// vectors) and every layout; a feature vector of another length is refused, `out` untouched.
TEST(SvmIo, RuntimeDimensionModelPredictsTheClosedFormAndTheFixedModel) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (auto layout : {SvmMulticlass::one_vs_one, SvmMulticlass::one_vs_rest})
    for (auto kernel : {SvmKernel::linear, SvmKernel::rbf})
      for (int classes : {2, 3, 5}) {
        const auto fixed = ctxfuse::test::random_model<3>(kernel, layout, classes, 300, classes != 5, 7 + classes);
        std::ostringstream os;
        write_ctxfuse_svm_model(os, fixed);
        std::istringstream in(os.str());
        SvmModel<Eigen::Dynamic> model;
        ASSERT_FALSE(try_read_ctxfuse_svm_model(in, "m", model).has_value());
        ASSERT_EQ(model.dimension(), 3);
        std::ostringstream again;
        write_ctxfuse_svm_model(again, model);
        EXPECT_EQ(again.str(), os.str());
        for (int i = 0; i < 40; ++i) {
          const Eigen::Vector3d x(u(rng), u(rng), u(rng));
          const Eigen::VectorXd xd = x;
          SvmPrediction<8> a, b;
          ASSERT_TRUE(svm_predict(fixed, x, a));
          ASSERT_TRUE(svm_predict(model, xd, b));
          ASSERT_EQ(b.num_machines, a.num_machines);
          for (int m = 0; m < b.num_machines; ++m) {
            const double exact = closed_form_decision(model, xd, m);
            const double scale = 1.0 + model.coefficients.row(m).cwiseAbs().sum();
            EXPECT_NEAR(b.decision_values[static_cast<std::size_t>(m)], exact, 1e-14 * scale);
            EXPECT_NEAR(b.decision_values[static_cast<std::size_t>(m)], a.decision_values[static_cast<std::size_t>(m)], 1e-14 * scale);
          }
          EXPECT_EQ(b.label, a.label);
          for (int c = 0; c < (a.has_probabilities ? classes : 0); ++c)
            EXPECT_NEAR(b.probabilities[static_cast<std::size_t>(c)], a.probabilities[static_cast<std::size_t>(c)], 1e-12);
        }
        SvmPrediction<8> out;
        out.label = 12345;
        for (int length : {2, 4}) {
          const Eigen::VectorXd wrong = Eigen::VectorXd::Ones(length);
          const ctxfuse::Status st = svm_predict(model, wrong, out);
          EXPECT_EQ(st.outcome, ctxfuse::Outcome::invalid_input);
          EXPECT_EQ(st.problem, ctxfuse::Problem::features_wrong_size);
        }
        EXPECT_EQ(out.label, 12345);
      }
}

// A libsvm file states no dimension: at Eigen::Dynamic it is the largest feature index, or the
// caller's (absent features are zero); a named dimension below an index is the file's problem.
TEST(SvmIo, LibsvmDimensionIsTheLargestIndexUnlessNamed) {
  std::istringstream in2(kHandLibsvm);
  const auto fixed = read_libsvm_model<2>(in2, "hand.model");
  SvmModel<Eigen::Dynamic> two, three;
  std::istringstream a(kHandLibsvm), b(kHandLibsvm), c(kHandLibsvm);
  ASSERT_FALSE(try_read_libsvm_model(a, "hand.model", two).has_value());
  EXPECT_EQ(two.dimension(), 2);
  EXPECT_EQ(two.support_vectors, fixed.support_vectors);
  ASSERT_FALSE(try_read_libsvm_model(b, "hand.model", three, 3).has_value());
  ASSERT_EQ(three.dimension(), 3);
  EXPECT_EQ(three.support_vectors.leftCols(2), fixed.support_vectors);
  EXPECT_TRUE(three.support_vectors.col(2).isZero(0.0));
  const SvmModel<Eigen::Dynamic> before = two;
  const auto problem = try_read_libsvm_model(c, "hand.model", two, 1);
  ASSERT_TRUE(problem.has_value());
  EXPECT_EQ(problem->line, 12);
  EXPECT_EQ(problem->field, "SV feature index");
  EXPECT_EQ(problem->message, "index 2 exceeds the model dimension 1");
  expect_identical(two, before);
  std::istringstream d(kHandLibsvm);
  const auto negative = try_read_libsvm_model(d, "hand.model", two, -1);
  ASSERT_TRUE(negative.has_value());
  EXPECT_EQ(negative->field, "dimension");
}

TEST(SvmIo, HugeClaimedCountsFailAtTheEndOfFileWithoutAllocatingThem) {
  std::string text = kHandLibsvm;
  text.replace(text.find("total_sv 3"), 10, "total_sv 99999999");
  text.replace(text.find("nr_sv 2 1"), 9, "nr_sv 99999998 1");
  std::istringstream in(text);
  try {
    (void)read_libsvm_model<2>(in, "huge.model");
    ADD_FAILURE();
  } catch (const SvmFileError& e) {
    EXPECT_EQ(e.field, "SV");
    EXPECT_EQ(e.line, 15);
    EXPECT_NE(std::string(e.what()).find("file ends after 3 of 99999999"), std::string::npos) << e.what();
  }
}

TEST(SvmIo, UnknownFormatAndMissingFileAreReported) {
  const auto path = temp_file("unknown.model");
  std::ofstream(path) << "hello world\n";
  try {
    (void)load_svm_model<2>(path);
    ADD_FAILURE();
  } catch (const SvmFileError& e) {
    EXPECT_EQ(e.field, "format");
    EXPECT_EQ(e.line, 1);
  }
  std::filesystem::remove(path);
  EXPECT_THROW((void)load_svm_model<2>(temp_file("does_not_exist.model")), SvmFileError);
}

TEST(SvmIo, TruncatedOrCorruptedFilesNeverCrash) {
  const auto m = ctxfuse::test::random_model<2>(SvmKernel::rbf, SvmMulticlass::one_vs_one, 3, 6, true, 2);
  std::ostringstream os;
  write_ctxfuse_svm_model(os, m);
  const std::vector<std::string> sources = {os.str(), kHandLibsvm};
  std::mt19937_64 rng(1);
  int loaded = 0, rejected = 0;
  for (const auto& good : sources) {
    std::vector<std::string> variants;
    for (std::size_t n = 0; n < good.size(); ++n) variants.push_back(good.substr(0, n));
    const std::string junk = "x:-.e+9 \n\t,0";
    for (int i = 0; i < 400; ++i) {
      std::string v = good;
      for (int e = 0; e < 3; ++e) v[rng() % v.size()] = junk[rng() % junk.size()];
      variants.push_back(v);
    }
    for (const auto& v : variants) {
      const auto path = temp_file("fuzz.model");
      std::ofstream(path) << v;
      try {
        const auto model = load_svm_model<2>(path);
        EXPECT_TRUE(svm_model_problem(model).empty());
        ++loaded;
      } catch (const SvmFileError&) {
        ++rejected;
      }
      std::filesystem::remove(path);
    }
  }
  EXPECT_GT(rejected, 0);
  EXPECT_GT(loaded, 0);  // corruption that only touches digits leaves valid files
}

}  // namespace
