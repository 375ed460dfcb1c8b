// Fault injection for the region pipeline through the replay's tamper hook (the Fault and its
// hook: fault_stream.hpp): a Checked handler runs the pipeline's own replay handler
// (region_imm::detail::Runner) and, after every step, checks the estimator's beliefs: finite,
// covariance symmetric and positive definite.
#pragma once

#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/pipelines/region_imm/run.hpp"
#include "fault_stream.hpp"

namespace ctxfuse::reliability {

/// The region pipeline's replay report of stream `s` (its streams: speed, uwb, gnss, epochs).
inline const io::StreamReport& report_of(const io::ReplayReport<4>& r, StreamId s) {
  switch (s) {
    case StreamId::speed: return r.streams[0];
    case StreamId::uwb: return r.streams[1];
    case StreamId::gnss: return r.streams[2];
    case StreamId::sat_epochs: return r.streams[3];
    default: return r.imu;
  }
}

/// Every belief the estimator holds: the IMM's modes and combined estimate, the federated
/// filter's locals and global estimate, GNSS alone's held position.
template <class Mixing>
void check_estimator(const pipelines::region_imm::Aided<pipelines::region_imm::ImmCore<Mixing>>& est,
                     BeliefChecks& c) {
  const auto& f = *est.core().f;
  c.check(f.template mode_belief<0>());
  c.check(f.template mode_belief<1>());
  c.check(f.template mode_belief<2>());
  c.check(f.combined());
}
inline void check_estimator(const pipelines::region_imm::Aided<pipelines::region_imm::FederatedCore>& est,
                     BeliefChecks& c) {
  const auto& f = *est.core().f;
  c.check(f.local(0));
  c.check(f.local(1));
  c.check(f.global());
}
inline void check_estimator(const pipelines::region_imm::GnssOnly& est, BeliefChecks& c) { c.check_position(est.last); }

/// The pipeline's replay handler with the checks after each step (once started).
template <class Est>
struct Checked {
  pipelines::region_imm::detail::Runner<Est> runner;
  BeliefChecks checks{};

  void after() {
    if (runner.started) check_estimator(runner.est, checks);
  }
  void propagate(const messages::ImuSample& u, double dt) {
    runner.propagate(u, dt);
    after();
  }
  template <class Msg>
  void forward(const Msg& m) {
    runner.on(m);
    after();
  }
  void on(const messages::SpeedSample& m) { forward(m); }
  void on(const messages::UwbRange& m) { forward(m); }
  void on(const messages::GnssFix& m) { forward(m); }
  void on(const messages::SatEpoch& m) { forward(m); }
};

}  // namespace ctxfuse::reliability
