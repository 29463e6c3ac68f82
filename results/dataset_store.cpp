#include "results/dataset_store.h"

#include <cmath>
#include <limits>

#include "datasets/environments.h"
#include "results/h5.h"

namespace sirl {
namespace {

using u64 = uint64_t;

void write_pref(H5File& f, const std::string& g, const PreferenceSet& p, const std::string& who) {
  f.write(g + "/pairs", p.pairs.data(), {u64(p.count), 2});
  f.write(g + "/label", p.label.data(), {u64(p.count)});
  f.write(g + "/human", p.human.data(), {u64(p.count)});
  f.set_attr(g, "description",
             "preference queries answered by " + who +
                 ": pairs [N,2] rows of inputs (A, B); label [N] 1 = A preferred, 0 = B, 0.5 = "
                 "equal; human [N] row of the reward set that answered");
  f.set_attr(g, "skipped", p.skipped);
}

PreferenceSet read_pref(const H5File& f, const std::string& g) {
  PreferenceSet p;
  std::vector<u64> dims;
  p.pairs = f.read_i32(g + "/pairs", {-1, 2}, &dims);
  p.count = int64_t(dims[0]);
  p.label = f.read_f32(g + "/label", {p.count});
  p.human = f.read_i32(g + "/human", {p.count});
  p.skipped = f.attr_int(g, "skipped");
  return p;
}

void write_rewards(H5File& f, const std::string& name, const RewardSet& r) {
  f.write(name, r.weights.data(), {u64(r.count), u64(r.dim)});
  f.set_attr(name, "description",
             "reward weights w [K, F] over the normalised features; R = w . phi*; unit norm rows");
}

RewardSet read_rewards(const H5File& f, const std::string& name, const std::string& short_name,
                       int F) {
  RewardSet r;
  std::vector<u64> dims;
  r.name = short_name;
  r.weights = f.read_f32(name, {-1, F}, &dims);
  r.count = int(dims[0]);
  r.dim = F;
  return r;
}

void check_index_range(const H5File& f, const std::string& name, const std::vector<int32_t>& v,
                       int64_t T) {
  for (int32_t i : v)
    if (i < 0 || i >= T)
      throw H5Error(f.path() + ": " + name + " holds row index " + std::to_string(i) +
                    " outside [0, " + std::to_string(T) + ")");
}

}  // namespace

namespace {

// /datasets/<env> attributes: the environment's registration (so figures and reports need no
// list of names), provenance and the simulated teacher.
void write_env_attrs(H5File& f, const std::string& g, const Dataset& d, const QueryBundle& q,
                     const std::string& version) {
  const u64 T = u64(d.count);
  f.set_attr(g, "env", d.env);
  const EnvSpec& e = env_spec(d.env);
  f.set_attr(g, "title", e.title);
  f.set_attr(g, "description", e.description);
  f.set_attr(g, "view", std::string(view_name(e.view)));
  f.set_attr(g, "in_claims", int64_t(e.in_claims));
  f.set_attr(g, "fig3_rank", int64_t(e.fig3_rank));
  f.set_attr(g, "vae_weak_claim", int64_t(e.vae_weak_claim));
  f.set_attr(g, "from_file", int64_t(e.from_file));
  f.set_attr(g, "beyond_paper", int64_t(e.beyond_paper));
  f.set_attr(g, "engine_version", version);
  f.set_attr(g, "generator_seed", int64_t(d.seed));
  f.set_attr(g, "query_seed", int64_t(q.seed));
  f.set_attr(g, "trajectories", int64_t(T));
  const Teacher& t = q.config.teacher;
  f.set_attr(g, "teacher_beta", t.beta);
  f.set_attr(g, "teacher_mistake", t.mistake);
  f.set_attr(g, "teacher_skip", t.skip);
  f.set_attr(g, "teacher_equal", t.equal);
  std::vector<std::string> mask;
  for (int k = 0; k < d.feature_count(); ++k)
    if (t.mask.empty() || t.mask[k]) mask.push_back(d.feature_names[k]);
  f.set_attr(g, "teacher_features", mask);
}

// Ξ: inputs, true features, objects and (sampled environments) the paths behind the inputs.
void write_trajectory_space(H5File& f, const std::string& g, const Dataset& d) {
  const u64 T = u64(d.count), F = u64(d.feature_count());
  f.write(g + "/inputs", d.inputs.data(), {T, u64(d.input_dim)});
  f.set_attr(
      g + "/inputs", "description",
      "trajectory inputs [T," + std::to_string(d.input_dim) + "] float32: " + d.input_description);
  f.write(g + "/features_raw", d.features_raw.data(), {T, F});
  f.set_attr(g + "/features_raw", "description",
             "true features phi* [T,F] in physical units (see @units)");
  f.set_attr(g + "/features_raw", "feature_names", d.feature_names);
  f.set_attr(g + "/features_raw", "units", d.feature_units);
  f.write(g + "/features", d.features.data(), {T, F});
  f.set_attr(g + "/features", "description",
             "normalised true features [T,F]: (raw - feature_min) / (feature_max - feature_min) "
             "over all T trajectories");
  f.set_attr(g + "/features", "feature_names", d.feature_names);
  f.write(g + "/feature_min", d.feature_min.data(), {F});
  f.write(g + "/feature_max", d.feature_max.data(), {F});
  f.write(g + "/objects", d.object_positions.data(),
          {u64(d.object_names.size()), u64(d.object_dim)});
  f.set_attr(g + "/objects", "names", d.object_names);
  f.set_attr(g + "/objects", "description",
             "object positions [O," + std::to_string(d.object_dim) + "] in " + d.object_units);

  if (!d.paths.empty()) {
    f.write(g + "/paths", d.paths.data(), {T, u64(d.path_len), u64(d.path_dofs)});
    f.set_attr(
        g + "/paths", "description",
        "configuration-space paths behind the inputs [T,waypoints,dofs] (joint angles, rad)");
  }
  if (!d.model_text.empty()) f.set_attr(g, "model_mjcf", d.model_text);
  if (!d.points.empty()) {
    f.write(g + "/points", d.points.data(), {T, u64(d.point_len), u64(d.point_dim)});
    f.set_attr(g + "/points", "description",
               "what a figure draws of each trajectory [T,points," + std::to_string(d.point_dim) +
                   "] (from the environment file)");
  }
}

// The reward sets and every query set of the bundle.
void write_query_bundle(H5File& f, const std::string& g, const QueryBundle& q) {
  write_rewards(f, g + "/rewards/test", q.rewards.test);
  write_rewards(f, g + "/rewards/multipref10", q.rewards.multipref10);
  write_rewards(f, g + "/rewards/multipref50", q.rewards.multipref50);
  write_rewards(f, g + "/rewards/singlepref", q.rewards.singlepref);

  f.write(g + "/queries/similarity", q.similarity.idx.data(), {u64(q.similarity.count), 3});
  f.set_attr(g + "/queries/similarity", "description",
             "similarity triplets [N,3]: rows of inputs (positive 1, positive 2, negative)");
  f.set_attr(g + "/queries/similarity", "skipped", q.similarity.skipped);
  write_pref(f, g + "/queries/singlepref", q.singlepref, "rewards/singlepref");
  write_pref(f, g + "/queries/multipref10", q.multipref10, "rewards/multipref10 (split evenly)");
  write_pref(f, g + "/queries/multipref50", q.multipref50, "rewards/multipref50 (split evenly)");

  const u64 R = q.tpa.size(), P = R ? u64(q.tpa[0].pairs.count) : 0;
  std::vector<int32_t> pairs;
  std::vector<float> labels;
  for (const auto& s : q.tpa) {
    pairs.insert(pairs.end(), s.pairs.pairs.begin(), s.pairs.pairs.end());
    labels.insert(labels.end(), s.pairs.label.begin(), s.pairs.label.end());
  }
  f.write(g + "/queries/tpa/pairs", pairs.data(), {R, P, 2});
  f.write(g + "/queries/tpa/label", labels.data(), {R, P});
  f.set_attr(g + "/queries/tpa", "description",
             "per test reward r: pairs [R,P,2] and labels [R,P]; the first @train of each reward "
             "train the head, the rest test");
  f.set_attr(g + "/queries/tpa", "train", R ? q.tpa[0].train : int64_t(0));
  f.write(g + "/queries/fpe/train", q.fpe.train.data(), {u64(q.fpe.train.size())});
  f.write(g + "/queries/fpe/test", q.fpe.test.data(), {u64(q.fpe.test.size())});
  f.set_attr(g + "/queries/fpe", "description",
             "FPE probe split: rows of inputs, 80 % train / 20 % test");
}

void read_trajectory_space(const H5File& f, const std::string& g, StoredDataset& s) {
  Dataset& d = s.data;
  std::vector<u64> dims;
  d.env = f.attr_string(g, "env");
  s.engine_version = f.attr_string(g, "engine_version");
  d.seed = uint64_t(f.attr_int(g, "generator_seed"));
  d.inputs = f.read_f32(g + "/inputs", {-1, -1}, &dims);
  d.count = int64_t(dims[0]);
  d.input_dim = int(dims[1]);
  if (d.count != f.attr_int(g, "trajectories"))
    throw H5Error(f.path() + ": " + g + "/inputs has " + std::to_string(d.count) +
                  " rows, @trajectories says " + std::to_string(f.attr_int(g, "trajectories")));
  d.feature_names = f.attr_strings(g + "/features", "feature_names");
  const int F = d.feature_count();
  d.features_raw = f.read_f32(g + "/features_raw", {d.count, F});
  d.feature_units = f.attr_strings(g + "/features_raw", "units");
  d.features = f.read_f32(g + "/features", {d.count, F});
  d.feature_min = f.read_f32(g + "/feature_min", {F});
  d.feature_max = f.read_f32(g + "/feature_max", {F});
  d.object_names = f.attr_strings(g + "/objects", "names");
  d.object_positions = f.read_f32(g + "/objects", {int64_t(d.object_names.size()), -1}, &dims);
  d.object_dim = int(dims[1]);
  if (f.exists(g + "/paths")) {
    d.paths = f.read_f32(g + "/paths", {d.count, -1, -1}, &dims);
    d.path_len = int(dims[1]);
    d.path_dofs = int(dims[2]);
    d.model_text = f.attr_string(g, "model_mjcf");
  }
  if (f.exists(g + "/points")) {
    d.points = f.read_f32(g + "/points", {d.count, -1, -1}, &dims);
    d.point_len = int(dims[1]);
    d.point_dim = int(dims[2]);
  }
}

void read_query_bundle(const H5File& f, const std::string& g, StoredDataset& s) {
  const Dataset& d = s.data;
  const int F = d.feature_count();
  std::vector<u64> dims;
  QueryBundle& q = s.queries;
  q.seed = uint64_t(f.attr_int(g, "query_seed"));
  Teacher& t = q.config.teacher;
  t.beta = f.attr_double(g, "teacher_beta");
  t.mistake = f.attr_double(g, "teacher_mistake");
  t.skip = f.attr_double(g, "teacher_skip");
  t.equal = f.attr_double(g, "teacher_equal");
  const auto perceived = f.attr_strings(g, "teacher_features");
  if (int(perceived.size()) != F) {
    t.mask.assign(F, 0);
    for (int k = 0; k < F; ++k)
      for (const auto& p : perceived) t.mask[k] |= p == d.feature_names[k];
  }
  q.rewards.test = read_rewards(f, g + "/rewards/test", "test", F);
  q.rewards.multipref10 = read_rewards(f, g + "/rewards/multipref10", "multipref10", F);
  q.rewards.multipref50 = read_rewards(f, g + "/rewards/multipref50", "multipref50", F);
  q.rewards.singlepref = read_rewards(f, g + "/rewards/singlepref", "singlepref", F);
  q.similarity.idx = f.read_i32(g + "/queries/similarity", {-1, 3}, &dims);
  q.similarity.count = int64_t(dims[0]);
  q.similarity.skipped = f.attr_int(g + "/queries/similarity", "skipped");
  check_index_range(f, g + "/queries/similarity", q.similarity.idx, d.count);
  q.singlepref = read_pref(f, g + "/queries/singlepref");
  q.multipref10 = read_pref(f, g + "/queries/multipref10");
  q.multipref50 = read_pref(f, g + "/queries/multipref50");
  for (const auto* p : {&q.singlepref, &q.multipref10, &q.multipref50})
    check_index_range(f, g + "/queries", p->pairs, d.count);
  const auto pairs = f.read_i32(g + "/queries/tpa/pairs", {q.rewards.test.count, -1, 2}, &dims);
  const int64_t P = int64_t(dims[1]);
  const auto labels = f.read_f32(g + "/queries/tpa/label", {q.rewards.test.count, P});
  check_index_range(f, g + "/queries/tpa/pairs", pairs, d.count);
  const int64_t train = f.attr_int(g + "/queries/tpa", "train");
  for (int r = 0; r < q.rewards.test.count; ++r) {
    TpaSet s_r;
    s_r.train = train;
    s_r.pairs.count = P;
    s_r.pairs.pairs.assign(pairs.begin() + r * P * 2, pairs.begin() + (r + 1) * P * 2);
    s_r.pairs.label.assign(labels.begin() + r * P, labels.begin() + (r + 1) * P);
    s_r.pairs.human.assign(P, r);
    q.tpa.push_back(std::move(s_r));
  }
  q.fpe.train = f.read_i32(g + "/queries/fpe/train", {-1});
  q.fpe.test = f.read_i32(g + "/queries/fpe/test", {-1});
  check_index_range(f, g + "/queries/fpe", q.fpe.train, d.count);
  check_index_range(f, g + "/queries/fpe", q.fpe.test, d.count);
  q.config.similarity = q.similarity.count;
  q.config.preference = q.singlepref.count;
  q.config.tpa_pairs = P;
  q.config.fpe_trajectories = int64_t(q.fpe.train.size() + q.fpe.test.size());
}

}  // namespace

void write_dataset(H5File& f, const Dataset& d, const QueryBundle& q, const std::string& version) {
  const std::string g = "/datasets/" + d.env;
  f.group(g);
  write_env_attrs(f, g, d, q, version);
  write_trajectory_space(f, g, d);
  write_query_bundle(f, g, q);
  f.flush();
}

void write_seed_queries(H5File& f, const std::string& env, int64_t seed, const QueryBundle& q) {
  const std::string g = "/datasets/" + env + "/seeds/s" + std::to_string(seed);
  f.group(g);
  f.set_attr(g, "seed", seed);
  f.set_attr(g, "query_seed", int64_t(q.seed));
  f.set_attr(g, "description",
             "seed " + std::to_string(seed) +
                 "'s rewards and query sets, answered by the profile's teacher (rows of "
                 "/datasets/" +
                 env + "/inputs)");
  write_query_bundle(f, g, q);
}

StoredDataset read_dataset(const H5File& f, const std::string& env) {
  const std::string g = "/datasets/" + env;
  if (!f.exists(g))
    throw H5Error(f.path() + ": no dataset for env '" + env + "' (missing group " + g + ")");
  StoredDataset s;
  read_trajectory_space(f, g, s);
  read_query_bundle(f, g, s);
  return s;
}

}  // namespace sirl
