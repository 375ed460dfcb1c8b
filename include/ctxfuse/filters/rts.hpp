// Step records of an error-state filter's forward pass and the Rauch-Tung-Striebel backward
// pass over them.
//
// Forward, around eskf::predict / eskf::update:
//   RtsRecorder<Model> rec;  rec.reserve(expected_epochs);
//   rec.start(t0, belief);                          // the first posterior
//   per prediction:  eskf::predict(model, belief, u, dt, opts, &F);  rec.predicted(F);
//   per epoch:       prior = belief; ...updates...; rec.record(t, prior, belief);
// An epoch is any time at which the smoothed estimate is wanted and every time at which an
// update (and hence a reset) happens; predictions between two epochs are composed into one
// transition Phi = F_n ... F_1, which is exact for the smoother (the RTS gain at an epoch only
// needs the transition to the next epoch). So memory is one record (two beliefs and one N x N
// transition, memory_bytes()) per epoch, not per IMU sample: per GNSS fix, or per constraint
// update, whichever the pipeline records.
//
// Backward (smooth), for epochs k = K-1 .. 0, with Phi_k the transition from epoch k to k+1:
//   C_k   = P_k Phi_k' Pbar_{k+1}^-1                  (P: filtered posterior, Pbar: prior)
//   dx_k  = C_k (xs_{k+1} [-] xbar_{k+1})             (on the manifold, about the prior)
//   xs_k  = x_k [+] dx_k
//   Ps_k  = P_k + C_k (Ps_{k+1} - Pbar_{k+1}) C_k'    (then reset: G Ps_k G' about xs_k)
// The transition is the one stored for that very step (time-varying F: using F_{k+1} for step
// k is the known pitfall); the difference to the smoothed successor is taken about the prior
// nominal, so the mean accounts for the update's reset at that epoch exactly; the covariance
// recursion uses Ps_{k+1} about the posterior nominal beside Pbar about the prior one (equal to
// first order in the update's correction; exact for vector states). Epochs without updates
// (gaps) have prior == posterior and need nothing special.
//
// The gain and the handling of states held by construction (zero prior variance and process
// noise) are filters/rts_gain.hpp's, shared with the fixed-lag ring (filters/fixed_lag_rts.hpp),
// and so is the rule for a record at the newest one's time: a second update there with no
// prediction since joins it.
#pragma once

#include <Eigen/Cholesky>

#include <cstddef>
#include <vector>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/filters/rts_gain.hpp"

namespace ctxfuse {

template <ErrorStateProcessModel Model>
class RtsRecorder {
 public:
  static constexpr int N = Model::dim;
  using Belief = ErrorStateBelief<typename Model::State, N>;
  struct Record {
    double t = 0.0;
    Belief prior;                    // after the predictions into this epoch, before its updates
    Belief posterior;                // after its updates; smoothed in place by smooth()
    SquareMatrix<N> transition;      // from the previous epoch's posterior to this prior
    bool restarts = false;           // a new start (restart()): nothing links it to the epoch before
  };

  void reserve(std::size_t epochs) { records_.reserve(epochs); }

  void start(double t, const Belief& posterior) {
    records_.clear();
    records_.push_back(Record{t, posterior, posterior, SquareMatrix<N>::Identity()});
    phi_.setIdentity();
    smoothed_ = false;
  }

  /// A new start after the filter lost its state (e.g. an INS re-aligned after an IMU gap):
  /// the epochs before and after are smoothed as two runs, nothing carried across.
  Status restart(double t, const Belief& posterior) {
    if (records_.empty()) {
      start(t, posterior);
      return Status{};
    }
    if (!(t > records_.back().t)) return Status::invalid(Problem::out_of_order_time);
    records_.push_back(Record{t, posterior, posterior, SquareMatrix<N>::Identity(), true});
    phi_.setIdentity();
    smoothed_ = false;
    return Status{};
  }

