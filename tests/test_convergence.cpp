// The one convergence rule (engine/convergence.h) on hand-made curves.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/convergence.h"
#include "engine/hyperparams.h"

namespace sirl {
namespace {

// The one convergence rule (engine/convergence.h) on hand-made curves.
TEST(Convergence, ComparesTheLastTwoTenthsOfTheCurve) {
  std::vector<float> c(20, 5.f);  // 20 epochs: windows of 2
  c[16] = c[17] = 2.f, c[18] = c[19] = 1.f;
  Convergence v = check_convergence(c);
  EXPECT_EQ(v.window, 2);
  EXPECT_DOUBLE_EQ(v.relative_change, 0.5);  // (2 − 1) / 2
  EXPECT_FALSE(v.converged);
  c[16] = c[17] = 1.f, c[18] = c[19] = 0.995f;  // 0.5 % lower: within 1 %
  v = check_convergence(c);
  EXPECT_NEAR(v.relative_change, 0.005, 1e-6);
  EXPECT_TRUE(v.converged);
  c[18] = c[19] = 1.02f;  // rising by 2 %: not settled either
  EXPECT_FALSE(check_convergence(c).converged);
  EXPECT_TRUE(check_convergence(std::vector<float>(50, 0.f)).converged);  // a loss at 0
  EXPECT_FALSE(check_convergence({1.f}).converged);  // one epoch cannot be judged
  EXPECT_EQ(check_convergence({1.f}).window, 0);
  EXPECT_EQ(check_convergence(std::vector<float>(300, 1.f)).window, 30);
}

// The heads' stopping rule: the convergence rule on the curve so far, from min_epochs on.
// A loss falling by 0.1 an epoch from 14 to 2.1 over 120 epochs (windows ≥ 10 apart by ≥ 1/14 ≫
// 1 %), then flat at 1: the first e whose two last tenths (windows of ⌊e/10⌋) lie wholly in the
// flat part is the first with e − 2·⌊e/10⌋ ≥ 120, e = 148 (at 147 the earlier window still holds
// one 2.1: a change of 1.1/14 ≫ 1 %).
TEST(Convergence, AConvergedRuleStopsAtTheFirstConvergedEpochAfterItsMinimum) {
  std::vector<float> c(400, 1.f);
  for (int i = 0; i < 120; ++i) c[i] = 2.f + 0.1f * float(120 - i);
  StopRule rule;
  rule.converged = true;
  rule.min_epochs = 100;
  int first = -1;
  for (int e = 1; e <= 400 && first < 0; ++e)
    if (stops_after(rule, c.data(), e)) first = e;
  EXPECT_EQ(first, 148);
  // Flat from the start: the minimum decides.
  const std::vector<float> flat(400, 3.f);
  EXPECT_FALSE(stops_after(rule, flat.data(), 99));
  EXPECT_TRUE(stops_after(rule, flat.data(), 100));
  // `fixed` never stops.
  StopRule fixed;
  EXPECT_FALSE(stops_after(fixed, flat.data(), 400));
  // A tighter tolerance waits for a smaller change: a loss falling 0.05 % an epoch changes by
  // ~0.5 % between windows of 10 (at e = 100): within 1 %, not within 0.1 %.
  std::vector<float> slope(400);
  for (int e = 0; e < 400; ++e) slope[e] = float(std::pow(0.9995, e));
  EXPECT_TRUE(stops_after(rule, slope.data(), 100));
  rule.rel_tol = 0.001;
  EXPECT_FALSE(stops_after(rule, slope.data(), 100));
}

}  // namespace
}  // namespace sirl

namespace sirl {
namespace {

// Each declared tpa.stop rule is accepted by the hyper-parameters' check and gives each mode's
// heads the StopRule its entry says, at that mode's tolerance; an unknown name is refused with
// every declared name in the message.
TEST(Convergence, EveryDeclaredTpaStopRuleValidatesAndStopsTheModesItNames) {
  for (const TpaStopRule& entry : kTpaStopRules) {
    Hyper h = paper_hyper("grid");
    h.tpa_stop = entry.name;
    h.tpa_stop_rel_tol = 0.02;
    h.tpa_stop_frozen_rel_tol = 0.005;
    EXPECT_NO_THROW(validate(h)) << entry.name;
    EXPECT_EQ(tpa_stop_rule(h, false).converged, entry.stops_unfrozen) << entry.name;
    EXPECT_EQ(tpa_stop_rule(h, true).converged, entry.stops_frozen) << entry.name;
    EXPECT_EQ(tpa_stop_rule(h, false).rel_tol, 0.02);
    EXPECT_EQ(tpa_stop_rule(h, true).rel_tol, 0.005);
    EXPECT_EQ(tpa_stop_may_end_early(entry.name), entry.stops_unfrozen || entry.stops_frozen);
  }
  EXPECT_FALSE(tpa_stop_may_end_early("fixed"));
  EXPECT_FALSE(tpa_stop_may_end_early("sometimes"));
  Hyper h = paper_hyper("grid");
  h.tpa_stop = "sometimes";
  try {
    validate(h);
    ADD_FAILURE() << "an undeclared rule was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    for (const TpaStopRule& entry : kTpaStopRules)
      EXPECT_NE(m.find(std::string("\"") + entry.name + "\" (" + entry.doc + ")"),
                std::string::npos)
          << m;
    EXPECT_NE(m.find("got \"sometimes\""), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace sirl
