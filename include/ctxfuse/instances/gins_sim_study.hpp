// The simulated GNSS/INS study's filter run (studies/gins_sim_study.hpp, run_gins_sim) compiled
// once for its two noise policies, part of the optional compiled target ctxfuse::instances
// (src/gins_sim_study.cpp; built when libsvm is found, as the study trains its scene SVM with
// it). A source that links ctxfuse::instances and includes this header runs the study without
// compiling the 16-state error-state filter, its updates and the RTS pass for itself; the tool
// and the study's test do. Header-only users include studies/gins_sim_study.hpp instead.
#pragma once

#include <vector>

#include "ctxfuse/studies/gins_sim_study.hpp"

namespace ctxfuse::studies {

extern template GinsSimRun run_gins_sim<policies::FixedGnssNoise>(const GinsSimDrive&, const sim::ImuConfig&,
                                                                  const GinsSimScheme&, policies::FixedGnssNoise,
                                                                  const std::vector<policies::SceneProbabilities>&,
                                                                  const GinsSimSettings&);
extern template GinsSimRun run_gins_sim<policies::SceneAdaptiveGnssNoise>(
    const GinsSimDrive&, const sim::ImuConfig&, const GinsSimScheme&, policies::SceneAdaptiveGnssNoise,
    const std::vector<policies::SceneProbabilities>&, const GinsSimSettings&);

}  // namespace ctxfuse::studies
