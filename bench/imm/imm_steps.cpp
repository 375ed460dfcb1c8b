// Runs N steps of one bench_imm workload and nothing else, for instruction counting
// (independent of what else the machine is doing, unlike times):
//   valgrind --tool=callgrind --callgrind-out-file=/dev/null bench_imm_steps imm 0
//   valgrind --tool=callgrind --callgrind-out-file=/dev/null bench_imm_steps imm 10000
// The difference of the two totals divided by 10000 is the count per step (the first run
// measures start-up and setup: gate quantiles, dynamic loading).
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "imm_variants.hpp"

namespace {
template <class T>
void keep(const T& value) {
  asm volatile("" : : "r"(&value) : "memory");
}
}  // namespace

int main(int argc, char** argv) {
  using namespace imm_bench;
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s imm|three_eskf STEPS\n", argv[0]);
    return 2;
  }
  const int steps = std::atoi(argv[2]);
  const auto keep_any = [](const auto& v) { keep(v); };
  Setup s;
  double t = 0.0;
  if (!std::strcmp(argv[1], "imm")) {
    auto f = make_imm(s);
    for (int i = 0; i < steps; ++i) imm_step(f, s, t, keep_any);
    std::printf("%.17g\n", f.combined().nominal.p.x());
  } else if (!std::strcmp(argv[1], "three_eskf")) {
    ThreeEskf e(s);
    for (int i = 0; i < steps; ++i) three_eskf_step(e, s, t, keep_any);
    std::printf("%.17g\n", e.a.nominal().p.x());
  } else {
    return 2;
  }
  return 0;
}
