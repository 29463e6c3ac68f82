// Plan expansion: task counts, frozen modes, shards, the cells of each figure.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "datasets/environments.h"
#include "engine/method_catalog.h"
#include "experiment/expected_epochs.h"
#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/simulation_tasks.h"
#include "jobs/run.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

// The cost model's expected head epochs: a measured table per environment, mode and tolerance,
// interpolated in log M between measured points and clamped to [minimum, cap]; the schedule's
// epochs wherever nothing was measured.
TEST(Plan, ExpectedHeadEpochsFollowTheMeasuredTableOfTheCellsTolerance) {
  Hyper h = paper_hyper("jaco");
  EXPECT_EQ(expected_head_epochs("jaco", true, 190, h), 1000);  // fixed: every epoch
  h.tpa_stop = "converged";
  EXPECT_NEAR(expected_head_epochs("jaco", false, 190, h), 100, 1e-12);
  EXPECT_NEAR(expected_head_epochs("jaco", true, 10, h), 101.6, 1e-12);  // tolerance 0.01
  h.tpa_stop_frozen_rel_tol = 0.001;
  EXPECT_NEAR(expected_head_epochs("jaco", true, 10, h), 367.9, 1e-12);
  EXPECT_NEAR(expected_head_epochs("jaco", true, 190, h), 533.5, 1e-12);
  EXPECT_NEAR(expected_head_epochs("jaco", true, 400, h), 533.5, 1e-12);  // beyond: nearest
  // M = 20 lies log(20/10) / log(50/10) of the way from M = 10 to M = 50 in log M:
  const double w = std::log(2.0) / std::log(5.0);
  EXPECT_NEAR(expected_head_epochs("jaco", true, 20, h), 367.9 + w * (742.6 - 367.9), 1e-9);
  EXPECT_NEAR(expected_head_epochs("jaco", false, 190, h), 100, 1e-12);  // unfrozen: its own
  // The schedule caps the expectation:
  h.tpa.epochs = 300;
  EXPECT_NEAR(expected_head_epochs("jaco", true, 50, h), 300, 1e-12);
  h.tpa.epochs = 1000;
  h.tpa_stop_frozen_rel_tol = 0.005;  // never measured: every epoch
  EXPECT_EQ(expected_head_epochs("jaco", true, 50, h), 1000);
  h.tpa_stop_min_epochs = 50;  // another minimum: never measured
  EXPECT_EQ(expected_head_epochs("jaco", false, 50, h), 1000);
}

// The cost model's expected preference-φ epochs under pref.stop: the measured table's entry of
// the same environment, method, pre-training, minimum and tolerance, clamped to [minimum, cap];
// the schedule's epochs for anything not measured.
TEST(Plan, ExpectedPrefEpochsFollowTheMeasuredTableOfTheRulesSettings) {
  Hyper h = paper_hyper("jaco");
  ASSERT_EQ(h.pref.epochs, 5000);
  EXPECT_EQ(expected_pref_epochs("jaco", "multipref10", 1000, false, h), 5000);  // fixed
  h.pref_stop = "converged";
  for (const char* m : {"singlepref", "multipref10", "multipref50"}) {
    EXPECT_NEAR(expected_pref_epochs("jaco", m, 1000, false, h), 500, 1e-12) << m;
    EXPECT_NEAR(expected_pref_epochs("jaco", m, 100, false, h), 500, 1e-12) << m;  // nearest N
  }
  EXPECT_EQ(expected_pref_epochs("jaco", "multipref10", 1000, true, h), 5000);  // +VAE: none
  Hyper g = paper_hyper("grid");
  g.pref_stop = "converged";
  EXPECT_EQ(expected_pref_epochs("grid", "multipref10", 1000, false, g), g.pref.epochs);  // none
  h.pref_stop_rel_tol = 0.001;  // another tolerance: never measured
  EXPECT_EQ(expected_pref_epochs("jaco", "singlepref", 1000, false, h), 5000);
  h.pref_stop_rel_tol = 0.01;
  h.pref_stop_min_epochs = 200;  // another minimum: never measured
  EXPECT_EQ(expected_pref_epochs("jaco", "singlepref", 1000, false, h), 5000);
  h.pref_stop_min_epochs = 500;
  h.pref.epochs = 300;  // the schedule caps the expectation
  EXPECT_NEAR(expected_pref_epochs("jaco", "singlepref", 1000, false, h), 300, 1e-12);
}

