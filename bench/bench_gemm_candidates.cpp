// The GEMM libraries a user would reach for, on the engine's own shapes, one thread:
//   eigen   kernels/gemm.h as the engine runs it (Eigen 3.4's GEMM in fixed column slices)
//   xsmm    libxsmm 1.17 JIT small-matrix kernels (libxsmm_smmdispatch), dispatched once
//   dnnl    oneDNN 2.6 matmul primitive (strides express the transposes), created once
//   dnnl_bf16  the same primitive on bf16 operands with fp32 output (vdpbf16ps where the CPU has
//           AVX512-BF16); each iteration also rounds both fp32 operands to bf16 (to_bf16_bits),
//           as a training step must: its weights change at every step
// Every op of one dense layer with `rows` inputs, `in` features and `out` units:
//   fwd  Y[rows,out]  = X[rows,in] · W[out,in]ᵀ    (nt)
//   dx   dX[rows,in]  = dY[rows,out] · W[out,in]  (nn)
//   dw   dW[out,in]   = dY[rows,out]ᵀ · X[rows,in] (tn)
// 2·rows·in·out FLOP each. Shapes: GridRobot's SIRL φ (19→128→128→6, 64 triplets = 192 rows),
// JacoRobot's (2037→1024→1024→6), the TPA heads (6→128→128→1, 64 pairs = 128 rows).
#include <benchmark/benchmark.h>
#include <libxsmm.h>

#include <omp.h>

#include <dnnl.hpp>
#include <random>
#include <string>
#include <vector>

#include "kernels/bf16.h"
#include "kernels/gemm.h"

namespace {

enum Op { kFwd, kDx, kDw };
enum Lib { kEigen, kXsmm, kDnnl, kDnnlBf16 };
const char* kOpName[] = {"fwd", "dx", "dw"};
const char* kLibName[] = {"eigen", "xsmm", "dnnl", "dnnl_bf16"};

// A product C[M,N] = op(A) · op(B) in row-major terms, with its operands' storage.
struct Product {
  int M, N, K;
  bool ta, tb;  // A stored [K,M] / B stored [N,K]
};

Product product(Op op, int rows, int in, int out) {
  switch (op) {
    case kFwd:
      return {rows, out, in, false, true};
    case kDx:
      return {rows, in, out, false, false};
    default:
      return {out, in, rows, true, false};
  }
}

std::vector<float> random_vec(size_t n, unsigned seed) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::vector<float> v(n);
  for (auto& x : v) x = u(g);
  return v;
}

