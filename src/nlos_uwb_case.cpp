// The one compiled instance of the NLOS UWB study's scoring of a recorded case and of its SVM
// training on the other cases (ctxfuse/instances/nlos_uwb.hpp). Apart from src/nlos_uwb.cpp,
// whose variant runs it calls through their extern declaration: two sources of the library
// that build side by side.
#include "ctxfuse/instances/nlos_uwb.hpp"

namespace ctxfuse::studies {

template pipelines::nlos_uwb::NlosSvm train_svm_on_cases<void>(std::span<const std::filesystem::path>,
                                                               const pipelines::nlos_uwb::Settings&);
template NlosUwbCaseReport evaluate_nlos_uwb_case<void>(const std::filesystem::path&, std::span<const std::filesystem::path>,
                                                        const pipelines::nlos_uwb::Settings&, const HanyangSpan&);

}  // namespace ctxfuse::studies