// A representation's cost is its method's declared training (MethodTraining): per epoch of its
// schedule, 3 rows through φ per SIRL triplet and 2 per preference pair, forward + backward (3 ×
// a forward's 2·in·out per layer), plus the one forward pass over Ξ it stores. Counted by hand
// from the widths here, not by MlpShape.
TEST(Plan, ARepresentationCostsItsMethodsRowsPerAnswerOverEveryEpochOfItsSchedule) {
  const Profile p = parse_profile(test::kSmallProfile, "t.toml");
  const Plan plan = make_plan(p);
  int checked_sirl = 0, checked_pref = 0, untrained = 0;
  for (const Task& t : plan.tasks) {
    if (!(t.kind == rep_kind())) continue;
    const Hyper& h = hyper_at(p, t.env, t.hyper);
    std::vector<int> w{env_spec(t.env).input_dim(p.data)};
    w.insert(w.end(), h.phi_hidden.begin(), h.phi_hidden.end());
    w.push_back(h.embedding_dim);
    double forward_per_row = 0;
    for (size_t i = 0; i + 1 < w.size(); ++i) forward_per_row += 2.0 * w[i] * w[i + 1];
    const double embed = forward_per_row * double(env_spec(t.env).trajectories(p.data));
    const std::string m = method_name(t.variant.method);
    if (m == "sirl") {
      EXPECT_DOUBLE_EQ(t.protocol_flops, 3 * forward_per_row * 3.0 * t.N * 7 + embed) << t.key;
      ++checked_sirl;
    } else if (m == "multipref10") {
      EXPECT_DOUBLE_EQ(t.protocol_flops, 3 * forward_per_row * 2.0 * t.N * h.pref.epochs + embed)
          << t.key;
      EXPECT_DOUBLE_EQ(t.flops, t.protocol_flops) << t.key;  // no early end
      ++checked_pref;
    } else if (m == "random") {
      EXPECT_DOUBLE_EQ(t.protocol_flops, embed) << t.key;  // no training: Ξ's embedding only
      ++untrained;
    }
  }
  EXPECT_GT(checked_sirl, 0);
  EXPECT_GT(checked_pref, 0);
  EXPECT_GT(untrained, 0);
}

// [tpa] stop = { sirl = "fixed" }: every TPA cell of SIRL (its [tpa] and [ablation] cells, frozen
// and unfrozen) runs the paper's epochs while every other method's heads stop by [hyper]'s rule.
// What a cell reads (its settings, so its digest) and what the plan expects it to cost say so.
TEST(Plan, AMethodsStopRuleOverridesHyperForEveryTpaCellOfThatMethod) {
  std::string text = test::kSmallProfile;
  const std::string M_line = "M = [10, 80]\n";
  text.replace(text.find(M_line), M_line.size(), M_line + "stop = { sirl = \"fixed\" }\n");
  text += "\"tpa.stop\" = \"converged\"\n";
  const Profile p = parse_profile(text, "t.toml");
  ASSERT_EQ(p.tpa_stop_by_method.size(), 1u);
  EXPECT_EQ(p.tpa_stop_by_method.at("sirl"), "fixed");
  const Plan plan = make_plan(p);
  int sirl_cells = 0, other_cells = 0;
  for (const Task& t : plan.tasks) {
    if (!(t.kind == tpa_kind())) continue;
    const std::string settings = tpa_kind().settings(t, p);
    const bool sirl = t.variant.name() == "sirl";
    (sirl ? sirl_cells : other_cells) += 1;
    EXPECT_NE(settings.find(sirl ? "tpa.stop = fixed" : "tpa.stop = converged"), std::string::npos)
        << t.key << "\n"
        << settings;
    // GridRobot's heads are expected to stop at 100 of the cap's 500 epochs under the rule.
    EXPECT_NEAR(t.flops / t.protocol_flops, sirl ? 1.0 : 0.2, 1e-12) << t.key;
    EXPECT_EQ(tpa_cell_hyper(p, t.env, t.hyper, t.variant).tpa_stop, sirl ? "fixed" : "converged");
  }
  EXPECT_GT(sirl_cells, 0);
  EXPECT_GT(other_cells, 0);
  // Without the override every cell reads "converged": the rule is what changed SIRL's.
  std::string plain = text;
  plain.erase(plain.find("stop = {"), std::string("stop = { sirl = \"fixed\" }\n").size());
  const Profile q = parse_profile(plain, "t.toml");
  for (const Task& t : make_plan(q).tasks) {
    if (t.kind == tpa_kind()) {
      EXPECT_NE(tpa_kind().settings(t, q).find("tpa.stop = converged"), std::string::npos);
    }
  }
}