void BM_Gemm(benchmark::State& state) {
  const Lib lib = Lib(state.range(0));
  const Op op = Op(state.range(1));
  const int rows = int(state.range(2)), in = int(state.range(3)), out = int(state.range(4));
  const Product p = product(op, rows, in, out);
  const std::vector<float> A = random_vec(size_t(p.M) * p.K, 1),
                           B = random_vec(size_t(p.N) * p.K, 2);
  std::vector<float> C(size_t(p.M) * p.N);
  const std::string label = std::string(kLibName[lib]) + " " + kOpName[op];
  state.SetLabel(label);

  if (lib == kEigen) {
    for (auto _ : state) {
      if (op == kFwd) sirl::matmul_nt(C.data(), A.data(), B.data(), p.M, p.N, p.K, false, 1);
      if (op == kDx) sirl::matmul_nn(C.data(), A.data(), B.data(), p.M, p.N, p.K, false, 1);
      if (op == kDw) sirl::matmul_tn(C.data(), A.data(), B.data(), p.M, p.N, p.K, false, 1);
      benchmark::ClobberMemory();
    }
  } else if (lib == kXsmm) {
    // Column-major view: Cᶜ[N,M] = op(Bᶜ) · op(Aᶜ), so the row-major B is libxsmm's A.
    const libxsmm_blasint m = p.N, n = p.M, k = p.K;
    const libxsmm_blasint lda = p.tb ? p.K : p.N, ldb = p.ta ? p.M : p.K, ldc = p.N;
    const float alpha = 1, beta = 0;
    const int flags =
        (p.tb ? LIBXSMM_GEMM_FLAG_TRANS_A : 0) | (p.ta ? LIBXSMM_GEMM_FLAG_TRANS_B : 0);
    const libxsmm_smmfunction kernel =
        libxsmm_smmdispatch(m, n, k, &lda, &ldb, &ldc, &alpha, &beta, &flags, nullptr);
    if (!kernel) {
      state.SkipWithError("libxsmm has no kernel for this shape/transpose");
      return;
    }
    for (auto _ : state) {
      kernel(B.data(), A.data(), C.data());
      benchmark::ClobberMemory();
    }
  } else {
    using dt = dnnl::memory::data_type;
    const dt in_t = lib == kDnnlBf16 ? dt::bf16 : dt::f32;
    dnnl::engine eng(dnnl::engine::kind::cpu, 0);
    dnnl::stream strm(eng);
    const dnnl::memory::desc a_md({p.M, p.K}, in_t,
                                  p.ta ? dnnl::memory::dims{1, p.M} : dnnl::memory::dims{p.K, 1});
    const dnnl::memory::desc b_md({p.K, p.N}, in_t,
                                  p.tb ? dnnl::memory::dims{1, p.K} : dnnl::memory::dims{p.N, 1});
    const dnnl::memory::desc c_md({p.M, p.N}, dt::f32, dnnl::memory::dims{p.N, 1});
    const dnnl::matmul::primitive_desc pd(dnnl::matmul::desc(a_md, b_md, c_md), eng);
    const dnnl::matmul prim(pd);
    std::vector<uint16_t> A16(A.size()), B16(B.size());
    const bool bf16 = lib == kDnnlBf16;
    dnnl::memory a(a_md, eng, bf16 ? static_cast<void*>(A16.data()) : (void*)A.data()),
        b(b_md, eng, bf16 ? static_cast<void*>(B16.data()) : (void*)B.data()),
        c(c_md, eng, C.data());
    state.SetLabel(label + " " + pd.impl_info_str());
    for (auto _ : state) {
      if (bf16) {
        sirl::to_bf16_bits(A.data(), A16.data(), A.size());
        sirl::to_bf16_bits(B.data(), B16.data(), B.size());
      }
      prim.execute(strm, {{DNNL_ARG_SRC, a}, {DNNL_ARG_WEIGHTS, b}, {DNNL_ARG_DST, c}});
      strm.wait();
      benchmark::ClobberMemory();
    }
  }
  state.counters["GFLOP/s"] = benchmark::Counter(2.0 * p.M * p.N * p.K * 1e-9,
                                                 benchmark::Counter::kIsIterationInvariantRate);
}

void shapes(benchmark::internal::Benchmark* b) {
  const int layers[][3] = {
      {192, 19, 128},    {192, 128, 128},   {192, 128, 6},   // GridRobot φ
      {192, 2037, 1024}, {192, 1024, 1024}, {192, 1024, 6},  // JacoRobot φ
      {128, 6, 128},     {128, 128, 128},   {128, 128, 1},   // a TPA head
      {128, 2037, 1024}, {128, 1024, 1024},  // an unfrozen JacoRobot TPA head, 64 pairs
  };
  for (const auto& l : layers)
    for (int op = 0; op < 3; ++op)
      for (int lib = 0; lib < 4; ++lib) b->Args({lib, op, l[0], l[1], l[2]});
  b->ArgNames({"lib", "op", "rows", "in", "out"});
}

}  // namespace

BENCHMARK(BM_Gemm)->Apply(shapes)->UseRealTime();

int main(int argc, char** argv) {
  // One core: oneDNN's OpenMP threads would blur it (libgomp has read OMP_NUM_THREADS already).
  omp_set_num_threads(1);
  libxsmm_init();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  libxsmm_finalize();
  return 0;
}
