// Model files are read with io/text.hpp: SvmFileError is an io::ParseError with the message
// "<file>:<line>: <field>: <what>", CRLF files read as LF files, and whole-valued labels
// written as decimals are accepted.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "classify_svm/svm_test_data.hpp"
#include "ctxfuse/classify/svm_io.hpp"

namespace {

using namespace ctxfuse::classify;

constexpr const char* kLibsvm =
    "svm_type c_svc\nkernel_type rbf\ngamma 0.5\nnr_class 2\ntotal_sv 3\nrho 0.25\nlabel 1 -1\n"
    "nr_sv 2 1\nSV\n0.5 1:1 2:2 \n0.25 2:-1 \n-0.75 1:-1 2:0.5 \n";

std::string with_crlf(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '\n') out += '\r';
    out += c;
  }
  return out;
}

TEST(SvmIoText, ErrorsAreParseErrorsNamingFileLineAndField) {
  std::string text = kLibsvm;
  text.replace(text.find("gamma 0.5"), 9, "gamma abc");
  std::istringstream in(text);
  try {
    (void)read_libsvm_model<2>(in, "m.txt");
    ADD_FAILURE() << "no error";
  } catch (const ctxfuse::io::ParseError& e) {
    EXPECT_STREQ(e.what(), "m.txt:3: gamma: expected a finite number, got 'abc'");
    EXPECT_EQ(e.file(), "m.txt");
    EXPECT_EQ(e.line(), 3u);
    const auto* svm = dynamic_cast<const SvmFileError*>(&e);
    ASSERT_NE(svm, nullptr);
    EXPECT_EQ(svm->line, 3);
    EXPECT_EQ(svm->field, "gamma");
  }
}

TEST(SvmIoText, AProblemOfTheWholeFileHasNoLineNumber) {
  const SvmFileError e("m.txt", 0, "file", "cannot open for reading");
  EXPECT_STREQ(e.what(), "m.txt: file: cannot open for reading");
  EXPECT_EQ(e.line, 0);
}

TEST(SvmIoText, CrlfFilesReadAsLfFiles) {
  std::istringstream lf(kLibsvm), crlf(with_crlf(kLibsvm));
  const auto a = read_libsvm_model<2>(lf, "lf");
  const auto b = read_libsvm_model<2>(crlf, "crlf");
  EXPECT_EQ(a.support_vectors, b.support_vectors);
  EXPECT_EQ(a.coefficients, b.coefficients);
  EXPECT_EQ(a.gamma, b.gamma);
  EXPECT_EQ(a.labels, b.labels);

  const auto m = ctxfuse::test::random_model<3>(SvmKernel::rbf, SvmMulticlass::one_vs_one, 3, 12, true, 4);
  std::ostringstream os;
  write_ctxfuse_svm_model(os, m);
  std::istringstream own(with_crlf(os.str()));
  const auto back = read_ctxfuse_svm_model<3>(own, "own");
  EXPECT_EQ(back.support_vectors, m.support_vectors);
  EXPECT_EQ(back.coefficients, m.coefficients);
  EXPECT_EQ(back.rho, m.rho);
  EXPECT_EQ(back.prob_a, m.prob_a);
}

TEST(SvmIoText, LabelsAreWholeValues) {
  std::string text = kLibsvm;
  text.replace(text.find("label 1 -1"), 10, "label 1.0 -1");
  std::istringstream ok(text);
  EXPECT_EQ(read_libsvm_model<2>(ok, "m").labels[0], 1);
  for (const char* bad : {"label 1.5 -1", "label 3e9 -1", "label nan -1"}) {
    std::string t = kLibsvm;
    t.replace(t.find("label 1 -1"), 10, bad);
    std::istringstream in(t);
    try {
      (void)read_libsvm_model<2>(in, "m");
      ADD_FAILURE() << bad << ": no error";
    } catch (const SvmFileError& e) {
      EXPECT_EQ(e.line, 7) << e.what();
      EXPECT_EQ(e.field, "label") << e.what();
    }
  }
}

}  // namespace
