// The one compiled instance of the NLOS-robust UWB studies' runs (ctxfuse/instances/nlos_uwb.hpp).
#include "ctxfuse/instances/nlos_uwb.hpp"

namespace ctxfuse::studies::detail {

template pipelines::nlos_uwb::Track run_nlos_uwb_variant<void>(std::size_t, std::span<const messages::UwbRange>,
                                                               const pipelines::nlos_uwb::NlosClassifier&,
                                                               const pipelines::nlos_uwb::Settings&);
template NlosSimReport evaluate_nlos_uwb_sim<void>(const sim::DriveConfig&, std::uint64_t, const NlosSimProtocol&,
                                                   const pipelines::nlos_uwb::Settings&);

}  // namespace ctxfuse::studies::detail
