// The paper's hyper-parameters per environment, and setting them by name.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

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

TEST(Hyper, SetByNameRoundTripsThroughDescribe) {
  Hyper h = paper_hyper("grid");
  set_hyper(h, "sirl.epochs", "42");
  set_hyper(h, "tpa.lr", "0.0025");
  set_hyper(h, "phi.hidden", "64,32");
  set_hyper(h, "phi.relu_output", "true");
  Hyper back = paper_hyper("jaco");
  std::string text = describe(h);
  for (size_t p = 0; p < text.size();) {
    const size_t eol = text.find('\n', p), eq = text.find(" = ", p);
    set_hyper(back, text.substr(p, eq - p), text.substr(eq + 3, eol - eq - 3));
    p = eol + 1;
  }
  EXPECT_EQ(describe(back), text);
  EXPECT_EQ(back.sirl.epochs, 42);
  EXPECT_EQ(back.phi_hidden, (std::vector<int>{64, 32}));
  EXPECT_DOUBLE_EQ(back.tpa.adam.lr, 0.0025);
  EXPECT_TRUE(back.phi_relu_output);
}

TEST(Hyper, BadKeysAndValuesAreRejectedWithTheirName) {
  Hyper h;
  auto message = [&](const char* k, const char* v) {
    try {
      set_hyper(h, k, v);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("sirl.epoch", "3").find("unknown hyper-parameter 'sirl.epoch'"),
            std::string::npos);
  EXPECT_NE(message("sirl.epochs", "3.5").find("sirl.epochs"), std::string::npos);
  EXPECT_NE(message("tpa.lr", "fast").find("a finite number"), std::string::npos);
  EXPECT_NE(message("phi.relu_output", "yes").find("true or false"), std::string::npos);
  Hyper bad;
  bad.sirl.adam.decay = 1.5;
  EXPECT_THROW(validate(bad), std::invalid_argument);
  bad = Hyper{};
  bad.tpa.batch = 0;
  EXPECT_THROW(validate(bad), std::invalid_argument);
}

}  // namespace
}  // namespace sirl
