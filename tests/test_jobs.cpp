// Profiles, plans, the scheduler and the task store (the batch engine's parts, without a run).
#include <gtest/gtest.h>

#include <unistd.h>

#include <map>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>

#include "jobs/estimate.h"
#include "jobs/plan.h"
#include "jobs/profile.h"
#include "jobs/run.h"
#include "jobs/scheduler.h"
#include "jobs/task_outputs.h"
#include "results/h5.h"
#include "results/task_store.h"

namespace sirl {
namespace {

const char* kProfile = R"(
name = "t"
envs = ["grid"]
seeds = [0, 1, 2]
[queries]
similarity = 300
preference = 300
tpa_pairs = 100
[fpe]
methods = ["sirl", "sirl+vae", "vae", "random"]
N = [100, 200, 300]
[tpa]
methods = ["sirl", "multipref10", "random"]
N = [100, 300]
M = [10, 80]
[ablation]
methods = ["sirl", "random"]
N = [300]
M = [80]
[hyper.grid]
"sirl.epochs" = 7
"tpa.hidden" = [32, 16]
)";

TEST(Profile, ParsesTheGridAndOverrides) {
  const Profile p = parse_profile(kProfile, "t.toml");
  EXPECT_EQ(p.name, "t");
  EXPECT_EQ(p.seeds, (std::vector<int64_t>{0, 1, 2}));
  ASSERT_EQ(p.fpe_methods.size(), 4u);
  EXPECT_TRUE(p.fpe_methods[1].vae);
  EXPECT_EQ(p.fpe_methods[1].method, Method::sirl);
  EXPECT_EQ(p.hyper.at("grid").sirl.epochs, 7);
  EXPECT_EQ(p.hyper.at("grid").tpa_hidden, (std::vector<int>{32, 16}));
  EXPECT_EQ(p.hyper.at("grid").pref.epochs, 5000);  // untouched: the paper's value
  EXPECT_EQ(p.queries.similarity, 300);
}

TEST(Plan, TaskCountsMatchTheGrid) {
  const Profile p = parse_profile(kProfile, "t.toml");
  const Plan plan = make_plan(p);
  const int S = 3;
  // VAE: one per seed (sirl+vae and vae need it).
  EXPECT_EQ(plan.count(TaskKind::vae), S);
  // FPE: sirl, sirl+vae × 3 N; vae and random once each (no N).
  EXPECT_EQ(plan.count(TaskKind::fpe), S * (2 * 3 + 2));
  // TPA main: sirl (frozen) and multipref10 (unfrozen) × 2 N × 2 M; random (unfrozen) × 2 M.
  // Ablation: sirl, sirl+vae × 2 frozen × 1 M; random × 2 frozen. Cells shared with the main
  // grid (sirl N300 M80 frozen; random M80 unfrozen) are counted once.
  const int main_cells = 2 * 2 * 2 + 2;
  const int ablation_new = 2 * 2 + 2 - 2;
  EXPECT_EQ(plan.count(TaskKind::tpa), S * (main_cells + ablation_new));
  // Representations: sirl N100/200/300, sirl+vae N100/200/300, vae, random, multipref10 N100/300.
  EXPECT_EQ(plan.count(TaskKind::rep), S * (3 + 3 + 1 + 1 + 2));
  // Every dependency precedes its dependent, and every FPE/TPA task depends on one rep.
  for (size_t i = 0; i < plan.tasks.size(); ++i) {
    for (int d : plan.tasks[i].deps) EXPECT_LT(size_t(d), i);
    if (plan.tasks[i].kind == TaskKind::fpe || plan.tasks[i].kind == TaskKind::tpa) {
      ASSERT_EQ(plan.tasks[i].deps.size(), 1u);
      EXPECT_EQ(plan.tasks[plan.tasks[i].deps[0]].kind, TaskKind::rep);
    }
  }
  std::set<std::string> keys;
  for (const auto& t : plan.tasks) EXPECT_TRUE(keys.insert(t.key).second) << t.key;
}

// frozen = "best" (the default): SIRL frozen, every other method unfrozen (the paper's best
// configurations, Fig. 5); an explicit list runs the listed modes for every method.
TEST(Plan, FrozenBestIsSirlFrozenAndTheOthersUnfrozen) {
  const Plan plan = make_plan(parse_profile(kProfile, "t.toml"));
  int sirl = 0, others = 0;
  for (const auto& t : plan.tasks) {
    if (t.kind != TaskKind::tpa || !t.in_main) continue;
    if (t.variant.method == Method::sirl) {
      EXPECT_TRUE(t.frozen) << t.key;
      ++sirl;
    } else {
      EXPECT_FALSE(t.frozen) << t.key;
      ++others;
    }
  }
  EXPECT_GT(sirl, 0);
  EXPECT_GT(others, 0);
  std::string both = kProfile;
  both.replace(both.find("M = [10, 80]"), 12, "M = [10, 80]\nfrozen = [true, false]");
  const Plan p2 = make_plan(parse_profile(both, "t.toml"));
  EXPECT_TRUE(p2.index.count("grid/s0/multipref10/N100/tpa/M10/frozen"));
  EXPECT_TRUE(p2.index.count("grid/s0/sirl/N100/tpa/M10/unfrozen"));
}

// sirl plan's estimate: each task takes its FLOPs over its kind's measured rate plus 2 ms, the
// one-thread total is their sum, and the parallel time lies between total/threads and the total.
TEST(Plan, EstimateAddsEachTasksFlopsOverItsKindsRate) {
  const Profile p = parse_profile(kProfile, "t.toml");
  const Plan plan = make_plan(p);
  const PlanEstimate e = estimate_plan(plan, p, 2);
  double total = 0;
  for (const auto& t : plan.tasks) {
    std::string kind = kind_name(t.kind);
    if (t.kind == TaskKind::rep) kind = t.variant.method == Method::sirl ? "rep_sirl" : "rep_pref";
    if (t.kind == TaskKind::tpa) kind = t.frozen ? "tpa_frozen" : "tpa_unfrozen";
    const auto it = e.gflops_per_s.find(t.env + "/" + kind);
    const double rate = it == e.gflops_per_s.end() ? 1e9 : std::max(it->second, 1e-3) * 1e9;
    total += t.flops / rate + 0.002;
  }
  for (const char* k : {"grid/rep_sirl", "grid/rep_pref", "grid/vae", "grid/tpa_frozen"})
    EXPECT_GT(e.gflops_per_s.at(k), 0.01) << k;  // measured, not the default
  EXPECT_NEAR(e.seconds_one_thread, total, 1e-9 * total);
  EXPECT_GE(e.seconds, total / 2 - 1e-9);
  EXPECT_LE(e.seconds, total + 1e-9);
  EXPECT_GT(e.peak_bytes, 0);
}

TEST(Plan, CostModelCountsTheFlopsByHand) {
  const Plan plan = make_plan(parse_profile(kProfile, "t.toml"));
  // φ 19→128→128→6: 2·(19·128 + 128·128 + 128·6) = 39,168 FLOPs per sample forward.
  const double phi = 2.0 * (19 * 128 + 128 * 128 + 128 * 6);
  // SIRL at N = 100 for 7 epochs: 3 (fwd + bwd) × 3N samples × epochs, plus embedding Ξ (1960).
  EXPECT_DOUBLE_EQ(plan.tasks[plan.index.at("grid/s0/sirl/N100/rep")].flops,
                   3 * phi * 300 * 7 + phi * 1960);
  // Random trains nothing: only the embedding of Ξ.
  EXPECT_DOUBLE_EQ(plan.tasks[plan.index.at("grid/s0/random/rep")].flops, phi * 1960);
  // A frozen TPA cell, head 6→32→16→1 (1,440 FLOPs forward), 20 heads × 2M = 20 samples × 500.
  const double head = 2.0 * (6 * 32 + 32 * 16 + 16 * 1);
  EXPECT_DOUBLE_EQ(plan.tasks[plan.index.at("grid/s0/sirl/N100/tpa/M10/frozen")].flops,
                   20 * 3 * head * 20 * 500);
}

TEST(Plan, ShardsPartitionTheWorkAndKeepDependencies) {
  const Plan plan = make_plan(parse_profile(kProfile, "t.toml"));
  std::vector<int> owners(plan.tasks.size(), 0);
  for (int s = 0; s < 3; ++s) {
    const auto in = shard_tasks(plan, s, 3);
    for (size_t i = 0; i < in.size(); ++i) {
      if (!in[i]) continue;
      if (plan.tasks[i].kind != TaskKind::vae) ++owners[i];
      for (int d : plan.tasks[i].deps) EXPECT_TRUE(in[d]) << plan.tasks[i].key;
    }
  }
  for (size_t i = 0; i < plan.tasks.size(); ++i)
    if (plan.tasks[i].kind != TaskKind::vae) EXPECT_EQ(owners[i], 1) << plan.tasks[i].key;
}

// The message of the ProfileError thrown for `text`.
std::string error_of(const std::string& text) {
  try {
    parse_profile(text, "bad.toml");
  } catch (const ProfileError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Profile, MalformedProfilesAreRejectedWithFileLineAndExpectation) {
  const std::string base = "name = \"x\"\nenvs = [\"grid\"]\nseeds = [0]\n";
  const std::string grid =
      "[fpe]\nmethods = [\"sirl\"]\nN = [100]\n[tpa]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n";
  EXPECT_EQ(error_of(base + grid), "no error");
  // An unknown key, on line 4.
  EXPECT_EQ(error_of(base + "sedes = [1]\n" + grid).rfind("bad.toml:4: unknown key 'sedes'", 0), 0u)
      << error_of(base + "sedes = [1]\n" + grid);
  // A wrong type.
  EXPECT_NE(error_of("name = \"x\"\nenvs = \"grid\"\nseeds = [0]\n" + grid)
                .find("bad.toml:2: envs must be an array of strings"),
            std::string::npos);
  // An unknown method, with the list of valid ones.
  auto m = error_of(base + "[fpe]\nmethods = [\"sirl\", \"pca\"]\nN = [100]\n" +
                    "[tpa]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n");
  EXPECT_NE(m.find("bad.toml:5"), std::string::npos) << m;
  EXPECT_NE(m.find("unknown method 'pca'"), std::string::npos) << m;
  EXPECT_NE(m.find("multipref10"), std::string::npos) << m;
  // M beyond the TPA training split.
  m = error_of(base + grid + "[queries]\ntpa_pairs = 10\n");
  EXPECT_NE(m.find("M = 10 exceeds the 8 training pairs"), std::string::npos) << m;
  m = error_of(base + "[fpe]\nmethods = [\"sirl\"]\nN = [5000]\n" +
               "[tpa]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n");
  EXPECT_NE(m.find("exceeds the query budget"), std::string::npos) << m;
  // A bad hyper-parameter, named.
  m = error_of(base + grid + "[hyper.grid]\n\"sirl.epoch\" = 3\n");
  EXPECT_NE(m.find("bad.toml:12"), std::string::npos) << m;
  EXPECT_NE(m.find("unknown hyper-parameter 'sirl.epoch'"), std::string::npos) << m;
  m = error_of(base + grid + "[hyper.grid]\n\"sirl.lr\" = -1\n");
  EXPECT_NE(m.find("sirl.lr must be > 0"), std::string::npos) << m;
  // "+vae" only where it applies; a missing table; TOML syntax errors keep their line.
  EXPECT_NE(error_of(base + "[fpe]\nmethods = [\"random+vae\"]\nN = [100]\n" +
                     "[tpa]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n")
                .find("VAE pre-training applies only"),
            std::string::npos);
  EXPECT_NE(error_of(base).find("nothing to run: give at least one of [fpe], [tpa], [ablation] or [study]"),
            std::string::npos)
      << error_of(base);
  EXPECT_NE(error_of(base + grid + "[grid]\nstore_weights = 1\n").find("store_weights must be"),
            std::string::npos);
  m = error_of(base + grid + "[hyper.grid]\n\"vae.elbo\" = \"avg\"\n");
  EXPECT_NE(m.find("vae.elbo must be \"sum\""), std::string::npos) << m;
  EXPECT_EQ(error_of(base + "[fpe\n").rfind("bad.toml:4:", 0), 0u) << error_of(base + "[fpe\n");
  EXPECT_NE(error_of(base + grid + "[teacher]\nmistake = 2\n").find("outside [0, 1]"),
            std::string::npos);
  // A duplicate method is refused like a duplicate seed (it used to be dropped silently).
  m = error_of(base + "[fpe]\nmethods = [\"sirl\", \"random\", \"sirl\"]\nN = [100]\n");
  EXPECT_NE(m.find("'sirl' is listed twice"), std::string::npos) << m;
  // A network that cannot fit is refused with its size, before anything allocates it.
  m = error_of(base + grid + "[hyper.grid]\n\"phi.hidden\" = [100000000, 100000000]\n");
  EXPECT_NE(m.find("GiB to train, this machine has"), std::string::npos) << m;
  // A float in an integer list: one file:line prefix, not two.
  m = error_of(base + grid + "[hyper.grid]\n\"phi.hidden\" = [1e8, 1e8]\n");
  EXPECT_EQ(m.find("bad.toml", 1), std::string::npos) << m;
  EXPECT_NE(m.find("must be an array of integers"), std::string::npos) << m;
}

// A profile may run any part of the grid: FPE only, TPA only, or the ablation only.
TEST(Profile, APartOfTheGridIsAProfileOfItsOwn) {
  const std::string base = "name = \"x\"\nenvs = [\"grid\", \"grid2\"]\nseeds = [0]\n";
  auto kinds = [](const Plan& plan) {
    std::map<std::string, int> n;
    for (const auto& t : plan.tasks) ++n[kind_name(t.kind)];
    return n;
  };
  auto fpe_only =
      kinds(make_plan(parse_profile(base + "[fpe]\nmethods = [\"sirl\"]\nN = [100]\n")));
  EXPECT_EQ(fpe_only["fpe"], 2);  // one per environment
  EXPECT_EQ(fpe_only["rep"], 2);
  EXPECT_EQ(fpe_only["tpa"], 0);
  auto tpa_only = kinds(
      make_plan(parse_profile(base + "[tpa]\nmethods = [\"random\"]\nN = [100]\nM = [10, 20]\n")));
  EXPECT_EQ(tpa_only["tpa"], 4);
  EXPECT_EQ(tpa_only["fpe"], 0);
  const Plan ab =
      make_plan(parse_profile(base + "[ablation]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n"));
  auto ab_kinds = kinds(ab);
  EXPECT_EQ(ab_kinds["tpa"], 2 * 4);  // frozen/unfrozen × with/without VAE, per environment
  EXPECT_EQ(ab_kinds["vae"], 2);
  for (const auto& t : ab.tasks)
    if (t.kind == TaskKind::tpa) EXPECT_TRUE(t.in_ablation && !t.in_main) << t.key;
}

// Fig. 5 and Fig. 7 read which cells belong to them from the file; the plan marks a cell both
// when the two grids share it.
TEST(Plan, MarksTheCellsOfTheMainGridAndOfTheAblation) {
  const std::string text =
      "name = \"x\"\nenvs = [\"grid\"]\nseeds = [0]\n[tpa]\nmethods = [\"sirl\"]\nN = [100]\n"
      "M = [10, 20]\n[ablation]\nmethods = [\"sirl\"]\nN = [100]\nM = [20]\n";
  const Plan plan = make_plan(parse_profile(text));
  const auto& frozen20 = plan.tasks[plan.index.at("grid/s0/sirl/N100/tpa/M20/frozen")];
  EXPECT_TRUE(frozen20.in_main && frozen20.in_ablation);
  const auto& frozen10 = plan.tasks[plan.index.at("grid/s0/sirl/N100/tpa/M10/frozen")];
  EXPECT_TRUE(frozen10.in_main && !frozen10.in_ablation);
  const auto& unfrozen20 = plan.tasks[plan.index.at("grid/s0/sirl/N100/tpa/M20/unfrozen")];
  EXPECT_TRUE(!unfrozen20.in_main && unfrozen20.in_ablation);
}

TEST(Profile, ShippedProfilesAreValid) {
  for (const char* name : {"smoke", "quick", "paper", "paper-grid"}) {
    const Profile p = load_profile(name);
    EXPECT_EQ(p.name, name);
    EXPECT_GT(make_plan(p).tasks.size(), 0u);
  }
  EXPECT_THROW(load_profile("no-such-profile"), ProfileError);
}

TEST(Scheduler, RunsEveryPendingTaskAfterItsDependencies) {
  const Plan plan = make_plan(parse_profile(kProfile, "t.toml"));
  const int n = int(plan.tasks.size());
  std::vector<char> pending(n, 1);
  pending[0] = 0;  // already done: its dependents must still run
  std::mutex mu;
  std::vector<int> order_of(n, -1);
  int next = 0;
  run_dag(plan, pending, 2, [&](int i) {
    std::lock_guard lock(mu);
    for (int d : plan.tasks[i].deps)
      if (pending[d]) EXPECT_GE(order_of[d], 0) << plan.tasks[i].key << " before its input";
    order_of[i] = next++;
  });
  EXPECT_EQ(next, n - 1);
  EXPECT_EQ(order_of[0], -1);
}

TEST(Scheduler, StopsAtTheFirstErrorAndRethrowsIt) {
  // 40 independent tasks (none waits for another, so only the stop flag can keep them from
  // running) on one thread: the first task to run throws, and no other task may start after it.
  Plan plan;
  for (int i = 0; i < 40; ++i) {
    Task t;
    t.key = "t" + std::to_string(i);
    t.flops = 40 - i;  // t0 has the highest rank: it runs first
    plan.index[t.key] = i;
    plan.tasks.push_back(t);
  }
  std::atomic<int> ran{0};
  const std::vector<char> pending(plan.tasks.size(), 1);
  try {
    run_dag(plan, pending, 1, [&](int i) {
      ++ran;
      throw std::runtime_error("boom in " + plan.tasks[i].key);
    });
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "boom in t0");
  }
  EXPECT_EQ(ran.load(), 1);
}

// The resumed path rebuilds φ and the VAE from records with the same get_* the fresh path uses;
// everything a later task reads must survive the trip, including shape flags the profile does
// not determine (the VAE method's φ keeps a linear output even under phi.relu_output = true).
TEST(TaskOutputs, RepresentationAndVaeRoundTripThroughARecordAndAFile) {
  Representation r;
  r.shape.widths = {5, 7, 3};
  r.shape.relu_on_output = true;
  r.shape.linear_layers = {0};
  r.params.resize(r.shape.param_count());
  for (size_t i = 0; i < r.params.size(); ++i) r.params[i] = float(i) * 0.25f - 3;
  r.method = Method::multipref50;
  r.vae_pretrain = true;
  r.queries = 321;
  r.loss_curve = {3, 2, 1.5f};
  r.train_flops = 12345;
  TaskRecord rec;
  rec.key = "grid/s0/multipref50+vae/N321/rep";
  put_representation(r, rec);
  const auto path = std::filesystem::temp_directory_path() /
                    ("sirl_task_outputs_" + std::to_string(::getpid()) + ".h5");
  {
    H5File f = H5File::create(path);
    write_record(f, "/r", rec);
  }
  const TaskRecord back = read_record(H5File::open_read(path), "/r");
  const Representation g = get_representation(back);
  EXPECT_EQ(g.shape.widths, r.shape.widths);
  EXPECT_EQ(g.shape.relu_on_output, true);
  EXPECT_EQ(g.shape.linear_layers, r.shape.linear_layers);
  EXPECT_EQ(g.params, r.params);
  EXPECT_EQ(g.method, r.method);
  EXPECT_EQ(g.vae_pretrain, true);
  EXPECT_EQ(g.queries, 321);
  EXPECT_EQ(g.loss_curve, r.loss_curve);
  EXPECT_EQ(g.train_flops, 12345);

  VaeModel v;
  v.shape = make_vae_shape(5, {4}, 2);
  v.params.assign(v.shape.param_count(), 0.5f);
  v.elbo = VaeElbo::mean_over_inputs;
  v.loss_curve = {4, 3};
  v.reconstruction_curve = {3.5f, 2.5f};
  v.kl_curve = {50, 50};
  v.kl_per_dim = {0.002f, 1.5f};
  v.latent_mean = {0.5f, -2};
  v.latent_std = {3, 0.25f};
  v.standardize = false;
  v.reconstruction_mse = 0.125;
  v.train_flops = 99;
  TaskRecord vr;
  vr.key = "grid/s0/vae";
  put_vae(v, vr);
  const VaeModel w = get_vae(deserialize(serialize(vr)));
  EXPECT_EQ(w.shape.encoder.widths, v.shape.encoder.widths);
  EXPECT_EQ(w.shape.decoder.widths, v.shape.decoder.widths);
  EXPECT_EQ(w.params, v.params);
  EXPECT_EQ(w.elbo, VaeElbo::mean_over_inputs);
  EXPECT_EQ(w.loss_curve, v.loss_curve);
  EXPECT_EQ(w.reconstruction_curve, v.reconstruction_curve);
  EXPECT_EQ(w.kl_curve, v.kl_curve);
  EXPECT_EQ(w.kl_per_dim, v.kl_per_dim);
  EXPECT_EQ(w.latent_mean, v.latent_mean);
  EXPECT_EQ(w.latent_std, v.latent_std);
  EXPECT_FALSE(w.standardize);
  EXPECT_EQ(w.reconstruction_mse, 0.125);
  EXPECT_EQ(w.train_flops, 99);
  // The φ a VAE method task hands on keeps the VAE's curve (a resumed run's did not, once).
  EXPECT_EQ(vae_mean_encoder(w).loss_curve, v.loss_curve);

  // A record without weights (store_weights = false) names what is missing.
  vr.arrays.erase("params");
  try {
    get_vae(vr);
    ADD_FAILURE() << "a VAE without params was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("grid/s0/vae: the stored record has no 'params'"),
              std::string::npos)
        << e.what();
  }
  std::filesystem::remove(path);
}

