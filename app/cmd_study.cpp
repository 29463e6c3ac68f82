// `sirl study simulate | analyze | import | serve`: the user study (paper §5).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/study_server.h"
#include "datasets/study.h"
#include "engine/study_analysis.h"
#include "experiment/install_paths.h"
#include "results/file_lock.h"
#include "results/h5.h"
#include "results/study_store.h"

namespace sirl::app {

int study_simulate(const std::string& env, int64_t trajectories, int users, int64_t n_sim,
                   int64_t n_pref, double beta, double mistake, uint64_t seed,
                   const std::string& out, bool force) {
  CohortConfig c;
  c.env = env;
  c.trajectories = trajectories;
  c.users = users;
  c.similarity = n_sim;
  c.preference = n_pref;
  c.beta = beta;
  c.mistake = mistake;
  c.seed = seed;
  // Checked before the file: a bad teacher or environment is a usage error that touches nothing.
  int64_t count = 0;
  try {
    const Dataset d = study_dataset(new_study(env, trajectories, seed));
    count = d.count;
    Teacher t;
    t.beta = beta;
    t.mistake = mistake;
    validate(t, d.feature_count());
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  check_replaceable(out, "study", force);  // after the arguments are checked
  if (const auto dir = std::filesystem::path(out).parent_path(); !dir.empty())
    std::filesystem::create_directories(dir);
  // One writer: a run or server holding out refuses this (naming its pid), --force or not.
  const FileLock lock(out, "sirl study simulate", "wait for it to finish, or choose another --out");
  const Study s = simulate_cohort(c);
  const auto parent = std::filesystem::path(out).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
  write_study(out, s);
  std::printf(
      "wrote %s: %d simulated participants on %s (%lld trajectories), %lld similarity + "
      "%lld preference answers each (beta %g, mistakes %g)\n",
      out.c_str(), users, env.c_str(), (long long)count, (long long)n_sim, (long long)n_pref, beta,
      mistake);
  return 0;
}

int study_analyze(const std::string& file, const std::string& out, int seeds, int splits,
                  int epochs, int tpa_epochs, int threads, bool random_frozen) {
  const Study s = read_study(file);
  Dataset d;
  try {
    d = study_dataset(s);
  } catch (const std::invalid_argument& e) {
    throw UsageError(file + ": " + e.what());
  }
  StudyAnalysisConfig c;
  c.hyper = paper_hyper(s.env);
  if (epochs > 0) c.hyper.sirl.epochs = epochs;
  if (tpa_epochs > 0) c.hyper.tpa.epochs = tpa_epochs;
  c.seeds = seeds;
  c.cv_splits = splits;
  c.threads = threads;
  c.random_frozen = random_frozen;
  const auto started = std::chrono::steady_clock::now();
  c.progress = [&](int done, int total) {
    const double el =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    std::fprintf(stderr, "sirl study analyze: participant %d/%d done, %.0f s elapsed, ETA %.0f s\n",
                 done, total, el, done > 0 ? el / done * (total - done) : 0.0);
  };
  const auto t0 = std::chrono::steady_clock::now();
  StudyAnalysis a;
  try {
    a = analyze_study(s, d, c);
  } catch (const std::invalid_argument& e) {
    throw UsageError(file + ": " + e.what());
  }
  std::fprintf(stderr, "sirl study analyze: %lld pooled triplets, %zu participants, %.1f s\n",
               (long long)a.triplets, a.participants.size(),
               std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  write_study_analysis(file, s.env, a, c, out);
  return 0;
}

void write_study_analysis(const std::string& study_file, const std::string& env,
                          const StudyAnalysis& a, const StudyAnalysisConfig& c,
                          const std::string& out) {
  std::filesystem::create_directories(out);
  const std::string h5 = out + "/study_analysis.h5";
  try {
    H5File f = H5File::create(h5 + ".partial");
    auto w = [&](const char* name, const std::vector<double>& v) {
      f.write(std::string("/study_analysis/") + name, v.data(), {uint64_t(v.size())});
    };
    f.group("/study_analysis");
    f.set_attr("/study_analysis", "study_file", study_file);
    f.set_attr("/study_analysis", "env", env);
    f.set_attr("/study_analysis", "triplets", int64_t(a.triplets));
    f.set_attr("/study_analysis", "seeds", int64_t(c.seeds));
    f.set_attr("/study_analysis", "cv_splits", int64_t(c.cv_splits));
    f.set_attr("/study_analysis", "sirl_epochs", int64_t(c.hyper.sirl.epochs));
    f.set_attr("/study_analysis", "tpa_epochs", int64_t(c.hyper.tpa.epochs));
    f.set_attr("/study_analysis", "hyper", describe(c.hyper));
    f.set_attr("/study_analysis", "random_mode",
               std::string(c.random_frozen ? "frozen" : "unfrozen"));
    w("fpe_sirl", a.fpe_sirl);
    w("fpe_random", a.fpe_random);
    w("real_sirl", a.real_sirl);
    w("real_random", a.real_random);
    w("heldout_sirl", a.heldout_sirl);
    w("heldout_random", a.heldout_random);
    w("simulated_sirl", a.simulated_sirl);
    w("simulated_random", a.simulated_random);
    w("real_random_other", a.real_random_other);
    w("heldout_random_other", a.heldout_random_other);
    w("simulated_random_other", a.simulated_random_other);
    std::vector<int32_t> both(a.both_features.begin(), a.both_features.end());
    f.write("/study_analysis/both_features", both.data(), {uint64_t(both.size())});
    f.write_strings("/study_analysis/participants", a.participants);
    f.close();  // a full disk shows here, not silently in a destructor
  } catch (const std::exception&) {
    std::error_code ec;
    std::filesystem::remove(h5 + ".partial", ec);
    throw;
  }
  std::filesystem::rename(h5 + ".partial", h5);
  plot_study(h5, out);
}

void plot_study(const std::string& analysis, const std::string& out,
                const std::string& study_file) {
  std::filesystem::create_directories(out);
  const std::string cmd = sh_quote(python_interpreter()) + " " +
                          sh_quote((data_dir() / "report" / "plot_study.py").string()) + " " +
                          sh_quote(analysis) + " --out " + sh_quote(out) +
                          (study_file.empty() ? "" : " --study-file " + sh_quote(study_file));
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("plotting failed: " + cmd);
}

namespace {

// `sirl study simulate`'s options.
std::string s_env = "jaco2", s_out, s_profile;
int64_t s_traj = 1000, s_sim = 100, s_pref = 100;
int s_users = 10;
double s_beta = 20, s_mistake = 0.05;
uint64_t s_seed = 0;
bool s_force = false;

// `sirl study analyze`'s options.
std::string a_file, a_out, a_profile;
int a_seeds = 5, a_splits = 50, a_epochs = 0, a_tpa_epochs = 0, a_threads = 1;
std::string a_random = "unfrozen";

CLI::App* register_study_simulate(CLI::App& study) {
  auto* sim = study.add_subcommand(
      "simulate",
      "Write a study file answered by simulated novices: noisy teachers (Boltzmann beta on the\n"
      "normalised features, mistakes), each with its own preference scenario (3 in 5 care\n"
      "about every feature).");
  sim->add_option("--env", s_env, study_env_help())->capture_default_str();
  sim->add_option("--profile", s_profile,
                  "A profile whose [environments.<name>] (files) --env may name");
  sim->add_option("--trajectories", s_traj, "JacoRobot trajectory space size")
      ->check(CLI::Range(int64_t(10), int64_t(1000000)))
      ->capture_default_str();
  sim->add_option("--users", s_users, "Participants")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  sim->add_option("--similarity", s_sim, "Similarity queries each")
      ->check(CLI::Range(int64_t(0), int64_t(100000)))
      ->capture_default_str();
  sim->add_option("--preference", s_pref, "Preference queries each")
      ->check(CLI::Range(int64_t(0), int64_t(100000)))
      ->capture_default_str();
  sim->add_option("--beta", s_beta, "Boltzmann rationality (inf = perfect)")
      ->check(positive_number())
      ->capture_default_str();
  sim->add_option("--mistake", s_mistake, "Probability of a flipped answer")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  sim->add_option("--seed", s_seed, "Seed of the data, queries and answers")->capture_default_str();
  sim->add_option("--out", s_out, "Study file to write")->required()->check(output_file());
  sim->add_flag("--force", s_force, "Replace --out even if it is not a study file");
  sim->callback([] {});
  return sim;
}

CLI::App* register_study_analyze(CLI::App& study) {
  auto* ana = study.add_subcommand(
      "analyze",
      "SIRL on the pooled similarity answers vs Random, as in the paper's §5: FPE (two-sided\n"
      "t-test over training seeds), TPA Real (70/30, cross-validated), Held-out (SIRL without\n"
      "that participant) and Simulated, each with a one-way ANOVA (method as the factor), also\n"
      "for the participants whose preference involves every feature. SIRL is evaluated frozen,\n"
      "Random unfrozen (the paper's best baseline; --random frozen to swap), and the report\n"
      "shows Random in the other mode beside it. Writes Fig. 6 and study_report.md (H3, H4).");
  ana->add_option("file", a_file, "Study file")->required()->check(CLI::ExistingFile);
  ana->add_option("--profile", a_profile,
                  "The profile that declares the study's environment, if it is read from a file");
  ana->add_option("--out", a_out, "Output directory (default: <file>-analysis)");
  ana->add_option("--seeds", a_seeds, "Training seeds for FPE")
      ->check(CLI::Range(2, 100))
      ->capture_default_str();
  ana->add_option("--splits", a_splits, "Cross-validation splits per participant")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  ana->add_option("--epochs", a_epochs, "SIRL epochs (default: the paper's 3000)")
      ->check(CLI::Range(1, 100000));
  ana->add_option("--tpa-epochs", a_tpa_epochs, "Reward-head epochs (default: the paper's)")
      ->check(CLI::Range(1, 100000));
  ana->add_option("--random", a_random,
                  "How Random is evaluated in H4: unfrozen (φ fine-tuned with each head, the "
                  "paper's best baseline) or frozen")
      ->check(CLI::IsMember({"unfrozen", "frozen"}))
      ->capture_default_str();
  ana->add_option("--threads", a_threads, "Threads inside each training (GEMM)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  ana->callback([] {});
  return ana;
}

// Two records of one participant are the same when every query, answer and timing is.
bool same_participant(const StudyParticipant& a, const StudyParticipant& b) {
  return a.token == b.token && a.scenario == b.scenario &&
         a.scenario_features == b.scenario_features && a.reward == b.reward &&
         a.similarity == b.similarity && a.preference == b.preference &&
         a.similarity_answer == b.similarity_answer && a.preference_answer == b.preference_answer &&
         a.similarity_ms == b.similarity_ms && a.preference_ms == b.preference_ms &&
         a.similarity_time == b.similarity_time && a.preference_time == b.preference_time;
}

std::string m_out;
std::vector<std::string> m_inputs;
bool m_force = false;

// `sirl study merge OUT IN...`: the participants of several study files (one server per
// participant, on one machine or several) in one file. The files must describe one study (the
// same environment, trajectory space and data seed); a participant in two files must be the same
// record in both (merge never chooses between two sets of answers).
int study_merge() {
  Study merged;
  std::map<std::string, std::string> from;  // participant id → the file it came from
  for (size_t i = 0; i < m_inputs.size(); ++i) {
    const std::string& in = m_inputs[i];
    std::error_code ec;
    if (std::filesystem::equivalent(in, m_out, ec))
      throw UsageError(m_out + " is also one of the inputs; merge writes a new file");
    const Study s = read_study(in);
    if (i == 0) {
      merged.env = s.env;
      merged.env_data = s.env_data;
      merged.trajectories = s.trajectories;
      merged.data_seed = s.data_seed;
    } else if (s.env_data != merged.env_data) {
      // Two studies on an environment from a file: the same file, or not one study.
      const auto file = [](const Study& st) {
        return st.env_data.empty() ? std::string("no file")
                                   : st.env_data.substr(0, st.env_data.find('\n'));
      };
      throw UsageError(in + " was collected on " + s.env + " from " + file(s) + ", " +
                       m_inputs.front() + " from " + file(merged) + ": not one study");
    } else if (s.env != merged.env || s.trajectories != merged.trajectories ||
               s.data_seed != merged.data_seed) {
      throw UsageError(in + " is a study on " + s.env + " (" + std::to_string(s.trajectories) +
                       " trajectories, data seed " + std::to_string(s.data_seed) + "), " +
                       m_inputs.front() + " on " + merged.env + " (" +
                       std::to_string(merged.trajectories) + ", " +
                       std::to_string(merged.data_seed) + "): not one study");
    }
    for (const StudyParticipant& p : s.participants) {
      if (const StudyParticipant* seen = merged.find(p.id)) {
        if (!same_participant(*seen, p))
          throw UsageError("participant " + p.id + " is in " + from[p.id] + " and " + in +
                           " with different queries or answers: merge does not choose; keep "
                           "one of the files' copy (e.g. leave the other file out)");
        continue;
      }
      from[p.id] = in;
      merged.participants.push_back(p);
    }
  }
  std::error_code ec;
  if (std::filesystem::exists(m_out, ec) && !m_force)
    throw UsageError(m_out +
                     " already exists; merge writes a new file: choose another name, or "
                     "--force to replace it");
  check_replaceable(m_out, "study", m_force);
  if (const auto dir = std::filesystem::path(m_out).parent_path(); !dir.empty())
    std::filesystem::create_directories(dir);
  const FileLock lock(m_out, "sirl study merge", "wait for it to finish, or choose another OUT");
  write_study(m_out, merged);
  int64_t sim = 0, pref = 0;
  for (const auto& p : merged.participants) sim += p.similarity_done(), pref += p.preference_done();
  std::printf(
      "wrote %s: %zu participants from %zu files on %s, %lld similarity and %lld preference "
      "answers\n",
      m_out.c_str(), merged.participants.size(), m_inputs.size(), merged.env.c_str(),
      static_cast<long long>(sim), static_cast<long long>(pref));
  return 0;
}

CLI::App* register_study_merge(CLI::App& study) {
  auto* m = study.add_subcommand(
      "merge",
      "Combine study files of one study (one `sirl study serve` per participant, here or on other "
      "machines) into one file: the same environment, trajectories and data seed; a participant "
      "in two files must be the same there");
  m->add_option("out", m_out, "The merged study file (a new file: see --force)")->required();
  m->add_option("inputs", m_inputs, "Study files")->required()->check(CLI::ExistingFile);
  m->add_flag("--force", m_force, "Replace OUT if it exists (never one of the inputs)");
  m->callback([] {});
  return m;
}

}  // namespace

void register_study(CLI::App& app, Runner& run) {
  auto* study = app.add_subcommand(
      "study",
      "The user study (paper §5): collect answers in a browser (serve), import answers collected\n"
      "elsewhere (import), simulate a cohort (simulate), combine study files (merge), and analyse\n"
      "a study file (analyze).");
  study->require_subcommand(1);

  CLI::App* sim = register_study_simulate(*study);
  CLI::App* ana = register_study_analyze(*study);
  register_study_serve(*study);
  register_study_import(*study);
  CLI::App* merge = register_study_merge(*study);

  run = [sim, ana, merge] {
    if (merge->parsed()) return study_merge();
    if (sim->parsed()) {
      declare_profile_environments(s_profile);
      return study_simulate(s_env, s_traj, s_users, s_sim, s_pref, s_beta, s_mistake, s_seed, s_out,
                            s_force);
    }
    if (ana->parsed()) {
      declare_profile_environments(a_profile);
      const std::string out = a_out.empty() ? a_file + "-analysis" : a_out;
      return study_analyze(a_file, out, a_seeds, a_splits, a_epochs, a_tpa_epochs, a_threads,
                           a_random == "frozen");
    }
    return run_study_serve_or_import();
  };
}

}  // namespace sirl::app
