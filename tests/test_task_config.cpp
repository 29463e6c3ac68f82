// Each task compiled once when it is planned (experiment/task_config.h): what its runner reads of
// the profile, compiled from the profile its digest's text comes from, and no Profile beyond it.
#include <gtest/gtest.h>

#include <string>

#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/simulation_tasks.h"
#include "experiment/study_tasks.h"
#include "experiment/task_config.h"
#include "experiment/task_kinds.h"
#include "experiment/task_runner.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

// Runners receive the task and a RunContext; the context builds the shared data from the profile
// and does not hand the profile out, so a runner can read only what its task compiled.
template <class C>
constexpr bool hands_out_a_profile = requires(const C& c) {
  c.profile();
};
static_assert(!hands_out_a_profile<RunContext>, "a runner would read settings the digest misses");

// What every kind's compiled configuration must hold, checked against the profile directly for
// each task of a plan: the digest's settings text and bf16 choice as the kind gives them now, the
// hyper-parameters of the task's point, and each kind's own section.
int check_every_task(const Profile& p) {
  int checked = 0;
  for (const Task& t : make_plan(p).tasks) {
    SCOPED_TRACE(p.name + ": " + t.key);
    const TaskKindSpec& kind = t.kind.spec();
    const TaskConfig& c = t.compiled();
    EXPECT_EQ(c.settings, kind.settings(t, p));
    EXPECT_EQ(c.bf16_products, kind.bf16_products(t, p));
    const bool study = std::string(kind.name).starts_with("study_");
    EXPECT_EQ(c.hyper.has_value(), !study);
    EXPECT_EQ(c.study.has_value(), study);
    if (c.hyper && (t.kind == tpa_kind() || t.kind == robust_tpa_kind())) {
      EXPECT_EQ(describe(*c.hyper), describe(tpa_cell_hyper(p, t.env, t.hyper, t.variant)));
    } else if (c.hyper) {
      EXPECT_EQ(describe(*c.hyper), describe(hyper_at(p, t.env, t.hyper)));
    }
    EXPECT_EQ(c.active.has_value(), t.kind == active_kind());
    if (c.active) {
      const ActiveRounds& want = p.active.at(t.env);
      EXPECT_EQ(c.active->members, want.members);
      EXPECT_EQ(c.active->pool, want.pool);
      EXPECT_EQ(c.active->round_epochs, want.round_epochs);
      EXPECT_EQ(c.active->rule, t.variant.selection);
      EXPECT_EQ(c.active->budget, queries_for(p, t.teacher).similarity);
      EXPECT_EQ(describe(c.active->hyper), describe(hyper_at(p, t.env, t.hyper)));
    }
    if (c.study) {
      EXPECT_EQ(c.study->seeds, p.study.seeds);
      EXPECT_EQ(c.study->cv_splits, p.study.splits);
      EXPECT_EQ(c.study->hyper.sirl.epochs, p.study.epochs);
      EXPECT_EQ(c.study->hyper.precision, p.precision);
      EXPECT_EQ(c.study_users, p.study.cohort.users);
    }
    EXPECT_EQ(c.teacher.has_value(), !t.teacher.empty());
    if (c.teacher) {
      EXPECT_EQ(c.teacher->tag, t.teacher);
    }
    EXPECT_EQ(c.external.has_value(), t.variant.method == Method::external && t.kind == rep_kind());
    ++checked;
  }
  return checked;
}

TEST(TaskConfig, EveryPlannedTaskCarriesWhatItsRunnerReadsCompiledFromTheProfile) {
  // smoke: every simulation kind and the study; beyond: active tasks and noisy teachers.
  const Profile smoke = load_profile("smoke"), beyond = load_profile("beyond");
  EXPECT_GT(check_every_task(smoke), 500);
  EXPECT_GT(check_every_task(beyond), 500);
  bool active = false, noisy = false, study = false;
  for (const Task& t : make_plan(beyond).tasks) {
    active = active || t.compiled().active.has_value();
    noisy = noisy || t.compiled().teacher.has_value();
  }
  for (const Task& t : make_plan(smoke).tasks) study = study || t.compiled().study.has_value();
  EXPECT_TRUE(active && noisy && study) << "the profiles no longer cover every section";
}

