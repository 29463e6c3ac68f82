// `sirl evaluate`: a representation trained elsewhere, scored by the paper's protocol. Its
// embeddings of Ξ (results/external_embeddings.h) join a profile as [external.<name>], and the
// profile runs as `sirl run` would: FPE and frozen TPA on the same held-out rows, test rewards,
// pairs, M values, head initialisations and seeds as every built-in method, in the same tables.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <string>

#include "app/commands.h"
#include "datasets/environments.h"
#include "engine/representation.h"
#include "experiment/plan.h"
#include "experiment/profile.h"
#include "jobs/run.h"
#include "probes/cpu_class.h"
#include "results/durable.h"
#include "results/external_embeddings.h"
#include "results/file_lock.h"
#include "results/results_file.h"

namespace sirl::app {
namespace {

// A TOML basic string holding s exactly.
std::string toml_string(const std::string& s) {
  std::string o = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += char(c);
    } else if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o += buf;
    } else {
      o += char(c);
    }
  }
  return o + "\"";
}

// Every array the profile's cells of the external method will read, read and checked now, so bad
// input is one line before anything is written: a missing (env, seed, N), another T, a d that
// changes within an environment, NaN or ±Inf.
void check_embeddings(const Profile& p, const ExternalMethod& m) {
  bool in_fpe = false, in_tpa = false;
  for (const auto& v : p.fpe_methods) in_fpe |= v.external == m.name;
  for (const auto& v : p.tpa.methods) in_tpa |= v.external == m.name;
  int arrays = 0;
  for (const auto& env : m.envs) {
    const EnvAxes& a = p.axes.at(env);
    std::set<int64_t> Ns;
    if (in_fpe) Ns.insert(a.fpe_N.begin(), a.fpe_N.end());
    if (in_tpa) Ns.insert(a.tpa_N.begin(), a.tpa_N.end());
    const int64_t T = env_spec(env).trajectories(p.data);
    int dim = 0;
    for (int64_t seed : a.seeds)
      for (int64_t N : Ns) {
        ExternalEmbedding e = read_external_embedding(m.embeddings, m.xxh3, env, seed, N, T);
        const std::string name = external_embedding_name(env, seed, N);
        if (dim && e.dim != dim)
          throw std::invalid_argument(m.embeddings + ": " + name +
                                      " has d = " + std::to_string(e.dim) + ", other arrays of " +
                                      env + " have d = " + std::to_string(dim));
        dim = e.dim;
        try {
          table_representation(std::move(e.values), T, e.dim, 1);
        } catch (const std::invalid_argument& err) {
          throw std::invalid_argument(m.embeddings + ": " + name + ": " + err.what());
        }
        ++arrays;
      }
  }
  if (arrays == 0)
    throw std::invalid_argument("profile " + p.name +
                                " has no [fpe] or [tpa] cells for an external method to join");
  std::fprintf(stderr, "sirl evaluate: %s: %d embeddings of Ξ checked (%s)\n", m.name.c_str(),
               arrays, m.embeddings.c_str());
}

// --against BASE.h5: a finished run of the same profile on this engine and CPU class. Its records
// become the start of OUT (under the profile with the external method), so the resume that follows
// computes only the external method's tasks: the built-in cells are the base run's, bit for bit,
// as a fresh run of this engine on this CPU class would compute them.
void seed_from_base(const std::string& base_file, const Profile& base, const Profile& p,
                    const std::string& out, bool force) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::equivalent(base_file, out, ec))
    throw UsageError("--against " + base_file + " is --out too; evaluate writes a new file");
  if (fs::exists(out, ec) && !force)
    throw UsageError(out + " already exists; remove it, choose another --out, or --force");
  const RunInfo info = read_run_info(base_file);
  const std::string why =
      !info.verified ? "no checksum verifies it"
      : info.profile_text != base.text
          ? "it was run under another profile text than " + base.path + "'s"
      : info.engine_version != engine_version() ? "it comes from engine " + info.engine_version
      : info.cpu_class != cpu_class()
          ? "it was computed on another CPU class (" + info.cpu_class + ")"
      : !info.shard.empty() ? "it is shard " + info.shard + " (merge the shards)"
                            : "";
  if (!why.empty())
    throw UsageError("--against " + base_file + ": " + why +
                     "; without --against the built-in cells are computed here");
  std::map<std::string, TaskRecord> records;
  for (auto& r : read_results_records(base_file)) records.emplace(r.key, std::move(r));
  RunInfo seeded = info;
  seeded.profile_text = p.text;
  seeded.profile_name = p.name;
  if (const auto dir = fs::path(out).parent_path(); !dir.empty()) fs::create_directories(dir);
  size_t reused = 0;
  {
    const FileLock lock(out, "sirl evaluate", "wait for it to finish, or choose another --out");
    reused = write_plan_records(out, p, seeded, records);
  }
  std::fprintf(stderr, "sirl evaluate: %zu of %zu tasks are %s's\n", reused,
               make_plan(p).tasks.size(), base_file.c_str());
}

