// The paper's hyper-parameters per environment, and setting them by name.
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/hyper_key_docs.h"
#include "engine/hyperparams.h"

namespace sirl {
namespace {

TEST(Hyper, PaperValuesPerEnvironment) {
  const Hyper g = paper_hyper("grid"), j = paper_hyper("jaco");
  EXPECT_EQ(g.phi_hidden, (std::vector<int>{128, 128}));
  EXPECT_EQ(j.phi_hidden, (std::vector<int>{1024, 1024}));
  EXPECT_EQ(g.sirl.epochs, 3000);
  EXPECT_EQ(g.sirl.batch, 64);
  EXPECT_DOUBLE_EQ(g.sirl.adam.lr, 0.004);
  EXPECT_DOUBLE_EQ(g.sirl.adam.decay, 0.99999);
  EXPECT_EQ(g.vae.epochs, 2000);
  EXPECT_EQ(g.vae.batch, 32);
  EXPECT_DOUBLE_EQ(g.vae_kl_weight, 0.01);
  EXPECT_EQ(g.pref.epochs, 5000);
  EXPECT_DOUBLE_EQ(g.pref.adam.lr, 0.01);
  EXPECT_DOUBLE_EQ(j.pref.adam.lr, 0.001);
  EXPECT_DOUBLE_EQ(g.pref_l2, 10);
  EXPECT_DOUBLE_EQ(j.pref_l2, 1);
  EXPECT_EQ(g.tpa.epochs, 500);
  EXPECT_EQ(j.tpa.epochs, 1000);
  EXPECT_EQ(j.tpa_hidden, (std::vector<int>{1024, 1024}));
  EXPECT_THROW(paper_hyper("mars"), std::invalid_argument);
}

TEST(Hyper, SetByNameCopiesEveryKeyExactly) {
  Hyper h = paper_hyper("grid");
  set_hyper(h, "sirl.epochs", int64_t{42});
  set_hyper(h, "tpa.lr", 0.0025);
  set_hyper(h, "pref.l2", int64_t{3});  // an integer where a number is asked
  set_hyper(h, "phi.hidden", std::vector<int>{64, 32});
  set_hyper(h, "tpa.hidden", int64_t{16});  // one width
  set_hyper(h, "phi.relu_output", true);
  set_hyper(h, "tpa.stop", std::string("converged"));
  EXPECT_EQ(h.sirl.epochs, 42);
  EXPECT_DOUBLE_EQ(h.tpa.adam.lr, 0.0025);
  EXPECT_EQ(h.pref_l2, 3.0);
  EXPECT_EQ(h.phi_hidden, (std::vector<int>{64, 32}));
  EXPECT_EQ(h.tpa_hidden, (std::vector<int>{16}));
  EXPECT_TRUE(h.phi_relu_output);
  EXPECT_EQ(h.tpa_stop, "converged");
  Hyper back = paper_hyper("jaco");
  for (const std::string& k : hyper_keys()) set_hyper(back, k, hyper_value(h, k));
  EXPECT_EQ(describe(back), describe(h));
  // The canonical texts: what names a hyper-parameter point.
  EXPECT_EQ(hyper_value_text(int64_t{3000}), "3000");
  EXPECT_EQ(hyper_value_text(0.5), "0.5");
  EXPECT_EQ(hyper_value_text(0.004), "0.0040000000000000001");
  EXPECT_EQ(hyper_value_text(std::vector<int>{128, 64}), "128,64");
  EXPECT_EQ(hyper_value_text(false), "false");
  EXPECT_EQ(hyper_value_text(std::string("bf16")), "bf16");
}

TEST(Hyper, EveryKeyIsDocumentedWithTheEnginesDefault) {
  const std::vector<HyperKeyDoc> docs = hyper_key_docs();
  const std::vector<std::string> keys = hyper_keys();
  ASSERT_EQ(docs.size(), keys.size());
  Hyper from_docs = paper_hyper("jaco");  // every value below overwrites jaco's own
  for (size_t i = 0; i < docs.size(); ++i) {
    EXPECT_EQ(docs[i].key, keys[i]);
    EXPECT_GE(docs[i].doc.size(), 10u) << docs[i].key << " has no doc line";
    set_hyper(from_docs, docs[i].key, docs[i].value);
  }
  // The documented defaults are the engine's (GridRobot's) values, every one of them.
  EXPECT_EQ(describe(from_docs), describe(Hyper{}));
  EXPECT_EQ(describe(from_docs), describe(paper_hyper("grid")));
}

// Each key's declared range or words (HyperAccept) is what validate() enforces: at a closed bound
// accepted, at an open one or beyond it refused with the key and the range; each word accepted and
// any other refused with the key and every word. Holds for any key added to the table.
TEST(Hyper, EveryKeyRefusesExactlyWhatItsDeclarationDoes) {
  auto refusal = [](const std::string& key, const HyperValue& v) -> std::string {
    Hyper h;
    set_hyper(h, key, v);
    try {
      validate(h);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  int numeric = 0, worded = 0;
  for (const HyperKeyDoc& k : hyper_key_docs()) {
    const HyperAccept& a = k.accept;
    const HyperType t = hyper_type(k.key);
    if (!a.words.empty()) {
      ASSERT_EQ(t, HyperType::word) << k.key;
      ++worded;
      for (const auto& w : a.words) EXPECT_EQ(refusal(k.key, w.first), "") << k.key;
      const std::string m = refusal(k.key, std::string("nonsense"));
      EXPECT_NE(m.find("hyper-parameter " + k.key + " must be"), std::string::npos) << m;
      for (const auto& w : a.words)
        EXPECT_NE(m.find("\"" + w.first + "\""), std::string::npos) << k.key << ": " << m;
      continue;
    }
    if (t != HyperType::integer && t != HyperType::number && t != HyperType::integer_list) continue;
    // A value of the key's type: an integer key takes integers, a widths key a list of one.
    auto value = [&](double x) -> HyperValue {
      if (t == HyperType::number) return x;
      if (t == HyperType::integer) return int64_t(x);
      return std::vector<int>{int(x)};
    };
    const double step = t == HyperType::number ? 0.25 : 1;  // beyond a bound, of the key's kind
    for (const auto& [bound, open, outward] :
         {std::tuple{a.lo, a.lo_open, -step}, std::tuple{a.hi, a.hi_open, step}}) {
      if (std::isinf(bound)) continue;
      ++numeric;
      const std::string at = refusal(k.key, value(bound));
      if (open)
        EXPECT_NE(at.find(k.key), std::string::npos) << k.key << " = " << bound << " accepted";
      else
        EXPECT_EQ(at, "") << k.key << " = " << bound;
      const std::string beyond = refusal(k.key, value(bound + outward));
      EXPECT_NE(beyond.find(k.key), std::string::npos)
          << k.key << " = " << bound + outward << " accepted";
      EXPECT_NE(beyond.find(range_text(a)), std::string::npos) << beyond;
    }
  }
  EXPECT_GE(numeric, 20);  // the schedules' epochs, batches, rates and decays among them
  EXPECT_EQ(worded, 4);    // vae.elbo, pref.stop, tpa.stop, precision
  // The texts themselves, by hand.
  EXPECT_EQ(range_text(HyperAccept{0, 1, true, false, {}}), "in (0, 1]");
  EXPECT_EQ(range_text(HyperAccept{2, INFINITY, false, false, {}}), ">= 2");
  EXPECT_EQ(range_text(HyperAccept{0, INFINITY, true, false, {}}), "> 0");
  EXPECT_EQ(words_text(HyperAccept{0, 0, false, false, {{"a", "one"}, {"b", ""}, {"c", "x"}}}),
            "\"a\" (one), \"b\" or \"c\" (x)");
}

TEST(Hyper, BadKeysAndValuesAreRejectedWithTheirName) {
  Hyper h;
  auto message = [&](const char* k, const HyperValue& v) {
    try {
      set_hyper(h, k, v);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("sirl.epoch", int64_t{3}).find("unknown hyper-parameter 'sirl.epoch'"),
            std::string::npos);
  EXPECT_NE(message("sirl.epochs", 3.5).find("sirl.epochs: '3.5' is not an integer"),
            std::string::npos);
  EXPECT_NE(message("sirl.epochs", int64_t{1} << 40).find("is not an integer"), std::string::npos);
  EXPECT_NE(message("tpa.lr", std::string("fast")).find("'fast' is not a finite number"),
            std::string::npos);
  EXPECT_NE(message("tpa.lr", std::numeric_limits<double>::infinity()).find("a finite number"),
            std::string::npos);
  EXPECT_NE(message("phi.relu_output", int64_t{1}).find("true or false"), std::string::npos);
  EXPECT_NE(message("phi.hidden", std::vector<int>{}).find("a list of widths"), std::string::npos);
  EXPECT_NE(message("precision", 16.0).find("a word"), std::string::npos);
  // Values that would break the arithmetic, stated here apart from the declarations: a rate or
  // decay of 0 (no step, or no step after the first), a negative count or penalty, a tolerance of
  // 1 (every loss "converged"), a convergence window of one epoch.
  const std::pair<const char*, HyperValue> breaking[] = {{"sirl.lr", 0.0},
                                                         {"vae.lr_decay", 0.0},
                                                         {"pref.lr_decay", 1.5},
                                                         {"tpa.batch", int64_t{0}},
                                                         {"sirl.epochs", int64_t{-1}},
                                                         {"tpa.l2", -0.5},
                                                         {"pref.stop_rel_tol", 1.0},
                                                         {"tpa.stop_min_epochs", int64_t{1}},
                                                         {"phi.embedding_dim", int64_t{0}},
                                                         {"tpa.hidden", std::vector<int>{16, 0}},
                                                         {"tpa.shadow_rel_tol", -0.1}};
  for (const auto& [key, v] : breaking) {
    Hyper h;
    set_hyper(h, key, v);
    EXPECT_THROW(validate(h), std::invalid_argument) << key << " = " << hyper_value_text(v);
  }
  Hyper off;
  set_hyper(off, "tpa.shadow_rel_tol", 0.0);  // 0 is "no shadow rule", not an error
  EXPECT_NO_THROW(validate(off));
  Hyper bad;
  bad.sirl.adam.decay = 1.5;
  EXPECT_THROW(validate(bad), std::invalid_argument);
  bad = Hyper{};
  bad.tpa.batch = 0;
  EXPECT_THROW(validate(bad), std::invalid_argument);
  // A network's depth is bounded before anything is sized from it.
  bad = Hyper{};
  bad.phi_hidden.assign(kMaxHiddenLayers + 1, 8);
  EXPECT_THROW(validate(bad), std::invalid_argument);
  bad = Hyper{};
  bad.tpa_hidden.assign(kMaxHiddenLayers, 8);  // at the bound: accepted
  EXPECT_NO_THROW(validate(bad));
  for (double tol : {0.0, 1.0, -0.01}) {
    bad = Hyper{};
    bad.tpa_stop_frozen_rel_tol = tol;
    try {
      validate(bad);
      ADD_FAILURE() << "tpa.stop_frozen_rel_tol = " << tol << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("tpa.stop_frozen_rel_tol must be in (0, 1)"),
                std::string::npos);
    }
  }
}

// Each cell's heads stop at their own mode's tolerance: tpa.stop_rel_tol for unfrozen cells,
// tpa.stop_frozen_rel_tol for frozen ones; the minimum and the mode word apply to both.
TEST(Hyper, TheStopRuleTakesTheTolerancesOfItsCellsMode) {
  Hyper h;
  set_hyper(h, "tpa.stop", std::string("converged"));
  set_hyper(h, "tpa.stop_rel_tol", 0.02);
  set_hyper(h, "tpa.stop_frozen_rel_tol", 0.001);
  set_hyper(h, "tpa.stop_min_epochs", int64_t{40});
  const StopRule f = tpa_stop_rule(h, true), u = tpa_stop_rule(h, false);
  EXPECT_TRUE(f.converged && u.converged);
  EXPECT_EQ(f.rel_tol, 0.001);
  EXPECT_EQ(u.rel_tol, 0.02);
  EXPECT_EQ(f.min_epochs, 40);
  EXPECT_EQ(u.min_epochs, 40);
  set_hyper(h, "tpa.stop", std::string("converged-unfrozen"));
  EXPECT_FALSE(tpa_stop_rule(h, true).converged);
  EXPECT_TRUE(tpa_stop_rule(h, false).converged);
}

}  // namespace
}  // namespace sirl
