// Fixed-lag Rauch-Tung-Striebel smoothing of a vector-state EKF: the smoothed mean a given lag
// behind the newest update, from the last `capacity` update records. The capacity is a
// runtime value (a lag in seconds holds as many records as the sensors' rates put in it), and
// the ring is allocated once, by the constructor: nothing allocates after it.
//
// Forward, around ekf::predict / ekf::update (the same call pattern as filters/rts.hpp):
//   lag.start(t0, belief);                                  // the first posterior
//   per prediction:  ekf::predict(model, belief, u, dt, opts, &F);  lag.predicted(F);
//   per update:      prior = belief; ekf::update(...);  lag.record(t, prior, belief);
// Predictions between two records compose into one transition Phi = F_n ... F_1 (exact for the
// smoother). Each record keeps its filtered mean and its prior mean; its RTS gain
//   C_k = P_k Phi_k' Pbar_{k+1}^-1
// is computed once, when record k+1 arrives (it needs only P_k, Phi_k and Pbar_{k+1}), so
// the backward pass of smoothed() is one N x N product per record:
//   xs_k = x_k + C_k (xs_{k+1} - xbar_{k+1}).
// This is the RTS mean recursion over the records that the window holds; with the whole run in
// the window it is the RTS smoother of the run (tests/filters/fixed_lag_rts_test.cpp checks it
// against the textbook equations written plainly). Only means are smoothed: callers of a
// fixed-lag output want the estimate, and the covariance recursion would double the cost.
//
// The gain, the held states' handling and the rule for a record at the newest one's time are
// filters/rts_gain.hpp's, shared with the whole-run recorder (filters/rts.hpp).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"
#include "ctxfuse/filters/rts_gain.hpp"

namespace ctxfuse {

template <int N>
class FixedLagRts {
 public:
  static constexpr int kDefaultCapacity = 64;
  /// A window of `capacity` records (at least 2).
  explicit FixedLagRts(int capacity = kDefaultCapacity)
      : capacity_(std::max(2, capacity)), ring_(static_cast<std::size_t>(capacity_)) {}
  int capacity() const { return capacity_; }

  struct Smoothed {
    double t = 0.0;
    Vector<N> mean = Vector<N>::Zero();
  };

  /// Forgets every record and starts from `posterior` at t (a new run: nothing before it is
  /// linked to what follows).
  void start(double t, const Gaussian<N>& posterior) {
    ++revision_;
    size_ = 0;
    head_ = 0;
    push(t, posterior.mean, posterior.mean);
    last_cov_ = posterior.cov;
    phi_.setIdentity();
  }

  bool started() const { return size_ > 0; }
  int size() const { return size_; }
  /// Changes whenever the window does (a start, an accepted record): a cache of smoothed()
  /// is current while it stays.
  std::size_t revision() const { return revision_; }

  /// One prediction's Jacobian, composed into the transition since the newest record.
  void predicted(const SquareMatrix<N>& F) { phi_ = (F * phi_).eval(); }

  /// An update at t: `prior` before it, `posterior` after. A second update at the newest
  /// record's time, with no prediction since, joins that record (its prior stays the one
  /// before the first). Refused before start() and for t before the newest record; a prior
  /// covariance that is not positive definite (apart from held states) ends the run: the
  /// smoother starts again from this posterior, and the status says why.
  Status record(double t, const Gaussian<N>& prior, const Gaussian<N>& posterior) {
    if (size_ == 0) return Status::invalid(Problem::time_not_set);
    Record& last = at(size_ - 1);
    switch (rts_record_kind<N>(t, last.t, phi_)) {
      case RtsRecordKind::out_of_order: return Status::invalid(Problem::out_of_order_time);
      case RtsRecordKind::joins_newest:
        ++revision_;
        last.mean = posterior.mean;
        last_cov_ = posterior.cov;
        return Status{};
      case RtsRecordKind::next: break;
    }
    if (const Status g = rts_gain<N>(last_cov_, phi_, prior.cov, last.gain); !g.accepted()) {
      start(t, posterior);
      return g;
    }
    ++revision_;
    push(t, prior.mean, posterior.mean);
    last_cov_ = posterior.cov;
    phi_.setIdentity();
    return Status{};
  }

  /// The smoothed mean at the newest record at least lag_s older than the newest one (to
  /// within kTimeTolerance: stamps that are sums of periods carry rounding); the oldest record
  /// held when the window is shorter than that (the returned time says which). lag_s = 0 (or
  /// one record) gives the newest filtered mean.
  static constexpr double kTimeTolerance = 1e-6;  // s; above double's 2.4e-7 s at Unix times
  Smoothed smoothed(double lag_s) const {
    if (size_ == 0) return {};
    const double newest_t = at(size_ - 1).t;
    Vector<N> xs = at(size_ - 1).mean;
    int k = size_ - 1;
    while (k > 0 && at(k).t > newest_t - lag_s + kTimeTolerance) {
      const Record& r = at(k - 1);
      xs = r.mean + r.gain * (xs - at(k).prior_mean);
      --k;
    }
    return {at(k).t, xs};
  }

 private:
  struct Record {
    double t = 0.0;
    Vector<N> prior_mean = Vector<N>::Zero();  // before this record's updates
    Vector<N> mean = Vector<N>::Zero();        // after them (filtered)
    SquareMatrix<N> gain = SquareMatrix<N>::Zero();  // C to the next record (set when it arrives)
  };

  Record& at(int i) { return ring_[static_cast<std::size_t>((head_ + i) % capacity_)]; }
  const Record& at(int i) const { return ring_[static_cast<std::size_t>((head_ + i) % capacity_)]; }

  void push(double t, const Vector<N>& prior_mean, const Vector<N>& mean) {
    if (size_ == capacity_) {  // the oldest record leaves the window
      head_ = (head_ + 1) % capacity_;
      --size_;
    }
    Record& r = at(size_++);
    r.t = t;
    r.prior_mean = prior_mean;
    r.mean = mean;
    r.gain.setZero();
  }

  int capacity_;
  std::vector<Record> ring_;
  int head_ = 0, size_ = 0;
  std::size_t revision_ = 0;
  SquareMatrix<N> last_cov_ = SquareMatrix<N>::Identity();  // the newest record's filtered covariance
  SquareMatrix<N> phi_ = SquareMatrix<N>::Identity();
};

}  // namespace ctxfuse
