// uhaptics-bench's main: Google Benchmark's, after registering the benchmarks that are made per
// registered device at run time (the CHAI3D tick, when the CHAI3D layer is built).
#include <benchmark/benchmark.h>

#ifdef UHAPTICS_BENCH_CHAI3D
#include "chai3d_tick_bench.hpp"
#endif

int main(int argc, char** argv) {
#ifdef UHAPTICS_BENCH_CHAI3D
  uhaptics::bench::registerChai3dTickBenchmarks();
#endif
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
