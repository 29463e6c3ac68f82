// Profiles: parsing, validation with file:line errors, partial grids, the shipped profiles.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/representation.h"
#include "engine/tpa.h"
#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/simulation_tasks.h"
#include "experiment/study_tasks.h"
#include "jobs/run.h"
#include "tests/profile_error.h"
#include "tests/scratch_dir.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

TEST(Profile, ParsesTheGridAndOverrides) {
  const Profile p = parse_profile(test::kSmallProfile, "t.toml");
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

TEST(Profile, MalformedProfilesAreRejectedWithFileLineAndExpectation) {
  const std::string base = "name = \"x\"\nenvs = [\"grid\"]\nseeds = [0]\n";
  const std::string grid =
      "[fpe]\nmethods = [\"sirl\"]\nN = [100]\n[tpa]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n";
  EXPECT_EQ(test::profile_error_of(base + grid), "no error");
  std::string m0;
  // An unknown key, on line 4.
  EXPECT_EQ(test::profile_error_of(base + "sedes = [1]\n" + grid)
                .rfind("bad.toml:4: unknown key 'sedes'", 0),
            0u)
      << test::profile_error_of(base + "sedes = [1]\n" + grid);
  // A width list longer than any network: refused at its line, before it is expanded.
  std::string layers = "[hyper.grid]\n\"phi.hidden\" = [";
  for (int i = 0; i < 100000; ++i) layers += i ? ",8" : "8";
  m0 = test::profile_error_of(base + grid + layers + "]\n");
  EXPECT_NE(m0.find("bad.toml:12: phi.hidden lists 100000 hidden layers; at most 64"),
            std::string::npos)
      << m0;
  // A wrong type.
  EXPECT_NE(test::profile_error_of("name = \"x\"\nenvs = \"grid\"\nseeds = [0]\n" + grid)
                .find("bad.toml:2: envs must be an array of strings"),
            std::string::npos);
  // An unknown method, with the list of valid ones.
  auto m = test::profile_error_of(base + "[fpe]\nmethods = [\"sirl\", \"pca\"]\nN = [100]\n" +
                                  "[tpa]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n");
  EXPECT_NE(m.find("bad.toml:5"), std::string::npos) << m;
  EXPECT_NE(m.find("unknown method 'pca'"), std::string::npos) << m;
  EXPECT_NE(m.find("multipref10"), std::string::npos) << m;
  // A reference listed as a method: the references run in every profile, beside the methods.
  m = test::profile_error_of(base + "[fpe]\nmethods = [\"sirl\", \"truth\"]\nN = [100]\n");
  EXPECT_NE(m.find("bad.toml:5"), std::string::npos) << m;
  EXPECT_NE(m.find("'truth' is a reference every profile scores"), std::string::npos) << m;
  // An unknown TPA protocol, on its line.
  m = test::profile_error_of(base + grid + "protocols = [\"linear\", \"probe\"]\n");
  EXPECT_NE(m.find("bad.toml:11"), std::string::npos) << m;
  EXPECT_NE(m.find("[tpa] protocols must be a non-empty array of \"paper\""), std::string::npos)
      << m;
  // M beyond the TPA training split.
  m = test::profile_error_of(base + grid + "[queries]\ntpa_pairs = 10\n");
  EXPECT_NE(m.find("M = 10 exceeds the 8 training pairs"), std::string::npos) << m;
  m = test::profile_error_of(base + "[fpe]\nmethods = [\"sirl\"]\nN = [5000]\n" +
                             "[tpa]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n");
  EXPECT_NE(m.find("exceeds the query budget"), std::string::npos) << m;
  // A bad hyper-parameter, named.
  m = test::profile_error_of(base + grid + "[hyper.grid]\n\"sirl.epoch\" = 3\n");
  EXPECT_NE(m.find("bad.toml:12"), std::string::npos) << m;
  EXPECT_NE(m.find("unknown hyper-parameter 'sirl.epoch'"), std::string::npos) << m;
  m = test::profile_error_of(base + grid + "[hyper.grid]\n\"sirl.lr\" = -1\n");
  EXPECT_NE(m.find("sirl.lr must be > 0"), std::string::npos) << m;
  m = test::profile_error_of(base + grid + "[hyper.grid]\n\"sirl.epochs\" = 0\n");
  EXPECT_NE(m.find("sirl.epochs must be >= 1"), std::string::npos) << m;
  {  // 1025 seeds: more than any list of a profile may hold
    std::string many = "seeds = [0";
    for (int i = 1; i <= 1024; ++i) many += "," + std::to_string(i);
    m = test::profile_error_of("name = \"x\"\nenvs = [\"grid\"]\n" + many + "]\n" + grid);
    EXPECT_NE(m.find("lists 1025 values; at most 1024"), std::string::npos) << m;
  }
  // "+vae" only where it applies; a missing table; TOML syntax errors keep their line.
  EXPECT_NE(test::profile_error_of(base + "[fpe]\nmethods = [\"random+vae\"]\nN = [100]\n" +
                                   "[tpa]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n")
                .find("VAE pre-training applies only"),
            std::string::npos);
  EXPECT_NE(
      test::profile_error_of(base).find(
          "nothing to run: give at least one of [fpe], [tpa], [ablation], [robustness] or [study]"),
      std::string::npos)
      << test::profile_error_of(base);
  EXPECT_NE(test::profile_error_of(base + grid + "[grid]\nstore_weights = 1\n")
                .find("store_weights must be"),
            std::string::npos);
  m = test::profile_error_of(base + grid + "[hyper.grid]\n\"vae.elbo\" = \"avg\"\n");
  EXPECT_NE(m.find("vae.elbo must be \"sum\""), std::string::npos) << m;
  EXPECT_EQ(test::profile_error_of(base + "[fpe\n").rfind("bad.toml:4:", 0), 0u)
      << test::profile_error_of(base + "[fpe\n");
  EXPECT_NE(test::profile_error_of(base + grid + "[teacher]\nmistake = 2\n").find("outside [0, 1]"),
            std::string::npos);
  // A duplicate method is refused like a duplicate seed (it used to be dropped silently).
  m = test::profile_error_of(base +
                             "[fpe]\nmethods = [\"sirl\", \"random\", \"sirl\"]\nN = [100]\n");
  EXPECT_NE(m.find("'sirl' is listed twice"), std::string::npos) << m;
  // A network too big for this machine is still a valid profile (a profile means the same on
  // every machine; `sirl run` refuses it: Profile.ARunRefusesATaskBeyondThisMachinesMemory).
  EXPECT_EQ(test::profile_error_of(base + grid +
                                   "[hyper.grid]\n\"phi.hidden\" = [100000000, 100000000]\n"),
            "no error");
  // [tpa] stop: a table of listed methods and known rules.
  EXPECT_EQ(test::profile_error_of(base + grid + "stop = { sirl = \"fixed\" }\n"), "no error");
  m = test::profile_error_of(base + grid + "stop = \"fixed\"\n");
  EXPECT_NE(m.find("bad.toml:11: [tpa] stop must be a table of method = rule"), std::string::npos)
      << m;
  m = test::profile_error_of(base + grid + "stop = { random = \"fixed\" }\n");
  EXPECT_NE(m.find("[tpa] stop: 'random' is not one of [tpa] methods"), std::string::npos) << m;
  m = test::profile_error_of(base + grid + "stop = { sirl = \"early\" }\n");
  EXPECT_NE(m.find("[tpa] stop.sirl: hyper-parameter tpa.stop must be"), std::string::npos) << m;
  m = test::profile_error_of(base + grid + "stop = { sirl = 1 }\n");
  EXPECT_NE(m.find("[tpa] stop.sirl must be a string"), std::string::npos) << m;
  // A rule belongs to the method, wherever its cells are listed: [robustness] takes none.
  m = test::profile_error_of(base + grid +
                             "[teacher]\nbeta = [\"inf\", 1]\n[robustness]\nmethods = [\"sirl\"]\n"
                             "N = [100]\nM = [10]\nstop = { sirl = \"fixed\" }\n");
  EXPECT_NE(m.find("unknown key 'stop'"), std::string::npos) << m;
  // A float in an integer list: one file:line prefix, not two.
  m = test::profile_error_of(base + grid + "[hyper.grid]\n\"phi.hidden\" = [1e8, 1e8]\n");
  EXPECT_EQ(m.find("bad.toml", 1), std::string::npos) << m;
  EXPECT_NE(m.find("must be an array of integers"), std::string::npos) << m;
}

// A φ of 10^8 × 10^8 weights needs ~149 million GiB to train: the run names the task and both
// sizes before it allocates anything or writes a file.
// A profile text from someone else's results file, or a pasted description, is bounded before
// it is parsed or printed (issue 65: a 50 MB description went to stdout whole).
TEST(Profile, OversizedTextsAndDescriptionsAreRefused) {
  std::string text = test::kSmallProfile;
  text.insert(text.find("envs"), "description = \"" + std::string(5000, 'x') + "\"\n");
  std::string err = test::profile_error_of(text);
  EXPECT_NE(err.find("description: 5000 characters; at most 4000"), std::string::npos) << err;
  EXPECT_NE(err.find("bad.toml:"), std::string::npos) << err;
  std::string huge = test::kSmallProfile;
  huge += "# " + std::string(2 << 20, 'x') + "\n";
  err = test::profile_error_of(huge);
  EXPECT_NE(err.find("a profile is at most 1048576"), std::string::npos) << err;
}

TEST(Profile, ARunRefusesATaskBeyondThisMachinesMemory) {
  const Profile p = parse_profile(
      "name = \"huge\"\nenvs = [\"grid\"]\nseeds = [0]\n[fpe]\nmethods = [\"sirl\"]\nN = [100]\n"
      "[tpa]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n"
      "[hyper.grid]\n\"phi.hidden\" = [100000000, 100000000]\n",
      "huge.toml");
  const test::ScratchDir scratch;
  RunOptions o;
  o.out = (scratch.path() / "huge.h5").string();
  o.quiet = true;
  try {
    run_profile(p, o);
    FAIL() << "the run started";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("task grid/s0/sirl/N100/rep needs "), std::string::npos) << m;
    EXPECT_NE(m.find(" GiB to train, this process may use "), std::string::npos) << m;
  }
  EXPECT_FALSE(std::filesystem::exists(o.out));
  EXPECT_FALSE(std::filesystem::exists(o.out + ".tasks"));
}

