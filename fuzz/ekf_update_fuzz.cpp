// The EKF's steps fed arbitrary bytes as numbers: prior mean and covariance, measurement
// matrix or anchor, noise, measurement and time step all come from the input. Whatever the
// numbers, a step must return a Status (no crash, no sanitizer report), and
//  - accepted: the belief is finite (whatever the prior) and its covariance
//    exactly symmetric (the filter mirrors it), the NIS non-negative and within the gate;
//  - anything else: the belief bit-for-bit unchanged (filters/ekf.hpp promises it).
// Numbers are decoded two ways (first byte, bit 0): raw IEEE doubles, which reach NaN, Inf,
// denormals and 1e308 at once, or "tame" values (a 16-bit mantissa times 2^-20..2^20) that
// pass validation often enough for the accepted path to be explored.
#include <bit>
#include <cmath>
#include <cstring>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"
#include "ctxfuse/policies/gating.hpp"
#include "fuzz_support.hpp"

using namespace ctxfuse;
using ctxfuse_fuzz::fail;

namespace {

class Numbers {
 public:
  Numbers(const std::uint8_t* d, std::size_t n, bool raw) : d_(d), n_(n), raw_(raw) {}
  double next() {
    if (raw_) {
      std::uint64_t u = 0;
      for (int k = 0; k < 8; ++k) u |= static_cast<std::uint64_t>(byte()) << (8 * k);  // little-endian
      return std::bit_cast<double>(u);
    }
    const auto m = static_cast<std::int16_t>(byte() | (byte() << 8));
    return std::ldexp(static_cast<double>(m) / 4096.0, static_cast<int>(byte() % 41) - 20);
  }
  template <int R, int C>
  Matrix<R, C> matrix() {
    Matrix<R, C> m;
    for (int j = 0; j < C; ++j)
      for (int i = 0; i < R; ++i) m(i, j) = next();
    return m;
  }

 private:
  std::uint8_t byte() { return i_ < n_ ? d_[i_++] : 0; }  // zeros past the end
  const std::uint8_t* d_;
  std::size_t n_, i_ = 0;
  bool raw_;
};

template <int N>
bool same_bits(const Gaussian<N>& a, const Gaussian<N>& b) {
  return std::memcmp(a.mean.data(), b.mean.data(), sizeof(double) * N) == 0 &&
         std::memcmp(a.cov.data(), b.cov.data(), sizeof(double) * N * N) == 0;
}

template <int N>
bool finite(const Gaussian<N>& b) {
  return b.mean.allFinite() && b.cov.allFinite();
}

template <int N>
void check(const Status& s, const Gaussian<N>& before, const Gaussian<N>& after, bool is_update) {
  if (s.accepted()) {
    // From any prior: a non-finite prior mean is refused (non_finite_prior), a non-finite
    // prior covariance makes the posterior's non-finite, which is refused too (the saved
    // input non-finite-prior-accepted is the case that used to pass).
    if (!finite(after)) fail("accepted step left a non-finite belief");
    if (after.cov != after.cov.transpose()) fail("accepted step left an asymmetric covariance");
    // Not "finite": without a gate (threshold +inf) an update whose NIS overflows to +inf
    // is accepted, a finite belief all the same (input ungated-infinite-nis).
    if (is_update && !(s.nis >= 0.0 && s.nis <= s.gate_threshold))
      fail("accepted update with a NIS that is negative, NaN or beyond the gate");
  } else if (!same_bits(before, after)) {
    fail("rejected step changed the belief");
  }
}

template <class Meas, class Gate>
void update(const Meas& meas, const Gaussian<4>& prior, const Vector<Meas::dim>& z, const Gate& gate) {
  Gaussian<4> b = prior;
  const Status s = ekf::update<4>(meas, b, z, gate);
  check(s, prior, b, true);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t mode = data[0];
  Numbers num(data + 1, size - 1, (mode & 1) != 0);
  Gaussian<4> prior;
  prior.mean = num.matrix<4, 1>();
  if (mode & 2) {
    prior.cov = num.matrix<4, 4>();  // anything, even asymmetric or indefinite
  } else {
    const Matrix<4, 4> A = num.matrix<4, 4>();
    prior.cov = A * A.transpose();  // a covariance when finite
  }
  const bool gated = (mode & 4) != 0;
  const policies::ChiSquareGate gate(0.99);

  models::LinearMeasurement<2, 4> lin;
  lin.H = num.matrix<2, 4>();
  lin.R = num.matrix<2, 2>();
  const Vector<2> z2 = num.matrix<2, 1>();
  if (gated) update(lin, prior, z2, gate); else update(lin, prior, z2, policies::NoGate{});

  using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
  models::RangeToPoint<L, 2> range;
  range.anchor = num.matrix<2, 1>();
  range.sigma = num.next();
  const Vector<1> z1 = num.matrix<1, 1>();
  if (gated) update(range, prior, z1, gate); else update(range, prior, z1, policies::NoGate{});

  models::LinearProcess<4> process;
  process.F = num.matrix<4, 4>();
  process.Q = num.matrix<4, 4>();
  const double dt = num.next();
  Gaussian<4> b = prior;
  const Status s = ekf::predict(process, b, NoInput{}, dt);
  check(s, prior, b, false);
  return 0;
}
