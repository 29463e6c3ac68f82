// Adam with an exponentially decaying learning rate lr·decay^step, matching
// torch.optim.Adam (β1 0.9, β2 0.999, ε 1e-8, no weight decay) stepped with
// torch.optim.lr_scheduler.ExponentialLR(γ = decay) after every optimizer step.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace sirl {

struct AdamConfig {
  double lr = 1e-3;
  double decay = 1.0;  // per step; the paper uses 0.99999
  double beta1 = 0.9;
  double beta2 = 0.999;
  double eps = 1e-8;
};

struct AdamState {
  std::vector<float> m, v;  // first and second moments, one per parameter
  int64_t step = 0;         // optimizer steps taken so far
  explicit AdamState(size_t n = 0) : m(n, 0.f), v(n, 0.f) {}
};

// The float scalars of one optimizer step (learning rate, bias corrections): what every
// element's update needs, computed once per step.
struct AdamStepScalars {
  float step_size = 0, bc2_sqrt = 1, b1 = 0, b2 = 0, eps = 0, one_minus_b1 = 0, one_minus_b2 = 0;
  float inv_bc2_sqrt = 1;  // RN(1 / bc2_sqrt), for divide_by_constant
};

// x / c, correctly rounded, for a divisor c fixed over many x: with inv_c = RN(1/c), the
// product q = RN(x·inv_c) is within an ulp of x/c, its remainder x − q·c is exact in an FMA, and
// one FMA correction gives RN(x/c) (Markstein's theorem), provided nothing overflows or
// underflows (x and x/c normal or 0; c normal). Adam divides √v by √(1 − β2^t) so: on these
// CPUs √v and the two divisions of an update share one unit and bound Adam even on data in
// cache, and two FMAs and a multiplication cost far less than a division. Checked against the
// division on every float significand for every divisor of β2 = 0.999's steps
// (tests/test_adam.cpp).
inline float divide_by_constant(float x, float c, float inv_c) {
  const float q = x * inv_c;
  return __builtin_fmaf(__builtin_fmaf(-q, c, x), inv_c, q);
}

// Learning rate used by step number `t` (1-based): lr·decay^(t−1).
double adam_lr(const AdamConfig& cfg, int64_t t);

// The scalars of step number `t` (1-based), whatever the state: models trained one after another
// (engine/epochs.h, run_model_epochs) each need step t's while another is at another step.
AdamStepScalars adam_step_scalars(const AdamConfig& cfg, int64_t t);

// Starts a step: counts it in `state` and returns its scalars.
AdamStepScalars adam_begin_step(const AdamConfig& cfg, AdamState& state);

// The element-wise update of one step on a range: p [n], g [n], m [n], v [n].
// One departure from PyTorch: a moment that falls below the smallest normal float (1.18e-38) is
// stored as 0. A zero gradient (SIRL's loss is exactly 0 from epoch ~107 on JacoRobot) decays m
// into that range within ~830 steps (0.9^k), and on Intel cores every arithmetic on a subnormal
// float takes a microcode assist (the Grid SIRL step ran about twice as slow with its moments
// subnormal: docs/kernels.md). m/denom with m subnormal and denom ≥ ε =
// 1e-8 moves p by < 1.2e-33, below half an ulp of any |p| > 1e-26, so the parameters keep PyTorch's
// bits. Updating a vector in pieces gives the same bits as one call over the whole (each element is
// independent): the fused backward pass (mlp_backward_adam) updates each slice of weights as soon
// as its gradient exists.
void adam_apply(const AdamStepScalars& s, float* p, const float* g, float* m, float* v, size_t n);

// The same update on a block of `rows` × `cols` elements of matrices stored by rows: p, m and v
// with row stride `ld`, g with `ldg` (a column slice of a layer's weights and its gradient
// scratch). One call instead of one per row: a GridRobot layer's 64-wide slices are 128 rows.
void adam_apply_rows(const AdamStepScalars& s, float* p, size_t ld, const float* g, size_t ldg,
                     float* m, float* v, size_t rows, size_t cols);

// One step over params [n] with gradient grad [n] (PyTorch's arithmetic, in float).
void adam_step(const AdamConfig& cfg, AdamState& state, float* params, const float* grad, size_t n);

}  // namespace sirl
