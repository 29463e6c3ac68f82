// `sirl dataset`: build an environment's trajectory space, answer every query set with a
// simulated teacher, and store it all in HDF5. `sirl inspect`: read one back and summarise it.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "app/commands.h"
#include "build_info.h"
#include "datasets/environments.h"
#include "datasets/grid_robot.h"
#include "datasets/jaco_robot.h"
#include "experiment/install_paths.h"
#include "experiment/profile.h"
#include "experiment/task_runner.h"
#include "results/dataset_store.h"
#include "results/file_lock.h"
#include "results/h5.h"
#include "results/results_file.h"

namespace sirl::app {
namespace {

struct DatasetArgs {
  std::string env = "grid", out;
  uint64_t seed = 0;
  int64_t similarity = 1000, preference = 1000, tpa_pairs = 250, fpe = 1000;
  double beta = std::numeric_limits<double>::infinity(), mistake = 0, skip = 0, equal = 0;
  std::vector<std::string> features;
  std::vector<int> obstacle1{1, 3}, obstacle2{3, 1}, laptop{2, 2};
  int64_t trajectories = 0;  // a sampled environment's Ξ size; 0: the environment's default
  std::vector<double> jaco_laptop{0.0, -0.8, 0.0}, jaco_human{-0.2, -0.5, 0.6};
  int threads = 0;
  bool force = false;
  std::string profile;  // --profile: a profile's training data instead
};

Teacher make_teacher(const DatasetArgs& a, const Dataset& d) {
  Teacher t{a.beta, a.mistake, a.skip, a.equal, {}};
  if (!a.features.empty()) {
    t.mask.assign(d.feature_count(), 0);
    for (const auto& name : a.features) {
      bool found = false;
      for (int k = 0; k < d.feature_count(); ++k)
        if (d.feature_names[k] == name) t.mask[k] = 1, found = true;
      if (!found) {
        std::string known;
        for (const auto& n : d.feature_names) known += (known.empty() ? "" : ", ") + n;
        throw UsageError("--features: unknown feature '" + name + "' (known: " + known + ")");
      }
    }
  }
  try {
    validate(t, d.feature_count());
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  return t;
}

int run_dataset(const DatasetArgs& a) {
  Dataset d;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    EnvConfig c;
    c.grid.obstacle1 = {a.obstacle1[0], a.obstacle1[1]};
    c.grid.obstacle2 = {a.obstacle2[0], a.obstacle2[1]};
    c.grid.laptop = {a.laptop[0], a.laptop[1]};
    c.jaco.threads = a.threads;
    for (int k = 0; k < 3; ++k)
      c.jaco.laptop[k] = a.jaco_laptop[k], c.jaco.human[k] = a.jaco_human[k];
    // A sampled Ξ (JacoRobot, Driver): --trajectories or its own default size, drawn from --seed.
    const EnvSpec& spec = env_spec(a.env);
    if (spec.set_sample)
      spec.set_sample(c, a.trajectories > 0 ? a.trajectories : spec.trajectories(c), a.seed);
    d = spec.make(c);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const double build_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  QueryBundleConfig qc;
  qc.similarity = a.similarity;
  qc.preference = a.preference;
  qc.tpa_pairs = a.tpa_pairs;
  qc.fpe_trajectories = a.fpe;
  qc.teacher = make_teacher(a, d);
  const QueryBundle q = make_query_bundle(d, qc, a.seed);
  check_replaceable(a.out, "dataset", a.force);  // after the arguments are checked
  if (const auto dir = std::filesystem::path(a.out).parent_path(); !dir.empty())
    std::filesystem::create_directories(dir);
  // One writer: a run or server holding a.out refuses this (naming its pid), --force or not.
  const FileLock lock(a.out, "sirl dataset", "wait for it to finish, or choose another --out");
  // Write to a temporary name and rename: a crash never leaves a half-written file at --out.
  const std::string tmp = a.out + ".partial";
  if (const auto dir = std::filesystem::path(a.out).parent_path(); !dir.empty())
    std::filesystem::create_directories(dir);
  try {
    H5File f = H5File::create(tmp);
    f.set_compression(true);  // shuffle + deflate: JacoRobot's inputs shrink severalfold
    f.set_attr("/", "engine_version", std::string(SIRL_VERSION));
    f.set_attr("/", "git_commit", std::string(SIRL_GIT_COMMIT));
    write_dataset(f, d, q, SIRL_VERSION);
    f.flush();
  } catch (const std::exception&) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);  // nothing half-written stays behind
    throw;
  }
  std::filesystem::rename(tmp, a.out);
  std::printf(
      "wrote %s: /datasets/%s with %lld trajectories x %d inputs (built in %.2f s), %d features; "
      "%lld similarity triplets (%lld skipped), 3 x %lld preference pairs, %d test rewards x %lld "
      "TPA pairs, FPE %zu/%zu\n",
      a.out.c_str(), d.env.c_str(), (long long)d.count, d.input_dim, build_s, d.feature_count(),
      (long long)q.similarity.count, (long long)q.similarity.skipped, (long long)qc.preference,
      q.rewards.test.count, (long long)qc.tpa_pairs, q.fpe.train.size(), q.fpe.test.size());
  return 0;
}

// `sirl dataset --profile`: what a method trained elsewhere needs, built as `sirl run` builds it
// (the same RunContext): per environment of the profile, Ξ with its true features and every
// seed's rewards and query sets (the triplets with their answers, the preference pairs with
// their labels, the TPA pairs and the FPE split).
int run_profile_dataset(const std::string& profile, const std::string& out, bool force) {
  Profile p;
  try {
    p = load_profile(profile, profile_settings());
  } catch (const ProfileError& e) {
    throw UsageError(e.what());
  }
  check_replaceable(out, "dataset", force);
  if (const auto dir = std::filesystem::path(out).parent_path(); !dir.empty())
    std::filesystem::create_directories(dir);
  const FileLock lock(out, "sirl dataset", "wait for it to finish, or choose another --out");
  RunContext ctx(p, [](const std::string& key) -> TaskRecord {
    throw std::logic_error("sirl dataset reads no task (" + key + ")");
  });
  const std::string tmp = out + ".partial";
  std::string summary;
  try {
    H5File f = H5File::create(tmp);
    f.set_compression(true);
    f.set_attr("/", "engine_version", std::string(SIRL_VERSION));
    f.set_attr("/", "git_commit", std::string(SIRL_GIT_COMMIT));
    f.set_attr("/", "profile_name", p.name);
    f.set_attr("/", "profile_text", p.text);
    for (const auto& env : p.envs) {
      const std::vector<int64_t>& seeds = p.axes.at(env).seeds;
      if (seeds.empty()) continue;
      const Dataset& d = ctx.dataset(env);
      write_dataset(f, d, ctx.bundle(env, seeds.front()), SIRL_VERSION);
      // What a method trained elsewhere needs to know of the run it joins: the seeds, the N
      // values `sirl evaluate` will ask it for (those of this environment's FPE and TPA cells),
      // and the hyper-parameters the built-in methods train with ("key = value" lines).
      const EnvAxes& axes = p.axes.at(env);
      std::set<int64_t> Ns(axes.fpe_N.begin(), axes.fpe_N.end());
      Ns.insert(axes.tpa_N.begin(), axes.tpa_N.end());
      auto texts = [](const auto& values) {
        std::vector<std::string> v;
        for (int64_t x : values) v.push_back(std::to_string(x));
        return v;
      };
      const std::string g = "/datasets/" + env;
      f.set_attr(g, "seeds", texts(seeds));
      f.set_attr(g, "evaluate_N", texts(Ns));
      f.set_attr(g, "hyper", describe(p.hyper.at(env)));
      for (int64_t seed : seeds) write_seed_queries(f, env, seed, ctx.bundle(env, seed));
      summary += (summary.empty() ? "" : "; ") + env + ": " + std::to_string(d.count) +
                 " trajectories, " + std::to_string(seeds.size()) + " seeds";
    }
    f.close();
  } catch (const std::exception&) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
  std::filesystem::rename(tmp, out);
  std::printf("wrote %s: profile %s's training data (%s)\n", out.c_str(), p.name.c_str(),
              summary.c_str());
  return 0;
}

int run_inspect(const std::string& file, const std::string& env, bool as_json) {
  // A results file carries a checksum (a dataset file has none: nothing to check): verified
  // before HDF5 reads a byte, as every other reader of results files does.
  verify_checksum(file);
  const H5File f = H5File::open_read(file);
  const StoredDataset s = read_dataset(f, env);
  const Dataset& d = s.data;
  if (as_json) {
    const auto& q = s.queries;
    nlohmann::json j{{"file", file},
                     {"env", env},
                     {"engine_version", s.engine_version},
                     {"query_seed", q.seed},
                     {"trajectories", d.count},
                     {"input_dim", d.input_dim},
                     {"similarity", q.similarity.count},
                     {"singlepref", q.singlepref.count},
                     {"multipref10", q.multipref10.count},
                     {"multipref50", q.multipref50.count},
                     {"tpa_rewards", q.tpa.size()},
                     {"tpa_pairs", q.config.tpa_pairs},
                     {"fpe_train", q.fpe.train.size()},
                     {"fpe_test", q.fpe.test.size()}};
    for (int k = 0; k < d.feature_count(); ++k)
      j["features"].push_back(
          {{"name", d.feature_names[k]}, {"min", d.feature_min[k]}, {"max", d.feature_max[k]}});
    std::printf("%s\n", j.dump(1, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
    return 0;
  }
  std::printf("%s /datasets/%s (engine %s, seed %llu)\n", file.c_str(), env.c_str(),
              s.engine_version.c_str(), (unsigned long long)s.queries.seed);
  std::printf("  trajectories %lld x %d inputs\n", (long long)d.count, d.input_dim);
  for (int k = 0; k < d.feature_count(); ++k)
    std::printf("  feature %-20s raw range [%g, %g]\n", d.feature_names[k].c_str(),
                d.feature_min[k], d.feature_max[k]);
  const auto& q = s.queries;
  std::printf(
      "  similarity %lld, singlepref %lld, multipref10 %lld, multipref50 %lld, tpa %zu x %lld, fpe "
      "%zu/%zu\n",
      (long long)q.similarity.count, (long long)q.singlepref.count, (long long)q.multipref10.count,
      (long long)q.multipref50.count, q.tpa.size(), (long long)q.config.tpa_pairs,
      q.fpe.train.size(), q.fpe.test.size());
  return 0;
}

// A sampled trajectory space's size; JacoRobot's: where the laptop and the person stand, threads.
void add_jaco_options(CLI::App* cmd, DatasetArgs& a) {
  cmd->add_option("--trajectories", a.trajectories,
                  "A sampled environment's trajectories (default: JacoRobot 10000 start-goal "
                  "pairs, one deformed trajectory each; Driver 2000 control sequences)")
      ->check(CLI::Range(int64_t(10), int64_t(10000000)));
  cmd->add_option("--jaco-laptop", a.jaco_laptop, "JacoRobot laptop position x,y,z (m, base frame)")
      ->delimiter(',')
      ->expected(3)
      ->capture_default_str();
  cmd->add_option("--jaco-human", a.jaco_human, "JacoRobot human position x,y,z (m, base frame)")
      ->delimiter(',')
      ->expected(3)
      ->capture_default_str();
  cmd->add_option("--threads", a.threads,
                  "Threads for JacoRobot generation (default: all cores; "
                  "the result does not depend on it)")
      ->check(CLI::Range(1, 4096));
}

// The seed and the sizes of the query sets.
void add_query_options(CLI::App* cmd, DatasetArgs& a) {
  cmd->add_option("--seed", a.seed, "Seed of the rewards and query sets")->capture_default_str();
  cmd->add_option("--similarity", a.similarity, "Similarity triplets N")
      ->check(CLI::Range(int64_t(1), int64_t(10000000)))
      ->capture_default_str();
  cmd->add_option("--preference", a.preference,
                  "Preference pairs for each of SinglePref, MultiPref-10, MultiPref-50")
      ->check(CLI::Range(int64_t(1), int64_t(10000000)))
      ->capture_default_str();
  cmd->add_option("--tpa-pairs", a.tpa_pairs,
                  "Labelled pairs per test reward (80 % train, 20 % test)")
      ->check(CLI::Range(int64_t(5), int64_t(1000000)))
      ->capture_default_str();
  cmd->add_option("--fpe", a.fpe, "Labelled trajectories for FPE (clamped to the dataset size)")
      ->check(CLI::Range(int64_t(2), int64_t(100000000)))
      ->capture_default_str();
}

// The simulated teacher who answers the queries.
void add_teacher_options(CLI::App* cmd, DatasetArgs& a) {
  cmd->add_option("--beta", a.beta,
                  "Teacher's Boltzmann rationality (inf = perfect oracle, the paper's)")
      ->check(positive_number())
      ->capture_default_str();
  cmd->add_option("--mistake", a.mistake, "Teacher's probability of flipping an answer")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--skip", a.skip,
                  "Teacher withholds answers when options differ by less than this")
      ->check(non_negative_number())
      ->capture_default_str();
  cmd->add_option("--equal", a.equal,
                  "Teacher answers 'equal' when options differ by less than this")
      ->check(non_negative_number())
      ->capture_default_str();
  cmd->add_option("--features", a.features,
                  "Features the teacher perceives (default all), e.g. laptop_distance")
      ->delimiter(',');
}

// GridRobot's layout: the obstacles and the laptop.
void add_grid_options(CLI::App* cmd, DatasetArgs& a) {
  cmd->add_option("--obstacle1", a.obstacle1, "GridRobot obstacle 1 cell x,y")
      ->delimiter(',')
      ->expected(2)
      ->capture_default_str();
  cmd->add_option("--obstacle2", a.obstacle2, "GridRobot obstacle 2 cell x,y")
      ->delimiter(',')
      ->expected(2)
      ->capture_default_str();
  cmd->add_option("--laptop", a.laptop, "GridRobot laptop cell x,y")
      ->delimiter(',')
      ->expected(2)
      ->capture_default_str();
}

}  // namespace

void register_dataset(CLI::App& app, Runner& run) {
  static DatasetArgs a;
  auto* cmd = app.add_subcommand(
      "dataset",
      "Build an environment's trajectory space and query sets (answered by a simulated "
      "teacher) and write them to HDF5 under /datasets/<env>/");
  cmd->add_option("--env", a.env, "Environment")
      ->check(CLI::IsMember(env_choices()))
      ->capture_default_str();
  cmd->add_option("--out", a.out, "Output HDF5 file (written atomically)")
      ->required()
      ->check(output_file());
  cmd->add_flag("--force", a.force,
                "Replace --out even if it is not a dataset file (a results or study file)");
  add_jaco_options(cmd, a);
  add_query_options(cmd, a);
  add_teacher_options(cmd, a);
  add_grid_options(cmd, a);
  cmd->add_option("--profile", a.profile,
                  "Write the training data of a profile's run instead: per environment Ξ and "
                  "every seed's query sets under /datasets/<env>/seeds/s<seed>, built exactly as "
                  "`sirl run` builds them (what a method trained elsewhere learns from before "
                  "`sirl evaluate`). Excludes the options above but --out and --force")
      ->excludes(cmd->get_option("--env"))
      ->excludes(cmd->get_option("--seed"))
      ->excludes(cmd->get_option("--trajectories"))
      ->excludes(cmd->get_option("--similarity"))
      ->excludes(cmd->get_option("--preference"))
      ->excludes(cmd->get_option("--tpa-pairs"))
      ->excludes(cmd->get_option("--fpe"))
      ->excludes(cmd->get_option("--beta"))
      ->excludes(cmd->get_option("--mistake"))
      ->excludes(cmd->get_option("--features"));
  add_set_option(cmd);
  cmd->get_option("--set")->needs(cmd->get_option("--profile"));
  run = [] {
    return a.profile.empty() ? run_dataset(a) : run_profile_dataset(a.profile, a.out, a.force);
  };
}

std::vector<std::string> arm_envs() {
  std::vector<std::string> v;
  for (const auto& e : environments())
    if (e.view == EnvView::arm) v.push_back(e.name);
  return v;
}

void register_render(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "render",
      "Draw a few JacoRobot end-effector paths over the table, laptop and human (PNG), from a\n"
      "dataset or results file (report/render_jaco.py, Debian's /usr/bin/python3).");
  static std::string env = "jaco", file, out, ids = "0,1,2,3,4,5";
  cmd->add_option("--env", env, "Environment group (one with an arm view)")
      ->check(CLI::IsMember(arm_envs()))
      ->capture_default_str();
  cmd->add_option("file", file, "HDF5 file with /datasets/<env>")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", out, "PNG to write")->required()->check(output_file());
  cmd->add_option("--ids", ids, "Trajectory rows, comma-separated")->capture_default_str();
  run = [] {
    const auto q = sh_quote;
    const std::string cmdline =
        q(python_interpreter()) + " " + q((data_dir() / "report" / "render_jaco.py").string()) +
        " " + q(file) + " --out " + q(out) + " --ids " + q(ids) + " --env " + q(env);
    const int rc = std::system(cmdline.c_str());
    return rc == 0 ? 0 : 1;
  };
}

void register_inspect(CLI::App& app, Runner& run) {
  static std::string file, env = "grid";
  auto* cmd = app.add_subcommand(
      "inspect", "Read a dataset file back (checking every shape and type) and summarise it");
  cmd->add_option("file", file, "HDF5 file written by `sirl dataset`")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--env", env, "Environment group to read")
      ->check(CLI::IsMember(env_choices()))
      ->capture_default_str();
  static bool as_json = false;
  cmd->add_flag("--json", as_json, "Print one JSON object instead");
  run = [] { return run_inspect(file, env, as_json); };
}

}  // namespace sirl::app
