// Multi-layer perceptron: Linear (+ReLU) stacks of any widths, forward and backward over a
// batch, llm.c style. All parameters of one model live in one flat buffer:
//   for each layer l: W_l [out_l, in_l] row-major (PyTorch's nn.Linear layout), then b_l [out_l].
// Activations are row-major [batch, width]: one sample per row.
// Templated on the scalar so gradient checks can run the very same code in double.
#pragma once
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "kernels/adam.h"
#include "kernels/aligned_vector.h"
#include "kernels/rng.h"

namespace sirl {

struct MlpShape {
  std::vector<int> widths;      // [in, hidden..., out], at least two entries
  bool relu_on_output = false;  // ReLU after the last Linear too (default: linear output)
  // Hidden layers whose output skips the ReLU. Used when φ (linear output) and a reward head are
  // stacked into one network for unfrozen training: the embedding layer stays linear.
  std::vector<int> linear_layers;
  // Precision "bf16": every matrix product (forward, ∂L/∂input, ∂L/∂W) takes bf16-rounded
  // operands and accumulates in fp32 (kernels/bf16.h); weights, biases, activations, gradients
  // and Adam's state stay fp32. Float only (the double instantiations refuse it).
  bool bf16_products = false;
  bool relu_after(int layer) const;

  int layers() const { return static_cast<int>(widths.size()) - 1; }
  int in() const { return widths.front(); }
  int out() const { return widths.back(); }
  size_t param_count() const;
  size_t weight_offset(int layer) const;
  size_t bias_offset(int layer) const {
    return weight_offset(layer) + size_t(widths[layer]) * widths[layer + 1];
  }
  // 2·in·out multiply-adds per layer per sample (biases and ReLU not counted).
  double forward_flops(int batch) const;
  // Training: forward + backward ≈ 3× the forward pass (the backward pass runs two products per
  // layer). The engine's counters and the planner's estimates both count with these.
  double train_flops(int batch) const { return 3 * forward_flops(batch); }  // one step
  double train_flops(int64_t rows_per_epoch, int epochs) const {
    return 3.0 * forward_flops(1) * double(rows_per_epoch) * epochs;
  }
};

// Throws std::invalid_argument on fewer than two widths or a width < 1.
void validate(const MlpShape& shape);

// What one forward pass keeps for its backward pass.
template <typename T>
struct MlpTape {
  int batch = 0;
  const T* input = nullptr;           // [batch, in], not owned: must outlive the backward call
  std::vector<AlignedVector<T>> act;  // act[l]: [batch, widths[l+1]] output of layer l (post-ReLU)
  AlignedVector<T> grad, grad_next;   // backward scratch, [batch, max width]
  // With bf16_products, the forward pass's bf16 operands of layer l: its input [batch, ni] and
  // its weights [no, ni], which the backward pass's products reuse (the weights are the ones the
  // forward pass saw, as the gradient of that pass must).
  std::vector<std::vector<uint16_t>> in16, w16;
  const T* output() const { return act.back().data(); }
  T* output() { return act.back().data(); }
};

// x [batch, in] → tape.output() [batch, out].
template <typename T>
void mlp_forward(const MlpShape& shape, const T* params, const T* x, int batch, MlpTape<T>& tape,
                 int threads = 1);

// dout [batch, out] = ∂L/∂output. Adds ∂L/∂params into dparams [P] (accumulates: zero it first
// for a fresh gradient). Writes ∂L/∂x into dx [batch, in] when dx is not null.
template <typename T>
void mlp_backward(const MlpShape& shape, const T* params, MlpTape<T>& tape,
                  const std::type_identity_t<T>* dout, std::type_identity_t<T>* dparams,
                  std::type_identity_t<T>* dx, int threads = 1);

// The backward pass fused with the optimizer step: dout [batch, out] = ∂L/∂output, and every
// weight and bias is updated by Adam (scalars `step` of adam_begin_step; moments m [P], v [P])
// as soon as its gradient exists, one fixed column slice of a layer's weights at a time (the
// slices of its product plan, kernels/product_plan.h), after that slice has served the layer's
// ∂L/∂input. The whole gradient is never stored: for networks larger than the cache this saves
// writing, zeroing and re-reading a gradient buffer as large as the weights every step. The result
// is bit-identical to mlp_backward into a zeroed gradient followed by adam_apply over [P] (a test
// checks it), for any thread count. dx [batch, in], when not null, receives ∂L/∂x (from the weights
// before the update, as mlp_backward's).
void mlp_backward_adam(const MlpShape& shape, float* params, MlpTape<float>& tape,
                       const float* dout, const AdamStepScalars& step, float* m, float* v,
                       int threads = 1, float* dx = nullptr);

// PyTorch's nn.Linear default: W ~ U(±1/√fan_in) (Kaiming-uniform with a = √5), b ~ U(±1/√fan_in).
// Draws layer by layer, W row-major then b, from `rng`.
void mlp_init(const MlpShape& shape, float* params, Rng& rng);

}  // namespace sirl
