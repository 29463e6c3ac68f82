// The `sirl` command line: one executable, one subcommand per job.
// Each subcommand lives in its own app/cmd_*.cpp and registers itself through commands.h.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "app/commands.h"
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
  // An unknown first word is an unknown command, not "a subcommand is required".
  if (argc > 1 && argv[1][0] != '-') {
    bool known = false;
    std::string names;
    for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
      known = known || sub->get_name() == argv[1];
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::fprintf(stderr, "sirl: error: unknown command '%s' (commands: %s; see `sirl --help`)\n",
                   argv[1], names.c_str());
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
