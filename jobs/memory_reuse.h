// How the process gets its large buffers back from the allocator. A JacoRobot TPA cell allocates
// its 20 heads' weights and Adam moments afresh (254 MB frozen, 1 GB unfrozen) and frees them when
// it ends. glibc serves blocks that large with mmap and returns them with munmap, so every cell
// pays to fault its pages in again, a measurable share of a frozen cell's time (`BM_TpaCell/jaco`;
// the measurement: docs/kernels.md, "The measurements behind the kernels' choices").
#pragma once

namespace sirl {

// Makes the allocator keep freed memory for the next allocation: no mmap for large blocks (they
// come from the heap, whose freed space the next cell reuses), no trimming of the heap's top, and
// one arena (the worker threads' own arenas would otherwise serve blocks over 64 MB with mmap
// anyway). Call once at the start of main, before any thread exists. The cost: the process's
// resident memory does not shrink while it runs; it stays at its high-water mark, freed holes
// included (quick on 2 threads: 3.09 GiB peak, where `sirl plan` estimates 2.74).
// Results do not depend on it (same table digests). A no-op with allocators other than glibc's.
void keep_freed_memory_for_reuse();

}  // namespace sirl
