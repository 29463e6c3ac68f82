#include "experiment/cost_model.h"

#include <algorithm>

#include "datasets/environments.h"
#include "engine/representation.h"

namespace sirl {

EnvSizes env_sizes(const Task& t, const Profile& p) {
  const EnvSpec& e = env_spec(t.env);
  const Hyper& h = t.hyper_values();
  const int in = e.input_dim(p.data);
  return {h, in, e.trajectories(p.data), phi_shape(in, h)};
}

double working_set(const MlpShape& s, int batch_rows) {
  double act = 0;
  for (int w : s.widths) act += double(w) * batch_rows;
  return 4.0 * (4.0 * double(s.param_count()) + 2 * act);
}

// Main-memory traffic of an Adam training whose state (weights and both moments, plus a
// gradient's worth of slack: 16 bytes a parameter) does not fit a core's share of the caches
// (kCacheShare: Zen 4's 1 MiB L2 + a 32 MiB L3 shared by 8 cores). Every optimizer step reads the
// weights three times (the forward pass, ∂L/∂input, Adam's update) and Adam's m and v, and writes
// the weights, m and v: 8 floats = 32 bytes a parameter. (The gradient is never stored: every
// step fuses Adam into its backward pass, kernels/mlp.h.) `models` step side by side, one step
// of each in turn (an active-selection ensemble), so all of their states must fit.
double stream_bytes(const MlpShape& s, int64_t rows_per_epoch, int batch, int epochs, int models) {
  const double state = 16.0 * double(s.param_count()) * models;
  if (state <= kCacheShare) return 0;
  const double steps = double(epochs) * double((rows_per_epoch + batch - 1) / std::max(1, batch));
  return 32.0 * double(s.param_count()) * models * steps;
}

// FPE reads φ(ξ) from its representation's stored embedding of Ξ; what it computes is the
// linear probe: the normal equations [d+1, d+1] and [d+1, F] over the training rows, and the
// predictions of every row (d = embedding width, F ≤ 8 features: the count is an estimate).
double probe_flops(int64_t rows, int d) {
  constexpr int kFeatures = 8;
  return 2.0 * double(rows) * (d + 1) * (d + 1 + 2 * kFeatures);
}

int probed_width(const Task& t, const EnvSizes& z) {
  if (t.variant.method == Method::raw) return z.input_dim;
  return t.variant.method == Method::truth ? 8 : z.h.embedding_dim;
}

double default_node_bandwidth(int cores) {
  constexpr double kStreamPerCore = 15.5e9, kSocketBandwidth = 460e9;
  return std::min(kSocketBandwidth, kStreamPerCore * std::max(1, cores));
}

}  // namespace sirl
