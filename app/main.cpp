// The `sirl` command line: one executable, one subcommand per job.
// Each subcommand lives in its own app/cmd_*.cpp and registers itself through commands.h.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <set>
#include <string>
#include <vector>

#include "app/commands.h"
#include "experiment/profile.h"
#include "experiment/suggest.h"
#include "jobs/memory_reuse.h"
#include "jobs/stop_request.h"
#include "results/file_lock.h"

namespace {
// An error message may quote bytes of a file someone else wrote (an attribute's name, a lock's
// text): it reaches the terminal as valid UTF-8 without control characters (no escapes), each
// other byte shown as '?'.
std::string printable(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    size_t len = c < 0x80           ? 1
                 : (c >> 5) == 0x6  ? 2
                 : (c >> 4) == 0xE  ? 3
                 : (c >> 3) == 0x1E ? 4
                                    : 0;
    bool ok = len > 0 && i + len <= s.size();
    for (size_t k = 1; ok && k < len; ++k) ok = (static_cast<unsigned char>(s[i + k]) >> 6) == 0x2;
    if (ok && len == 1 && ((c < 0x20 && c != '\n' && c != '\t') || c == 0x7F)) ok = false;
    if (!ok) {
      out += '?';
      ++i;
      continue;
    }
    out.append(s, i, len);
    i += len;
  }
  return out;
}
// " (did you mean …?)" for an unknown command: a command it is a typo of, or, for a profile's
// name (`sirl quick`), the command that runs it.
std::string suggestion(const std::string& typed, const std::vector<std::string>& commands) {
  if (std::string s = sirl::did_you_mean(typed, commands); !s.empty()) return s;
  std::string profile = sirl::closest_name(typed, sirl::bundled_profiles());
  return profile.empty() ? "" : " (did you mean 'sirl reproduce " + profile + "'?)";
}

// A command's description cut to its first sentence (for a command the help's table misses).
std::string first_sentence(std::string d) {
  for (char& c : d)
    if (c == '\n') c = ' ';
  const size_t end = d.find(". ");
  if (end != std::string::npos) d.resize(end);
  if (!d.empty() && d.back() == '.') d.pop_back();
  return d;
}

// The top-level help: what sirl is, where to start, and every command in a group with one line
// (bare `sirl` and `sirl --help` print it; `sirl CMD --help` has the rest). A command the table
// does not list still appears, under "More", with its description's first sentence.
std::string short_help(CLI::App& app) {
  struct Entry {
    const char* name;
    const char* line;
  };
  const std::vector<std::pair<std::string, std::vector<Entry>>> groups{
      {"Reproduce the paper",
       {{"reproduce", "run a profile, then draw every figure and write the report (the main job)"},
        {"run", "run a profile's grid into an HDF5 results file (resumable, cached per task)"},
        {"plan", "what a profile runs and how long it takes here, without running it"}}},
      {"Your own representation",
       {{"evaluate", "score an embeddings file of yours beside the paper's methods"},
        {"dataset", "write an environment's trajectories and simulated answers to HDF5"}}},
      {"Read a results file",
       {{"show", "what a results file holds: profile, machine, tasks done, verdicts (--json)"},
        {"export", "every table of a results file as CSV"},
        {"inspect", "check and summarise a dataset file"},
        {"render", "draw JacoRobot trajectories over the scene (PNG)"}}},
      {"The user study", {{"study", "serve the study page; import, simulate and analyse answers"}}},
      {"On a cluster",
       {{"submit", "a Slurm batch script for a profile (job array or MPI), sized by `sirl plan`"},
        {"status", "what became of a submission's shards"},
        {"merge", "combine shard files into one results file"},
        {"gc", "trim a task cache to what the given profiles need"}}},
      {"This build",
       {{"version", "the build, the CPU class results depend on, this core's roof"}}}};
  std::string s =
      std::string("sirl-bench ") + sirl::app::engine_version() +
      ": the SIRL paper (Bobu, Liu et al., HRI 2023) as a fast, deterministic "
      "benchmark.\n\n"
      "Start here:\n"
      "  sirl reproduce smoke    the whole pipeline in about a minute: results, "
      "figures, report\n"
      "  sirl reproduce quick    every figure of the paper at a reduced scale (about "
      "15 min on 2 cores)\n"
      "  sirl plan paper         what the full protocol costs here, without running it\n";
  std::set<std::string> registered, listed;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
    registered.insert(sub->get_name());
  const auto line = [](const std::string& name, const std::string& text) {
    return "  " + name + std::string(name.size() < 11 ? 11 - name.size() : 1, ' ') + text + "\n";
  };
  for (const auto& [title, entries] : groups) {
    s += "\n" + title + ":\n";
    for (const Entry& e : entries)
      if (registered.count(e.name)) {
        s += line(e.name, e.line);
        listed.insert(e.name);
      }
  }
  std::string more;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
    if (!listed.count(sub->get_name()))
      more += line(sub->get_name(), first_sentence(sub->get_description()));
  if (!more.empty()) s += "\nMore:\n" + more;
  s += "\n`sirl CMD --help` lists a command's options; `sirl --version` prints the version.\n";
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  sirl::keep_freed_memory_for_reuse();  // before any thread exists (jobs/memory_reuse.h)
  CLI::App app{
      "sirl-bench: reproduces the SIRL paper (Bobu, Liu et al., HRI 2023) - learning "
      "robot-behaviour\n"
      "representations from 'which two of these three are most alike?' answers - as a fast,\n"
      "deterministic benchmark. Run `sirl <command> --help` for the options of each command.",
      "sirl"};
  app.require_subcommand(1);
  app.fallthrough(false);
  // `sirl --version`: one line; `sirl version` prints the build, the CPU class and the roof.
  app.set_version_flag("--version", std::string("sirl-bench ") + sirl::app::engine_version() +
                                        " (commit " + sirl::app::git_commit() +
                                        "; `sirl version` for the build and CPU)");
  sirl::app::register_all(app);
  // Bare `sirl`, `sirl --help` and `sirl -h`: the short grouped help, exit 0.
  if (argc == 1 ||
      (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h"))) {
    std::fputs(short_help(app).c_str(), stdout);
    return 0;
  }
  // An unknown first word is an unknown command, not "a subcommand is required".
  if (argc > 1 && argv[1][0] != '-') {
    bool known = false;
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
      known = known || sub->get_name() == argv[1];
      names.push_back(sub->get_name());
    }
    if (!known) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      std::fprintf(stderr,
                   "sirl: error: unknown command '%s'%s (commands: %s; see `sirl --help`)\n",
                   printable(argv[1]).c_str(), suggestion(argv[1], names).c_str(), list.c_str());
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One line naming the option and what it accepts; exit code 2 for every usage error.
    std::fprintf(stderr, "sirl: error: %s (see `sirl --help`)\n", e.what());
    return 2;
  }
  try {
    return sirl::app::run_selected(app);
  } catch (const sirl::app::UsageError& e) {
    std::fprintf(stderr, "sirl: error: %s\n", printable(e.what()).c_str());
    return 2;
  } catch (const sirl::FileBusy& e) {  // another process holds the output: every command's 2
    std::fprintf(stderr, "sirl: error: %s\n", printable(e.what()).c_str());
    return 2;
  } catch (const sirl::StopRequested&) {
    std::fprintf(stderr,
                 "sirl: stopped on %s: every finished task is committed and every training in "
                 "progress saved its state; rerun the same command to continue (exit %d)\n",
                 sirl::stop_signal_name(), sirl::kExitStopped);
    return sirl::kExitStopped;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sirl: error: %s\n", printable(e.what()).c_str());
    return 1;
  }
}
