// `sirl study merge`: the participants of several study files of one study in one file; files of
// another study refused, a participant recorded differently in two files refused, one recorded
// the same in both kept once; the inputs never changed.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "datasets/study.h"
#include "results/study_store.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {

namespace fs = std::filesystem;

int sirl_cli(const std::string& args, std::string& out) {
  FILE* p = ::popen((std::string(SIRL_BINARY) + " " + args + " 2>&1").c_str(), "r");
  out.clear();
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  const int rc = ::pclose(p);
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128 + WTERMSIG(rc);
}

std::string bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(StudyMerge, CombinesParticipantsOfOneStudyAndRefusesConflicts) {
  const test::ScratchDir scratch;
  CohortConfig c;
  c.env = "grid";
  c.users = 3;
  c.similarity = 6;
  c.preference = 4;
  const Study a = simulate_cohort(c);
  Study b = a;  // the same study, other people: sim02 is in both, the same record
  b.participants.erase(b.participants.begin());
  for (auto& p : b.participants)
    if (p.id != "sim02") p.id = "lab-" + p.id;
  const std::string fa = scratch.file("a.h5"), fb = scratch.file("b.h5"),
                    out = scratch.file("merged.h5");
  write_study(fa, a);
  write_study(fb, b);
  const std::string before_a = bytes(fa), before_b = bytes(fb);
  std::string msg;
  ASSERT_EQ(sirl_cli("study merge " + out + " " + fa + " " + fb, msg), 0) << msg;
  const Study m = read_study(out);
  std::vector<std::string> ids;
  for (const auto& p : m.participants) ids.push_back(p.id);
  EXPECT_EQ(ids, (std::vector<std::string>{"sim01", "sim02", "sim03", "lab-sim03"}));
  EXPECT_EQ(m.find("lab-sim03")->similarity_answer, a.find("sim03")->similarity_answer);
  EXPECT_EQ(m.env, "grid");
  EXPECT_EQ(bytes(fa), before_a);
  EXPECT_EQ(bytes(fb), before_b);

  // sim02 answered differently in a third file: refused, nothing written.
  Study conflict = a;
  conflict.find("sim02")->similarity_answer[0] =
      (conflict.find("sim02")->similarity_answer[0] + 1) % 3;
  const std::string fc = scratch.file("c.h5"), out2 = scratch.file("m2.h5");
  write_study(fc, conflict);
  EXPECT_EQ(sirl_cli("study merge " + out2 + " " + fa + " " + fc, msg), 2) << msg;
  EXPECT_NE(msg.find("participant sim02 is in"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(out2));

  // Another study (another data seed): refused.
  Study other = a;
  other.data_seed = 7;
  const std::string fo = scratch.file("o.h5");
  write_study(fo, other);
  EXPECT_EQ(sirl_cli("study merge " + out2 + " " + fa + " " + fo, msg), 2) << msg;
  EXPECT_NE(msg.find("not one study"), std::string::npos) << msg;
  // An existing output is replaced only with --force, never an input.
  EXPECT_EQ(sirl_cli("study merge " + out + " " + fa, msg), 2) << msg;
  EXPECT_EQ(sirl_cli("study merge --force " + fa + " " + fa + " " + fb, msg), 2) << msg;
  EXPECT_EQ(bytes(fa), before_a);
}

}  // namespace
}  // namespace sirl
