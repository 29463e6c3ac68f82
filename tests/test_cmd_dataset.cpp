// sirl dataset (the command): writing a dataset file, its messages, and refusing bad numbers.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "datasets/grid_robot.h"
#include "results/dataset_store.h"
#include "results/h5.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {
namespace fs = std::filesystem;

// A file in this process's scratch directory (removed with it when the process ends).
fs::path temp(const std::string& name) {
  static const test::ScratchDir scratch("sirl_cmd_dataset");
  return scratch.path() / (name + ".h5");
}

// The CLI end to end: `sirl dataset` then `sirl inspect`, and a truncated file gives a one-line
// error and a non-zero exit code, not a crash.
int run(const std::string& cmd, std::string* out = nullptr) {
  const std::string full = cmd + " > " + temp("cli_out").string() + " 2>&1";
  const int rc = std::system(full.c_str());
  if (out) {
    std::ifstream f(temp("cli_out"));
    *out = std::string(std::istreambuf_iterator<char>(f), {});
  }
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128 + WTERMSIG(rc);
}

TEST(DatasetCli, WriteInspectAndRefuseCorruptFiles) {
  const std::string sirl = SIRL_BINARY;
  const auto path = temp("cli");
  std::string out;
  ASSERT_EQ(
      run(sirl + " dataset --env grid --out " + path.string() + " --seed 3 --similarity 200", &out),
      0)
      << out;
  EXPECT_EQ(run(sirl + " inspect " + path.string(), &out), 0) << out;
  EXPECT_NE(out.find("similarity 200"), std::string::npos) << out;
  ASSERT_EQ(run(sirl + " inspect " + path.string() + " --json", &out), 0) << out;
  const nlohmann::json j = nlohmann::json::parse(out);
  EXPECT_EQ(j["similarity"].get<int64_t>(), 200);
  EXPECT_EQ(j["env"], "grid");
  EXPECT_EQ(j["features"].size(), 4u);  // GridRobot's four
  fs::resize_file(path, fs::file_size(path) / 3);
  const int rc = run(sirl + " inspect " + path.string(), &out);
  EXPECT_EQ(rc, 1) << out;
  EXPECT_NE(out.find("sirl: error: " + path.string()), std::string::npos) << out;
  EXPECT_EQ(run(sirl + " dataset --env grid --out " + path.string() + " --laptop 9,9", &out), 2)
      << out;
  EXPECT_NE(out.find("outside the 5x5 grid"), std::string::npos) << out;
  EXPECT_EQ(run(sirl + " dataset --env grid --out " + path.string() + " --mistake 2", &out), 2)
      << out;
  EXPECT_NE(out.find("--mistake"), std::string::npos) << out;
  EXPECT_EQ(run(sirl + " dataset --env grid --out " + path.string() + " --features nope", &out), 2)
      << out;
  EXPECT_EQ(run(sirl + " frobnicate", &out), 2) << out;
  EXPECT_NE(out.find("unknown command 'frobnicate'"), std::string::npos) << out;
  // Two grid objects on one cell would make two features one.
  EXPECT_EQ(run(sirl + " dataset --env grid --out " + path.string() + " --laptop 1,3", &out), 2)
      << out;
  EXPECT_NE(out.find("different cells"), std::string::npos) << out;
  // Like `sirl run`, `sirl dataset` creates the directory of its --out.
  const fs::path nested = fs::path(temp("cli_dir")).replace_extension("") / "a" / "b.h5";
  EXPECT_EQ(run(sirl + " dataset --env grid --out " + nested.string(), &out), 0) << out;
  EXPECT_TRUE(fs::exists(nested));
  fs::remove_all(nested.parent_path().parent_path());
  fs::remove(path);
  fs::remove(temp("cli_out"));
}

// Numbers on the command line are read strictly, with one readable line each (issue 17 item 15):
// CLI11 alone reads "0x10" as 16, "-1" as 2⁶⁴ − 1 for a seed, and prints DBL_MAX in full.
TEST(DatasetCli, NumbersAreStrictAndErrorsAreOneReadableLine) {
  const std::string sirl = SIRL_BINARY;
  const auto path = temp("cli_numbers");
  std::string out;
  const std::vector<std::pair<std::string, std::string>> cases{
      {" dataset --out " + path.string() + " --threads 0x10", "--threads: must be a non-negative"},
      {" dataset --out " + path.string() + " --seed -1", "--seed: must be a non-negative"},
      {" dataset --out " + path.string() + " --similarity ' 3'", "--similarity: must be"},
      {" dataset --out " + path.string() + " --beta -1", "--beta: must be a number > 0"},
      {" run smoke --out " + path.string() + " --shard ' 0/2'", "--shard must look like i/n"},
      {" run smoke --out " + path.string() + " --shard ''", "--shard: must look like i/n"},
      {" run smoke --out " + path.string() + " --shard 0/2/2", "--shard must look like i/n"},
      {" run smoke --out " + path.string() + " --shard 00/2", "--shard must look like i/n"},
      {" run smoke --out " + path.string() + " --shard 1/02", "--shard must look like i/n"},
      {" inspect " + path.string() + ".missing", "File does not exist"},
  };
  for (const auto& [args, words] : cases) {
    EXPECT_EQ(run(sirl + args, &out), 2) << args << "\n" << out;
    EXPECT_NE(out.find(words), std::string::npos) << args << "\n" << out;
    EXPECT_LT(out.size(), 300u) << "one short line: " << out;
    EXPECT_FALSE(fs::exists(path)) << args << " wrote a file";
  }
}

}  // namespace
}  // namespace sirl
