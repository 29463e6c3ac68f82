// This core's fp32 roof, measured in-process: the GFLOP/s of independent FMA chains on the widest
// vectors the CPU has (the loop bench/bench_roofline.cpp times at length). `sirl run` records it
// with the results, and /tables/timings gives each task's share of it (its `roof_percent`).
#pragma once

namespace sirl {

// Best of a few ~5 ms probes, measured once per process (thread-safe); ~20 ms the first time.
double fp32_roof_gflops_per_core();

}  // namespace sirl
