// This core's roofs, measured in-process with the loops bench/bench_roofline.cpp times at length
// (probes/peak_loops.h). `sirl run` records them with the results, and /tables/timings gives
// each task's share of the roof of its precision (its `roof_percent`).
#pragma once

namespace sirl {

// Best of a few short probes of the peak loop, measured once per process (thread-safe).
double fp32_roof_gflops_per_core();

// The peak of the unit bf16 products run on here (gemm_bf16.h's bf16_backend()): AMX tdpbf16ps
// where oneDNN uses AMX, else vdpbf16ps; 0 where bf16 products are emulated (then they are fp32
// arithmetic, and the fp32 roof is theirs). Measured once per process, a few ms the first time.
double bf16_roof_gflops_per_core();

// This core's main-memory bandwidth in GB/s: a STREAM triad a[i] = b[i] + s·c[i] over three
// 32 MiB arrays (beyond a core's share of the caches), counting 12 bytes per element; best of 3
// passes after one that faults the pages in. Measured once per process (thread-safe), with 96 MiB
// allocated while it runs. The memory roof of a task that streams its weights and Adam state:
// its FLOPs per byte streamed times this (/tables/timings' memory_roof_gflops).
double stream_gbs_per_core();

}  // namespace sirl
