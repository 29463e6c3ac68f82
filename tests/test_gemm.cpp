// The three row-major products (kernels/gemm.h) against a double-precision loop, on the engine's
// shapes and on ones that exercise every edge of the blocking: N not a multiple of the 64/256
// column slices, M above the 256-row blocks, K from 1 to 2037, accumulate on and off, 1 and 2
// threads. Runs on whichever backend this process uses (libxsmm, or Eigen under
// SIRL_KERNELS=generic: ctest runs both). A wrong leading dimension, a swapped transpose, a
// dropped row block or a lost `accumulate` puts errors of order 1 in C, far above the tolerance
// (float rounding over K terms of size ~1: 1e-5·√K relative to Σ|a·b|).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "kernels/aligned_vector.h"
#include "kernels/gemm.h"
#include "kernels/gemm_blocking.h"
#include "kernels/rng.h"

namespace sirl {
namespace {

enum Op { kNT, kTN, kNN };

struct Case {
  int M, N, K;
};

void check(Op op, Case c, bool accumulate, int threads) {
  Rng rng(uint64_t(c.M * 7919 + c.N * 31 + c.K + op));
  std::vector<float> A(size_t(c.M) * c.K), B(size_t(c.N) * c.K), C(size_t(c.M) * c.N);
  for (auto& x : A) x = float(rng.uniform(-1, 1));
  for (auto& x : B) x = float(rng.uniform(-1, 1));
  for (auto& x : C) x = float(rng.uniform(-1, 1));
  const std::vector<float> C0 = C;
  // Storage: nt A[M,K] B[N,K]; tn A[K,M] B[K,N]; nn A[M,K] B[K,N].
  auto a = [&](int i, int k) {
    return double(op == kTN ? A[size_t(k) * c.M + i] : A[size_t(i) * c.K + k]);
  };
  auto b = [&](int k, int j) {
    return double(op == kNT ? B[size_t(j) * c.K + k] : B[size_t(k) * c.N + j]);
  };
  if (op == kNT) matmul_nt(C.data(), A.data(), B.data(), c.M, c.N, c.K, accumulate, threads);
  if (op == kTN) matmul_tn(C.data(), A.data(), B.data(), c.M, c.N, c.K, accumulate, threads);
  if (op == kNN) matmul_nn(C.data(), A.data(), B.data(), c.M, c.N, c.K, accumulate, threads);
  int bad = 0;
  for (int i = 0; i < c.M; ++i)
    for (int j = 0; j < c.N; ++j) {
      double s = accumulate ? C0[size_t(i) * c.N + j] : 0.0, mag = std::abs(s);
      for (int k = 0; k < c.K; ++k) s += a(i, k) * b(k, j), mag += std::abs(a(i, k) * b(k, j));
      const double got = C[size_t(i) * c.N + j];
      if (std::abs(got - s) > 1e-5 * std::sqrt(double(c.K)) * (mag + 1e-30) && bad++ < 3)
        ADD_FAILURE() << "op " << op << " M" << c.M << " N" << c.N << " K" << c.K << " acc "
                      << accumulate << " threads " << threads << ": C[" << i << "," << j
                      << "] = " << got << ", expected " << s;
    }
  EXPECT_EQ(bad, 0);
}

TEST(Gemm, MatchesADoubleReferenceOnEveryEdgeOfTheBlocking) {
  RecordProperty("backend", gemm_backend());
  const Case cases[] = {
      {192, 128, 19},
      {192, 6, 128},
      {128, 1, 128},
      {128, 128, 6},  // the engine's layers
      {300, 130, 7},
      {257, 65, 33},
      {5, 300, 1},
      {1, 1, 1},        // blocking edges
      {192, 64, 2037},  // a long K
      {10, 128, 128},
      {20, 300, 700},  // nt transposing A
      {64, 520, 600},  // oneDNN's (two dimensions >= 512, none below 32), a ragged last slice
      // a big layer libxsmm serves, by blocks of weight rows: its weight gradient (700 units ×
      // 400 inputs, 20 rows: tn by row blocks of 163) and its ∂L/∂input (nn summed over k-blocks)
      {700, 400, 20},
      {20, 400, 700},
  };
  for (const Case& c : cases)
    for (Op op : {kNT, kTN, kNN})
      for (bool acc : {false, true}) check(op, c, acc, c.N > 64 ? 2 : 1);
}

// matmul_nt transposes whichever operand is smaller (A for a few rows through a wide layer, else
// the slice of B); both must give the bits of matmul_nn on an explicitly transposed B, so that a
// forward pass computes the same numbers whatever the batch and layer sizes. (Products oneDNN
// serves, two dimensions ≥ 512, are left out: its sgemm reads a transposed B with other kernels,
// and on Zen 5's AVX-512 those sum in another order — 192 × 1024 × 2037 differed in the last bit.)
TEST(Gemm, NtGivesTheBitsOfNnOnTheTransposedMatrix) {
  for (const Case c :
       {Case{10, 128, 128}, Case{64, 128, 128}, Case{20, 1024, 2037}, Case{40, 300, 2037},
        Case{250, 200, 300}, Case{7, 6, 128}, Case{300, 130, 7}}) {
    Rng rng(uint64_t(c.M + c.N + c.K));
    std::vector<float> A(size_t(c.M) * c.K), B(size_t(c.N) * c.K), Bt(B.size());
    for (auto& x : A) x = float(rng.uniform(-1, 1));
    for (auto& x : B) x = float(rng.uniform(-1, 1));
    for (int j = 0; j < c.N; ++j)
      for (int k = 0; k < c.K; ++k) Bt[size_t(k) * c.N + j] = B[size_t(j) * c.K + k];
    std::vector<float> nt(size_t(c.M) * c.N), nn(nt.size());
    matmul_nt(nt.data(), A.data(), B.data(), c.M, c.N, c.K, false, 1);
    matmul_nn(nn.data(), A.data(), Bt.data(), c.M, c.N, c.K, false, 1);
    EXPECT_EQ(nt, nn) << "M" << c.M << " N" << c.N << " K" << c.K << " on " << gemm_backend();
  }
}

// The products oneDNN serves (two dimensions ≥ 512) give the same bits on 1 and 2 threads:
// 300 rows (the forward product's two row blocks) and 32 rows through JacoRobot's first layer
// (a VAE or preference batch: the forward product in column blocks, the last one ragged),
// written and accumulated.
TEST(Gemm, BigProductsAreTheSameBitsOnOneAndTwoThreads) {
  for (const Case c : {Case{300, 1024, 700}, Case{32, 1100, 2037}})
    for (bool acc : {false, true}) {
      const int M = c.M, N = c.N, K = c.K;
      Rng rng(9);
      std::vector<float> A(size_t(M) * K), B(size_t(N) * K), C0(size_t(M) * N);
      for (auto& x : A) x = float(rng.uniform(-1, 1));
      for (auto& x : B) x = float(rng.uniform(-1, 1));
      for (auto& x : C0) x = float(rng.uniform(-1, 1));
      std::vector<float> one_nt, one_nn, one_tn;
      for (int threads : {1, 2}) {
        std::vector<float> nt = C0, nn = C0, tn = C0;
        matmul_nt(nt.data(), A.data(), B.data(), M, N, K, acc, threads);  // B as [N, K]
        matmul_nn(nn.data(), A.data(), B.data(), M, N, K, acc, threads);  // B as [K, N]
        matmul_tn(tn.data(), A.data(), B.data(), M, N, K, acc, threads);  // A as [K, M]
        if (threads == 1) {
          one_nt = nt, one_nn = nn, one_tn = tn;
        } else {
          EXPECT_EQ(nt, one_nt) << "M" << M << " acc " << acc;
          EXPECT_EQ(nn, one_nn) << "M" << M << " acc " << acc;
          EXPECT_EQ(tn, one_tn) << "M" << M << " acc " << acc;
        }
      }
    }
}

// The engine keeps activations and scratch 64-byte aligned for speed (kernels/aligned_vector.h);
// the bits must not depend on it. Each product, with every operand and C shifted by 0, 1, 5 and
// 15 floats from a cache line, gives the bits of the aligned call: a Grid layer (libxsmm), a
// 20-row JacoRobot layer (libxsmm, 256-wide slices) and a product oneDNN serves.
TEST(Gemm, ProductsAreTheSameBitsWhereverTheOperandsStart) {
  for (const Case c : {Case{192, 128, 128}, Case{20, 300, 2037}, Case{64, 520, 600}})
    for (Op op : {kNT, kTN, kNN})
      for (bool acc : {false, true}) {
        const size_t a_n = size_t(c.M) * c.K, b_n = size_t(c.N) * c.K, c_n = size_t(c.M) * c.N;
        Rng rng(uint64_t(c.M + op));
        std::vector<float> A(a_n), B(b_n), C0(c_n);
        for (auto& x : A) x = float(rng.uniform(-1, 1));
        for (auto& x : B) x = float(rng.uniform(-1, 1));
        for (auto& x : C0) x = float(rng.uniform(-1, 1));
        std::vector<float> first;
        for (int shift : {0, 1, 5, 15}) {
          AlignedVector<float> a(a_n + shift), b(b_n + shift), out(c_n + shift);
          std::copy(A.begin(), A.end(), a.begin() + shift);
          std::copy(B.begin(), B.end(), b.begin() + shift);
          std::copy(C0.begin(), C0.end(), out.begin() + shift);
          float *pa = a.data() + shift, *pb = b.data() + shift, *pc = out.data() + shift;
          if (op == kNT) matmul_nt(pc, pa, pb, c.M, c.N, c.K, acc, 1);
          if (op == kTN) matmul_tn(pc, pa, pb, c.M, c.N, c.K, acc, 1);
          if (op == kNN) matmul_nn(pc, pa, pb, c.M, c.N, c.K, acc, 1);
          std::vector<float> got(pc, pc + c_n);
          if (shift == 0)
            first = got;
          else
            EXPECT_EQ(got, first) << "op " << op << " M" << c.M << " N" << c.N << " K" << c.K
                                  << " acc " << acc << " shifted by " << shift;
        }
      }
}

// gemm.h's promise for the *_cols forms: where a product goes by column slices, each slice,
// written in place (ldc = N) or into a compact scratch (ldc = nj), has the bits of that slice of
// the whole product; written and accumulated. All three on a Grid layer and two 20-row JacoRobot
// layers (the second a big one, whose ∂L/∂input matmul_nn sums over k-blocks); ∂L/∂input alone
// where the forward and weight-gradient products go by row blocks instead (a big layer's weight
// gradient, oneDNN's products).
TEST(Gemm, ColumnSlicesGiveTheWholeProductsBits) {
  struct Sliced {
    Case c;
    std::vector<Op> ops;
  };
  const std::vector<Op> all{kNT, kTN, kNN};
  for (const Sliced& sliced :
       {Sliced{{192, 128, 19}, all}, Sliced{{20, 1024, 300}, all}, Sliced{{20, 400, 700}, all},
        Sliced{{700, 400, 20}, {kNN}}, Sliced{{64, 520, 600}, {kNN}}})
    for (Op op : sliced.ops)
      for (bool acc : {false, true}) {
        const Case c = sliced.c;
        Rng rng(uint64_t(c.N + op));
        std::vector<float> A(size_t(c.M) * c.K), B(size_t(c.N) * c.K), C0(size_t(c.M) * c.N);
        for (auto& x : A) x = float(rng.uniform(-1, 1));
        for (auto& x : B) x = float(rng.uniform(-1, 1));
        for (auto& x : C0) x = float(rng.uniform(-1, 1));
        std::vector<float> whole = C0, in_place = C0, compact = C0;
        const auto product = [&](float* C, const std::vector<float>& a) {
          if (op == kNT) matmul_nt(C, a.data(), B.data(), c.M, c.N, c.K, acc, 1);
          if (op == kTN) matmul_tn(C, a.data(), B.data(), c.M, c.N, c.K, acc, 1);
          if (op == kNN) matmul_nn(C, a.data(), B.data(), c.M, c.N, c.K, acc, 1);
        };
        product(whole.data(), A);
        const int w = gemm_column_slice(c.N);
        for (int j0 = 0; j0 < c.N; j0 += w) {
          const int nj = std::min(w, c.N - j0);
          std::vector<float> s(size_t(c.M) * nj);
          for (int i = 0; i < c.M; ++i)
            for (int j = 0; j < nj; ++j) s[size_t(i) * nj + j] = C0[size_t(i) * c.N + j0 + j];
          const auto cols = [&](float* Cs, int ldc) {
            if (op == kNT) matmul_nt_cols(Cs, ldc, A.data(), B.data(), c.M, c.N, c.K, acc, j0, nj);
            if (op == kTN) matmul_tn_cols(Cs, ldc, A.data(), B.data(), c.M, c.N, c.K, acc, j0, nj);
            if (op == kNN) matmul_nn_cols(Cs, ldc, A.data(), B.data(), c.M, c.N, c.K, acc, j0, nj);
          };
          cols(in_place.data() + j0, c.N);
          cols(s.data(), nj);
          for (int i = 0; i < c.M; ++i)
            for (int j = 0; j < nj; ++j) compact[size_t(i) * c.N + j0 + j] = s[size_t(i) * nj + j];
        }
        EXPECT_EQ(in_place, whole) << "op " << op << " M" << c.M << " N" << c.N << " K" << c.K
                                   << " acc " << acc << ", in place";
        EXPECT_EQ(compact, whole) << "op " << op << " M" << c.M << " N" << c.N << " K" << c.K
                                  << " acc " << acc << ", compact";
      }
}

TEST(AlignedVector, StartsOnACacheLineAtEverySize) {
  for (size_t n : {size_t(1), size_t(3), size_t(17), size_t(1000), size_t(1) << 20}) {
    AlignedVector<float> v(n, 1.f);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(v.data()) % 64, 0u) << n;
    v.resize(3 * n + 5, 2.f);  // a reallocation keeps the alignment and the values
    EXPECT_EQ(reinterpret_cast<uintptr_t>(v.data()) % 64, 0u) << n;
    EXPECT_EQ(v[n - 1], 1.f);
    EXPECT_EQ(v[3 * n + 4], 2.f);
  }
}

TEST(Gemm, TheBackendIsTheOneTheEnvironmentAsksFor) {
  const char* v = std::getenv("SIRL_KERNELS");
  if (v && std::strcmp(v, "generic") == 0)
    EXPECT_STREQ(gemm_backend(), "eigen");
  else
    EXPECT_TRUE(std::string(gemm_backend()) == "libxsmm+onednn" ||
                std::string(gemm_backend()) == "libxsmm" || std::string(gemm_backend()) == "eigen");
}

}  // namespace
}  // namespace sirl
