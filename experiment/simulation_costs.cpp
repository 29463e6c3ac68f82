#include "experiment/simulation_costs.h"

#include <algorithm>

#include "datasets/queries.h"
#include "engine/method_catalog.h"
#include "engine/tpa.h"
#include "experiment/cost_model.h"
#include "experiment/expected_epochs.h"
#include "experiment/task_config.h"
#include "kernels/linear_bradley_terry.h"
#include "kernels/vae.h"

namespace sirl {

void vae_cost(Task& t, const Profile& p) {
  const EnvSizes z = env_sizes(t, p);
  const VaeShape vs = make_vae_shape(z.input_dim, z.h.phi_hidden, z.h.embedding_dim);
  // training, then one pass over Ξ measuring the posterior (train_vae)
  t.flops = vs.encoder.train_flops(z.trajectories, z.h.vae.epochs) +
            vs.decoder.train_flops(z.trajectories, z.h.vae.epochs) +
            vs.encoder.forward_flops(int(z.trajectories)) +
            vs.decoder.forward_flops(int(z.trajectories));
  t.bytes = working_set(vs.encoder, z.h.vae.batch) + working_set(vs.decoder, z.h.vae.batch);
  t.stream_bytes = stream_bytes(vs.encoder, z.trajectories, z.h.vae.batch, z.h.vae.epochs) +
                   stream_bytes(vs.decoder, z.trajectories, z.h.vae.batch, z.h.vae.epochs);
}

void rep_cost(Task& t, const Profile& p) {
  const EnvSizes z = env_sizes(t, p);
  t.flops = 0;
  if (t.variant.method == Method::external) {  // reads its embedding of Ξ: no arithmetic
    t.protocol_flops = 0;
    t.bytes = 4.0 * double(z.trajectories) * double(z.h.embedding_dim);
    return;
  }
  // A trained method: `rows_per_answer` rows through φ per answer, every epoch of its schedule.
  if (const MethodTraining& how = method_spec(t.variant.method).training; how.train) {
    const TrainSchedule& s = z.h.*how.schedule;
    const int64_t rows = how.rows_per_answer * t.N;
    const int batch_rows = how.rows_per_answer * s.batch;
    t.protocol_flops = z.phi.train_flops(rows, s.epochs);
    t.flops = t.protocol_flops;
    // Trainings that end at their fixed point (the exact skip): what they are expected to run.
    if (how.stops_at_fixed_point)
      if (const double e = expected_sirl_epochs(t.env, t.N, t.variant.vae, z.h); e < s.epochs)
        t.flops *= e / s.epochs;
    t.bytes = working_set(z.phi, batch_rows);
    t.stream_bytes = stream_bytes(z.phi, rows, batch_rows, s.epochs);
    // Preference φ stopped by pref.stop: the epochs they are expected to run, their traffic too.
    if (how.preferences)
      if (const double e = expected_pref_epochs(t.env, method_spec(t.variant.method).name, t.N,
                                                t.variant.vae, z.h);
          e < s.epochs) {
        t.flops *= e / s.epochs;
        t.stream_bytes *= e / s.epochs;
      }
  }
  t.flops += z.phi.forward_flops(int(z.trajectories));  // the embedding of Ξ it stores
  t.protocol_flops += z.phi.forward_flops(int(z.trajectories));
}

void fpe_cost(Task& t, const Profile& p) {
  const EnvSizes z = env_sizes(t, p);
  const int w = probed_width(t, z);
  t.flops = probe_flops(p.queries.fpe_trajectories, w);
  t.bytes = 4.0 * double(p.queries.fpe_trajectories) * (w + 16);
}

void tpa_cost(Task& t, const Profile& p) {
  const EnvSizes z = env_sizes(t, p);
  const Hyper& h = t.hyper_values();
  const MlpShape net = tpa_network(z.phi, h, t.frozen);
  t.protocol_flops = kTestRewards * net.train_flops(2 * t.M, h.tpa.epochs);
  // Under tpa.stop = "converged" the heads stop early: what they are expected to run.
  t.flops = t.protocol_flops;
  if (const double e = expected_head_epochs(t.env, t.frozen, t.M, h); e < h.tpa.epochs)
    t.flops *= e / h.tpa.epochs;
  t.bytes = kTestRewards * working_set(net, 2 * h.tpa.batch);
  // The heads train one after another (engine/tpa.h): what must fit the cache is one head's.
  t.stream_bytes = kTestRewards * stream_bytes(net, 2 * t.M, 2 * h.tpa.batch, h.tpa.epochs);
  if (t.flops < t.protocol_flops) t.stream_bytes *= t.flops / t.protocol_flops;
}

void linear_tpa_cost(Task& t, const Profile& p) {
  const EnvSizes z = env_sizes(t, p);
  // Per reward: the standardisation, Gram matrix of the smaller side of ≤ M pair differences × w
  // features and its eigensolver once per fold and once for the final fit (every penalty of the
  // grid reuses its fold's), then about 10 Newton steps in the span per (fold, penalty) and for
  // the final fit; then the rewards of the held-out rows.
  const LinearBtOptions o;
  const double spans = double(o.folds) + 1;
  const double fits = double(o.alpha_grid.size()) * o.folds + 1;
  const double w = probed_width(t, z), m = double(t.M), g = std::min(w, m);
  const double held = 2.0 * double(queries_for(p, t.teacher).tpa_pairs);
  const double n = 2.0 * m;
  t.flops = kTestRewards * (spans * (6 * m * w + 2 * m * w * g + 9 * g * g * g) +
                            fits * 10 * 2 * m * g * g + 2 * held * w);
  t.protocol_flops = t.flops;
  t.bytes = 8.0 * ((n + held) * w + 2 * g * g + n * w);
}

ActiveConfig active_config(const Task& t, const Profile& p, const Hyper& hyper) {
  ActiveConfig c;
  static_cast<ActiveRounds&>(c) = p.active.at(t.env);
  c.rule = t.variant.selection;
  c.budget = queries_for(p, t.teacher).similarity;  // as many as the uniform set holds
  c.hyper = hyper;
  return c;
}

void active_cost(Task& t, const Profile& p) {
  const EnvSizes z = env_sizes(t, p);
  const ActiveConfig& c = *t.compiled().active;
  // Round r ≥ 1 trains K members for E epochs on the r·batch triplets answered before it, then
  // embeds its pool's rows (≤ 3·pool) with each member.
  t.flops = 0;
  const int64_t rounds = (c.budget + c.batch - 1) / c.batch;
  for (int64_t r = 1; r < rounds; ++r) {
    t.flops += c.members * z.phi.train_flops(3 * std::min(c.budget, r * c.batch), c.round_epochs);
    t.flops += c.members * z.phi.forward_flops(int(std::min<int64_t>(3 * c.pool, z.trajectories)));
  }
  t.bytes = c.members * working_set(z.phi, 3 * z.h.sirl.batch);
  t.stream_bytes = 0;
  for (int64_t r = 1; r < rounds; ++r)
    t.stream_bytes += stream_bytes(z.phi, 3 * std::min(c.budget, r * c.batch), 3 * z.h.sirl.batch,
                                   c.round_epochs, c.members);
}

}  // namespace sirl
