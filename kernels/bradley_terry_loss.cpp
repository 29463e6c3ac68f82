#include "kernels/bradley_terry_loss.h"

#include <cmath>

namespace sirl {
namespace {
// log(1 + e^x) without overflow.
template <typename T>
T softplus(T x) {
  return x > 0 ? x + std::log1p(std::exp(-x)) : std::log1p(std::exp(x));
}
template <typename T>
T sigmoid(T x) {
  return x >= 0 ? T(1) / (T(1) + std::exp(-x)) : std::exp(x) / (T(1) + std::exp(x));
}
}  // namespace

template <typename T>
T bradley_terry_loss(const T* r, const T* label, int B, T l2_weight, T* dr) {
  const T inv_b = T(1) / T(B);
  T ce = 0, l2 = 0;
  for (int i = 0; i < B; ++i) {
    const T z = r[i] - r[B + i], l = label[i];
    // −log σ(z) = softplus(−z);  −log σ(−z) = softplus(z)
    ce += l * softplus(-z) + (1 - l) * softplus(z);
    l2 += r[i] * r[i] + r[B + i] * r[B + i];
    if (dr) {
      const T g = (sigmoid(z) - l) * inv_b;  // ∂CE/∂z
      dr[i] = g + 2 * l2_weight * r[i] * inv_b;
      dr[B + i] = -g + 2 * l2_weight * r[B + i] * inv_b;
    }
  }
  return ce * inv_b + l2_weight * l2 * inv_b;
}

template <typename T>
double preference_accuracy(const T* r, const T* label, int B) {
  int ok = 0, n = 0;
  for (int i = 0; i < B; ++i) {
    if (label[i] == T(0.5)) continue;
    ++n;
    ok += (r[i] > r[B + i]) == (label[i] > T(0.5));
  }
  return n > 0 ? double(ok) / n : 0.0;
}

template float bradley_terry_loss<float>(const float*, const float*, int, float, float*);
template double bradley_terry_loss<double>(const double*, const double*, int, double, double*);
template double preference_accuracy<float>(const float*, const float*, int);
template double preference_accuracy<double>(const double*, const double*, int);

}  // namespace sirl
