// The command line's first contact: the short grouped help (bare `sirl`, `sirl --help`: exit 0,
// every command listed, nothing wider than 100 columns), and "did you mean" for a mistyped
// command or profile, from an edit distance checked on hand-computed cases.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "experiment/suggest.h"

namespace sirl {
namespace {

TEST(Suggest, EditDistanceCountsInsertionsDeletionsSubstitutionsAndSwaps) {
  EXPECT_EQ(edit_distance("", ""), 0);
  EXPECT_EQ(edit_distance("quick", "quick"), 0);
  EXPECT_EQ(edit_distance("QUICK", "quick"), 0);   // case is no typo
  EXPECT_EQ(edit_distance("quikc", "quick"), 1);   // neighbours swapped
  EXPECT_EQ(edit_distance("smok", "smoke"), 1);    // one left out
  EXPECT_EQ(edit_distance("smokee", "smoke"), 1);  // one too many
  EXPECT_EQ(edit_distance("rum", "run"), 1);       // one wrong
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3);
  EXPECT_EQ(edit_distance("", "abc"), 3);
  EXPECT_EQ(edit_distance("ca", "abc"), 3);  // OSA: a swap is not edited again
}

TEST(Suggest, OnlyAClearlyClosestNameIsSuggested) {
  const std::vector<std::string> profiles{"smoke", "quick", "paper", "paper-grid", "beyond"};
  EXPECT_EQ(closest_name("quikc", profiles), "quick");
  EXPECT_EQ(closest_name("papr", profiles), "paper");
  EXPECT_EQ(closest_name("paper-gird", profiles), "paper-grid");
  EXPECT_EQ(closest_name("xyz", profiles), "");        // nothing close
  EXPECT_EQ(closest_name("q", profiles), "");          // one letter is anything
  EXPECT_EQ(closest_name("run", {"rum", "ran"}), "");  // two equally close: no guess
  EXPECT_EQ(closest_name(std::string(100000, 'a'), profiles), "");
  EXPECT_EQ(did_you_mean("smok", profiles), " (did you mean 'smoke'?)");
  EXPECT_EQ(did_you_mean("zzzzz", profiles), "");
}

// Runs `sirl ARGS`, returning its exit code and stdout + stderr (stdout alone: with_stderr false).
int run_sirl(const std::string& args, std::string& out, bool with_stderr = true) {
  const std::string cmd =
      std::string(SIRL_BINARY) + " " + args + (with_stderr ? " 2>&1" : " 2>/dev/null");
  FILE* p = ::popen(cmd.c_str(), "r");
  out.clear();
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  const int rc = ::pclose(p);
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128 + WTERMSIG(rc);
}

TEST(CliHelp, BareSirlAndHelpPrintTheShortHelpWithEveryCommand) {
  std::string bare, help;
  EXPECT_EQ(run_sirl("", bare), 0) << bare;
  EXPECT_EQ(run_sirl("--help", help), 0) << help;
  EXPECT_EQ(bare, help);
  // Every registered command: the names the unknown-command error lists.
  std::string err;
  EXPECT_EQ(run_sirl("no-such-command", err), 2);
  const size_t from = err.find("(commands: ");
  ASSERT_NE(from, std::string::npos) << err;
  std::string list = err.substr(from + 11, err.find(';', from) - from - 11);
  std::stringstream names(list);
  int n = 0;
  for (std::string name; std::getline(names, name, ',');) {
    name.erase(0, name.find_first_not_of(' '));
    EXPECT_NE(bare.find("\n  " + name + " "), std::string::npos) << name << " missing from help";
    ++n;
  }
  EXPECT_GE(n, 10);
  std::stringstream lines(bare);
  for (std::string line; std::getline(lines, line);) {
    size_t columns = 0;  // UTF-8 characters, not bytes
    for (unsigned char c : line) columns += (c & 0xC0) != 0x80;
    EXPECT_LE(columns, 100u) << line;
  }
}

// scripts/sirl-completion.bash completes every command the binary has (its list is written out,
// so a new command must be added there), and a profile where one goes.
TEST(CliHelp, BashCompletionKnowsEveryCommandAndTheProfiles) {
  std::string err;
  run_sirl("no-such-command", err);
  const size_t from = err.find("(commands: ");
  ASSERT_NE(from, std::string::npos) << err;
  const std::string script = std::string(SIRL_SOURCE_DIR) + "/scripts/sirl-completion.bash";
  const std::string bin = std::string(SIRL_BINARY);
  const auto complete = [&](const std::string& words) {
    const std::string cmd =
        "bash -c 'source " + script + "; COMP_WORDS=(" + bin + " " + words +
        "); COMP_CWORD=$((${#COMP_WORDS[@]}-1)); _sirl; echo \" ${COMPREPLY[*]} \"'";
    std::string out;
    FILE* p = ::popen(cmd.c_str(), "r");
    char buf[4096];
    for (size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
    ::pclose(p);
    return out;
  };
  const std::string all = complete("\"\"");
  std::stringstream names(err.substr(from + 11, err.find(';', from) - from - 11));
  for (std::string name; std::getline(names, name, ',');) {
    name.erase(0, name.find_first_not_of(' '));
    EXPECT_NE(all.find(" " + name + " "), std::string::npos) << name << " not completed: " << all;
  }
  EXPECT_NE(complete("reproduce qui").find(" quick "), std::string::npos);
  EXPECT_NE(complete("run --sha").find(" --shard "), std::string::npos);
}

// --json on the read-only commands: `sirl plan` agrees with its own --tasks list, `sirl version`
// with its text.
TEST(CliHelp, PlanAndVersionSpeakJson) {
  const std::string micro = std::string(SIRL_SOURCE_DIR) + "/tests/data/micro.toml";
  std::string out, tasks;
  ASSERT_EQ(run_sirl("plan " + micro + " --json", out, false), 0) << out;
  ASSERT_EQ(run_sirl("plan " + micro + " --tasks", tasks), 0) << tasks;
  const nlohmann::json j = nlohmann::json::parse(out);
  std::set<std::string> keys;
  std::stringstream lines(tasks);
  for (std::string line; std::getline(lines, line);)
    if (!line.empty()) keys.insert(line.substr(0, line.find(' ')));
  EXPECT_EQ(j["tasks"].get<size_t>(), keys.size());
  size_t by_kind = 0;
  for (const auto& [kind, v] : j["kinds"].items()) by_kind += v["tasks"].get<size_t>();
  EXPECT_EQ(by_kind, keys.size());
  EXPECT_GT(j["prediction"]["wall_seconds"].get<double>(), 0);
  for (const auto& k : j["prediction"]["critical_path"])
    EXPECT_TRUE(keys.count(k.get<std::string>())) << k;
  std::string text, json_text;
  ASSERT_EQ(run_sirl("version", text), 0);
  ASSERT_EQ(run_sirl("version --json", json_text, false), 0);
  const nlohmann::json v = nlohmann::json::parse(json_text);
  EXPECT_NE(text.find("cpu class: " + v["cpu_class"].get<std::string>() + "\n"), std::string::npos)
      << text;
  EXPECT_NE(text.find("commit:    " + v["commit"].get<std::string>()), std::string::npos);
}

TEST(CliHelp, MistypedCommandsAndProfilesGetASuggestion) {
  std::string out;
  EXPECT_EQ(run_sirl("reprodce", out), 2);
  EXPECT_NE(out.find("did you mean 'reproduce'?"), std::string::npos) << out;
  EXPECT_EQ(run_sirl("quikc", out), 2);  // a profile's name where a command goes
  EXPECT_NE(out.find("did you mean 'sirl reproduce quick'?"), std::string::npos) << out;
  EXPECT_EQ(run_sirl("plan smok", out), 2);  // a usage error
  EXPECT_NE(out.find("did you mean 'smoke'?"), std::string::npos) << out;
  EXPECT_EQ(out.find('\n'), out.size() - 1) << "one line: " << out;
}

}  // namespace
}  // namespace sirl
