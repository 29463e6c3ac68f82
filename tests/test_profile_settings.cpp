// The profile sections declared as data (experiment/profile_settings.h): every declared key is
// parsed with its declared range and type, refused outside it with file:line, defaults to its
// struct's value, and the reference page is the declarations' own output.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "experiment/profile.h"
#include "experiment/profile_settings.h"
#include "experiment/task_settings.h"
#include "tests/profile_error.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

// The small profile without its [queries] table (each test adds the tables it checks).
std::string small_profile_base() {
  std::string text = test::kSmallProfile;
  const size_t from = text.find("[queries]"), to = text.find("[fpe]");
  return text.erase(from, to - from);
}

// The small profile with table `section` holding `keys` (key → TOML value), the key under test
// on line `line` of the text (returned).
std::string with_section(const std::string& section, const std::map<std::string, std::string>& keys,
                         const std::string& tested, int* line) {
  std::string text = small_profile_base();
  text += "[" + section + "]\n";
  for (const auto& [k, v] : keys) {
    if (k == tested) *line = int(std::count(text.begin(), text.end(), '\n')) + 1;
    text += k + " = " + v + "\n";
  }
  return text;
}

std::string toml_number(double v, bool integer) {
  if (integer) return std::to_string(int64_t(v));
  std::ostringstream o;
  o.precision(17);
  o << v;
  return o.str();
}

// For every numeric key the declaration `settings` gives section `name` (a parsed profile's
// struct read by `field_of`): a value just outside each finite bound is refused naming the file,
// the line, the key and the declared range; a value at the bound passes the range check; a
// fraction for an integer key is refused as not an integer. `base` holds values that keep the
// section's cross-key rules satisfied (pool ≥ batch).
template <class Settings, class S, class Read>
void check_declared_ranges(const std::string& name, Settings settings, const S& defaults,
                           const std::map<std::string, std::string>& base, Read field_of) {
  int numeric = 0;
  settings(defaults, [&](const SettingInfo& k, const auto& field) {
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
      ++numeric;
      const bool integer = std::is_integral_v<T>;
      SCOPED_TRACE(name + "." + k.key);
      auto try_value = [&](double v) {
        std::map<std::string, std::string> keys = base;
        keys[k.key] = toml_number(v, integer);
        int line = 0;
        return std::make_pair(test::profile_error_of(with_section(name, keys, k.key, &line)), line);
      };
      for (double bound : {k.lo, k.hi}) {
        if (std::isinf(bound)) continue;
        const auto [inside, line_in] = try_value(bound);
        EXPECT_EQ(inside.find("is outside"), std::string::npos) << inside;
        if (inside == "no error") {
          std::map<std::string, std::string> keys = base;
          keys[k.key] = toml_number(bound, integer);
          int line = 0;
          const Profile p = parse_profile(with_section(name, keys, k.key, &line), "bad.toml");
          EXPECT_EQ(double(field_of(p, k.key)), bound);
        }
        const double step = integer ? 1 : std::max(std::abs(bound) * 1e-3, 1e-12);
        const double outside = bound == k.lo ? bound - step : bound + step;
        const auto [refused, line] = try_value(outside);
        EXPECT_NE(refused.find("bad.toml:" + std::to_string(line) + ": " + k.key + " = "),
                  std::string::npos)
            << refused;
        EXPECT_NE(refused.find("is outside ["), std::string::npos) << refused;
      }
      if (integer) {
        std::map<std::string, std::string> keys = base;
        keys[k.key] = "2.5";
        int line = 0;
        const std::string m = test::profile_error_of(with_section(name, keys, k.key, &line));
        EXPECT_NE(m.find("bad.toml:" + std::to_string(line) + ": " + k.key + " must be an integer"),
                  std::string::npos)
            << m;
      }
    }
  });
  EXPECT_GT(numeric, 3);
}

// The field a declaration names, read from a parsed profile by key (through the declaration).
template <class Settings, class S>
double declared_field(Settings settings, const S& s, const std::string& key) {
  double out = NAN;
  settings(s, [&](const SettingInfo& k, const auto& field) {
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_arithmetic_v<T>)
      if (key == k.key) out = double(field);
  });
  return out;
}

