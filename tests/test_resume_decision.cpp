// The policy of `sirl run` for an existing results file at --out, decided without running
// anything: which files are refused (and why), which are read for reusable records, and what
// --force changes. (Which records are reused is decided per task by its digest: jobs/run.cpp.)
#include <gtest/gtest.h>

#include <string>

#include "jobs/run.h"

namespace sirl {
namespace {

RunInfo written(const std::string& shard) {
  RunInfo i;
  i.profile_name = "smoke";
  i.shard = shard;
  i.tasks_done = 42;
  return i;
}

TEST(ResumeDecision, TheSamePartOfTheGridIsRead) {
  const ResumeDecision d = resume_decision(written(""), "", false);
  EXPECT_TRUE(d.reuse);
  EXPECT_EQ(d.refusal, "");
  EXPECT_TRUE(resume_decision(written("1/2"), "1/2", false).reuse);
}

TEST(ResumeDecision, AnotherPartOfTheGridIsRefused) {
  const ResumeDecision d = resume_decision(written("0/2"), "", false);
  EXPECT_FALSE(d.reuse);
  EXPECT_EQ(d.refusal, "with shard 0/2 (42 tasks), and this run is the whole run");
  EXPECT_EQ(resume_decision(written(""), "1/2", false).refusal,
            "with the whole run (42 tasks), and this run is shard 1/2");
  EXPECT_EQ(resume_decision(written("0/2"), "1/2", false).refusal,
            "with shard 0/2 (42 tasks), and this run is shard 1/2");
}

TEST(ResumeDecision, ForceNeverRefusesAndNeverReuses) {
  for (const RunInfo& other : {written(""), written("0/2")}) {
    const ResumeDecision d = resume_decision(other, "", true);
    EXPECT_EQ(d.refusal, "");
    EXPECT_FALSE(d.reuse);
  }
}

TEST(ResumeDecision, AnUnverifiedFileIsNeverReused) {
  RunInfo i = written("");
  i.verified = false;
  const ResumeDecision d = resume_decision(i, "", false);
  EXPECT_EQ(d.refusal, "");
  EXPECT_FALSE(d.reuse);
}

}  // namespace
}  // namespace sirl