// [pref] stop = { singlepref = "converged", grid2 = { singlepref = "fixed" } }: the φ of that
// variant alone trains by the rule (its +VAE variant and the other preference methods keep
// [hyper]'s), in every environment but the one whose own entry says otherwise; the rule is in
// the φ's settings, so in its digest.
TEST(Plan, APreferenceMethodsStopRuleReachesItsOwnPhiOnly) {
  const std::string text =
      "name = \"t\"\nenvs = [\"grid\", \"grid2\"]\nseeds = [0]\n"
      "[queries]\nsimilarity = 300\npreference = 300\ntpa_pairs = 100\n"
      "[fpe]\nmethods = [\"singlepref\", \"singlepref+vae\", \"multipref10\"]\nN = [100]\n"
      "[pref]\nstop = { singlepref = \"converged\", grid2 = { singlepref = \"fixed\" } }\n";
  const Profile p = parse_profile(text, "t.toml");
  int reps = 0;
  for (const Task& t : make_plan(p).tasks) {
    if (!(t.kind == rep_kind())) continue;
    ++reps;
    const bool stops = t.variant.name() == "singlepref" && t.env == "grid";
    EXPECT_EQ(rep_task_hyper(p, t.env, t.hyper, t.variant).pref_stop, stops ? "converged" : "fixed")
        << t.key;
    EXPECT_EQ(t.hyper_values().pref_stop, stops ? "converged" : "fixed") << t.key;
    const std::string settings = rep_kind().settings(t, p);
    EXPECT_EQ(settings.find("pref.stop = converged") != std::string::npos, stops) << t.key << "\n"
                                                                                  << settings;
  }
  EXPECT_EQ(reps, 2 * 3);
  // The same φ without the table is [hyper]'s "fixed": a different digest.
  std::string plain = text;
  plain.erase(plain.find("[pref]"));
  const Plan a = make_plan(p), b = make_plan(parse_profile(plain, "t.toml"));
  const auto settings_of = [](const Plan& plan, const Profile& q, const std::string& key) {
    for (const Task& t : plan.tasks)
      if (t.key == key) return rep_kind().settings(t, q);
    return std::string("missing ") + key;
  };
  const Profile q = parse_profile(plain, "t.toml");
  EXPECT_NE(settings_of(a, p, "grid/s0/singlepref/N100/rep"),
            settings_of(b, q, "grid/s0/singlepref/N100/rep"));
  EXPECT_EQ(settings_of(a, p, "grid/s0/multipref10/N100/rep"),
            settings_of(b, q, "grid/s0/multipref10/N100/rep"));

  // Refused: a method not trained on preferences, one the profile does not run, a rule that is
  // not one, another key in [pref].
  const auto error_of = [&](const std::string& table) {
    try {
      parse_profile(text.substr(0, text.find("[pref]")) + table, "bad.toml");
    } catch (const ProfileError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("[pref]\nstop = { sirl = \"converged\" }\n")
                .find("[pref] stop: 'sirl' is not trained on preferences"),
            std::string::npos);
  EXPECT_NE(error_of("[pref]\nstop = { multipref50 = \"converged\" }\n")
                .find("[pref] stop: 'multipref50' is not run by this profile"),
            std::string::npos);
  const std::string rule = error_of("[pref]\nstop = { singlepref = \"sometimes\" }\n");
  EXPECT_NE(rule.find("bad.toml:"), std::string::npos) << rule;
  EXPECT_NE(rule.find("[pref] stop.singlepref: hyper-parameter pref.stop must be \"fixed\""),
            std::string::npos)
      << rule;
  EXPECT_NE(error_of("[pref]\nepochs = 3\n").find("unknown key 'epochs' in [pref]"),
            std::string::npos);
}

// [tpa] stop = { sirl = "fixed", jaco = { "sirl+vae" = "converged" } }: an environment's entry
// applies in that environment only and wins over the entry for every environment; a table must
// be named after one of the profile's envs.
TEST(Plan, AnEnvironmentsStopRuleAppliesThereOnlyAndWinsOverTheGeneralOne) {
  const std::string head =
      "name = \"t\"\nenvs = [\"grid\", \"jaco\"]\nseeds = [0]\n"
      "[tpa]\nmethods = [\"sirl\", \"sirl+vae\", \"random\"]\nN = [100]\n"
      "M = [10]\n";
  const std::string hyper = "[hyper.jaco]\n\"tpa.stop\" = \"converged-unfrozen\"\n";
  const Profile p = parse_profile(head +
                                      "stop = { \"sirl+vae\" = \"fixed\", sirl = \"fixed\", "
                                      "jaco = { \"sirl+vae\" = \"converged\" } }\n" +
                                      hyper,
                                  "t.toml");
  const auto rule = [&](const std::string& env, const char* method) {
    return tpa_cell_hyper(p, env, "", parse_variant(method)).tpa_stop;
  };
  EXPECT_EQ(rule("jaco", "sirl+vae"), "converged");  // the environment's own entry
  EXPECT_EQ(rule("grid", "sirl+vae"), "fixed");      // the general entry elsewhere
  EXPECT_EQ(rule("jaco", "sirl"), "fixed");
  EXPECT_EQ(rule("jaco", "random"), "converged-unfrozen");  // no entry: [hyper.jaco]'s rule
  EXPECT_EQ(rule("grid", "random"), "fixed");               // no entry: the default
  // The reference truth's heads (frozen, on the true features) take a rule of their own too; a
  // profile without references has no truth cells to give one.
  const Profile t =
      parse_profile(head + "stop = { jaco = { truth = \"converged\" } }\n" + hyper, "t.toml");
  EXPECT_EQ(tpa_cell_hyper(t, "jaco", "", Variant{Method::truth}).tpa_stop, "converged");
  EXPECT_EQ(tpa_cell_hyper(t, "jaco", "", parse_variant("sirl")).tpa_stop, "converged-unfrozen");
  bool truth_cell = false;
  for (const Task& c : make_plan(t).tasks)
    if (c.kind == tpa_kind() && c.variant.method == Method::truth && c.env == "jaco") {
      truth_cell = true;
      EXPECT_EQ(c.hyper_values().tpa_stop, "converged") << c.key;
    }
  EXPECT_TRUE(truth_cell);
  try {
    parse_profile("references = false\n" + head + "stop = { truth = \"converged\" }\n" + hyper,
                  "t.toml");
    ADD_FAILURE() << "a rule for truth in a profile without references was accepted";
  } catch (const ProfileError& e) {
    EXPECT_NE(std::string(e.what()).find("'truth' is not one of [tpa] methods"), std::string::npos)
        << e.what();
  }
  const auto error = [&](const std::string& stop) {
    try {
      parse_profile(head + stop + hyper, "t.toml");
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("stop = { jaco2 = { sirl = \"fixed\" } }\n")
                .find("must be named after one of envs (grid, jaco)"),
            std::string::npos);
  EXPECT_NE(error("stop = { jaco = { vae = \"fixed\" } }\n")
                .find("stop.jaco: 'vae' is not one of [tpa] methods"),
            std::string::npos);
  EXPECT_NE(error("stop = { jaco = { sirl = \"early\" } }\n").find("stop.jaco.sirl"),
            std::string::npos);
}

// The paper profile stops reward heads only where a rule was tested equivalent on JacoRobot
// (docs/stopping-rule.md): unfrozen cells by the first rule, SIRL+VAE's frozen cells by the
// second, SIRL and every other frozen cell at the paper's epochs; GridRobot's at the paper's.
TEST(Plan, ThePaperProfileStopsHeadsOnlyWhereARuleWasTestedEquivalent) {
  const Profile p = load_profile("paper");
  const Plan plan = make_plan(p);
  int stopped = 0;
  double total = 0, protocol = 0;
  for (const Task& t : plan.tasks) {
    total += t.flops, protocol += t.protocol_flops;
    if (!(t.kind == tpa_kind())) continue;
    const Hyper h = tpa_cell_hyper(p, t.env, t.hyper, t.variant);
    const StopRule r = tpa_stop_rule(h, t.frozen);
    const bool want = t.env == "jaco" && t.variant.name() != "sirl" &&
                      (!t.frozen || t.variant.name() == "sirl+vae");
    EXPECT_EQ(r.converged, want) << t.key;
    if (want) {
      EXPECT_EQ(r.rel_tol, t.frozen ? 0.001 : 0.01) << t.key;
    }
    stopped += want;
  }
  EXPECT_GT(stopped, 0);
  EXPECT_LT(total, protocol);  // what `sirl plan paper` prints as executed against the protocol
}

// The paper profile stops a preference φ by pref.stop only where the rule's test held
// (docs/stopping-rule.md, "Preference φ that stop when they have learned"): JacoRobot's φ of the
// methods whose FPE and TPA were both equivalent, without VAE pre-training; every other φ runs
// the paper's 5000 epochs.
TEST(Plan, ThePaperProfileStopsPreferencePhiOnlyWhereTheRuleWasTestedEquivalent) {
  const std::set<std::string> held = {};  // the methods equivalent on both metrics
  const Profile p = load_profile("paper");
  int prefs = 0;
  for (const Task& t : make_plan(p).tasks) {
    if (!(t.kind == rep_kind()) || !method_spec(t.variant.method).training.preferences) continue;
    ++prefs;
    const bool want = t.env == "jaco" && !t.variant.vae && held.count(t.variant.name());
    EXPECT_EQ(t.hyper_values().pref_stop, want ? "converged" : "fixed") << t.key;
    if (want) {
      EXPECT_EQ(t.hyper_values().pref_stop_min_epochs, 500) << t.key;
      EXPECT_EQ(t.hyper_values().pref_stop_rel_tol, 0.01) << t.key;
    }
  }
  EXPECT_GT(prefs, 0);
}

TEST(Plan, TaskCountsMatchTheGrid) {
  const Profile p = parse_profile(test::kSmallProfile, "t.toml");
  const Plan plan = make_plan(p);
  const int S = 3;
  // VAE: one per seed (sirl+vae and vae need it).
  EXPECT_EQ(plan.count(vae_kind()), S);
  // FPE: sirl, sirl+vae × 3 N; vae and random once each (no N); the references truth and raw.
  EXPECT_EQ(plan.count(fpe_kind()), S * (2 * 3 + 2 + 2));
  // TPA main: sirl (frozen) and multipref10 (unfrozen) × 2 N × 2 M; random (unfrozen) × 2 M.
  // Ablation: sirl, sirl+vae × 2 frozen × 1 M; random × 2 frozen. Cells shared with the main
  // grid (sirl N300 M80 frozen; random M80 unfrozen) are counted once.
  // The truth reference under the paper's head × 2 M (raw has linear heads only).
  const int main_cells = 2 * 2 * 2 + 2;
  const int ablation_new = 2 * 2 + 2 - 2;
  EXPECT_EQ(plan.count(tpa_kind()), S * (main_cells + ablation_new + 2));
  // Linear evaluation: every [tpa] cell once (φ frozen: no modes), truth and raw × 2 M.
  EXPECT_EQ(plan.count(linear_tpa_kind()), S * (main_cells + 2 * 2));
  // Representations: sirl N100/200/300, sirl+vae N100/200/300, vae, random, multipref10 N100/300.
  EXPECT_EQ(plan.count(rep_kind()), S * (3 + 3 + 1 + 1 + 2));
  // Every dependency precedes its dependent, and every FPE/TPA task depends on one rep but a
  // reference's, which reads none (φ is a function of Ξ).
  for (size_t i = 0; i < plan.tasks.size(); ++i) {
    for (int d : plan.tasks[i].deps) EXPECT_LT(size_t(d), i);
    const Task& t = plan.tasks[i];
    if (is_reference(t.variant.method)) {
      EXPECT_TRUE(t.deps.empty()) << t.key;
      continue;
    }
    if (t.kind == fpe_kind() || t.kind == tpa_kind() || t.kind == linear_tpa_kind()) {
      ASSERT_EQ(plan.tasks[i].deps.size(), 1u);
      EXPECT_EQ(plan.tasks[plan.tasks[i].deps[0]].kind, rep_kind());
    }
  }
  std::set<std::string> keys;
  for (const auto& t : plan.tasks) EXPECT_TRUE(keys.insert(t.key).second) << t.key;
}

// [tpa] protocols: "linear" alone drops every paper-protocol cell of [tpa] (the ablation's stay),
// "paper" alone every linear one; a linear cell's key ends in /linear, reads the same φ as the
// paper's cell and is frozen.
TEST(Plan, TheTpaProtocolsChooseWhichCellsRun) {
  auto with = [](const std::string& protocols) {
    std::string text = test::kSmallProfile;
    text.replace(text.find("M = [10, 80]\n"), 13, "M = [10, 80]\nprotocols = " + protocols + "\n");
    return make_plan(parse_profile(text, "t.toml"));
  };
  const Plan both = make_plan(parse_profile(test::kSmallProfile, "t.toml"));
  const Plan linear = with("[\"linear\"]"), paper = with("[\"paper\"]");
  EXPECT_EQ(paper.count(linear_tpa_kind()), 0);
  EXPECT_EQ(paper.count(tpa_kind()), both.count(tpa_kind()));
  EXPECT_EQ(linear.count(linear_tpa_kind()), both.count(linear_tpa_kind()));
  for (const Task& t : linear.tasks) {
    if (t.kind == tpa_kind()) {
      EXPECT_TRUE(t.in_ablation && !t.in_main) << t.key;
    }
  }
  const Task& cell = both.tasks[size_t(both.index.at("grid/s0/multipref10/N100/tpa/M10/linear"))];
  EXPECT_TRUE(cell.frozen);
  EXPECT_EQ(cell.input(rep_kind()), "grid/s0/multipref10/N100/rep");
  EXPECT_EQ(both.index.count("grid/s0/raw/tpa/M10/linear"), 1u);
  EXPECT_EQ(both.index.count("grid/s0/raw/tpa/M10/frozen"), 0u);  // raw: linear heads only
  EXPECT_EQ(both.index.count("grid/s0/truth/tpa/M10/frozen"), 1u);
  for (const char* bad : {"[]", "[\"paper\", \"paper\"]", "[\"probe\"]", "\"linear\""})
    EXPECT_THROW(with(bad), ProfileError) << bad;
}

// frozen = "best" (the default): SIRL frozen, every other method unfrozen (the paper's best
// configurations, Fig. 5); an explicit list runs the listed modes for every method.
TEST(Plan, FrozenBestIsSirlFrozenAndTheOthersUnfrozen) {
  const Plan plan = make_plan(parse_profile(test::kSmallProfile, "t.toml"));
  int sirl = 0, others = 0;
  for (const auto& t : plan.tasks) {
    if (t.kind != tpa_kind() || !t.in_main) continue;
    if (t.variant.method == Method::sirl || is_reference(t.variant.method)) {
      EXPECT_TRUE(t.frozen) << t.key;
      ++sirl;
    } else {
      EXPECT_FALSE(t.frozen) << t.key;
      ++others;
    }
  }
  EXPECT_GT(sirl, 0);
  EXPECT_GT(others, 0);
  std::string both = test::kSmallProfile;
  both.replace(both.find("M = [10, 80]"), 12, "M = [10, 80]\nfrozen = [true, false]");
  const Plan p2 = make_plan(parse_profile(both, "t.toml"));
  EXPECT_TRUE(p2.index.count("grid/s0/multipref10/N100/tpa/M10/frozen"));
  EXPECT_TRUE(p2.index.count("grid/s0/sirl/N100/tpa/M10/unfrozen"));
}

TEST(Plan, ShardsPartitionTheWorkAndKeepDependencies) {
  const Plan plan = make_plan(parse_profile(test::kSmallProfile, "t.toml"));
  std::vector<int> owners(plan.tasks.size(), 0);
  for (int s = 0; s < 3; ++s) {
    const auto in = shard_tasks(plan, s, 3);
    for (size_t i = 0; i < in.size(); ++i) {
      if (!in[i]) continue;
      if (plan.tasks[i].kind != vae_kind()) ++owners[i];
      for (int d : plan.tasks[i].deps) EXPECT_TRUE(in[d]) << plan.tasks[i].key;
    }
  }
  for (size_t i = 0; i < plan.tasks.size(); ++i) {
    if (plan.tasks[i].kind != vae_kind()) {
      EXPECT_EQ(owners[i], 1) << plan.tasks[i].key;
    }
  }
}

// Fig. 5 and Fig. 7 read which cells belong to them from the file; the plan marks a cell both
// when the two grids share it.
TEST(Plan, MarksTheCellsOfTheMainGridAndOfTheAblation) {
  const std::string text =
      "name = \"x\"\nenvs = [\"grid\"]\nseeds = [0]\n[tpa]\nmethods = [\"sirl\"]\nN = [100]\n"
      "M = [10, 20]\n[ablation]\nmethods = [\"sirl\"]\nN = [100]\nM = [20]\n";
  const Plan plan = make_plan(parse_profile(text));
  const auto& frozen20 = plan.tasks[plan.index.at("grid/s0/sirl/N100/tpa/M20/frozen")];
  EXPECT_TRUE(frozen20.in_main && frozen20.in_ablation);
  const auto& frozen10 = plan.tasks[plan.index.at("grid/s0/sirl/N100/tpa/M10/frozen")];
  EXPECT_TRUE(frozen10.in_main && !frozen10.in_ablation);
  const auto& unfrozen20 = plan.tasks[plan.index.at("grid/s0/sirl/N100/tpa/M20/unfrozen")];
  EXPECT_TRUE(!unfrozen20.in_main && unfrozen20.in_ablation);
}

// The cost model's main-memory traffic of a TPA cell (what /tables/timings turns into its memory
// roof): the 20 heads train one after another, so a cell streams only when one head's weights and
// moments (16 bytes a parameter) outgrow a core's cache share (5 MiB), and then 32 bytes a
// parameter a step. By hand, with quick's settings (64 pairs a batch, 15 JacoRobot epochs):
//  - GridRobot unfrozen, φ 19→128→128→6 (19 846) + head 6→128→128→1 (17 537): 37 383 parameters,
//    598 KB: in cache (before, the 20 heads' 12 MB together counted as streaming);
//  - JacoRobot unfrozen, φ 2037→1024→1024→6 (3 142 662) + head 6→1024→1024→1 (1 057 793):
//    4 200 455 parameters; M = 10 is one step an epoch: 20 × 32 × 4 200 455 × 15 bytes;
//  - JacoRobot frozen, the head alone (1 057 793 parameters, 17 MB), M = 100: 2 steps an epoch.
TEST(Plan, ATpaCellStreamsOnlyWhatOneHeadCannotKeepInCache) {
  const Profile p = parse_profile(R"(
name = "stream"
envs = ["grid", "jaco"]
seeds = [0]
[tpa]
methods = ["sirl", "multipref10"]
N = [100]
M = [10, 100]
frozen = [true, false]
[hyper.jaco]
"tpa.epochs" = 15
)",
                                  "stream.toml");
  int grid = 0, jaco10 = 0, jaco100 = 0;
  for (const Task& t : make_plan(p).tasks) {
    if (t.kind != tpa_kind()) continue;
    if (t.env == "grid") {
      EXPECT_EQ(t.stream_bytes, 0.0) << t.key;
      grid += !t.frozen;
    } else if (!t.frozen && t.M == 10) {
      EXPECT_DOUBLE_EQ(t.stream_bytes, 20.0 * 32 * 4200455 * 15) << t.key;
      ++jaco10;
    } else if (t.frozen && t.M == 100) {
      EXPECT_DOUBLE_EQ(t.stream_bytes, 20.0 * 32 * 1057793 * 2 * 15) << t.key;
      ++jaco100;
    }
  }
  EXPECT_GT(grid, 0);
  EXPECT_GT(jaco10, 0);
  EXPECT_GT(jaco100, 0);
}

}  // namespace
}  // namespace sirl