TEST(ProfileSettings, EveryDeclaredKeyIsReadWithItsDeclaredRangeAndType) {
  check_declared_ranges("queries", kQueriesSettings, QueryBundleConfig{},
                        {{"similarity", "300"}, {"preference", "300"}, {"tpa_pairs", "100"}},
                        [](const Profile& p, const std::string& key) {
                          return declared_field(kQueriesSettings, p.queries, key);
                        });
  check_declared_ranges("active", kActiveSettings, ActiveRounds{},
                        {{"pool", "10000000"}, {"batch", "1"}},
                        [](const Profile& p, const std::string& key) {
                          return declared_field(kActiveSettings, p.active.at("grid"), key);
                        });
  check_declared_ranges("study", kStudySettings, StudyPlan{}, {{"env", "\"grid\""}},
                        [](const Profile& p, const std::string& key) {
                          return declared_field(kStudySettings, p.study, key);
                        });
  check_declared_ranges("teacher", kTeacherSettings, QueryBundleConfig{}, {},
                        [](const Profile& p, const std::string& key) {
                          return declared_field(kTeacherSettings, p.queries, key);
                        });
}

// Every list key of an environment's table: its declared lower bound is read into that
// environment's axes (the other environments keep the profile's), one below it is refused with
// file:line, an empty list means "no such cell here" (seeds excepted); store_weights is a TOML
// boolean.
TEST(ProfileSettings, AnEnvironmentsTableReadsEachDeclaredListWithItsRange) {
  int lists = 0;
  const EnvAxes defaults;
  kEnvTableSettings(defaults, [&](const SettingInfo& k, const auto& field) {
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_same_v<T, std::vector<int64_t>>) {
      ++lists;
      SCOPED_TRACE(k.key);
      int line = 0;
      const auto at = [&](const std::string& v) {
        return with_section("grid", {{k.key, v}}, k.key, &line);
      };
      const Profile p = parse_profile(at("[" + toml_number(k.lo, true) + "]"), "t.toml");
      kEnvTableSettings(p.axes.at("grid"), [&](const SettingInfo& j, const auto& read) {
        if constexpr (std::is_same_v<std::decay_t<decltype(read)>, std::vector<int64_t>>)
          if (std::string(j.key) == k.key) {
            EXPECT_EQ(read, std::vector<int64_t>{int64_t(k.lo)});
          }
      });
      const std::string below = test::profile_error_of(at("[" + toml_number(k.lo - 1, true) + "]"));
      EXPECT_NE(below.find("bad.toml:" + std::to_string(line) + ": " + k.key + ": "),
                std::string::npos)
          << below;
      EXPECT_NE(below.find("is outside ["), std::string::npos) << below;
      const std::string empty = test::profile_error_of(at("[]"));
      if (std::string(k.key) == "seeds")
        EXPECT_NE(empty.find("seeds must not be empty"), std::string::npos) << empty;
      else
        EXPECT_EQ(empty, "no error");
    }
  });
  EXPECT_EQ(lists, 6);
  int line = 0;
  const std::string m = test::profile_error_of(
      with_section("grid", {{"store_weights", "\"no\""}}, "store_weights", &line));
  EXPECT_NE(m.find("bad.toml:" + std::to_string(line) + ": store_weights must be true or false"),
            std::string::npos)
      << m;
  EXPECT_FALSE(parse_profile(with_section("grid", {{"store_weights", "false"}}, "", &line), "t")
                   .axes.at("grid")
                   .store_weights);
}