// precision: fp32 by default; "bf16" at the top reaches every environment's networks and the
// study's; [hyper.<env>] can set one environment apart; anything else is refused with file:line.
TEST(Profile, PrecisionReachesEveryNetwork) {
  const std::string base = "name = \"x\"\nenvs = [\"grid\", \"grid2\"]\nseeds = [0]\n";
  const std::string grid = "[fpe]\nmethods = [\"sirl\"]\nN = [100]\n";
  Profile p = parse_profile(base + grid, "p.toml");
  EXPECT_EQ(p.hyper.at("grid").precision, "fp32");
  EXPECT_FALSE(phi_shape(19, p.hyper.at("grid")).bf16_products);
  p = parse_profile(
      "precision = \"bf16\"\n" + base + grid + "[hyper.grid2]\nprecision = \"fp32\"\n", "p.toml");
  EXPECT_EQ(p.precision, "bf16");
  EXPECT_TRUE(phi_shape(19, p.hyper.at("grid")).bf16_products);
  EXPECT_TRUE(
      tpa_network(phi_shape(19, p.hyper.at("grid")), p.hyper.at("grid"), false).bf16_products);
  EXPECT_FALSE(phi_shape(19, p.hyper.at("grid2")).bf16_products);
  EXPECT_EQ(study_config(p).hyper.precision, "bf16");
  EXPECT_NE(describe(p.hyper.at("grid")).find("precision = bf16\n"), std::string::npos);
  std::string m = test::profile_error_of("precision = \"fp16\"\n" + base + grid);
  EXPECT_EQ(m.rfind("bad.toml:1:", 0), 0u) << m;
  EXPECT_NE(m.find("precision must be \"fp32\" or \"bf16\""), std::string::npos) << m;
  m = test::profile_error_of(base + grid + "[hyper.grid]\nprecision = \"int8\"\n");
  EXPECT_NE(m.find("precision must be \"fp32\" or \"bf16\""), std::string::npos) << m;
}

