// The one compiled instance of the GNSS/INS pipeline for Nav20 (ctxfuse/instances/gins_nav20.hpp).
#include "ctxfuse/instances/gins_nav20.hpp"

namespace ctxfuse::pipelines::gins {

template RunResult run<Nav20>(std::span<const messages::ImuSample>, std::span<const messages::GnssFix>, const Settings&,
                              const RunOptions&);
template TrajectoryRow trajectory_row<Nav20>(double, const eskf::Belief<Nav20>&, const Eigen::Vector3d&);

}  // namespace ctxfuse::pipelines::gins

namespace ctxfuse::instances {

using pipelines::gins::Nav20;

GinsNav20Pass::GinsNav20Pass(const pipelines::gins::Settings& s, const pipelines::gins::Installation& inst,
                             const pipelines::gins::Constraints& c, std::vector<pipelines::gins::OutageWindow> windows,
                             double gnss_rate_hz)
    : pass_(std::make_unique<pipelines::gins::ForwardPass<Nav20>>(s, inst, c, std::move(windows), gnss_rate_hz)) {}
GinsNav20Pass::~GinsNav20Pass() = default;

void GinsNav20Pass::propagate(const messages::ImuSample& u, double dt) { pass_->propagate(u, dt); }
void GinsNav20Pass::on(const messages::ImuSample& u) { pass_->on(u); }
void GinsNav20Pass::on(const messages::MagSample& m) { pass_->on(m); }
void GinsNav20Pass::on(const messages::GnssFix& fix) { pass_->on(fix); }
void GinsNav20Pass::finish() { pass_->finish(); }

bool GinsNav20Pass::aligned() const { return pass_->aligned(); }
const eskf::Belief<Nav20>& GinsNav20Pass::belief() const { return pass_->belief(); }
const pipelines::gins::PassCounts& GinsNav20Pass::counts() const { return pass_->counts(); }
const std::vector<RtsRecorder<Nav20>::Record>& GinsNav20Pass::records() const { return pass_->recorder().records(); }
const Eigen::Vector3d& GinsNav20Pass::gnss_lever() const { return pass_->gnss_lever(); }

}  // namespace ctxfuse::instances
