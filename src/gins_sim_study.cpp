// The one compiled instance of the simulated GNSS/INS study's filter run
// (ctxfuse/instances/gins_sim_study.hpp).
#include "ctxfuse/instances/gins_sim_study.hpp"

namespace ctxfuse::studies {

template GinsSimRun run_gins_sim<policies::FixedGnssNoise>(const GinsSimDrive&, const sim::ImuConfig&, const GinsSimScheme&,
                                                           policies::FixedGnssNoise,
                                                           const std::vector<policies::SceneProbabilities>&,
                                                           const GinsSimSettings&);
template GinsSimRun run_gins_sim<policies::SceneAdaptiveGnssNoise>(const GinsSimDrive&, const sim::ImuConfig&,
                                                                   const GinsSimScheme&, policies::SceneAdaptiveGnssNoise,
                                                                   const std::vector<policies::SceneProbabilities>&,
                                                                   const GinsSimSettings&);

}  // namespace ctxfuse::studies
