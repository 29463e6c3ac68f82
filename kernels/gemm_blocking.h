// The blocking rules of the matrix products (gemm.h, gemm_bf16.h): how each product is cut,
// from its shape alone (and, for the fused backward pass's walk over weight rows, the thread
// count), so that its bits never depend on the thread count or on which part form computes it.
// Code outside the kernels reads them through plan_product (kernels/product_plan.h).
#pragma once

namespace sirl {

// Every product without another cut below computes C's N columns in fixed slices [j0, j0 + nj),
// j0 = 0, w, 2w, …, with w = gemm_column_slice(N), whatever the thread count (the *_cols forms
// compute one).
int gemm_column_slice(int N);

// A float product oneDNN serves (two dimensions ≥ 512, none below 32) runs on its dense kernels
// in blocks of C's rows, all N columns at once: gemm_row_block(M, N, K) is the block height (fixed
// by the shape), 0 for a product that goes by column slices. matmul_nt and matmul_tn do so block
// by block (matmul_nn keeps column slices), and matmul_tn does so for a big layer libxsmm serves
// too (gemm_weight_row_block); matmul_tn_rows computes one block.
int gemm_row_block(int M, int N, int K);

// The fused backward pass's block of weight rows for a weight gradient dW[M,N] = A[K,M]ᵀ·B[K,N]
// (M units, N inputs, K batch rows): gemm_row_block's where oneDNN serves the product; for a big
// layer libxsmm serves (≥ 256 Ki weights, few batch rows: a TPA cell of M = 10 trains on 20),
// blocks of ~64 Ki weights, so that a block's weights, Adam moments and gradient stay in cache and
// are read contiguously (column slices of a 1024 × 2037 layer read its rows 1 KiB at a time, and
// Adam ran at half speed on them); for a layer of 4 Ki to 256 Ki weights on one thread, blocks of
// 256 rows (Adam over whole rows); 0 where it goes by column slices. matmul_tn computes a big
// layer's gradient by these blocks too, so both have the same bits.
int gemm_weight_row_block(int M, int N, int K, int threads = 1);

// Where gemm_nn_by_k_blocks(M, N, K) (∂L/∂input of a big layer libxsmm serves), matmul_nn sums
// over blocks kn = gemm_weight_row_block(K, N, M) of its inner dimension, one after the other
// (matmul_nn_k_block computes one), so the fused backward pass can compute ∂L/∂input block by
// block while it updates the same blocks of weight rows, reading each once, with matmul_nn's bits.
bool gemm_nn_by_k_blocks(int M, int N, int K);
// (bf16 products: gemm_bf16_weight_row_block in gemm_bf16.h.)

}  // namespace sirl
