// Profiles that compose: `extends` (parents' tables with the file's keys on top) and `--set`
// (KEY=VALUE on top of that), resolved before validation, errors naming the file that set the
// bad value, and a recorded text that is the resolved profile.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/simulation_tasks.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

namespace fs = std::filesystem;

struct ComposeDir {
  fs::path path = fs::temp_directory_path() / ("sirl-compose-" + std::to_string(::getpid()));
  ComposeDir() { fs::create_directories(path); }
  ~ComposeDir() { fs::remove_all(path); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path / name) << text;
    return (path / name).string();
  }
};

std::string compose_error(const std::string& file, const std::vector<std::string>& sets = {}) {
  try {
    load_profile(file, sets);
  } catch (const ProfileError& e) {
    return e.what();
  }
  return "no error";
}

std::vector<std::string> plan_keys(const Profile& p) {
  std::vector<std::string> k;
  for (const auto& t : make_plan(p).tasks) k.push_back(t.key);
  return k;
}

TEST(ProfileCompose, AChildIsItsParentsTablesWithItsOwnKeysOnTop) {
  ComposeDir d;
  d.write("base.toml", test::kSmallProfile);
  const std::string child = d.write("child.toml", R"(extends = "base"
name = "child"
seeds = [4]
[queries]
similarity = 400
[hyper.grid]
"tpa.epochs" = 11
)");
  const Profile p = load_profile(child);
  EXPECT_EQ(p.name, "child");
  EXPECT_EQ(p.seeds, (std::vector<int64_t>{4}));  // an array replaces the parent's
  EXPECT_EQ(p.queries.similarity, 400);           // a table merges key by key:
  EXPECT_EQ(p.queries.preference, 300);           //   the parent's other keys stay
  EXPECT_EQ(p.hyper.at("grid").sirl.epochs, 7);   // [hyper.grid] from the parent
  EXPECT_EQ(p.hyper.at("grid").tpa.epochs, 11);   //   and the child
  ASSERT_EQ(p.fpe_methods.size(), 4u);            // untouched tables: the parent's
  // --set goes on top of both, in order; the recorded text is the resolved profile, and parsing
  // it gives the same plan.
  const Profile s =
      load_profile(child, {"seeds=[0,1]", "hyper.grid.\"sirl.epochs\"=9", "seeds=[2]"});
  EXPECT_EQ(s.seeds, (std::vector<int64_t>{2}));
  EXPECT_EQ(s.hyper.at("grid").sirl.epochs, 9);
  EXPECT_EQ(s.hyper.at("grid").tpa.epochs, 11);
  const Profile again = parse_profile(s.text, "stored");
  EXPECT_EQ(plan_keys(again), plan_keys(s));
  EXPECT_EQ(again.hyper.at("grid").sirl.epochs, 9);
  EXPECT_EQ(again.seeds, s.seeds);
  // Without extends or --set the text is the file's, byte for byte.
  const Profile plain = load_profile(d.write("plain.toml", test::kSmallProfile));
  EXPECT_EQ(plain.text, std::string(test::kSmallProfile));
}

TEST(ProfileCompose, ParentsMergeLeftToRightAndResolveBesideTheChild) {
  ComposeDir d;
  d.write("base.toml", test::kSmallProfile);
  fs::create_directories(d.path / "sub");
  d.write("sub/a.toml", "extends = \"../base.toml\"\nname = \"a\"\nseeds = [1]\n");
  d.write("sub/b.toml",
          "extends = \"../base.toml\"\nname = \"b\"\nseeds = [2]\n[queries]\n"
          "similarity = 350\n");
  const Profile p = load_profile(d.write("sub/c.toml", "extends = [\"a\", \"b.toml\"]\n"));
  EXPECT_EQ(p.name, "b");  // the later parent wins
  EXPECT_EQ(p.seeds, (std::vector<int64_t>{2}));
  EXPECT_EQ(p.queries.similarity, 350);
}

TEST(ProfileCompose, ErrorsNameTheFileThatSetTheValue) {
  ComposeDir d;
  const std::string base = d.write("base.toml", test::kSmallProfile);
  // base's [fpe] N = 300 exceeds the child's budget: the error points at base.toml's [fpe].
  const std::string child =
      d.write("child.toml", "extends = \"base\"\n[queries]\nsimilarity = 250\n");
  const std::string e = compose_error(child);
  EXPECT_NE(e.find(base + ":9:"), std::string::npos) << e;  // its [fpe] table
  EXPECT_NE(e.find("N = 300"), std::string::npos) << e;
  // A bad value from --set names the setting.
  EXPECT_NE(compose_error(child, {"seeds=[0,\"x\"]"}).find("--set seeds=[0,\"x\"]"),
            std::string::npos);
  EXPECT_NE(compose_error(child, {"nonsense=1"}).find("unknown key 'nonsense'"), std::string::npos);
  EXPECT_NE(compose_error(child, {"seeds"}).find("expected KEY=VALUE"), std::string::npos);
  EXPECT_NE(compose_error(child, {"seeds=[0,"}).find("--set seeds=[0,"), std::string::npos);
  // Cycles and unknown parents.
  d.write("x.toml", "extends = \"y\"\nname = \"x\"\n");
  const std::string y = d.write("y.toml", "extends = \"x\"\nname = \"y\"\n");
  EXPECT_NE(compose_error(y).find("makes a cycle"), std::string::npos);
  EXPECT_NE(compose_error(d.write("z.toml", "extends = \"nowhere\"\n")).find("'nowhere' not found"),
            std::string::npos);
  EXPECT_NE(compose_error(d.write("w.toml", "extends = 3\n")).find("extends must be"),
            std::string::npos);
  // A stored text never holds extends: parse_profile refuses one.
  EXPECT_THROW(parse_profile("extends = \"base\"\n", "t"), ProfileError);
}