// A byte flipped in a committed task's data (here a weight of a 4096-float array, which HDF5
// itself never checks) is caught by the record's checksum: refused with the task's name, the
// file removed so that a rerun computes the task again.
TEST(TaskStore, ACorruptedCommitIsRefusedByNameAndRemoved) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("sirl_task_store_corrupt_" + std::to_string(getpid()));
  fs::remove_all(dir);
  TaskRecord r;
  r.key = "grid/s0/sirl/N100/rep";
  r.kind = "rep";
  r.text["env"] = "grid";
  std::vector<float> w(4096);
  for (size_t i = 0; i < w.size(); ++i) w[i] = 0.25f + float(i);
  r.arrays["params"] = {{4096}, w};
  TaskStore s(dir);
  s.commit(r);
  EXPECT_EQ(s.load(r.key), r);
  // Find weight 2000 (2000.25f) in the file and flip one bit of it.
  fs::path file;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".h5") file = e.path();
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const float target = 2000.25f;
  const size_t at = bytes.find(std::string(reinterpret_cast<const char*>(&target), 4));
  ASSERT_NE(at, std::string::npos);
  bytes[at] = char(bytes[at] ^ 0x01);
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
  try {
    s.load(r.key);
    ADD_FAILURE() << "a corrupted task was loaded";
  } catch (const H5Error& e) {
    EXPECT_NE(std::string(e.what()).find("task grid/s0/sirl/N100/rep"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("corrupted"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(TaskStore(dir).has(r.key));  // a rerun computes it again
  fs::remove_all(dir);
}

// (Durability under a crash is batch_engine.py's kill -9 test; this one is the file format.)
TEST(TaskStore, CommitsRoundTripAndTornCommitsAreSwept) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("sirl_task_store_test_" + std::to_string(getpid()));
  fs::remove_all(dir);
  TaskRecord r;
  r.key = "grid/s0/sirl/N100/tpa/M10/frozen";
  r.kind = "tpa";
  r.text["env"] = "grid";
  r.num["tpa"] = 0.8125;
  r.arrays["loss_curves"] = {{2, 3}, {1, 2, 3, 4, 5, 6}};
  r.arrays["empty"] = {{0}, {}};
  {
    TaskStore s(dir);
    s.commit(r);
    EXPECT_TRUE(s.has(r.key));
  }
  std::ofstream(dir / "0123456789abcdef.h5.tmp") << "torn";  // an interrupted commit
  TaskStore again(dir);
  EXPECT_EQ(again.keys(), std::vector<std::string>{r.key});
  EXPECT_EQ(again.load(r.key), r);
  EXPECT_FALSE(fs::exists(dir / "0123456789abcdef.h5.tmp"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sirl
