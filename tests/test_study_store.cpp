// The study file: a round trip of every field, and refusing files that are not studies.
#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "datasets/study.h"
#include "results/h5.h"
#include "results/study_store.h"
#include "tests/scratch_dir.h"
#include "tests/small_study.h"

namespace sirl {
namespace {

using test::simulated_cohort;

TEST(StudyStore, FileRoundTripsAndRejectsForeignFiles) {
  namespace fs = std::filesystem;
  const test::ScratchDir scratch;
  const std::string path = scratch.file("study.h5");
  Study s = simulated_cohort(3, 20.0, 0.05);
  s.trajectories = 777;  // not the defaults: the file must carry them
  s.data_seed = 42;
  for (auto& p : s.participants) {  // distinct response times and timestamps per answer
    p.similarity_ms.resize(p.similarity_answer.size());
    p.similarity_time.resize(p.similarity_answer.size());
    p.preference_ms.resize(p.preference_answer.size());
    p.preference_time.resize(p.preference_answer.size());
    for (size_t i = 0; i < p.similarity_ms.size(); ++i) {
      p.similarity_ms[i] = 900.0f + i;
      p.similarity_time[i] = 1.7e9 + 0.5 * i;
    }
    for (size_t i = 0; i < p.preference_ms.size(); ++i) {
      p.preference_ms[i] = 100.0f + i;
      p.preference_time[i] = 1.8e9 + 0.25 * i;
    }
  }
  s.participants[1].preference_answer.resize(7);  // a participant halfway through phase 2
  s.participants[1].preference_ms.resize(7);
  s.participants[1].preference_time.resize(7);
  s.participants[2].scenario = "Stay \"far\" from the laptop.";
  write_study(path, s);
  // The tokens are credentials: the file is its owner's alone.
  const fs::perms mode = fs::status(path).permissions();
  EXPECT_EQ(mode & (fs::perms::group_all | fs::perms::others_all), fs::perms::none);
  const Study r = read_study(path);
  EXPECT_EQ(r.env, "grid");
  EXPECT_EQ(r.trajectories, 777);
  EXPECT_EQ(r.data_seed, 42u);
  ASSERT_EQ(r.participants.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const auto &a = s.participants[i], &b = r.participants[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.token, b.token);
    EXPECT_EQ(a.scenario, b.scenario);
    EXPECT_EQ(a.scenario_features, b.scenario_features);
    EXPECT_EQ(a.similarity, b.similarity);
    EXPECT_EQ(a.preference, b.preference);
    EXPECT_EQ(a.similarity_answer, b.similarity_answer);
    EXPECT_EQ(a.preference_answer, b.preference_answer);
    EXPECT_EQ(a.similarity_ms, b.similarity_ms);
    EXPECT_EQ(a.preference_ms, b.preference_ms);
    EXPECT_EQ(a.similarity_time, b.similarity_time);
    EXPECT_EQ(a.preference_time, b.preference_time);
    EXPECT_EQ(a.reward, b.reward);
  }
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  {
    H5File f = H5File::create(path);
    f.group("/other");
  }
  EXPECT_THROW(read_study(path), H5Error);
}

}  // namespace
}  // namespace sirl