// A chain where every file names the next twice reaches the last one 2^depth ways: each file is
// resolved once (24 levels would otherwise read 16 million files), and a chain deeper than any
// honest profile's is refused by name.
TEST(ProfileCompose, AFileReachedManyWaysIsResolvedOnceAndDepthIsBounded) {
  ComposeDir d;
  d.write("p24.toml", test::kSmallProfile);
  for (int i = 23; i >= 0; --i)
    d.write("p" + std::to_string(i) + ".toml", "extends = [\"p" + std::to_string(i + 1) +
                                                   "\", \"p" + std::to_string(i + 1) + "\"]\n" +
                                                   (i == 0 ? "seeds = [7]\n" : ""));
  const Profile p = load_profile((d.path / "p0.toml").string());
  EXPECT_EQ(p.seeds, (std::vector<int64_t>{7}));
  d.write("q40.toml", test::kSmallProfile);
  for (int i = 39; i >= 0; --i)
    d.write("q" + std::to_string(i) + ".toml", "extends = \"q" + std::to_string(i + 1) + "\"\n");
  EXPECT_NE(compose_error((d.path / "q0.toml").string()).find("nests deeper than 32"),
            std::string::npos);
}

}  // namespace
}  // namespace sirl

namespace sirl {
namespace {

// [external.<name>] joins [fpe] and [tpa] with frozen cells only, even where the grid asks for
// both modes (it has no weights to fine-tune), and only in the environments it lists.
TEST(ProfileExternal, TakesFrozenCellsOnlyAndOnlyInItsEnvironments) {
  std::string text = test::kSmallProfile;
  text.replace(text.find("[tpa]"), 5, "[tpa]\nfrozen = [true, false]");
  text.replace(text.find("envs = [\"grid\"]"), 15, "envs = [\"grid\", \"grid2\"]");
  text += "[external.mine]\nembeddings = \"e.h5\"\nxxh3 = \"" + std::string(32, 'a') +
          "\"\nenvs = [\"grid\"]\n";
  const Profile p = parse_profile(text, "/tmp/x/p.toml");
  EXPECT_EQ(external_method(p, "mine").embeddings, "/tmp/x/e.h5");  // beside the profile
  int frozen = 0, fpe = 0;
  for (const auto& t : make_plan(p).tasks) {
    if (t.variant.method != Method::external) continue;
    EXPECT_EQ(t.env, "grid") << t.key;
    if (t.kind == tpa_kind()) {
      EXPECT_TRUE(t.frozen) << t.key;
      frozen += t.frozen;
    }
    fpe += t.kind == fpe_kind();
  }
  EXPECT_EQ(frozen, 3 * 2 * 2);  // seeds × N × M
  EXPECT_EQ(fpe, 3 * 3);         // seeds × N
  // A built-in method of that grid still gets both modes.
  int sirl_unfrozen = 0;
  for (const auto& t : make_plan(p).tasks)
    sirl_unfrozen += t.kind == tpa_kind() && t.variant.method == Method::sirl && !t.frozen;
  EXPECT_GT(sirl_unfrozen, 0);
  // Names and keys refused with the line that set them.
  auto error = [&](const std::string& extra) {
    try {
      parse_profile(std::string(test::kSmallProfile) + extra, "p.toml");
    } catch (const ProfileError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string digest = "xxh3 = \"" + std::string(32, 'a') + "\"\n";
  EXPECT_NE(error("[external.sirl]\nembeddings = \"e.h5\"\n" + digest).find("built-in"),
            std::string::npos);
  EXPECT_NE(error("[external.mine]\nembeddings = \"e.h5\"\nxxh3 = \"abc\"\n").find("32 lowercase"),
            std::string::npos);
  EXPECT_NE(error("[external.mine]\n" + digest).find("missing key 'embeddings'"),
            std::string::npos);
  EXPECT_NE(error("[external.mine]\nembeddings = \"e.h5\"\n" + digest + "envs = [\"jaco\"]\n")
                .find("not one of the profile's envs"),
            std::string::npos);
  EXPECT_NE(error("[fpe2]\n").find("p.toml:"), std::string::npos);
}

}  // namespace
}  // namespace sirl
