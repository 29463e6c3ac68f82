// Adam with its moments stored as bfloat16: the same update as adam_apply (kernels/adam.h) in
// fp32 arithmetic, from moments read as bf16 and written back rounded to the nearest bf16 (ties to
// even). The weights and the gradient stay fp32. Per parameter and step it moves 20 bytes instead
// of 28 (p, g, m, v read; p, m, v written), which is what bounds the memory-bound trainings (a
// JacoRobot reward head fine-tuning its own 3.1 M-weight copy of φ streams all of it every step).
//
// Exactly: with m, v holding bf16 values, the step computes m' = m·β1 + g·(1−β1) and
// v' = v·β2 + g²·(1−β2) in fp32 (a moment below the smallest normal float stored as 0, as
// adam_apply does), moves p by the fp32 m' and v' (so p's update is adam_apply's on those moments,
// bit for bit), and stores RN_bf16(m'), RN_bf16(v'). Whether training with it keeps the paper's
// results is an equivalence question, not a property of this kernel.
//
// No training uses it: on one Zen 5 core the fp32 update is bound by its arithmetic, and this one
// is slower (BM_AdamUpdate; docs/performance-history.md has the runs). It stays as the measured
// candidate for where the update is memory-bound (cores sharing bandwidth, other CPU classes).
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/adam.h"

namespace sirl {

// p [n], g [n] fp32; m [n], v [n] bf16 bit patterns (the upper 16 bits of an fp32 value).
void adam_apply_bf16_moments(const AdamStepScalars& s, float* p, const float* g, uint16_t* m,
                             uint16_t* v, size_t n);

// A block of `rows` × `cols` of matrices stored by rows (p, m, v with row stride ld, g with ldg),
// as adam_apply_rows.
void adam_apply_rows_bf16_moments(const AdamStepScalars& s, float* p, size_t ld, const float* g,
                                  size_t ldg, uint16_t* m, uint16_t* v, size_t rows, size_t cols);

}  // namespace sirl
