// kernels/gemm_bf16.h: products of bf16 operands with fp32 accumulation, on the native kernel
// (oneDNN's vdpbf16ps matmul, where the CPU has AVX512-BF16) and on the emulation (fp32 kernels
// on the widened operands). Checked against a double reference on the same bf16 values, for
// bit-identity across thread counts and slice forms, and, where a product is emulated, bit for
// bit against the fp32 kernel on bf16-rounded copies (what precision "bf16" computed before
// native kernels existed).
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "kernels/bf16.h"
#include "kernels/gemm.h"
#include "kernels/gemm_bf16.h"
#include "kernels/gemm_blocking.h"
#include "kernels/rng.h"
#include "probes/cpu_class.h"

namespace sirl {
namespace {

enum class Op { kNt, kTn, kNn };

struct Case {
  Op op;
  int M, N, K;
  bool acc;
};

// Storage sizes of A and B for C[M,N] = op(A)·op(B) (gemm.h's conventions).
size_t a_size(const Case& c) {
  return size_t(c.M) * c.K;
}
size_t b_size(const Case& c) {
  return size_t(c.N) * c.K;
}
double a_at(const Case& c, const std::vector<double>& a, int i, int k) {
  return c.op == Op::kTn ? a[size_t(k) * c.M + i] : a[size_t(i) * c.K + k];
}
double b_at(const Case& c, const std::vector<double>& b, int k, int j) {
  return c.op == Op::kNt ? b[size_t(j) * c.K + k] : b[size_t(k) * c.N + j];
}

void run_bf16(const Case& c, float* C, const uint16_t* A, const uint16_t* B, int threads) {
  if (c.op == Op::kNt) matmul_bf16_nt(C, A, B, c.M, c.N, c.K, c.acc, threads);
  if (c.op == Op::kTn) matmul_bf16_tn(C, A, B, c.M, c.N, c.K, c.acc, threads);
  if (c.op == Op::kNn) matmul_bf16_nn(C, A, B, c.M, c.N, c.K, c.acc, threads);
}
void run_fp32(const Case& c, float* C, const float* A, const float* B) {
  if (c.op == Op::kNt) matmul_nt(C, A, B, c.M, c.N, c.K, c.acc, 1);
  if (c.op == Op::kTn) matmul_tn(C, A, B, c.M, c.N, c.K, c.acc, 1);
  if (c.op == Op::kNn) matmul_nn(C, A, B, c.M, c.N, c.K, c.acc, 1);
}
// The same product one column slice at a time, into a compact scratch (the fused pass's form).
void run_bf16_cols(const Case& c, float* C, const uint16_t* A, const uint16_t* B) {
  const int w = gemm_column_slice(c.N);
  for (int j0 = 0; j0 < c.N; j0 += w) {
    const int nj = std::min(w, c.N - j0);
    std::vector<float> cs(size_t(c.M) * nj);
    for (int i = 0; i < c.M; ++i)
      for (int j = 0; j < nj; ++j) cs[size_t(i) * nj + j] = C[size_t(i) * c.N + j0 + j];
    if (c.op == Op::kNt) matmul_bf16_nt_cols(cs.data(), nj, A, B, c.M, c.N, c.K, c.acc, j0, nj);
    if (c.op == Op::kTn) matmul_bf16_tn_cols(cs.data(), nj, A, B, c.M, c.N, c.K, c.acc, j0, nj);
    if (c.op == Op::kNn) matmul_bf16_nn_cols(cs.data(), nj, A, B, c.M, c.N, c.K, c.acc, j0, nj);
    for (int i = 0; i < c.M; ++i)
      for (int j = 0; j < nj; ++j) C[size_t(i) * c.N + j0 + j] = cs[size_t(i) * nj + j];
  }
}

struct Operands {
  std::vector<float> a32, b32, c0;  // fp32 originals; C's prior content (for accumulate)
  std::vector<uint16_t> a16, b16;   // their bf16 roundings
};
Operands operands(const Case& c, uint64_t seed) {
  Rng rng(seed);
  Operands o;
  o.a32.resize(a_size(c));
  o.b32.resize(b_size(c));
  o.c0.resize(size_t(c.M) * c.N);
  for (auto& v : o.a32) v = float(rng.normal());
  for (auto& v : o.b32) v = float(rng.normal());
  for (auto& v : o.c0) v = float(rng.normal());
  o.a16.resize(o.a32.size());
  o.b16.resize(o.b32.size());
  to_bf16_bits(o.a32.data(), o.a16.data(), o.a32.size());
  to_bf16_bits(o.b32.data(), o.b16.data(), o.b32.size());
  return o;
}

std::vector<double> widened(const std::vector<uint16_t>& h) {
  std::vector<double> d(h.size());
  for (size_t i = 0; i < h.size(); ++i) d[i] = std::bit_cast<float>(uint32_t(h[i]) << 16);
  return d;
}

// Shapes: JacoRobot- and Grid-like layers large enough for the native kernel (every dimension
// ≥ 32; N = 300 gives a full 256-wide slice and a 44-wide one), and narrow ones that are always
// emulated (a 6-wide embedding, a 1-unit head, a 19-feature input).
std::vector<Case> cases() {
  std::vector<Case> out;
  for (Op op : {Op::kNt, Op::kTn, Op::kNn})
    for (bool acc : {false, true}) {
      out.push_back({op, 96, 300, 130, acc});
      out.push_back({op, 64, 128, 128, acc});
      out.push_back({op, 40, 6, 200, acc});
      out.push_back({op, 33, 1, 64, acc});
      out.push_back({op, 50, 128, 19, acc});
    }
  // A weight gradient oneDNN serves in fp32 (two dimensions ≥ 512): natively by row blocks of 256,
  // the last one 8 rows (emulated: below 32)
  for (bool acc : {false, true}) out.push_back({Op::kTn, 520, 600, 40, acc});
  return out;
}

std::string name(const Case& c) {
  const char* ops[] = {"nt", "tn", "nn"};
  return std::string(ops[int(c.op)]) + " " + std::to_string(c.M) + "x" + std::to_string(c.N) + "x" +
         std::to_string(c.K) + (c.acc ? " accumulate" : "");
}

// Every element against Σ_k a·b in double on the same bf16 values (exact products, so only fp32
// accumulation differs: within 2⁻¹⁶ of Σ|a·b| for K ≤ 300, while rounding an operand to bf16 moves
// a product by up to 2⁻⁸), and against the fp32 product of the unrounded operands, which must
// differ somewhere (the operands really are rounded).
TEST(GemmBf16, ProductsAreOfBf16OperandsWithFp32Accumulation) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(name(c));
    const Operands o = operands(c, 11 + c.M + c.N);
    const auto a = widened(o.a16), b = widened(o.b16);
    std::vector<float> C = o.c0, C32 = o.c0;
    run_bf16(c, C.data(), o.a16.data(), o.b16.data(), 1);
    run_fp32(c, C32.data(), o.a32.data(), o.b32.data());
    double largest_gap = 0;
    for (int i = 0; i < c.M; ++i)
      for (int j = 0; j < c.N; ++j) {
        double s = c.acc ? o.c0[size_t(i) * c.N + j] : 0.0, mag = std::fabs(s);
        for (int k = 0; k < c.K; ++k) {
          const double t = a_at(c, a, i, k) * b_at(c, b, k, j);
          s += t;
          mag += std::fabs(t);
        }
        const size_t at = size_t(i) * c.N + j;
        ASSERT_NEAR(C[at], s, std::ldexp(mag, -16) + 1e-30) << "C[" << i << "," << j << "]";
        largest_gap = std::max(largest_gap, double(std::fabs(C[at] - C32[at])));
      }
    EXPECT_GT(largest_gap, 1e-4);
  }
}

