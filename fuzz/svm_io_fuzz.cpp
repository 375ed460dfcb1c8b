// classify/svm_io.hpp: the first byte chooses the format (libsvm's model file or ours) and
// the model shape (2 features / up to 3 classes, as the region recogniser, 3 / 8, or the file's
// dimension / 8); the rest is the file. The non-throwing and the throwing reader must agree. A
// model the reader accepts must predict on a fixed point with a status, not a crash, and
// survive a round trip through our writer: written, read back and written again it gives the
// same text (the writer uses 17 digits so that a reload is bit-exact).
#include <sstream>
#include <string>

#include "ctxfuse/classify/svm_io.hpp"
#include "fuzz_support.hpp"

namespace classify = ctxfuse::classify;
using ctxfuse_fuzz::fail;

namespace {

template <int Dim, int MaxClasses>
void one(bool libsvm, const std::string& text) {
  using Model = classify::SvmModel<Dim, MaxClasses>;
  std::istringstream in(text);
  Model model;
  // The non-throwing reader; the throwing one must agree with it.
  const auto problem = libsvm ? classify::try_read_libsvm_model(in, "fuzz", model)
                              : classify::try_read_ctxfuse_svm_model(in, "fuzz", model);
  std::istringstream again_in(text);
  try {
    (void)(libsvm ? classify::read_libsvm_model<Dim, MaxClasses>(again_in, "fuzz")
                  : classify::read_ctxfuse_svm_model<Dim, MaxClasses>(again_in, "fuzz"));
    if (problem) fail("the try_ reader refuses a file the throwing reader accepts");
  } catch (const classify::SvmFileError& e) {
    if (!problem || problem->what() != e.what()) fail("the try_ reader's problem differs from the throwing reader's");
  }
  if (problem) return;
  classify::SvmPrediction<MaxClasses> out;
  const typename Model::Feature x = Model::Feature::Constant(model.dimension(), 0.5);
  (void)classify::svm_predict(model, x, out);
  std::ostringstream first;
  classify::write_ctxfuse_svm_model(first, model);
  std::istringstream back(first.str());
  Model again;
  if (const auto back_problem = classify::try_read_ctxfuse_svm_model(back, "fuzz (written back)", again)) {
    std::fprintf(stderr, "%s\n", back_problem->what().c_str());
    fail("an accepted model, written by us, is refused by our reader");
  }
  std::ostringstream second;
  classify::write_ctxfuse_svm_model(second, again);
  if (second.str() != first.str()) fail("write / read / write is not the identity");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  const bool libsvm = (data[0] & 1) != 0;
  if (data[0] & 4)
    one<Eigen::Dynamic, 8>(libsvm, text);
  else if (data[0] & 2)
    one<3, 8>(libsvm, text);
  else
    one<2, 3>(libsvm, text);
  return 0;
}