// A list for each [teacher] axis key makes one noisy teacher per value other than the main
// teacher's, each differing from the main teacher in that key alone; a list for a key that is not
// an axis is refused.
TEST(ProfileSettings, ATeacherListIsANoiseAxisOnlyForTheDeclaredAxisKeys) {
  const std::string robustness = "[robustness]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n";
  const QueryBundleConfig defaults;
  kTeacherSettings(defaults, [&](const SettingInfo& k, const double& main) {
    SCOPED_TRACE(k.key);
    const double a = std::isinf(k.hi) ? 0.5 : k.hi / 2, b = std::isinf(k.hi) ? 2 : k.hi / 4;
    const std::string list = "[" + toml_number(a, false) + ", " + toml_number(main, false) + ", " +
                             toml_number(b, false) + "]";
    int line = 0;
    const std::string text = with_section("teacher", {{k.key, list}}, k.key, &line) + robustness;
    if (!k.axis) {
      const std::string m = test::profile_error_of(text);
      EXPECT_NE(m.find("bad.toml:" + std::to_string(line) + ": " + k.key + " must be a number"),
                std::string::npos)
          << m;
      return;
    }
    if (std::isinf(main)) return;  // "inf" is a string in TOML: beta's list is checked below
    const Profile p = parse_profile(text, "t.toml");
    ASSERT_EQ(p.robustness.teachers.size(), 2u);  // the main teacher's value is the reference
    for (const TeacherPoint& tp : p.robustness.teachers) {
      EXPECT_EQ(tp.axis, k.key);
      EXPECT_EQ(declared_field(kTeacherSettings, tp.queries, k.key), tp.level);
      kTeacherSettings(tp.queries, [&](const SettingInfo& j, const double& v) {
        if (std::string(j.key) != k.key) {
          EXPECT_EQ(v, declared_field(kTeacherSettings, p.queries, j.key)) << j.key;
        }
      });
    }
    EXPECT_EQ(p.robustness.teachers[0].level, a);
    EXPECT_EQ(p.robustness.teachers[1].level, b);
  });
  const Profile p =
      parse_profile(std::string(test::kSmallProfile) +
                        "[teacher]\nbeta = [\"inf\", 10, 1]\nmistake = 0.1\n" + robustness,
                    "t.toml");
  ASSERT_EQ(p.robustness.teachers.size(), 2u);
  EXPECT_EQ(p.robustness.teachers[0].tag, "beta=10");
  EXPECT_EQ(p.robustness.teachers[1].tag, "beta=1");
  EXPECT_EQ(p.robustness.teachers[1].queries.teacher.beta, 1);
  EXPECT_EQ(p.robustness.teachers[1].queries.teacher.mistake, 0.1);  // the main teacher's
  EXPECT_TRUE(std::isinf(p.queries.teacher.beta));
}

// The grid's tables: each required key of [fpe], [tpa] and [ablation], left out, is refused by
// name with the table's line; each integer list's declared lower bound is accepted and one
// below it refused with the value and the range.
TEST(ProfileSettings, EveryRequiredKeyOfTheGridsTablesIsDemandedAndItsListsRanged) {
  const std::string base = test::kSmallProfile;
  const auto table_text = [&](const std::string& name) {
    const size_t from = base.find("[" + name + "]");
    const size_t to = base.find("\n[", from + 1);
    return std::make_pair(from, to + 1);
  };
  const auto check = [&](const std::string& name, auto settings, const auto& defaults) {
    int required = 0;
    settings(defaults, [&](const SettingInfo& k, const auto& field) {
      if (!k.required) return;
      ++required;
      SCOPED_TRACE("[" + name + "] " + k.key);
      const auto [from, to] = table_text(name);
      std::string table = base.substr(from, to - from), text = base;
      const size_t at = table.find("\n" + std::string(k.key) + " = ");
      ASSERT_NE(at, std::string::npos) << table;
      const size_t end = table.find('\n', at + 1);
      std::string without = table;
      without.erase(at, end - at);
      text.replace(from, to - from, without);
      const int line = int(std::count(base.begin(), base.begin() + from, '\n')) + 1;
      const std::string m = test::profile_error_of(text);
      EXPECT_NE(m.find("bad.toml:" + std::to_string(line) + ": missing key '" + k.key + "'"),
                std::string::npos)
          << m;
      using T = std::decay_t<decltype(field)>;
      if constexpr (std::is_same_v<T, std::vector<int64_t>>) {
        for (const auto& [v, ok] : {std::pair{k.lo, true}, {k.lo - 1, false}}) {
          std::string with = table;
          with.replace(at + 1, end - at - 1,
                       std::string(k.key) + " = [" + toml_number(v, true) + "]");
          std::string t2 = base;
          t2.replace(from, to - from, with);
          const std::string e = test::profile_error_of(t2);
          if (ok)
            EXPECT_EQ(e.find("is outside"), std::string::npos) << e;
          else
            EXPECT_NE(e.find(std::string(k.key) + ": " + toml_number(v, true) + " is outside [" +
                             toml_number(k.lo, true) + ", "),
                      std::string::npos)
                << e;
        }
      }
    });
    EXPECT_GE(required, 2) << name;
  };
  check("fpe", kFpeSettings, Profile{});
  check("tpa", kTpaSettings, TpaGrid{});
  check("ablation", kAblationSettings, Profile{});
}