// Bits: the same for 1 and 2 threads, and for the whole product and its slices into a compact
// scratch (the fused backward's form).
TEST(GemmBf16, BitsDoNotDependOnThreadsOrSliceForm) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(name(c));
    const Operands o = operands(c, 23 + c.K);
    std::vector<float> one = o.c0, two = o.c0, cols = o.c0;
    run_bf16(c, one.data(), o.a16.data(), o.b16.data(), 1);
    run_bf16(c, two.data(), o.a16.data(), o.b16.data(), 2);
    run_bf16_cols(c, cols.data(), o.a16.data(), o.b16.data());
    ASSERT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(float)), 0);
    ASSERT_EQ(std::memcmp(one.data(), cols.data(), one.size() * sizeof(float)), 0);
  }
}

// A product the native kernel does not take (any dimension < 32, every product on a CPU without
// AVX512-BF16, or SIRL_BF16=emulate) is the fp32 kernel on bf16-rounded fp32 copies, bit for bit.
// Two computations of one product that agree bit for bit on the AVX-512 paths but sum in other
// orders on the AVX2 ones (docs/kernels.md, "AVX2 paths"). Bits where they hold; elsewhere each
// fp32 sum lies within γ_K·Σ|a·b| of the exact one (Higham: γ_K = K·u/(1 − K·u), u = 2⁻²⁴), so
// the two differ by at most 2γ_K·Σ|a·b| (+ |C₀| when accumulating). `a`, `b`: the operands the
// product used, as doubles.
void expect_same_product(const Case& c, const float* got, const float* want,
                         const std::vector<double>& a, const std::vector<double>& b,
                         const std::vector<float>& c0, int row0 = 0, int rows = -1) {
  if (rows < 0) rows = c.M;
  if (avx512_in_use()) {
    ASSERT_EQ(std::memcmp(got, want, size_t(rows) * c.N * sizeof(float)), 0)
        << "AVX-512 paths: the bits of one product, however it is computed";
    return;
  }
  const double u = std::ldexp(1.0, -24), gamma = c.K * u / (1 - c.K * u);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < c.N; ++j) {
      const size_t at = size_t(row0 + i) * c.N + j;
      double mag = c.acc ? std::fabs(double(c0[at])) : 0.0;
      for (int k = 0; k < c.K; ++k) mag += std::fabs(a_at(c, a, row0 + i, k) * b_at(c, b, k, j));
      const size_t here = size_t(i) * c.N + j;
      ASSERT_LE(std::fabs(double(got[here]) - double(want[here])), 2 * gamma * mag + 1e-30)
          << "C[" << row0 + i << "," << j << "]: two summation orders of one product";
    }
}