struct EvaluateArgs {
  std::string embeddings, name, profile = "quick", out, figures, against;
  std::vector<std::string> envs;
  int threads = 0;
  bool force = false, quiet = false, with_study = false;
};

int run_evaluate(const EvaluateArgs& a) {
  if (const std::string why = external_name_problem(a.name); !why.empty())
    throw UsageError("--name: " + why);
  Profile base;
  try {
    base = load_profile(a.profile, profile_settings());
  } catch (const ProfileError& e) {
    throw UsageError(e.what());
  }
  for (const auto& e : base.external)
    if (e.name == a.name)
      throw UsageError("--name: profile " + base.name + " already has [external." + a.name + "]");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(a.embeddings, ec))
    throw UsageError(a.embeddings + ": no such file");
  const std::string path = std::filesystem::absolute(a.embeddings).lexically_normal().string();
  std::string digest;
  try {
    digest = file_digest(path);
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }
  // The profile as run and recorded: the base's text with the method declared at its end.
  std::string text = base.text + "\n\n# added by `sirl evaluate`\n[external." + a.name +
                     "]\nembeddings = " + toml_string(path) + "\nxxh3 = \"" + digest + "\"\n";
  if (!a.envs.empty()) {
    text += "envs = [";
    for (size_t i = 0; i < a.envs.size(); ++i) text += (i ? ", " : "") + toml_string(a.envs[i]);
    text += "]\n";
  }
  Profile p;
  try {
    p = parse_profile(text, base.path);
    check_embeddings(p, external_method(p, a.name));
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const std::string stem = std::filesystem::path(a.profile).stem().string();
  const std::string out = a.out.empty() ? "out/" + stem + "+" + a.name + ".h5" : a.out;
  if (!a.with_study) p.study.enabled = false;
  if (!a.against.empty()) seed_from_base(a.against, base, p, out, a.force);
  const int rc = run_loaded_profile(p, out, a.threads, a.force && a.against.empty(), "", a.quiet,
                                    !a.with_study);
  if (rc != 0) return rc;
  if (!a.figures.empty()) {
    draw_figures(out, a.figures);
    std::printf("figures: %s/ (report: %s/report.md)\n", a.figures.c_str(), a.figures.c_str());
  }
  return 0;
}

}  // namespace

void register_evaluate(CLI::App& app, Runner& run) {
  static EvaluateArgs a;
  auto* cmd = app.add_subcommand(
      "evaluate",
      "Score a representation trained elsewhere by the paper's protocol, next to the built-in\n"
      "methods: FPE and frozen TPA on the same Ξ, held-out rows, test rewards, pairs, M, head\n"
      "initialisations and seeds, in the same tables, figures and report. EMBEDDINGS is an HDF5\n"
      "file with one float32 array [T, d] per environment × seed × N of the profile, at\n"
      "/<env>/s<seed>/N<N> (row i = φ(ξ_i), Ξ in the order of `sirl dataset --profile`'s\n"
      "/datasets/<env>/inputs). The run is the profile's with [external.<name>] added (its text\n"
      "is recorded in the results file; --profile with such a section evaluates several). "
      "Unfrozen\n"
      "TPA cells need weights to fine-tune: an external method has frozen cells only.\n"
      "Example: sirl dataset --profile smoke --out train.h5; (train, write emb.h5);\n"
      "         sirl evaluate emb.h5 --name mine --profile smoke --figures out/smoke+mine-figures");
  cmd->add_option("embeddings", a.embeddings, "HDF5 file of the embeddings (layout above)")
      ->required();
  cmd->add_option("--name", a.name,
                  "The method's name in tables and figures: a-z, 0-9, '_', '-', not a built-in "
                  "method's")
      ->required();
  cmd->add_option("--profile", a.profile,
                  "Profile: a name in configs/ (" + bundled_profile_names() + ") or a .toml path")
      ->capture_default_str();
  cmd->add_option("--out", a.out, "Results file (default: out/<profile>+<name>.h5)")
      ->check(output_file());
  cmd->add_option("--figures", a.figures,
                  "Also draw the figures and the report (the method next to the built-in ones) "
                  "into this folder");
  cmd->add_option("--against", a.against,
                  "A finished results file of the same profile, engine and CPU class (e.g. "
                  "out/quick.h5 from `sirl reproduce`): its cells are reused, so only the "
                  "external method's are computed")
      ->check(CLI::ExistingFile);
  cmd->add_option("--envs", a.envs,
                  "The environments the file has embeddings for (default: every one of the "
                  "profile's); the method has no cells in the others")
      ->delimiter(',');
  cmd->add_option("--threads", a.threads, "Worker threads (default: every core)")
      ->check(CLI::Range(1, 4096));
  cmd->add_flag("--force", a.force, "Overwrite results from another profile or engine version");
  cmd->add_flag("--quiet", a.quiet, "No progress output");
  cmd->add_flag("--with-study", a.with_study,
                "Also run the profile's simulated user study (skipped by default: an external "
                "method has no part in it)");
  add_set_option(cmd);
  add_cache_options(cmd);
  run = [] { return run_evaluate(a); };
}

}  // namespace sirl::app
