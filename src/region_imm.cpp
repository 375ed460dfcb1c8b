// The one compiled instance of the region pipeline's run (ctxfuse/instances/region_imm.hpp).
#include "ctxfuse/instances/region_imm.hpp"

namespace ctxfuse::pipelines::region_imm::detail {

template RunResult run_any<void>(const messages::SensorLog&, Estimator, const Settings&, const RunOptions&, UpdateObserver);

}  // namespace ctxfuse::pipelines::region_imm::detail
