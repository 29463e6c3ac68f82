// The method catalog (engine/method_catalog.h): every method's name round-trips, and what the
// figures and the report read from it is the paper's: its figure order, its best modes, its
// baselines; variants get their labels and colours from their method. The checks hold for any
// entry: a method added as docs/ARCHITECTURE.md shows passes them without editing this file.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <stdexcept>
#include <string>

#include "datasets/queries.h"
#include "engine/method_catalog.h"
#include "experiment/profile.h"

namespace sirl {
namespace {

TEST(MethodCatalog, EveryNameRoundTripsAndIsUnique) {
  std::set<std::string> names, labels, colours;
  for (const MethodSpec& s : method_catalog()) {
    EXPECT_EQ(parse_method(s.name), s.method) << s.name;
    EXPECT_STREQ(method_name(s.method), s.name);
    EXPECT_TRUE(names.insert(s.name).second) << s.name;
    EXPECT_TRUE(labels.insert(s.label).second) << s.label;
    if (s.role != MethodRole::external) {
      EXPECT_TRUE(colours.insert(s.colour).second) << s.colour;
    }
  }
  // The paper's methods and the references are there (a catalog may hold more).
  for (const char* name :
       {"sirl", "vae", "multipref10", "multipref50", "singlepref", "random", "truth", "raw"})
    EXPECT_TRUE(names.count(name)) << name;
  // An unknown name lists exactly what a profile may list, in catalog order.
  std::string listable;
  for (const MethodSpec& s : method_catalog())
    if (s.listable) listable += (listable.empty() ? "" : ", ") + std::string(s.name);
  for (const char* name : {"sirl", "vae", "multipref10", "multipref50", "singlepref", "random"})
    EXPECT_NE(listable.find(name), std::string::npos) << name;
  try {
    parse_method("sirll");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "unknown method 'sirll' (expected one of " + listable + ")");
  }
}

// The paper's Figs. 4 and 5 draw SIRL, SIRL+VAE, VAE, MultiPref-10, MultiPref-50, SinglePref and
// Random in this order; the references are reference lines; the other "+vae" variants and the
// active-query variants are not method lines.
// A method that learns from answers declares how it trains: its function, schedule, settings
// prefix, rows through φ per answer (a triplet 3, a pair 2) and rate class; a preference method
// also the set it trains on, whose humans are the paper's (MultiPref-10: 10, MultiPref-50: 50,
// SinglePref: 1). Methods that learn from no answers train nothing in their own task.
TEST(MethodCatalog, EveryMethodThatLearnsFromAnswersDeclaresItsTraining) {
  const RewardSets humans = make_reward_sets(8, 1);
  const std::map<std::string, int> paper_humans{
      {"multipref10", 10}, {"multipref50", 50}, {"singlepref", 1}};
  for (const MethodSpec& s : method_catalog()) {
    const MethodTraining& how = s.training;
    const std::string queries = s.queries;
    if (queries.empty()) {
      EXPECT_EQ(how.train, nullptr) << s.name;
      continue;
    }
    ASSERT_NE(how.train, nullptr) << s.name;
    EXPECT_NE(how.schedule, nullptr) << s.name;
    EXPECT_NE(std::string(how.hyper_prefix), "") << s.name;
    EXPECT_NE(std::string(how.rate_class), "") << s.name;
    EXPECT_EQ(how.rows_per_answer, queries == "similarity" ? 3 : 2) << s.name;
    if (queries == "preference") {
      ASSERT_NE(how.humans, nullptr) << s.name;
      ASSERT_NE(how.preferences, nullptr) << s.name;
      // The paper's preference methods have the paper's humans; any other at least one.
      if (const auto it = paper_humans.find(s.name); it != paper_humans.end())
        EXPECT_EQ((humans.*how.humans).count, it->second) << s.name;
      else
        EXPECT_GE((humans.*how.humans).count, 1) << s.name;
    }
  }
}

// Named enums read their names from one table both ways (datasets/enum_names.h): every query
// selection round-trips, and an unknown name is refused with every valid one listed.
TEST(MethodCatalog, SelectionNamesRoundTripAndAnUnknownOneListsThem) {
  for (Selection s : {Selection::uniform, Selection::vote, Selection::infogain})
    EXPECT_EQ(parse_selection(selection_name(s)), s);
  EXPECT_STREQ(selection_name(Selection::infogain), "infogain");
  try {
    parse_selection("greedy");
    ADD_FAILURE() << "an unknown selection was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "unknown query selection 'greedy' (expected uniform, vote or infogain)");
  }
  EXPECT_STREQ(selection_name(static_cast<Selection>(7)), "?");
  EXPECT_STREQ(role_name(MethodRole::reference), "reference");
}

// The paper's methods are drawn in its order (a method added to the catalog may take a place
// between them, so their positions are compared, not their values); SIRL first.
TEST(MethodCatalog, FigureOrderIsThePapers) {
  const char* order[] = {"sirl",        "sirl+vae",   "vae",   "multipref10",
                         "multipref50", "singlepref", "random"};
  int last = -1;
  for (const char* name : order) {
    const Variant v = parse_variant(name);
    const int at = variant_style(v.method, v.vae, v.selection, v.name()).figure_order;
    EXPECT_GT(at, last) << name;
    last = at;
  }
  EXPECT_EQ(variant_style(Method::sirl, false, Selection::uniform, "sirl").figure_order, 0);
  for (const char* name : {"multipref10+vae", "singlepref+vae", "sirl@vote", "sirl+vae@infogain"}) {
    const Variant v = parse_variant(name);
    EXPECT_EQ(variant_style(v.method, v.vae, v.selection, v.name()).figure_order, -1) << name;
  }
  EXPECT_EQ(variant_style(Method::truth, false, Selection::uniform, "truth").figure_order, -1);
  EXPECT_EQ(variant_style(Method::truth, false, Selection::uniform, "truth").dashes, "6 3");
  EXPECT_EQ(variant_style(Method::truth, false, Selection::uniform, "truth").role, "reference");
}

TEST(MethodCatalog, VariantsTakeTheirMethodsLabelAndColour) {
  const auto style = [](const char* name) {
    const Variant v = parse_variant(name);
    return variant_style(v.method, v.vae, v.selection, v.name());
  };
  EXPECT_EQ(style("sirl+vae").label, "SIRL+VAE");
  EXPECT_EQ(style("sirl+vae").colour, "#ff9896");  // SIRL+VAE's own line in Figs. 4 and 5
  EXPECT_EQ(style("multipref10+vae").label, "MultiPref-10+VAE");
  EXPECT_EQ(style("multipref10+vae").colour, style("multipref10").colour);
  EXPECT_EQ(style("sirl@vote").label, "SIRL (active: vote entropy)");
  EXPECT_EQ(style("sirl@vote").selection, "vote");
  EXPECT_EQ(style("sirl@vote").selection_order, 1);
  EXPECT_EQ(style("sirl").selection_label, "uniform (the paper)");
  EXPECT_EQ(style("multipref50").queries, "preference");
  EXPECT_EQ(style("sirl").queries, "similarity");
  EXPECT_EQ(style("random").queries, "");
  EXPECT_EQ(style("vae").role, "baseline");
  EXPECT_EQ(style("sirl").role, "sirl");
  // Externals: their own name as label, colours by their position, after every built-in line.
  const VariantStyle a = variant_style(Method::external, false, Selection::uniform, "mine", 0);
  const VariantStyle b = variant_style(Method::external, false, Selection::uniform, "yours", 1);
  const VariantStyle g = variant_style(Method::external, false, Selection::uniform, "other", 6);
  EXPECT_EQ(a.label, "mine");
  EXPECT_NE(a.colour, b.colour);
  EXPECT_EQ(g.colour, a.colour);  // six colours, then around again
  EXPECT_GT(a.figure_order, 6);
  EXPECT_LT(a.figure_order, b.figure_order);
}

// The paper's best TPA modes: SIRL (with or without VAE) frozen, every other method unfrozen;
// an external method and the references have no weights: frozen.
TEST(MethodCatalog, BestModesAreThePapers) {
  EXPECT_TRUE(is_best_mode(parse_variant("sirl"), true));
  EXPECT_TRUE(is_best_mode(parse_variant("sirl+vae"), true));
  for (const char* name : {"vae", "multipref10", "multipref50", "singlepref", "random"}) {
    EXPECT_TRUE(is_best_mode(parse_variant(name), false)) << name;
    EXPECT_FALSE(is_best_mode(parse_variant(name), true)) << name;
  }
  Variant ext;
  ext.method = Method::external;
  EXPECT_TRUE(is_best_mode(ext, true));
  EXPECT_TRUE(method_spec(Method::raw).best_frozen);
  // VAE pre-training: exactly the methods that learn from answers, external ones aside.
  for (const MethodSpec& s : method_catalog())
    EXPECT_EQ(s.accepts_vae, s.uses_queries && s.method != Method::external) << s.name;
}

}  // namespace
}  // namespace sirl
