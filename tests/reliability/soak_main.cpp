// The soak program (issue 18 item 5; soak.hpp says what it checks): `reliability_soak [hours]
// [seed]`, 24 simulated hours by default. Prints one line per simulated hour (CPU time per IMU
// step of each filter with its checks, largest horizontal error), then the totals and the
// ratio of the last hour's time per step to the first's. Exit status 1 when a check failed
// or an error exceeded the bounds soak::kDay
// (soak.hpp; for runs of up to 24 h). scripts/soak.sh builds and runs it.
#include <cstdio>
#include <cstdlib>

#include "soak_run.hpp"

namespace soak = ctxfuse::reliability::soak;

namespace {
void print_filter(const char* name, const soak::FilterReport& r, double bound_gnss, double bound_any) {
  std::printf("%s: %zu steps, %zu GNSS updates (%zu gated), %zu refused; checks failed: %zu non-finite, %zu asymmetric, %zu not PD"
              " (worst asymmetry %.2e); largest horizontal error %.3f m at fixes 30 s after outages (bound %.1f), %.3f m anywhere (bound %.1f)\n",
              name, r.steps, r.updates, r.gated, r.refused, r.non_finite, r.asymmetric, r.not_pd, r.worst_asymmetry,
              r.max_error_gnss, bound_gnss, r.max_error, bound_any);
  std::printf("%s: horizontal error against its own covariance: largest e' P^-1 e %.1f, %zu of %zu epochs (%.4f %%) above the"
              " chi-square(2) 99.9 %% quantile (bound 1 %%)\n",
              name, r.max_position_nees, r.nees_above_999, r.nees_checked,
              100.0 * static_cast<double>(r.nees_above_999) / static_cast<double>(r.nees_checked));
  const auto& t = r.bucket_ns_per_step;
  if (t.size() >= 2)
    std::printf("%s: time per step first hour %.1f ns, last hour %.1f ns, last / first %.3f\n", name, t.front(), t.back(),
                t.back() / t.front());
}
}  // namespace

int main(int argc, char** argv) {
  soak::Config c;
  const double hours = argc > 1 ? std::atof(argv[1]) : 24.0;
  if (!(hours > 0.0) || hours > 1000.0) {
    std::fprintf(stderr, "usage: %s [hours (default 24)] [seed]\n", argv[0]);
    return 2;
  }
  c.seconds = hours * 3600.0;
  if (argc > 2) c.seed = std::strtoull(argv[2], nullptr, 10);
  std::printf("soak: %.2f simulated h at 100 Hz (%.0f IMU epochs), seed %llu, GNSS 1 Hz with a %.0f s outage every %.0f s\n",
              hours, c.seconds * 100.0, static_cast<unsigned long long>(c.seed), c.outage_s, c.outage_period_s);
  std::printf("hour | INS ns/step | IMM ns/step | INS max error (m) | IMM max error (m)\n");
  const double wall = soak::thread_cpu_ns();
  const soak::Report r = soak::run(c, [](const soak::Report& rep, std::size_t b) {
    std::printf("%4zu | %11.1f | %11.1f | %17.3f | %17.3f\n", b + 1, rep.ins.bucket_ns_per_step[b],
                rep.imm.bucket_ns_per_step[b], rep.ins.bucket_max_error[b], rep.imm.bucket_max_error[b]);
    std::fflush(stdout);
  });
  const soak::Bounds& b = soak::kDay;
  print_filter("GNSS/INS", r.ins, b.ins_gnss, b.ins_any);
  print_filter("IMM", r.imm, b.imm_gnss, b.imm_any);
  std::printf("CPU time %.1f s\n", (soak::thread_cpu_ns() - wall) * 1e-9);
  const bool ok = r.passed(b);
  std::printf("soak: %s\n", ok ? "passed" : "FAILED");
  return ok ? 0 : 1;
}