TEST(GemmBf16, EmulatedProductsAreTheFp32KernelOnRoundedCopies) {
  int checked = 0;
  for (const Case& c : cases()) {
    if (bf16_native() && std::min({c.M, c.N, c.K}) >= 32) continue;
    SCOPED_TRACE(name(c));
    const Operands o = operands(c, 5 + c.N);
    std::vector<float> ar(o.a32.size()), br(o.b32.size());
    round_to_bf16(o.a32.data(), ar.data(), ar.size());
    round_to_bf16(o.b32.data(), br.data(), br.size());
    std::vector<float> C = o.c0, ref = o.c0;
    run_bf16(c, C.data(), o.a16.data(), o.b16.data(), 2);
    run_fp32(c, ref.data(), ar.data(), br.data());
    expect_same_product(c, C.data(), ref.data(), widened(o.a16), widened(o.b16), o.c0);
    ++checked;
  }
  EXPECT_GE(checked, 18);  // the narrow shapes at least
}

// A weight gradient of a shape oneDNN serves in fp32 goes by row blocks: natively gemm.h's
// (fixed by the shape), emulated the fp32 kernel's own. Each block alone (the fused backward
// pass's form) has the bits of that block of the whole.
TEST(GemmBf16, WeightGradientsOfOneDnnShapesGoByRowBlocks) {
  const int M = 520, N = 600, K = 40;
  const int block = gemm_bf16_weight_row_block(M, N, K);
  EXPECT_EQ(block, bf16_native() ? gemm_row_block(M, N, K) : gemm_weight_row_block(M, N, K));
  if (block == 0) GTEST_SKIP() << "no row blocks with the " << gemm_backend() << " kernels";
  if (bf16_native()) {
    EXPECT_EQ(gemm_bf16_weight_row_block(128, 128, 64), 0);  // GridRobot's: column slices
  }
  const Case c{Op::kTn, M, N, K, false};
  const Operands o = operands(c, 41);
  std::vector<float> whole(size_t(M) * N);
  run_bf16(c, whole.data(), o.a16.data(), o.b16.data(), 2);
  for (int i0 = 0; i0 < M; i0 += block) {
    const int mi = std::min(block, M - i0);
    std::vector<float> rows(size_t(mi) * N, -1.f);
    matmul_bf16_tn_rows(rows.data(), o.a16.data(), o.b16.data(), M, N, K, false, i0, mi);
    SCOPED_TRACE("rows " + std::to_string(i0) + ".." + std::to_string(i0 + mi));
    expect_same_product(c, rows.data(), whole.data() + size_t(i0) * N, widened(o.a16),
                        widened(o.b16), o.c0, i0, mi);
  }
}

TEST(GemmBf16, NamesItsBackend) {
  const std::string b = bf16_backend();
  if (bf16_native()) {
    EXPECT_TRUE(b == "onednn-avx512_bf16" || b == "onednn-amx_bf16") << b;
  } else {
    EXPECT_EQ(b, "emulated");
  }
  if (const char* e = std::getenv("SIRL_BF16"); e && std::strcmp(e, "emulate") == 0) {
    EXPECT_FALSE(bf16_native());
  }
}

}  // namespace
}  // namespace sirl