TEST(TaskConfig, AnExternalMethodsRepresentationCarriesItsDeclaration) {
  std::string text = test::kSmallProfile;
  const std::string xxh3(32, 'a');
  text += "[external.mine]\nembeddings = \"e.h5\"\nxxh3 = \"" + xxh3 + "\"\n";
  const Profile p = parse_profile(text, "/tmp/x/p.toml");
  int reps = 0;
  for (const Task& t : make_plan(p).tasks) {
    if (!(t.kind == rep_kind()) || t.variant.method != Method::external) continue;
    ASSERT_TRUE(t.compiled().external.has_value()) << t.key;
    EXPECT_EQ(t.compiled().external->embeddings, "/tmp/x/e.h5");
    EXPECT_EQ(t.compiled().external->xxh3, xxh3);
    ++reps;
  }
  EXPECT_GT(reps, 0);
  check_every_task(p);
}

// The compiled configuration is the plan's snapshot: a profile changed after planning changes
// nothing a planned task runs with (a runner cannot see the change), and a plan made from the
// changed profile compiles the new value into both the runner's section and the digest's text.
TEST(TaskConfig, ATaskRunsWithWhatWasCompiledWhenItWasPlanned) {
  Profile p = load_profile("beyond");
  const Plan before = make_plan(p);
  const std::string env = before.tasks.front().env;
  const int members = p.active.at(env).members;
  p.active.at(env).members = members + 1;
  const Plan after = make_plan(p);
  int compared = 0;
  for (size_t i = 0; i < before.tasks.size(); ++i) {
    const Task& a = before.tasks[i];
    if (!(a.kind == active_kind()) || a.env != env) continue;
    const Task& b = after.tasks[size_t(after.index.at(a.key))];
    EXPECT_EQ(a.compiled().active->members, members);
    EXPECT_EQ(b.compiled().active->members, members + 1);
    EXPECT_NE(a.compiled().settings, b.compiled().settings) << "the digest would not see it";
    ++compared;
  }
  EXPECT_GT(compared, 0);
}

// A preference φ's digest leaves pref.stop's minimum and tolerance out under the paper's "fixed"
// schedule (they change no bit: results stored before the rule existed are still found), and
// names the rule and both values once it can end training.
TEST(TaskConfig, APreferencePhisDigestNamesItsStopRuleOnlyWhenTheRuleCanEndIt) {
  std::string text = test::kSmallProfile;
  const Profile fixed = parse_profile(text, "t.toml");
  text.replace(text.find("[hyper.grid]\n"), 13,
               "[hyper.grid]\n\"pref.stop\" = \"converged\"\n\"pref.stop_min_epochs\" = 50\n");
  const Profile converged = parse_profile(text, "t.toml");
  int reps = 0;
  for (const Profile* p : {&fixed, &converged})
    for (const Task& t : make_plan(*p).tasks) {
      if (!(t.kind == rep_kind())) continue;
      const std::string& s = t.compiled().settings;
      if (t.variant.method != Method::multipref10) {
        EXPECT_EQ(s.find("pref.stop"), std::string::npos) << t.key << "\n" << s;
        continue;
      }
      ++reps;
      if (p == &fixed) {
        EXPECT_EQ(s.find("pref.stop"), std::string::npos) << s;
        EXPECT_NE(s.find("pref.epochs = "), std::string::npos) << s;
      } else {
        EXPECT_NE(s.find("pref.stop = converged\n"), std::string::npos) << s;
        EXPECT_NE(s.find("pref.stop_min_epochs = 50\n"), std::string::npos) << s;
        EXPECT_NE(s.find("pref.stop_rel_tol = "), std::string::npos) << s;
      }
    }
  EXPECT_GT(reps, 0);
  std::string bad = test::kSmallProfile;
  bad.replace(bad.find("[hyper.grid]\n"), 13, "[hyper.grid]\n\"pref.stop\" = \"sometimes\"\n");
  try {
    parse_profile(bad, "t.toml");
    ADD_FAILURE() << "an unknown pref.stop was accepted";
  } catch (const ProfileError& e) {
    EXPECT_NE(std::string(e.what()).find("pref.stop must be \"fixed\""), std::string::npos)
        << e.what();
  }
}

TEST(TaskConfig, ATaskNotPlannedByAddTaskHasNoConfigurationAndAStudyTaskNoHyperParameters) {
  Task t;
  t.key = "grid/s0/vae";
  t.kind = vae_kind();
  EXPECT_THROW(t.compiled(), std::logic_error);
  EXPECT_THROW(t.hyper_values(), std::logic_error);
  for (const Task& s : make_plan(load_profile("smoke")).tasks)
    if (s.kind == study_analysis_kind()) {
      EXPECT_NO_THROW(s.compiled());
      EXPECT_THROW(s.hyper_values(), std::logic_error) << "the study reads [study], not [hyper]";
      EXPECT_GT(s.input_keys_in_order.size(), s.input_keys.size())
          << "the analysis reads many tasks of one kind, in order";
    }
}

}  // namespace
}  // namespace sirl
