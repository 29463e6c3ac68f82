// The resume policy of `sirl run` for an existing results file, decided without running anything:
// which files are refused (and why), which are reused, and what --force changes.
#include <gtest/gtest.h>

#include <string>

#include "jobs/run.h"

namespace sirl {
namespace {

RunInfo written(const std::string& text, const std::string& engine, const std::string& shard) {
  RunInfo i;
  i.profile_name = "smoke";
  i.profile_text = text;
  i.engine_version = engine;
  i.shard = shard;
  i.tasks_done = 42;
  return i;
}

TEST(ResumeDecision, TheSameRunIsReused) {
  const ResumeDecision d = resume_decision(written("P", "0.8.0", ""), "P", "0.8.0", "", false);
  EXPECT_TRUE(d.reuse);
  EXPECT_EQ(d.refusal, "");
}

TEST(ResumeDecision, AnotherProfileIsRefusedNamingIt) {
  const ResumeDecision d = resume_decision(written("P", "0.8.0", ""), "Q", "0.8.0", "", false);
  EXPECT_FALSE(d.reuse);
  EXPECT_EQ(d.refusal, "under a different profile ('smoke')");
}

TEST(ResumeDecision, AnotherEngineIsRefusedNamingBoth) {
  const ResumeDecision d = resume_decision(written("P", "0.7.0", ""), "P", "0.8.0", "", false);
  EXPECT_FALSE(d.reuse);
  EXPECT_EQ(d.refusal, "by engine 0.7.0 (this is 0.8.0)");
}

TEST(ResumeDecision, AnotherPartOfTheGridIsRefused) {
  const ResumeDecision d = resume_decision(written("P", "0.8.0", "0/2"), "P", "0.8.0", "", false);
  EXPECT_FALSE(d.reuse);
  EXPECT_EQ(d.refusal, "with shard 0/2 (42 tasks), and this run is the whole run");
  EXPECT_EQ(resume_decision(written("P", "0.8.0", ""), "P", "0.8.0", "1/2", false).refusal,
            "with the whole run (42 tasks), and this run is shard 1/2");
}

TEST(ResumeDecision, ForceNeverRefusesAndNeverReusesAnotherRun) {
  for (const RunInfo& other :
       {written("Q", "0.8.0", ""), written("P", "0.7.0", ""), written("P", "0.8.0", "0/2")}) {
    const ResumeDecision d = resume_decision(other, "P", "0.8.0", "", true);
    EXPECT_EQ(d.refusal, "");
    EXPECT_FALSE(d.reuse);
  }
  EXPECT_TRUE(resume_decision(written("P", "0.8.0", ""), "P", "0.8.0", "", true).reuse);
}

TEST(ResumeDecision, AnUnverifiedFileIsNeverReused) {
  RunInfo i = written("P", "0.8.0", "");
  i.verified = false;
  const ResumeDecision d = resume_decision(i, "P", "0.8.0", "", false);
  EXPECT_EQ(d.refusal, "");
  EXPECT_FALSE(d.reuse);
}

}  // namespace
}  // namespace sirl
