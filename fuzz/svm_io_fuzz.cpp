// classify/svm_io.hpp: the first byte chooses the format (libsvm's model file or ours) and
// the model shape (2 features / up to 3 classes, as the region recogniser, or 3 / 8); the
// rest is the file. A model the reader accepts must predict on a fixed point with a status,
// not a crash, and survive a round trip through our writer: written, read back and written
// again it gives the same text (the writer uses 17 digits so that a reload is bit-exact).
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
  try {
    model = libsvm ? classify::read_libsvm_model<Dim, MaxClasses>(in, "fuzz")
                   : classify::read_ctxfuse_svm_model<Dim, MaxClasses>(in, "fuzz");
  } catch (const classify::SvmFileError&) {
    return;
  }
  classify::SvmPrediction<MaxClasses> out;
  const typename Model::Feature x = Model::Feature::Constant(0.5);
  (void)classify::svm_predict(model, x, out);
  std::ostringstream first;
  classify::write_ctxfuse_svm_model(first, model);
  std::istringstream back(first.str());
  Model again;
  try {
    again = classify::read_ctxfuse_svm_model<Dim, MaxClasses>(back, "fuzz (written back)");
  } catch (const classify::SvmFileError& e) {
    std::fprintf(stderr, "%s\n", e.what());
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
  if (data[0] & 2)
    one<3, 8>(libsvm, text);
  else
    one<2, 3>(libsvm, text);
  return 0;
}
