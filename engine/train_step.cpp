#include "engine/train_step.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "kernels/bradley_terry_loss.h"
#include "kernels/triplet_loss.h"

namespace sirl {

Trainer::Trainer(MlpShape s, AdamConfig cfg, std::vector<float> initial_params)
    : shape(std::move(s)), adam_cfg(cfg), params(std::move(initial_params)), adam(params.size()) {
  validate(shape);
  if (params.size() < shape.param_count())
    throw std::invalid_argument("Trainer: fewer parameters than the network has");
}

namespace {

// The backward pass from t.d_out fused with Adam (mlp_backward_adam); parameters past the
// network's (none for these steps' callers) get the zero gradient they would have had.
void backward_and_update(Trainer& t, int threads) {
  const AdamStepScalars step = adam_begin_step(t.adam_cfg, t.adam);
  mlp_backward_adam(t.shape, t.params.data(), t.tape, t.d_out.data(), step, t.adam.m.data(),
                    t.adam.v.data(), threads);
  const size_t P = t.shape.param_count(), rest = t.params.size() - P;
  if (rest > 0) {
    const std::vector<float> zero(rest, 0.f);
    adam_apply(step, t.params.data() + P, zero.data(), t.adam.m.data() + P, t.adam.v.data() + P,
               rest);
  }
}

}  // namespace

void gather_by_role(const float* X, int in, const int32_t* idx, int B, int roles, float* out) {
  for (int role = 0; role < roles; ++role)
    for (int i = 0; i < B; ++i)
      std::memcpy(out + (size_t(role) * B + i) * in, X + size_t(idx[size_t(i) * roles + role]) * in,
                  sizeof(float) * in);
}

float triplet_train_step(Trainer& t, const float* X, const int32_t* triplets, int B, float margin,
                         int threads) {
  const int in = t.shape.in(), d = t.shape.out();
  t.batch_x.resize(size_t(3) * B * in);
  gather_by_role(X, in, triplets, B, 3, t.batch_x.data());
  mlp_forward(t.shape, t.params.data(), t.batch_x.data(), 3 * B, t.tape, threads);
  t.d_out.resize(size_t(3) * B * d);
  const float loss = symmetric_triplet_loss(t.tape.output(), B, d, margin, t.d_out.data());
  backward_and_update(t, threads);
  return loss;
}

float preference_train_step(Trainer& t, const float* X, const int32_t* pairs, const float* label,
                            int B, float l2_weight, int threads) {
  const int in = t.shape.in();
  t.batch_x.resize(size_t(2) * B * in);
  gather_by_role(X, in, pairs, B, 2, t.batch_x.data());
  mlp_forward(t.shape, t.params.data(), t.batch_x.data(), 2 * B, t.tape, threads);
  t.d_out.resize(size_t(2) * B);
  const float loss = bradley_terry_loss(t.tape.output(), label, B, l2_weight, t.d_out.data());
  backward_and_update(t, threads);
  return loss;
}

float multihead_preference_train_step(Trainer& t, int K, const float* X, const int32_t* pairs,
                                      const float* label, const int32_t* human, int B,
                                      float l2_weight, int threads) {
  const int in = t.shape.in(), d = t.shape.out();
  const size_t P = t.shape.param_count();
  const float* heads = t.params.data() + P;  // [K, d + 1]
  t.batch_x.resize(size_t(2) * B * in);
  gather_by_role(X, in, pairs, B, 2, t.batch_x.data());
  mlp_forward(t.shape, t.params.data(), t.batch_x.data(), 2 * B, t.tape, threads);
  const float* emb = t.tape.output();  // [2B, d]: A rows then B rows
  // r [2B]: each row scored by its pair's head.
  std::vector<float> r(size_t(2) * B), dr(size_t(2) * B);
  for (int j = 0; j < 2 * B; ++j) {
    const float* w = heads + size_t(human[j % B]) * (d + 1);
    float s = w[d];
    for (int k = 0; k < d; ++k) s += w[k] * emb[size_t(j) * d + k];
    r[j] = s;
  }
  const float loss = bradley_terry_loss(r.data(), label, B, l2_weight, dr.data());
  // The heads' gradient, rows in order, and ∂L/∂φ from the heads before their update.
  std::vector<float> dheads(t.params.size() - P, 0.f);  // [K, d + 1]
  t.d_out.resize(size_t(2) * B * d);
  for (int j = 0; j < 2 * B; ++j) {
    const int h = human[j % B];
    const float* w = heads + size_t(h) * (d + 1);
    float* dw = dheads.data() + size_t(h) * (d + 1);
    for (int k = 0; k < d; ++k) {
      t.d_out[size_t(j) * d + k] = dr[j] * w[k];  // ∂L/∂φ = dr · w
      dw[k] += dr[j] * emb[size_t(j) * d + k];    // ∂L/∂w = dr · φ
    }
    dw[d] += dr[j];
  }
  // One Adam step over [φ | heads]: φ's in its fused backward pass (the same bits as a stored
  // gradient and adam_step, without writing, zeroing and re-reading a gradient of φ's size).
  const AdamStepScalars step = adam_begin_step(t.adam_cfg, t.adam);
  mlp_backward_adam(t.shape, t.params.data(), t.tape, t.d_out.data(), step, t.adam.m.data(),
                    t.adam.v.data(), threads);
  adam_apply(step, t.params.data() + P, dheads.data(), t.adam.m.data() + P, t.adam.v.data() + P,
             dheads.size());
  return loss;
}

BatchedTrainer::BatchedTrainer(MlpShape s, int m, AdamConfig cfg, std::vector<float> initial)
    : shape(std::move(s)),
      models(m),
      adam_cfg(cfg),
      params(std::move(initial)),
      adam(params.size()),
      work(size_t(std::max(m, 0))),
      losses(m, 0.f) {
  validate(shape);
  if (params.size() != size_t(models) * shape.param_count())
    throw std::invalid_argument("BatchedTrainer: parameters are not models × the network's");
}

namespace {

// Model m's step of t on its B examples idx [B, roles] (row indices into X): its gather, forward
// pass, loss and backward pass with its Adam update back to back on the calling thread. A
// GridRobot head's weights, moments and activations (~0.4 MB) then stay in L2 from its forward to
// its backward pass, where a pass over all 20 heads (8 MB) would have evicted them.
// loss(out, d_out) returns the model's loss and writes ∂L/∂output.
template <typename Loss>
float step_of_model(BatchedTrainer& t, int m, const AdamStepScalars& step, const float* X,
                    const int32_t* idx, int B, int roles, Loss&& loss) {
  const MlpShape& s = t.shape;
  const int in = s.in(), rows = roles * B;
  const size_t P = s.param_count();
  BatchedTrainer::ModelWork& w = t.work[m];
  w.x.resize(size_t(rows) * in);
  w.d_out.resize(size_t(rows) * s.out());
  gather_by_role(X, in, idx, B, roles, w.x.data());
  mlp_forward(s, t.params.data() + m * P, w.x.data(), rows, w.tape, 1);
  t.losses[m] = loss(w.tape.output(), w.d_out.data());
  mlp_backward_adam(s, t.params.data() + m * P, w.tape, w.d_out.data(), step,
                    t.adam.m.data() + m * P, t.adam.v.data() + m * P, 1);
  return t.losses[m];
}

}  // namespace

float preference_train_step_of_model(BatchedTrainer& t, int m, const AdamStepScalars& step,
                                     const float* X, const int32_t* pairs, const float* label,
                                     int B, float l2_weight) {
  return step_of_model(t, m, step, X, pairs, B, 2, [&](const float* r, float* dr) {
    return bradley_terry_loss(r, label, B, l2_weight, dr);
  });
}

float triplet_train_step_of_model(BatchedTrainer& t, int m, const AdamStepScalars& step,
                                  const float* X, const int32_t* triplets, int B, float margin) {
  const int d = t.shape.out();
  return step_of_model(t, m, step, X, triplets, B, 3, [&](const float* emb, float* demb) {
    return symmetric_triplet_loss(emb, B, d, margin, demb);
  });
}

double epoch_train_flops(const MlpShape& s, int64_t n, int batch, int roles, int copies,
                         double total) {
  for (int64_t i0 = 0; i0 < n; i0 += batch)
    total += copies * s.train_flops(roles * int(std::min<int64_t>(batch, n - i0)));
  return total;
}

}  // namespace sirl
