// How a matrix product is cut into parts, decided once from its shape, its precision and (for the
// fused backward pass's walk over a layer's weights) the thread count. The MLP's passes iterate a
// plan's parts with the kernels' part forms (gemm.h: *_cols, *_rows, matmul_nn_k_block; their
// bf16 twins in gemm_bf16.h), and the whole-product kernels compute by the same parts, so a
// product has the same bits whichever way it is walked.
#pragma once

namespace sirl {

// C[M,N] (+)= A·Bᵀ (nt: the forward pass, Y = X Wᵀ), Aᵀ·B (tn: a weight gradient, dW = dYᵀ X),
// A·B (nn: ∂L/∂input, dX = dY W).
enum class Product { nt, tn, nn };

struct ProductPlan {
  // C's columns in fixed slices [j0, j0 + column_slice): the parts of every product that has no
  // other cut, whatever the thread count.
  int column_slice = 0;
  // tn: > 0 where C (a weight gradient, M units × N inputs) goes by blocks of this many rows,
  // all N columns at once, so that a block's weights and Adam moments are read contiguously.
  int row_block = 0;
  // nn (fp32): > 0 where the product is the sum over blocks of this many of the inner dimension
  // (a layer's units), one after the other, so a caller may compute it block by block
  // (matmul_nn_k_block): the fused backward pass does, on one thread, while it updates the same
  // blocks of weight rows (k_block is then the weight gradient's row_block).
  int k_block = 0;
};

ProductPlan plan_product(Product op, int M, int N, int K, int threads = 1, bool bf16 = false);

}  // namespace sirl
