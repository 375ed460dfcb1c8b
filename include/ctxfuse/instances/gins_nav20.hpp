// The GNSS/INS pipeline for the 20-state layout (pipelines/gins) compiled once, part of the
// optional compiled target ctxfuse::instances (src/, docs/architecture.md): src/gins_nav20.cpp
// holds the explicit instantiations and the definitions below. A source that links
// ctxfuse::instances and includes this header does not compile the forward pass (the 20-state
// prediction, its updates, the RTS smoother) for itself; the tool, the gins and reliability
// tests that run the pipeline and bench_gins_drive do. Header-only users include
// pipelines/gins/run.hpp instead and need nothing else.
//
// `extern template` keeps a source that includes this header from instantiating gins::run and
// gins::trajectory_row (non-inline templates). It cannot do that for the members of
// ForwardPass, which are inline (defined in its class body): a source that steps the pass
// itself uses instances::GinsNav20Pass, whose members are defined in src/gins_nav20.cpp.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "ctxfuse/pipelines/gins/run.hpp"

namespace ctxfuse::pipelines::gins {

extern template RunResult run<Nav20>(std::span<const messages::ImuSample>, std::span<const messages::GnssFix>, const Settings&,
                                     const RunOptions&);
extern template TrajectoryRow trajectory_row<Nav20>(double, const eskf::Belief<Nav20>&, const Eigen::Vector3d&);

}  // namespace ctxfuse::pipelines::gins

namespace ctxfuse::instances {

/// gins::ForwardPass<Nav20> with the same members (those a replay handler and its caller use),
/// defined out of line. The settings are held by reference, as ForwardPass holds them.
class GinsNav20Pass {
 public:
  GinsNav20Pass(const pipelines::gins::Settings& s, const pipelines::gins::Installation& inst,
                const pipelines::gins::Constraints& c, std::vector<pipelines::gins::OutageWindow> windows,
                double gnss_rate_hz);
  ~GinsNav20Pass();
  GinsNav20Pass(const GinsNav20Pass&) = delete;
  GinsNav20Pass& operator=(const GinsNav20Pass&) = delete;

  void propagate(const messages::ImuSample& u, double dt);
  void on(const messages::ImuSample& u);
  void on(const messages::MagSample& m);
  void on(const messages::GnssFix& fix);
  void finish();

  bool aligned() const;
  const eskf::Belief<pipelines::gins::Nav20>& belief() const;
  const pipelines::gins::PassCounts& counts() const;
  const std::vector<RtsRecorder<pipelines::gins::Nav20>::Record>& records() const;
  const Eigen::Vector3d& gnss_lever() const;

 private:
  std::unique_ptr<pipelines::gins::ForwardPass<pipelines::gins::Nav20>> pass_;
};

}  // namespace ctxfuse::instances
