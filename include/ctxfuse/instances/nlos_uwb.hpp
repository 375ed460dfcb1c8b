// The NLOS-robust UWB studies' runs compiled once, part of the optional compiled target
// ctxfuse::instances (src/nlos_uwb.cpp and src/nlos_uwb_case.cpp; built when libsvm is found,
// as the studies train their SVMs with it): the variants of studies/nlos_uwb.hpp on a
// recording and the simulated protocol of studies/nlos_uwb_sim.hpp, each instantiating every
// estimator and policy of the pipeline, and the scoring of a recorded case with the SVM
// trained on the other cases. A source that links ctxfuse::instances and includes this header
// calls run_nlos_uwb_variant(s), train_svm_on_cases, evaluate_nlos_uwb_case and
// evaluate_nlos_uwb_sim without compiling them; the tool and the pipeline's tests do.
// Header-only users include the studies' headers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>

#include "ctxfuse/studies/nlos_uwb.hpp"
#include "ctxfuse/studies/nlos_uwb_sim.hpp"

namespace ctxfuse::studies::detail {

extern template pipelines::nlos_uwb::Track run_nlos_uwb_variant<void>(std::size_t, std::span<const messages::UwbRange>,
                                                                      const pipelines::nlos_uwb::NlosClassifier&,
                                                                      const pipelines::nlos_uwb::Settings&);
extern template NlosSimReport evaluate_nlos_uwb_sim<void>(const sim::DriveConfig&, std::uint64_t, const NlosSimProtocol&,
                                                          const pipelines::nlos_uwb::Settings&);

}  // namespace ctxfuse::studies::detail

namespace ctxfuse::studies {

extern template pipelines::nlos_uwb::NlosSvm train_svm_on_cases<void>(std::span<const std::filesystem::path>,
                                                                      const pipelines::nlos_uwb::Settings&);
extern template NlosUwbCaseReport evaluate_nlos_uwb_case<void>(const std::filesystem::path&,
                                                               std::span<const std::filesystem::path>,
                                                               const pipelines::nlos_uwb::Settings&, const HanyangSpan&);

}  // namespace ctxfuse::studies