// A profile may run any part of the grid: FPE only, TPA only, or the ablation only.
TEST(Profile, APartOfTheGridIsAProfileOfItsOwn) {
  const std::string base = "name = \"x\"\nenvs = [\"grid\", \"grid2\"]\nseeds = [0]\n";
  auto kinds = [](const Plan& plan) {
    std::map<std::string, int> n;
    for (const auto& t : plan.tasks) ++n[t.kind.name()];
    return n;
  };
  auto fpe_only =
      kinds(make_plan(parse_profile(base + "[fpe]\nmethods = [\"sirl\"]\nN = [100]\n")));
  EXPECT_EQ(fpe_only["fpe"], 2 * 3);  // per environment: the method's and the references'
  EXPECT_EQ(fpe_only["rep"], 2);
  EXPECT_EQ(fpe_only["tpa"], 0);
  auto tpa_only = kinds(
      make_plan(parse_profile(base + "[tpa]\nmethods = [\"random\"]\nN = [100]\nM = [10, 20]\n")));
  EXPECT_EQ(tpa_only["tpa"], 4 + 4);  // random's cells and the truth reference's, 2 M × 2 envs
  EXPECT_EQ(tpa_only["tpa_linear"], 4 + 8);  // random's, truth's and raw's
  EXPECT_EQ(tpa_only["fpe"], 0);
  const Plan ab =
      make_plan(parse_profile(base + "[ablation]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n"));
  auto ab_kinds = kinds(ab);
  EXPECT_EQ(ab_kinds["tpa"], 2 * 4);  // frozen/unfrozen × with/without VAE, per environment
  EXPECT_EQ(ab_kinds["vae"], 2);
  for (const auto& t : ab.tasks)
    if (t.kind == tpa_kind()) {
      EXPECT_TRUE(t.in_ablation && !t.in_main) << t.key;
    }
}

TEST(Profile, ShippedProfilesAreValid) {
  for (const char* name : {"smoke", "quick", "paper", "paper-grid"}) {
    const Profile p = load_profile(name);
    EXPECT_EQ(p.name, name);
    EXPECT_GT(make_plan(p).tasks.size(), 0u);
  }
  EXPECT_THROW(load_profile("no-such-profile"), ProfileError);
}

}  // namespace
}  // namespace sirl
