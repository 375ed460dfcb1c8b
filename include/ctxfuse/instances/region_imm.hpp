// The region pipeline's run compiled once, part of the optional compiled target
// ctxfuse::instances (src/region_imm.cpp): a source that links it and includes this header
// calls region_imm::run without instantiating the ten estimators behind it (the three IMMs,
// the federated filter, the single EKFs and their aided wrapper). Header-only users include
// pipelines/region_imm/run.hpp instead and need nothing else.
#pragma once

#include "ctxfuse/pipelines/region_imm/run.hpp"

namespace ctxfuse::pipelines::region_imm::detail {

extern template RunResult run_any<void>(const messages::SensorLog&, Estimator, const Settings&, const RunOptions&,
                                        UpdateObserver);

}  // namespace ctxfuse::pipelines::region_imm::detail
