// Runs N steps of one zero-overhead variant and nothing else, for instruction counting:
//   valgrind --tool=callgrind --callgrind-out-file=/dev/null bench_zero_overhead_steps engine 20000
// Instruction counts do not depend on what else the machine is doing, unlike times.
#include <cstdio>
#include <cstdlib>
#include <cstring>

#define CTXFUSE_KEEP(x) keep(x)
template <class T>
void keep(const T& value) {
  asm volatile("" : : "r"(&value) : "memory");
}
#include "zero_overhead_variants.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s engine|handwritten|dynamic STEPS\n", argv[0]);
    return 2;
  }
  const int steps = std::atoi(argv[2]);
  const auto run = [steps](auto filter) {
    for (int i = 0; i < steps; ++i) filter.step(i);
    std::printf("%.17g\n", filter.state().p.x());
  };
  if (!std::strcmp(argv[1], "engine")) run(zero_overhead::EngineFilter{});
  else if (!std::strcmp(argv[1], "handwritten")) run(zero_overhead::HandWrittenFilter{});
  else if (!std::strcmp(argv[1], "dynamic")) run(zero_overhead::DynamicFilter{});
  else return 2;
  return 0;
}
