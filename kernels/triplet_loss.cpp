#include "kernels/triplet_loss.h"

#include <algorithm>
#include <limits>

namespace sirl {
namespace {
template <typename T>
T sqdist(const T* a, const T* b, int d) {
  T s = 0;
  for (int k = 0; k < d; ++k) s += (a[k] - b[k]) * (a[k] - b[k]);
  return s;
}
}  // namespace

template <typename T>
T symmetric_triplet_loss(const T* emb, int B, int d, T margin, T* demb) {
  if (demb) std::fill(demb, demb + size_t(3) * B * d, T(0));
  const T inv_b = T(1) / T(B);
  T loss = 0;
  for (int i = 0; i < B; ++i) {
    const T* p1 = emb + size_t(i) * d;
    const T* p2 = emb + size_t(B + i) * d;
    const T* n = emb + size_t(2 * B + i) * d;
    const T dpp = sqdist(p1, p2, d), d1n = sqdist(p1, n, d), d2n = sqdist(p2, n, d);
    const T h1 = dpp - d1n + margin;  // anchor P1
    const T h2 = dpp - d2n + margin;  // anchor P2
    loss += std::max(h1, T(0)) + std::max(h2, T(0));
    if (!demb) continue;
    T* g1 = demb + size_t(i) * d;
    T* g2 = demb + size_t(B + i) * d;
    T* gn = demb + size_t(2 * B + i) * d;
    for (int k = 0; k < d; ++k) {
      T a = 0, b = 0, c = 0;  // ∂/∂p1, ∂/∂p2, ∂/∂n
      if (h1 > 0) {           // ∂h1: p1 → 2(n − p2), p2 → 2(p2 − p1), n → 2(p1 − n)
        a += 2 * (n[k] - p2[k]);
        b += 2 * (p2[k] - p1[k]);
        c += 2 * (p1[k] - n[k]);
      }
      if (h2 > 0) {  // ∂h2: p2 → 2(n − p1), p1 → 2(p1 − p2), n → 2(p2 − n)
        b += 2 * (n[k] - p1[k]);
        a += 2 * (p1[k] - p2[k]);
        c += 2 * (p2[k] - n[k]);
      }
      g1[k] = a * inv_b;
      g2[k] = b * inv_b;
      gn[k] = c * inv_b;
    }
  }
  return loss * inv_b;
}

template <typename T>
T triplet_max_hinge(const T* emb, int B, int d, T margin) {
  T worst = -std::numeric_limits<T>::infinity();
  for (int i = 0; i < B; ++i) {
    const T* p1 = emb + size_t(i) * d;
    const T* p2 = emb + size_t(B + i) * d;
    const T* n = emb + size_t(2 * B + i) * d;
    const T dpp = sqdist(p1, p2, d);
    worst = std::max({worst, dpp - sqdist(p1, n, d) + margin, dpp - sqdist(p2, n, d) + margin});
  }
  return worst;
}

template <typename T>
double triplet_accuracy(const T* emb, int B, int d) {
  int ok = 0;
  for (int i = 0; i < B; ++i) {
    const T* p1 = emb + size_t(i) * d;
    const T* p2 = emb + size_t(B + i) * d;
    const T* n = emb + size_t(2 * B + i) * d;
    const T dpp = sqdist(p1, p2, d);
    ok += dpp < sqdist(p1, n, d) && dpp < sqdist(p2, n, d);
  }
  return B > 0 ? double(ok) / B : 0.0;
}

template float symmetric_triplet_loss<float>(const float*, int, int, float, float*);
template double symmetric_triplet_loss<double>(const double*, int, int, double, double*);
template float triplet_max_hinge<float>(const float*, int, int, float);
template double triplet_max_hinge<double>(const double*, int, int, double);
template double triplet_accuracy<float>(const float*, int, int);
template double triplet_accuracy<double>(const double*, int, int);

}  // namespace sirl
