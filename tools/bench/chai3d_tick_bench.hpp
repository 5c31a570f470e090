#pragma once
// The CHAI3D tick benchmarks are registered at run time, one pair per registered device
// (chai3d_tick_bench.cpp); main.cpp calls this before running the suite.
namespace uhaptics::bench {
void registerChai3dTickBenchmarks();
}  // namespace uhaptics::bench