// [tpa] protocols: each declared protocol alone is accepted; an unknown name is refused with a
// message naming every declared one; a profile without the key runs all of them.
TEST(ProfileSettings, TpaProtocolsAreTheDeclaredOnes) {
  std::vector<std::string> all;
  for (const ProtocolInfo& c : kTpaProtocols) {
    all.push_back(c.name);
    std::string text = test::kSmallProfile;
    text.insert(text.find("[ablation]"), std::string("protocols = [\"") + c.name + "\"]\n");
    EXPECT_EQ(parse_profile(text, "t.toml").tpa_protocols, std::vector<std::string>{c.name});
  }
  EXPECT_EQ(parse_profile(test::kSmallProfile, "t.toml").tpa_protocols, all);
  std::string text = test::kSmallProfile;
  text.insert(text.find("[ablation]"), "protocols = [\"paper\", \"cubic\"]\n");
  const std::string m = test::profile_error_of(text);
  for (const ProtocolInfo& c : kTpaProtocols)
    EXPECT_NE(m.find(std::string("\"") + c.name + "\" (" + c.doc + ")"), std::string::npos) << m;
}

// An empty table leaves every key at its struct's default: the declaration's defaults are the
// structs' own (one source), and the digest's text of a default section is the default struct's.
TEST(ProfileSettings, AnAbsentKeyIsItsStructsDefault) {
  const Profile p = parse_profile(
      small_profile_base() + "[queries]\n[active]\n[study]\nenv = \"grid\"\n", "t.toml");
  EXPECT_EQ(settings_text(p.queries, kQueriesSettings),
            settings_text(QueryBundleConfig{}, kQueriesSettings));
  EXPECT_EQ(describe_active(p.active.at("grid")), describe_active(ActiveRounds{}));
  StudyPlan want;
  want.cohort.env = "grid";
  EXPECT_EQ(settings_text(p.study, kStudySettings), settings_text(want, kStudySettings));
  EXPECT_TRUE(p.study.enabled);
}

// The digest's text of a section, worked out by hand for one [active] table: the declared keys
// in order, each value exact. (A change to it changes every active task's digest.)
TEST(ProfileSettings, ASectionsDigestTextIsItsDeclaredKeysInOrder) {
  const Profile p = parse_profile(
      std::string(test::kSmallProfile) + "[active]\nmu = 0.25\npool = 3000\nmembers = 7\n",
      "t.toml");
  EXPECT_EQ(describe_active(p.active.at("grid")),
            "active members=7 pool=3000 batch=100 round_epochs=50 mu=0.25\n");
  const std::string m = test::profile_error_of(std::string(test::kSmallProfile) +
                                               "[study]\nenv = \"grid\"\nrandom = \"both\"\n");
  EXPECT_NE(m.find("[study] random must be \"unfrozen\" or \"frozen\""), std::string::npos) << m;
  const Profile f = parse_profile(
      std::string(test::kSmallProfile) + "[study]\nenv = \"grid\"\nrandom = \"frozen\"\n",
      "t.toml");
  EXPECT_TRUE(f.study.random_frozen);
  EXPECT_NE(settings_text(f.study, kStudySettings).find(" random=frozen"), std::string::npos);
}

TEST(ProfileSettings, TheKeysPageIsTheDeclarationsOwnTable) {
  std::ifstream in(std::string(SIRL_SOURCE_DIR) + "/docs/profile-keys.md");
  ASSERT_TRUE(in) << "docs/profile-keys.md is missing";
  std::stringstream page;
  page << in.rdbuf();
  EXPECT_NE(page.str().find(profile_keys_markdown()), std::string::npos)
      << "docs/profile-keys.md differs from the declarations: regenerate its tables with "
         "`sirl plan --keys`";
}

}  // namespace
}  // namespace sirl
