// The bf16 precision mode: the rounding itself against hand-worked bit patterns, and the MLP's
// products against a double reference on bf16-rounded operands, layer by layer.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "kernels/bf16.h"
#include "kernels/mlp.h"

namespace sirl {
namespace {

float from_bits(uint32_t u) {
  return std::bit_cast<float>(u);
}
uint32_t bits(float x) {
  return std::bit_cast<uint32_t>(x);
}

TEST(Bf16, RoundsToNearestTiesToEven) {
  EXPECT_EQ(round_to_bf16(1.0f), 1.0f);
  EXPECT_EQ(round_to_bf16(-2.5f), -2.5f);  // already a bf16 value
  // bf16 keeps 7 mantissa bits: next to 1 are 1 − 2⁻⁸ and 1 + 2⁻⁷.
  EXPECT_EQ(round_to_bf16(1.0f + std::ldexp(1.0f, -8)), 1.0f);  // tie, 1 is even
  EXPECT_EQ(round_to_bf16(1.0f + 3 * std::ldexp(1.0f, -8)),     // tie between 1 + 2⁻⁷ (odd)
            1.0f + std::ldexp(1.0f, -6));                       // and 1 + 2⁻⁶ (even)
  EXPECT_EQ(round_to_bf16(1.0f + std::ldexp(1.0f, -8) + std::ldexp(1.0f, -20)),
            1.0f + std::ldexp(1.0f, -7));  // just above the tie
  EXPECT_EQ(round_to_bf16(1.0f + std::ldexp(1.0f, -8) - std::ldexp(1.0f, -20)), 1.0f);
  EXPECT_EQ(round_to_bf16(-(1.0f + 3 * std::ldexp(1.0f, -8))), -(1.0f + std::ldexp(1.0f, -6)));
  // 0.1f = 0x3dcccccd → 0x3dcd (the dropped half 0xcccd is above 0x8000).
  EXPECT_EQ(bits(round_to_bf16(0.1f)), 0x3dcd0000u);
  // Denormals round like any value: 0x00008000 is a tie to the even 0, 0x00018000 one to 0x0002.
  EXPECT_EQ(bits(round_to_bf16(from_bits(0x00008000u))), 0u);
  EXPECT_EQ(bits(round_to_bf16(from_bits(0x00018000u))), 0x00020000u);
  // The largest float is above bf16's largest (0x7f7f0000) by more than half an ulp: → inf.
  EXPECT_EQ(round_to_bf16(std::numeric_limits<float>::max()),
            std::numeric_limits<float>::infinity());
  EXPECT_EQ(round_to_bf16(-std::numeric_limits<float>::infinity()),
            -std::numeric_limits<float>::infinity());
  // NaN stays NaN, even one whose payload lives only in the dropped bits.
  EXPECT_TRUE(std::isnan(round_to_bf16(from_bits(0x7f800001u))));
  EXPECT_TRUE(std::isnan(round_to_bf16(std::numeric_limits<float>::quiet_NaN())));
  // Every result has its low 16 bits clear; the array form is the scalar one.
  std::vector<float> x{0.3f, -7.77f, 1e-30f, 65504.f}, y(4);
  round_to_bf16(x.data(), y.data(), x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    EXPECT_EQ(bits(y[i]) & 0xffffu, 0u);
    EXPECT_EQ(y[i], round_to_bf16(x[i]));
    EXPECT_LE(std::fabs(y[i] - x[i]), std::ldexp(std::fabs(x[i]), -8));  // half an ulp of 2⁻⁷
  }
}

// The packed form (the native kernels' operand) is round_to_bf16's upper half, for every upper
// half with the lower halves that matter: exact, just below, at and above a tie, and the largest
// (NaNs, infinities and denormals included).
TEST(Bf16, BitsAreTheRoundedValuesUpperHalf) {
  std::vector<float> x;
  for (uint32_t hi = 0; hi < 0x10000u; ++hi)
    for (uint32_t lo : {0x0000u, 0x0001u, 0x7fffu, 0x8000u, 0x8001u, 0xffffu})
      x.push_back(from_bits(hi << 16 | lo));
  std::vector<uint16_t> y(x.size());
  to_bf16_bits(x.data(), y.data(), x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    const float r = round_to_bf16(x[i]);
    if (std::isnan(r)) {
      ASSERT_TRUE(std::isnan(from_bits(uint32_t(y[i]) << 16))) << std::hex << bits(x[i]);
      ASSERT_EQ(y[i] & 0x0040u, 0x0040u) << "quiet";
    } else {
      ASSERT_EQ(uint32_t(y[i]) << 16, bits(r)) << std::hex << bits(x[i]);
    }
  }
}

std::vector<double> rounded(const float* x, size_t n) {
  std::vector<double> r(n);
  for (size_t i = 0; i < n; ++i) r[i] = round_to_bf16(x[i]);
  return r;
}

// The forward pass, one layer at a time from the network's own activations: y = bf16(in)·bf16(W)ᵀ
// + b (then ReLU), summed in double. fp32 accumulation over K ≤ 300 terms stays within 1e-5 of
// it; the fp32 network's outputs differ from the bf16 ones by ~1e-3.
TEST(Bf16, ForwardLayersAreProductsOfRoundedOperands) {
  MlpShape s{{300, 70, 40, 3}};
  Rng rng(4);
  const int batch = 17;
  std::vector<float> p(s.param_count()), x(size_t(batch) * s.in());
  mlp_init(s, p.data(), rng);
  for (auto& v : x) v = float(rng.normal());
  MlpShape b = s;
  b.bf16_products = true;
  MlpTape<float> t32, t16;
  mlp_forward(s, p.data(), x.data(), batch, t32);
  mlp_forward(b, p.data(), x.data(), batch, t16);
  double largest_gap = 0;
  for (int l = 0; l < s.layers(); ++l) {
    const int ni = s.widths[l], no = s.widths[l + 1];
    const float* in = l == 0 ? x.data() : t16.act[l - 1].data();
    const auto inr = rounded(in, size_t(batch) * ni);
    const auto wr = rounded(p.data() + s.weight_offset(l), size_t(no) * ni);
    const float* bias = p.data() + s.bias_offset(l);
    for (int r = 0; r < batch; ++r)
      for (int j = 0; j < no; ++j) {
        double y = bias[j];
        for (int k = 0; k < ni; ++k) y += inr[size_t(r) * ni + k] * wr[size_t(j) * ni + k];
        if (s.relu_after(l)) y = std::max(y, 0.0);
        const size_t at = size_t(r) * no + j;
        ASSERT_NEAR(t16.act[l][at], y, 1e-5 * (1 + std::fabs(y))) << "layer " << l;
        largest_gap = std::max(largest_gap, double(std::fabs(t16.act[l][at] - t32.act[l][at])));
      }
  }
  EXPECT_GT(largest_gap, 1e-4);  // the flag changes the products
}

// One Linear layer (no ReLU), so ∂L/∂(pre-activation) is dout itself: dW = bf16(dout)ᵀ·bf16(x),
// dx = bf16(dout)·bf16(W), db = Σ dout (not a product: fp32 dout).
TEST(Bf16, BackwardProductsAreOfRoundedOperands) {
  MlpShape s{{90, 33}};
  s.bf16_products = true;
  Rng rng(8);
  const int batch = 12, ni = 90, no = 33;
  std::vector<float> p(s.param_count()), x(size_t(batch) * ni), dout(size_t(batch) * no);
  mlp_init(s, p.data(), rng);
  for (auto& v : x) v = float(rng.normal());
  for (auto& v : dout) v = float(rng.normal());
  MlpTape<float> t;
  mlp_forward(s, p.data(), x.data(), batch, t);
  std::vector<float> dp(p.size(), 0.f), dx(x.size(), 0.f);
  mlp_backward(s, p.data(), t, dout.data(), dp.data(), dx.data());
  const auto xr = rounded(x.data(), x.size()), gr = rounded(dout.data(), dout.size());
  const auto wr = rounded(p.data(), size_t(no) * ni);
  for (int j = 0; j < no; ++j)
    for (int k = 0; k < ni; ++k) {
      double w = 0;
      for (int r = 0; r < batch; ++r) w += gr[size_t(r) * no + j] * xr[size_t(r) * ni + k];
      ASSERT_NEAR(dp[size_t(j) * ni + k], w, 1e-5 * (1 + std::fabs(w)));
    }
  for (int j = 0; j < no; ++j) {
    double db = 0;
    for (int r = 0; r < batch; ++r) db += dout[size_t(r) * no + j];
    ASSERT_NEAR(dp[s.bias_offset(0) + j], db, 1e-5 * (1 + std::fabs(db)));
  }
  for (int r = 0; r < batch; ++r)
    for (int k = 0; k < ni; ++k) {
      double d = 0;
      for (int j = 0; j < no; ++j) d += gr[size_t(r) * no + j] * wr[size_t(j) * ni + k];
      ASSERT_NEAR(dx[size_t(r) * ni + k], d, 1e-5 * (1 + std::fabs(d)));
    }
}

// A bf16 backward pass on the tape of an fp32 forward pass is refused (its bf16 copies are
// missing), not run on stale or absent operands.
TEST(Bf16, BackwardRefusesAnFp32Tape) {
  MlpShape s{{4, 3}};
  Rng rng(2);
  std::vector<float> p(s.param_count()), x(8), dout(6), dp(p.size());
  mlp_init(s, p.data(), rng);
  MlpTape<float> t;
  mlp_forward(s, p.data(), x.data(), 2, t);
  MlpShape b = s;
  b.bf16_products = true;
  EXPECT_THROW(mlp_backward(b, p.data(), t, dout.data(), dp.data(), static_cast<float*>(nullptr)),
               std::logic_error);
}

TEST(Bf16, DoubleNetworksRefuseIt) {
  MlpShape s{{3, 2}};
  s.bf16_products = true;
  std::vector<double> p(s.param_count(), 0.1), x(3, 1.0);
  MlpTape<double> t;
  EXPECT_THROW(mlp_forward(s, p.data(), x.data(), 1, t), std::invalid_argument);
}

}  // namespace
}  // namespace sirl
