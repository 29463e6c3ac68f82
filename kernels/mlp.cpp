#include "kernels/mlp.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "kernels/bf16.h"
#include "kernels/gemm.h"
#include "kernels/gemm_bf16.h"
#include "kernels/product_plan.h"

namespace sirl {

void validate(const MlpShape& shape) {
  if (shape.widths.size() < 2)
    throw std::invalid_argument("MLP needs at least an input and an output width");
  for (int w : shape.widths)
    if (w < 1) throw std::invalid_argument("MLP width must be >= 1, got " + std::to_string(w));
  for (int l : shape.linear_layers)
    if (l < 0 || l + 1 >= shape.layers())
      throw std::invalid_argument("MLP linear_layers entry " + std::to_string(l) +
                                  " is not a hidden layer");
}

bool MlpShape::relu_after(int layer) const {
  if (layer + 1 == layers()) return relu_on_output;
  return std::find(linear_layers.begin(), linear_layers.end(), layer) == linear_layers.end();
}

size_t MlpShape::weight_offset(int layer) const {
  size_t off = 0;
  for (int l = 0; l < layer; ++l) off += size_t(widths[l]) * widths[l + 1] + widths[l + 1];
  return off;
}

size_t MlpShape::param_count() const {
  return weight_offset(layers());
}

double MlpShape::forward_flops(int batch) const {
  double f = 0;
  for (int l = 0; l < layers(); ++l) f += 2.0 * widths[l] * widths[l + 1];
  return f * batch;
}

namespace {

// The products of a layer in the shape's precision. fp32: gemm.h on the operands themselves.
// bf16 (bf16_products): each operand is rounded once into a bf16 copy, then gemm_bf16.h
// multiplies the copies. The forward pass keeps its copies of each layer's input and weights in
// the tape for the backward pass; ∂L/∂(pre-activation) is rounded into a scratch per thread (the
// batched training steps run models on OpenMP threads).

// The forward pass's bf16 copies of layer l's operands, which a bf16 backward pass needs.
const std::vector<uint16_t>& tape_copy(const std::vector<std::vector<uint16_t>>& copies, int l) {
  if (size_t(l) >= copies.size())
    throw std::logic_error("a bf16 backward pass needs the tape of a bf16 forward pass");
  return copies[l];
}

std::vector<uint16_t>& bf16_scratch() {
  thread_local std::vector<uint16_t> g;
  return g;
}
const uint16_t* bf16_copy(const float* x, size_t n, std::vector<uint16_t>& scratch) {
  scratch.resize(n);
  to_bf16_bits(x, scratch.data(), n);
  return scratch.data();
}
template <typename T>
void require_float(const MlpShape& s) {
  if (s.bf16_products && !std::is_same_v<T, float>)
    throw std::invalid_argument("bf16 products are for float networks only");
}

}  // namespace

template <typename T>
void mlp_forward(const MlpShape& s, const T* params, const T* x, int batch, MlpTape<T>& tape,
                 int threads) {
  require_float<T>(s);
  const int L = s.layers();
  tape.batch = batch;
  tape.input = x;
  tape.act.resize(L);
  if (!s.bf16_products) {  // no stale copies for a backward pass to pick up
    tape.in16.clear();
    tape.w16.clear();
  }
  const T* in = x;
  for (int l = 0; l < L; ++l) {
    const int ni = s.widths[l], no = s.widths[l + 1];
    auto& y = tape.act[l];
    y.resize(size_t(batch) * no);
    const T* W = params + s.weight_offset(l);  // [no, ni]
    const T* b = params + s.bias_offset(l);    // [no]
    // y [batch, no] = in [batch, ni] · Wᵀ
    bool bf16 = false;
    if constexpr (std::is_same_v<T, float>) {
      if ((bf16 = s.bf16_products)) {
        tape.in16.resize(L);
        tape.w16.resize(L);
        matmul_bf16_nt(y.data(), bf16_copy(in, size_t(batch) * ni, tape.in16[l]),
                       bf16_copy(W, size_t(no) * ni, tape.w16[l]), batch, no, ni, false, threads);
      }
    }
    if (!bf16) matmul_nt(y.data(), in, W, batch, no, ni, false, threads);
    const bool relu = s.relu_after(l);
    for (int r = 0; r < batch; ++r) {
      T* row = y.data() + size_t(r) * no;
      if (relu)
        for (int j = 0; j < no; ++j) row[j] = std::max(row[j] + b[j], T(0));
      else
        for (int j = 0; j < no; ++j) row[j] += b[j];
    }
    in = y.data();
  }
}

namespace {

// Both backward passes start alike: scratch for ∂L/∂(pre-activation), seeded with dout.
template <typename T>
void begin_backward(const MlpShape& s, MlpTape<T>& tape, const T* dout) {
  const int maxw = *std::max_element(s.widths.begin(), s.widths.end());
  tape.grad.resize(size_t(tape.batch) * maxw);
  tape.grad_next.resize(size_t(tape.batch) * maxw);
  std::copy(dout, dout + size_t(tape.batch) * s.out(), tape.grad.data());
}

// The ReLU mask of layer l on g [batch, no]: output > 0 ⇔ pre-activation > 0.
template <typename T>
void mask_relu(const MlpShape& s, int l, const MlpTape<T>& tape, T* g) {
  if (!s.relu_after(l)) return;
  const T* y = tape.act[l].data();
  for (size_t i = 0; i < size_t(tape.batch) * s.widths[l + 1]; ++i)
    if (y[i] <= T(0)) g[i] = T(0);
}

}  // namespace

template <typename T>
void mlp_backward(const MlpShape& s, const T* params, MlpTape<T>& tape,
                  const std::type_identity_t<T>* dout, std::type_identity_t<T>* dparams,
                  std::type_identity_t<T>* dx, int threads) {
  require_float<T>(s);
  const int L = s.layers(), batch = tape.batch;
  begin_backward<T>(s, tape, dout);  // g holds ∂L/∂(pre-activation) of layer l, [batch, no]
  for (int l = L - 1; l >= 0; --l) {
    const int ni = s.widths[l], no = s.widths[l + 1];
    T* g = tape.grad.data();
    mask_relu<T>(s, l, tape, g);
    const T* in = l == 0 ? tape.input : tape.act[l - 1].data();  // [batch, ni]
    T* dW = dparams + s.weight_offset(l);                        // [no, ni]
    T* db = dparams + s.bias_offset(l);                          // [no]
    const T* W = params + s.weight_offset(l);                    // [no, ni]
    T* d_in = l > 0 ? tape.grad_next.data() : dx;                // [batch, ni] or none
    // dW [no, ni] += gᵀ [no, batch] · in [batch, ni]
    // d_in [batch, ni] = g [batch, no] · W [no, ni]
    bool bf16 = false;
    if constexpr (std::is_same_v<T, float>) {
      if ((bf16 = s.bf16_products)) {
        const uint16_t* gh = bf16_copy(g, size_t(batch) * no, bf16_scratch());
        matmul_bf16_tn(dW, gh, tape_copy(tape.in16, l).data(), no, ni, batch, true, threads);
        if (d_in)
          matmul_bf16_nn(d_in, gh, tape_copy(tape.w16, l).data(), batch, ni, no, false, threads);
      }
    }
    if (!bf16) {
      matmul_tn(dW, g, in, no, ni, batch, true, threads);
      if (d_in) matmul_nn(d_in, g, W, batch, ni, no, false, threads);
    }
    for (int r = 0; r < batch; ++r)
      for (int j = 0; j < no; ++j) db[j] += g[size_t(r) * no + j];
    if (l > 0) std::swap(tape.grad, tape.grad_next);
  }
}

namespace {

// Layer l's ReLU mask on g [batch, no] (output > 0 ⇔ pre-activation > 0) and, in the same pass,
// db [no] = Σ_rows g, rows in order (the same values and order as mask_relu then mlp_backward's
// sum); then the biases' Adam update.
void mask_relu_and_step_bias(const MlpShape& s, int l, const MlpTape<float>& tape, float* g,
                             const AdamStepScalars& step, float* params, float* m, float* v) {
  const int batch = tape.batch, no = s.widths[l + 1];
  const size_t b_off = s.bias_offset(l);
  thread_local AlignedVector<float> db;
  db.assign(no, 0.f);
  const float* y = s.relu_after(l) ? tape.act[l].data() : nullptr;
  for (int r = 0; r < batch; ++r) {
    float* gr = g + size_t(r) * no;
    if (y) {
      const float* yr = y + size_t(r) * no;
      for (int j = 0; j < no; ++j) {
        gr[j] = yr[j] <= 0.f ? 0.f : gr[j];
        db[j] += gr[j];
      }
    } else {
      for (int j = 0; j < no; ++j) db[j] += gr[j];
    }
  }
  adam_apply(step, params + b_off, db.data(), m + b_off, v + b_off, no);
}

// Layer l's weights: ∂L/∂input into d_in [batch, ni] (if not null) from the weights before their
// update, and each part of W's gradient (a column slice or a block of rows) followed at once by
// that part's Adam update. g: [batch, no] ∂L/∂(pre-activation), masked.
void step_layer_weights(const MlpShape& s, int l, MlpTape<float>& tape, float* g, float* d_in,
                        const AdamStepScalars& step, float* params, float* m, float* v,
                        int threads) {
  const int batch = tape.batch, ni = s.widths[l], no = s.widths[l + 1];
  const float* in = l == 0 ? tape.input : tape.act[l - 1].data();  // [batch, ni]
  const size_t w_off = s.weight_offset(l);
  float* W = params + w_off;  // [no, ni]
  // The products' operands; with bf16_products, bf16 copies: g's rounded now, the input's and
  // W's from the forward pass (taken before any slice updates W, as ∂L/∂input needs the old
  // weights).
  const bool h = s.bf16_products;
  const uint16_t* gh = h ? bf16_copy(g, size_t(batch) * no, bf16_scratch()) : nullptr;
  const uint16_t* inh = h ? tape_copy(tape.in16, l).data() : nullptr;
  const uint16_t* Wh = h ? tape_copy(tape.w16, l).data() : nullptr;
  // The weight gradient's parts (column slices or blocks of rows) and ∂L/∂input's.
  const ProductPlan dw = plan_product(Product::tn, no, ni, batch, threads, h);
  const ProductPlan dx = plan_product(Product::nn, batch, ni, no, 1, h);
  const int width = dw.column_slice, slices = (ni + width - 1) / width;
  const auto slice = [&](int p) {
    const int j0 = p * width, nj = std::min(width, ni - j0);
    // d_in[:, j0..] [batch, nj] = g [batch, no] · W[:, j0..] [no, nj], with W before its update
    if (d_in && h) matmul_bf16_nn_cols(d_in + j0, ni, gh, Wh, batch, ni, no, false, j0, nj);
    if (d_in && !h) matmul_nn_cols(d_in + j0, ni, g, W, batch, ni, no, false, j0, nj);
    // dW[:, j0..] [no, nj] = gᵀ [no, batch] · in[:, j0..] [batch, nj], written over a scratch
    // (not added to a zeroed one: the same values but for the sign of a zero sum, which Adam's
    // m = β1·m + (1−β1)·g and v = β2·v + (1−β2)·g² cannot tell from m = v = +0 on)
    thread_local AlignedVector<float> dw;
    dw.resize(size_t(no) * nj);
    if (h)
      matmul_bf16_tn_cols(dw.data(), nj, gh, inh, no, ni, batch, false, j0, nj);
    else
      matmul_tn_cols(dw.data(), nj, g, in, no, ni, batch, false, j0, nj);
    // W[:, j0..] (row stride ni) with its scratch gradient [no, nj]
    adam_apply_rows(step, W + j0, ni, dw.data(), nj, m + w_off + j0, v + w_off + j0, no, nj);
  };
  // A weight gradient that goes by blocks of W's rows (kernels/product_plan.h): ∂L/∂input
  // first, whole, from the old W, then each block: its gradient and its Adam update.
  const int row_block = dw.row_block;
  // On one thread, where ∂L/∂input is a sum over the same blocks (its inner dimension is W's
  // rows), it goes block by block too, each block of W read once, before its update. With more
  // threads the blocks run at once, and ∂L/∂input comes first.
  const bool d_in_by_blocks = row_block && d_in && threads <= 1 && dx.k_block == row_block;
  const auto rows = [&](int p) {
    const int i0 = p * row_block, mi = std::min(row_block, no - i0);
    // d_in [batch, ni] (+)= g[:, i0..] [batch, mi] · W[i0.., :] [mi, ni], W before its update
    if (d_in_by_blocks) matmul_nn_k_block(d_in, g, W, batch, ni, no, p > 0, i0, mi);
    thread_local AlignedVector<float> dw;
    dw.resize(size_t(mi) * ni);  // written over, as the slices' scratch above
    if (h)
      matmul_bf16_tn_rows(dw.data(), gh, inh, no, ni, batch, false, i0, mi);
    else
      matmul_tn_rows(dw.data(), g, in, no, ni, batch, false, i0, mi);
    const size_t at = w_off + size_t(i0) * ni;
    adam_apply(step, params + at, dw.data(), m + at, v + at, size_t(mi) * ni);
  };
  const int blocks = row_block ? (no + row_block - 1) / row_block : 0;
  // (No OpenMP region at all on one thread: even a serialised one costs microseconds, and a
  // TPA step of 20 small heads runs 60 of these loops.)
  if (row_block && d_in && !d_in_by_blocks) {
    if (h)
      matmul_bf16_nn(d_in, gh, Wh, batch, ni, no, false, threads);
    else
      matmul_nn(d_in, g, W, batch, ni, no, false, threads);
  }
  const int parts = row_block ? blocks : slices;
  const auto part = [&](int p) { row_block ? rows(p) : slice(p); };
  if (threads > 1 && parts > 1) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int p = 0; p < parts; ++p) part(p);
  } else {
    for (int p = 0; p < parts; ++p) part(p);
  }
}

}  // namespace