  /// One prediction's transition F (eskf::predict's F_used), composed since the last epoch.
  /// Block-sparse when the model declares `transition_blocks` (the pattern eskf::predict's
  /// covariance step already relies on): the whole-drive forward pass of the GNSS/INS pipeline
  /// spent a third of its time in Eigen's blocked GEMM on this 20 x 20 product (perf,
  /// docs/benchmarks.md "gins"). Otherwise coefficient-based, for the same reason.
  void predicted(const SquareMatrix<N>& F) {
    if constexpr (requires { Model::transition_blocks; }) {
      block_sparse_product<Model::transition_blocks>(F, phi_, phi_next_);
    } else {
      phi_next_.noalias() = F.lazyProduct(phi_);
    }
    phi_ = phi_next_;
  }

  /// Closes an epoch. At the newest epoch's time with no prediction since, the update joins
  /// that epoch (its posterior replaced, its prior kept; records().size() does not grow).
  /// Refused (nothing stored) before start() and for any other stamp that does not advance.
  Status record(double t, const Belief& prior, const Belief& posterior) {
    if (records_.empty()) return Status::invalid(Problem::time_not_set);
    switch (rts_record_kind<N>(t, records_.back().t, phi_)) {
      case RtsRecordKind::out_of_order: return Status::invalid(Problem::out_of_order_time);
      case RtsRecordKind::joins_newest: records_.back().posterior = posterior; return Status{};
      case RtsRecordKind::next: break;
    }
    records_.push_back(Record{t, prior, posterior, phi_});
    phi_.setIdentity();
    return Status{};
  }

  /// The backward pass; afterwards records()[k].posterior is the smoothed belief at epoch k.
  /// On a failure (a prior covariance that is not positive definite apart from held states)
  /// the records from the failed epoch down keep their filtered values and the status names
  /// the problem.
  Status smooth(const Model& model) {
    if (records_.size() < 2 || smoothed_) return Status{};
    // The smoothed covariance of epoch k+1 before its reset, in the prior's tangent space.
    SquareMatrix<N> Ps_next = records_.back().posterior.cov;
    typename Model::State xs_next = records_.back().posterior.nominal;
    for (std::size_t k = records_.size() - 1; k-- > 0;) {
      Record& r = records_[k];
      const Record& n = records_[k + 1];
      if (n.restarts) {  // the last epoch of the run before: its filtered belief stands
        Ps_next = r.posterior.cov;
        xs_next = r.posterior.nominal;
        continue;
      }
      SquareMatrix<N> C;
      if (const Status g = rts_gain<N>(r.posterior.cov, n.transition, n.prior.cov, C); !g.accepted()) return g;
      const Vector<N> dx = C * model.difference(xs_next, n.prior.nominal);
      SquareMatrix<N> Ps = r.posterior.cov + C * (Ps_next - n.prior.cov) * C.transpose();
      symmetrize(Ps);
      if (!all_finite(Ps) || !all_finite(dx)) return Status::failure(Problem::non_finite_covariance);
      // Carried to the next (earlier) step un-reset, about this epoch's filtered posterior
      // nominal, and used there beside Pbar about the prior nominal: the two tangent spaces
      // differ by this epoch's update reset, the identity to first order in the update's
      // correction (exactly for vector states).
      Ps_next = Ps;
      if constexpr (requires { { model.reset_jacobian(r.posterior.nominal, dx) } -> std::convertible_to<SquareMatrix<N>>; }) {
        const SquareMatrix<N> G = model.reset_jacobian(r.posterior.nominal, dx);
        r.posterior.cov = G * Ps * G.transpose();
        symmetrize(r.posterior.cov);
      } else {
        r.posterior.cov = Ps;
      }
      r.posterior.nominal = model.inject(r.posterior.nominal, dx);
      xs_next = r.posterior.nominal;
    }
    smoothed_ = true;
    return Status{};
  }

  const std::vector<Record>& records() const { return records_; }
  std::size_t memory_bytes() const { return records_.capacity() * sizeof(Record); }

 private:
  std::vector<Record> records_;
  SquareMatrix<N> phi_ = SquareMatrix<N>::Identity();
  SquareMatrix<N> phi_next_;  // F phi_, written before phi_ is
  bool smoothed_ = false;
};

}  // namespace ctxfuse
