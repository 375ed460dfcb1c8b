// `ctxfuse demo` section "region_imm": the region paper's tables on the simulated drive
// (cli/region_imm_report.hpp). The drive runs as the streams a recording would hold
// (sim::sensor_log); training and validation of the recogniser use other simulated drives
// (studies/region_training.hpp: seeds + 101, + 102 and + 103 train, seed + 202 validates), as the
// paper trains, validates and tests on separate data.
#include <ostream>
#include <string>

#include "cli/region_imm_report.hpp"
#include "cli/registry.hpp"
#include "ctxfuse/instances/region_imm.hpp"  // run() compiled once (ctxfuse::instances)
#include "ctxfuse/studies/region_training.hpp"
#include "ctxfuse/sim/streams.hpp"

namespace ctxfuse::cli {
namespace {

void run_section(const DemoContext& ctx, Json& json, std::ostream& out) {
  const sim::Drive& test = *ctx.drive;
  using Drives = ctxfuse::studies::RegionTrainingDrives;
  const auto seed = test.config.seed;
  const messages::SensorLog log = sim::sensor_log(test);
  const sim::TruthLog truth = sim::truth_log(test);
  const ri::Recogniser rec = train_region_recogniser(test.config);
  const std::string note = "trained on seeds " + std::to_string(seed + Drives::train_seed_offset) + "-" +
                           std::to_string(seed + Drives::train_seed_offset + Drives::train_drives - 1) + ", validated on seed " +
                           std::to_string(seed + Drives::validate_seed_offset);
  region_imm_report({log, truth, rec, note, ctx.plotter}, json, out);
}

const RegisterDemoSection reg_region_imm{{"region_imm", "Region-aware IMM, seamless indoor/outdoor (paper A)", run_section}};

}  // namespace
}  // namespace ctxfuse::cli
