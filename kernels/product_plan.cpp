#include "kernels/product_plan.h"

#include "kernels/gemm.h"
#include "kernels/gemm_bf16.h"
#include "kernels/gemm_blocking.h"

namespace sirl {

ProductPlan plan_product(Product op, int M, int N, int K, int threads, bool bf16) {
  ProductPlan p;
  p.column_slice = gemm_column_slice(N);
  if (op == Product::tn)
    p.row_block = bf16 ? gemm_bf16_weight_row_block(M, N, K, threads)
                       : gemm_weight_row_block(M, N, K, threads);
  if (op == Product::nn && !bf16 && gemm_nn_by_k_blocks(M, N, K))
    p.k_block = gemm_weight_row_block(K, N, M);
  return p;
}

}  // namespace sirl
