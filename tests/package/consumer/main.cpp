// Downstream use of ctxfuse, compiled with nothing but the ctxfuse::ctxfuse target's usage
// requirements: a missing include directory, dependency or language level fails to build,
// and a wrong result fails the exit code. Expected values are worked out by hand below.
#include <ctxfuse/ctxfuse.hpp>

#include <boost/hana.hpp>

#include <cmath>
#include <cstdio>

namespace {

using Position = ctxfuse::StateBlock<"p", 2>;
using Velocity = ctxfuse::StateBlock<"v", 2>;
using Bias = ctxfuse::StateBlock<"b", 1>;
using State = ctxfuse::Layout<Position, Velocity, Bias>;

bool check(bool ok, const char* what) {
  if (!ok) std::printf("ctxfuse consumer: FAILED: %s\n", what);
  return ok;
}

}  // namespace

int main() {
  bool ok = true;
  // Blocks p(2), v(2), b(1): offsets 0, 2, 4, size 5.
  ok &= check(State::size == 5 && State::offset<"v">() == 2 && State::offset<"b">() == 4,
              "layout offsets");

  // One constant-velocity step of 0.5 s written through the named views:
  // p = (1, 2) + 0.5 * (4, -2) = (3, 1).
  State::StateVector x;
  x << 1.0, 2.0, 4.0, -2.0, 0.25;
  State::get<"p">(x) += 0.5 * State::get<"v">(x);
  ok &= check(x(0) == 3.0 && x(1) == 1.0 && x(2) == 4.0 && x(4) == 0.25, "named views");

  // Map of the sub-layout {v, b} into the full state: v sits at 2..3, b at 4.
  using Sub = ctxfuse::Layout<Velocity, Bias>;
  const auto sub = ctxfuse::LayoutMap<Sub, State>::extract(x);
  ok &= check(sub(0) == 4.0 && sub(1) == -2.0 && sub(2) == 0.25, "layout map");

  // One scalar Kalman cycle, by hand: prior x = 0, P = 4; predict with F = 1, Q = 1 gives
  // P = 5; update with z = 2, R = 1 gives K = 5/6, x = 5/3, P = (1 - K) P = 5/6.
  ctxfuse::models::LinearProcess<1> process;
  process.Q(0, 0) = 1.0;
  ctxfuse::models::LinearMeasurement<1, 1> measurement;
  measurement.H(0, 0) = 1.0;
  ctxfuse::Gaussian<1> belief;
  belief.cov(0, 0) = 4.0;
  const bool predicted = ctxfuse::ekf::predict(process, belief, ctxfuse::NoInput{}, 0.1).accepted();
  const bool updated =
      ctxfuse::ekf::update<1>(measurement, belief, ctxfuse::Vector<1>::Constant(2.0)).accepted();
  ok &= check(predicted && updated && std::abs(belief.mean(0) - 5.0 / 3.0) < 1e-12 &&
                  std::abs(belief.cov(0, 0) - 5.0 / 6.0) < 1e-12,
              "Kalman predict/update");

  // Boost.Hana must be reachable through the target as well: 1 + 2 + 3 = 6.
  const int hana_sum = boost::hana::fold_left(boost::hana::make_tuple(1, 2, 3), 0,
                                              [](int s, int v) { return s + v; });
  ok &= check(hana_sum == 6, "boost::hana");

  if (ok) std::printf("ctxfuse consumer: ok\n");
  return ok ? 0 : 1;
}