void mlp_backward_adam(const MlpShape& s, float* params, MlpTape<float>& tape, const float* dout,
                       const AdamStepScalars& step, float* m, float* v, int threads, float* dx) {
  begin_backward<float>(s, tape, dout);
  for (int l = s.layers() - 1; l >= 0; --l) {
    float* g = tape.grad.data();  // [batch, no] ∂L/∂(pre-activation)
    mask_relu_and_step_bias(s, l, tape, g, step, params, m, v);
    float* d_in = l > 0 ? tape.grad_next.data() : dx;  // [batch, ni]
    step_layer_weights(s, l, tape, g, d_in, step, params, m, v, threads);
    if (l > 0) std::swap(tape.grad, tape.grad_next);
  }
}

void mlp_init(const MlpShape& s, float* params, Rng& rng) {
  validate(s);
  for (int l = 0; l < s.layers(); ++l) {
    const int ni = s.widths[l], no = s.widths[l + 1];
    const double bound = 1.0 / std::sqrt(double(ni));
    float* W = params + s.weight_offset(l);
    for (size_t i = 0; i < size_t(no) * ni; ++i) W[i] = float(rng.uniform(-bound, bound));
    float* b = params + s.bias_offset(l);
    for (int j = 0; j < no; ++j) b[j] = float(rng.uniform(-bound, bound));
  }
}

#define SIRL_INSTANTIATE(T)                                                                 \
  template void mlp_forward<T>(const MlpShape&, const T*, const T*, int, MlpTape<T>&, int); \
  template void mlp_backward<T>(const MlpShape&, const T*, MlpTape<T>&, const T*, T*, T*, int);
SIRL_INSTANTIATE(float)
SIRL_INSTANTIATE(double)
#undef SIRL_INSTANTIATE

}  // namespace sirl
