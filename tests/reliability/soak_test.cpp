// The soak's short variant (issue 18 item 5; soak.hpp): 10 simulated minutes at 100 Hz
// (60,000 IMU epochs, one 60 s GNSS outage) through the GNSS/INS filter and the plain IMM,
// with the checks and bounds of the 24 h program. Time per step is not asserted here (the
// program reports it, scripts/soak.sh).
#include <gtest/gtest.h>

#include "ctxfuse/instances/region_imm.hpp"  // region_imm::run compiled once (ctxfuse::instances)
#include "soak_run.hpp"

namespace {
namespace soak = ctxfuse::reliability::soak;

void expect_clean(const char* name, const soak::FilterReport& r, std::size_t fixes, double bound_gnss, double bound_any) {
  const double max_share = soak::kTenMinutes.max_share_above_999;
  SCOPED_TRACE(name);
  EXPECT_EQ(r.steps, 60000u);
  EXPECT_EQ(r.updates, fixes);
  EXPECT_EQ(r.refused, 0u);
  EXPECT_EQ(r.non_finite, 0u);
  EXPECT_EQ(r.asymmetric, 0u);
  EXPECT_EQ(r.not_pd, 0u);
  EXPECT_LE(r.max_error_gnss, bound_gnss);
  EXPECT_LE(r.max_error, bound_any);
  EXPECT_LE(r.share_above_999(), max_share);
  std::printf("%s: largest horizontal error %.3f m at settled fixes, %.3f m anywhere; e' P^-1 e largest %.1f, share above"
              " 99.9 %% %.5f; %zu of %zu fixes gated; worst asymmetry %.2e\n",
              name, r.max_error_gnss, r.max_error, r.max_position_nees, r.share_above_999(), r.gated, r.updates,
              r.worst_asymmetry);
}

TEST(Soak, TenMinutesAt100HzStayFiniteSymmetricPositiveDefiniteAndBounded) {
  soak::Config c;
  c.seconds = 600.0;
  c.bucket_s = 300.0;
  const soak::Report r = soak::run(c);
  // 600 epochs less the 60 of the outage.
  const soak::Bounds& b = soak::kTenMinutes;
  expect_clean("GNSS/INS", r.ins, 540u, b.ins_gnss, b.ins_any);
  expect_clean("IMM", r.imm, 540u, b.imm_gnss, b.imm_any);
  EXPECT_EQ(r.ins.bucket_max_error.size(), 2u);
  EXPECT_EQ(r.imm.bucket_ns_per_step.size(), 2u);
}

}  // namespace
