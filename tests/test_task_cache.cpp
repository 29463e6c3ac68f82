// The task cache and task digests: ids by digest and class, reuse across classes only when asked,
// one computer per task (a second claim waits), gc keeping what profiles and live runs need,
// abandoned temporary files swept but a live writer's kept; and which profile edits change which
// tasks' digests.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <thread>

#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/task_digest.h"
#include "jobs/task_cache.h"
#include "jobs/task_checkpoints.h"
#include "results/h5.h"
#include "tests/scratch_dir.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

namespace fs = std::filesystem;

const std::string kDigestA(32, 'a'), kDigestB(32, 'b'), kDigestC(32, 'c');

TaskRecord cache_record(const std::string& key) {
  TaskRecord r;
  r.key = key;
  r.kind = "fpe";
  r.num["fpe"] = 0.25;
  return r;
}

TEST(TaskCache, FilesByDigestAndClassAndReusesAnotherClassOnlyWhenAsked) {
  const test::ScratchDir scratch;
  TaskCache cache(scratch.path() / "c");
  const std::string id = TaskCache::id(kDigestA, "zen5");
  EXPECT_EQ(id.size(), 32u + 1 + 8);
  EXPECT_TRUE(id.starts_with(kDigestA + "-"));
  EXPECT_NE(id, TaskCache::id(kDigestA, "zen4"));
  cache.store().commit(cache_record("grid/s0/sirl/N100/fpe"), id);
  EXPECT_EQ(cache.find(kDigestA, "zen5", false), id);
  EXPECT_EQ(cache.find(kDigestA, "zen4", false), "");
  EXPECT_EQ(cache.find(kDigestA, "zen4", true), id);
  EXPECT_EQ(cache.find(kDigestB, "zen5", true), "");
  EXPECT_EQ(cache.store().load(id, "grid/s0/sirl/N100/fpe"), cache_record("grid/s0/sirl/N100/fpe"));
  EXPECT_THROW(cache.store().load(id, "grid/s0/sirl/N200/fpe"), H5Error);
}

TEST(TaskCache, SeesACommitOfAnotherProcessAfterItOpened) {
  const test::ScratchDir scratch;
  TaskCache mine(scratch.path() / "c");
  TaskStore other(scratch.path() / "c");  // another process's view of the folder
  const std::string id = TaskCache::id(kDigestA, "zen5");
  EXPECT_EQ(mine.find(kDigestA, "zen5", false), "");
  other.commit(cache_record("k"), id);
  EXPECT_EQ(mine.find(kDigestA, "zen5", false), id);
  EXPECT_EQ(mine.store().load(id, "k"), cache_record("k"));
}

TEST(TaskCache, ASecondClaimOnATaskWaitsForTheFirst) {
  const test::ScratchDir scratch;
  TaskCache cache(scratch.path() / "c");
  std::atomic<bool> released{false}, waited{false}, second_has_it{false};
  std::thread second;
  {
    const TaskCache::Claim first = cache.claim(kDigestA);
    second = std::thread([&] {
      const TaskCache::Claim c = cache.claim(kDigestA, [&] { waited = true; });
      second_has_it = true;
      EXPECT_TRUE(released.load()) << "the second claim was granted while the first held it";
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    EXPECT_FALSE(second_has_it.load());
    released = true;
  }
  second.join();
  EXPECT_TRUE(waited.load());
  EXPECT_TRUE(second_has_it.load());
  const TaskCache::Claim other = cache.claim(kDigestB);  // another task: not held by anyone
}

TEST(TaskCache, GcKeepsWhatProfilesAndLiveRunsNeedAndRemovesTheRest) {
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "c";
  {
    TaskCache cache(dir);  // a run that ended
    for (const std::string& d : {kDigestA, kDigestB, kDigestC})
      cache.store().commit(cache_record("key-" + d.substr(0, 1)), TaskCache::id(d, "zen5"));
    cache.store().commit(cache_record("legacy/key"));  // an old engine's file, by key
  }
  // A live run (held runs/ file) needs B; C is being computed (its lock is held).
  TaskCache live(dir);
  live.register_needs({kDigestB});
  const TaskCache::Claim computing = live.claim(kDigestC);

  GcSummary dry = collect_garbage(dir, {kDigestA}, true);
  EXPECT_EQ(dry.removed, 1);
  EXPECT_EQ(dry.kept, 3);
  EXPECT_EQ(dry.held, 2);
  EXPECT_EQ(TaskStore::ids_in(dir).size(), 4u) << "--dry-run removed something";

  const GcSummary s = collect_garbage(dir, {kDigestA}, false);
  EXPECT_EQ(s.removed, 1);
  EXPECT_GT(s.removed_bytes, 0u);
  const std::vector<std::string> left = TaskStore::ids_in(dir);
  EXPECT_EQ(std::set<std::string>(left.begin(), left.end()),
            (std::set<std::string>{TaskCache::id(kDigestA, "zen5"), TaskCache::id(kDigestB, "zen5"),
                                   TaskCache::id(kDigestC, "zen5")}));
}

// A run lists the cache when it opens it and declares its needs a moment later: a gc sweeping
// in between must wait for the declaration, never remove what the run has listed (the run would
// then find its result gone and call it corrupted).
TEST(TaskCache, GcWaitsForAStartingRunToDeclareItsNeeds) {
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "c";
  const std::string id = TaskCache::id(kDigestA, "zen5");
  TaskStore(dir).commit(cache_record("k"), id);
  std::atomic<bool> swept{false};
  std::thread gc;
  {
    TaskCache starting(dir);  // has listed the folder: it holds the result of A
    ASSERT_EQ(starting.find(kDigestA, "zen5", false), id);
    gc = std::thread([&] {
      collect_garbage(dir, {}, false);  // no profile keeps A
      swept = true;
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    EXPECT_FALSE(swept.load()) << "gc swept while a run was between listing and declaring";
    starting.register_needs({kDigestA});
    gc.join();
    EXPECT_TRUE(fs::exists(TaskStore::file_for(dir, id))) << "gc removed what the run listed";
    EXPECT_EQ(starting.store().load(id, "k"), cache_record("k"));
  }
  EXPECT_EQ(collect_garbage(dir, {}, false).removed, 1);  // the run has ended: A goes
}

TEST(TaskCache, GcOfNothingNeededEmptiesTheCacheOnceTheRunHasEnded) {
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "c";
  {
    TaskCache cache(dir);
    cache.register_needs({kDigestA});
    cache.store().commit(cache_record("k"), TaskCache::id(kDigestA, "zen5"));
    EXPECT_EQ(collect_garbage(dir, {}, false).removed, 0) << "removed what a live run needs";
  }
  const GcSummary s = collect_garbage(dir, {}, false);
  EXPECT_EQ(s.removed, 1);
  EXPECT_TRUE(TaskStore::ids_in(dir).empty());
  EXPECT_TRUE(fs::is_empty(dir / "runs")) << "an ended run's needs file stays";
}

TEST(TaskCache, OpeningSweepsAbandonedTemporaryFilesButNotALiveWritersOnes) {
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "c";
  fs::create_directories(dir);
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  const std::string live = "0123456789abcdef.h5." + std::string(host) + "." +
                           std::to_string(::getpid()) + ".tmp",
                    dead = "0123456789abcdee.h5." + std::string(host) + ".999999999.tmp",
                    dead_users = "0123456789abcdea.h5." + std::string(host) + ".999999998.tmp",
                    elsewhere = "0123456789abcded.h5.another-host.1.tmp",
                    legacy = "0123456789abcdec.h5.tmp", users = "0123456789abcdeb.h5.tmp";
  for (const auto& n : {live, dead, elsewhere}) std::ofstream(dir / n) << "SIRLTASK partial";
  // A dead writer's name on bytes that are not the store's: the user's (issue 65: swept before).
  std::ofstream(dir / dead_users) << "my notes";
  // An engine before 0.10.0 named its temporaries "<final>.tmp": no writer is named, so nothing
  // says the file is ours, whatever its bytes (issue 65: swept when they began as a commit).
  std::ofstream(dir / legacy) << "SIRLTASK partial";
  std::ofstream(dir / users) << "my notes";
  TaskStore store(dir);
  EXPECT_TRUE(fs::exists(dir / live));
  EXPECT_FALSE(fs::exists(dir / dead));
  EXPECT_TRUE(fs::exists(dir / dead_users));
  EXPECT_TRUE(fs::exists(dir / elsewhere));
  EXPECT_TRUE(fs::exists(dir / legacy));
  EXPECT_TRUE(fs::exists(dir / users));
}

// A cache folder may hold the user's own files (a results file, notes): opening it, running and
// gc never read or remove what the store did not write, and a checkpoints/ folder that is a
// symbolic link is refused, not emptied (issue 57: both deleted files before).
TEST(TaskCache, NothingTheCacheDidNotWriteIsEverRemoved) {
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "c", elsewhere = scratch.path() / "elsewhere";
  fs::create_directories(dir);
  fs::create_directories(elsewhere);
  const std::vector<std::string> mine{"base.h5",
                                      "0123456789abcdee.h5",  // a commit's name, the user's text
                                      "notes.h5",
                                      "notes.tmp",
                                      "run.h5.tmp",
                                      "0123456789ABCDEF.h5",
                                      "0123456789abcdef.h5.bak"};
  for (const auto& n : mine) std::ofstream(dir / n) << "the user's " << n;
  // Bytes that begin as a commit's, at a commit's name, that do not read as one: nothing says
  // they are the store's (issue 65: removed when the store opened).
  std::ofstream(dir / "4123456789abcdef.h5") << "SIRLTASK2 the user's";
  std::ofstream(elsewhere / "thesis.h5") << "not the cache's";
  std::ofstream(elsewhere / "0123456789abcdef.h5") << "named like a commit, but not the cache's";
  {
    TaskCache cache(dir);
    cache.store().commit(cache_record("k"), TaskCache::id(kDigestA, "zen5"));
  }
  // In runs/ and locks/, files no run writes: a needs file is "<host>.<pid>" of digests, a task
  // lock "<digest>.lock" and empty (issue 65: gc removed anything unheld there).
  const std::vector<fs::path> theirs{
      dir / "runs" / "notes.txt", dir / "runs" / "vm.99999999999999999999", dir / "runs" / "vm.123",
      dir / "locks" / "notes.txt", dir / "locks" / (kDigestB + ".lock")};
  for (const auto& p : theirs) std::ofstream(p) << "the user's";
  fs::create_directory_symlink(elsewhere, dir / "checkpoints");
  EXPECT_THROW(CheckpointStore(dir / "checkpoints", 0), std::runtime_error);
  TaskStore reopened(dir);
  EXPECT_EQ(reopened.keys().size(), 1u);
  const GcSummary s = collect_garbage(dir, {}, false);
  EXPECT_EQ(s.removed, 1);  // the one commit
  for (const auto& n : mine) {
    std::ifstream in(dir / n);
    std::string text;
    std::getline(in, text);
    EXPECT_EQ(text, "the user's " + n) << n << " was removed or changed";
  }
  EXPECT_TRUE(fs::exists(elsewhere / "thesis.h5"));
  EXPECT_TRUE(fs::exists(elsewhere / "0123456789abcdef.h5"));
  EXPECT_TRUE(fs::exists(dir / "4123456789abcdef.h5"));
  for (const auto& p : theirs) EXPECT_TRUE(fs::exists(p)) << p << " was removed";
}

TEST(TaskCache, VerifyNamesAndRemovesADamagedResult) {
  const test::ScratchDir scratch;
  TaskCache cache(scratch.path() / "c");
  const std::string id = TaskCache::id(kDigestA, "zen5");
  TaskRecord r = cache_record("grid/s0/sirl/N100/fpe");
  r.arrays["w"] = TaskRecord::Array::of(std::vector<float>(1000, 1.0f));
  cache.store().commit(r, id);
  EXPECT_EQ(cache.store().verify(id, r.key), "");
  const fs::path file = TaskStore::file_for(cache.dir(), id);
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(-200, std::ios::end);
    f.put('\x5a');
  }
  const std::string why = cache.store().verify(id, r.key);
  EXPECT_NE(why.find("grid/s0/sirl/N100/fpe"), std::string::npos) << why;
  EXPECT_NE(why.find("corrupted"), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(file));
  EXPECT_EQ(cache.find(kDigestA, "zen5", true), "");
}

// ---- digests ----

std::map<std::string, std::string> plan_digests_by_key(const Profile& p) {
  const Plan plan = make_plan(p);
  const std::vector<std::string> d = task_digests(plan);
  std::map<std::string, std::string> out;
  for (size_t i = 0; i < plan.tasks.size(); ++i) out[plan.tasks[i].key] = d[i];
  return out;
}

// The keys whose digest differs between two profiles (tasks in both).
std::set<std::string> digest_changes(const std::string& a, const std::string& b) {
  const auto da = plan_digests_by_key(parse_profile(a)), db = plan_digests_by_key(parse_profile(b));
  std::set<std::string> out;
  for (const auto& [k, d] : da)
    if (auto it = db.find(k); it != db.end() && it->second != d) out.insert(k);
  return out;
}

std::string small_profile_with(const std::string& line) {
  std::string text = test::kSmallProfile;
  const size_t at = text.find("[hyper.grid]\n") + std::string("[hyper.grid]\n").size();
  return text.insert(at, line + "\n");
}

TEST(TaskDigest, IsDeterministicAndDistinctPerTask) {
  const auto a = plan_digests_by_key(parse_profile(test::kSmallProfile));
  EXPECT_EQ(a, plan_digests_by_key(parse_profile(test::kSmallProfile)));
  std::set<std::string> distinct;
  for (const auto& [k, d] : a) {
    EXPECT_EQ(d.size(), 32u);
    distinct.insert(d);
  }
  EXPECT_EQ(distinct.size(), a.size());
}

TEST(TaskDigest, ATpaSettingChangesTpaCellsOnly) {
  const std::set<std::string> c =
      digest_changes(test::kSmallProfile, small_profile_with("\"tpa.lr\" = 0.002"));
  ASSERT_FALSE(c.empty());
  for (const auto& k : c) EXPECT_TRUE(k.find("/tpa/") != std::string::npos) << k;
}

TEST(TaskDigest, APreferenceSettingChangesPreferenceMethodsAndTheirCellsOnly) {
  const std::set<std::string> c =
      digest_changes(test::kSmallProfile, small_profile_with("\"pref.epochs\" = 9"));
  ASSERT_FALSE(c.empty());
  for (const auto& k : c) EXPECT_TRUE(k.find("/multipref10/") != std::string::npos) << k;
}

TEST(TaskDigest, TheVaesSettingsChangeTheVaeAndWhatReadsIt) {
  const std::set<std::string> c =
      digest_changes(test::kSmallProfile, small_profile_with("\"vae.epochs\" = 9"));
  EXPECT_TRUE(c.count("grid/s0/vae"));
  EXPECT_TRUE(c.count("grid/s0/sirl+vae/N100/rep"));
  EXPECT_TRUE(c.count("grid/s0/sirl+vae/N100/fpe"));
  EXPECT_FALSE(c.count("grid/s0/sirl/N100/rep"));
  EXPECT_FALSE(c.count("grid/s0/random/fpe"));
}

TEST(TaskDigest, TheQueryBudgetChangesWhatLearnsFromAnswers) {
  std::string text = test::kSmallProfile;
  text.replace(text.find("similarity = 300"), 16, "similarity = 301");
  const std::set<std::string> c = digest_changes(test::kSmallProfile, text);
  EXPECT_TRUE(c.count("grid/s0/sirl/N100/rep"));
  EXPECT_FALSE(c.count("grid/s0/vae")) << "the VAE learns from no answer";
}

TEST(TaskDigest, JoiningTheAblationChangesACellsRecordSoItsDigest) {
  std::string text = test::kSmallProfile;
  text.replace(text.find("M = [80]"), 8, "M = [10]");
  const std::set<std::string> c = digest_changes(test::kSmallProfile, text);
  EXPECT_TRUE(c.count("grid/s0/sirl/N300/tpa/M10/frozen")) << "in_ablation changed";
  EXPECT_FALSE(c.count("grid/s0/sirl/N300/rep"));
}

// Ξ's settings are the environment's own (EnvSpec::describe_data): a JacoRobot data setting
// changes every JacoRobot task's digest and no GridRobot task's.
TEST(TaskDigest, AnEnvironmentsDataSettingChangesItsTasksOnly) {
  const std::string base =
      "name = \"t\"\nenvs = [\"grid\", \"jaco\"]\nseeds = [0]\n"
      "[fpe]\nmethods = [\"sirl\", \"random\"]\nN = [100]\n[jaco]\ntrajectories = 200\n";
  for (const char* line : {"data_seed = 3", "max_deformation = 0.25"}) {
    const std::set<std::string> c = digest_changes(base, base + line + "\n");
    const auto all = plan_digests_by_key(parse_profile(base));
    ASSERT_EQ(all.size(),
              12u);  // per environment: SIRL's and Random's φ, their FPE, truth's and raw's FPE
    for (const auto& [k, d] : all) EXPECT_EQ(c.count(k), k.starts_with("jaco/") ? 1u : 0u) << k;
  }
}

TEST(TaskDigest, AddingASeedChangesNoExistingTask) {
  std::string text = test::kSmallProfile;
  text.replace(text.find("seeds = [0, 1, 2]"), 17, "seeds = [0, 1, 2, 3]");
  EXPECT_TRUE(digest_changes(test::kSmallProfile, text).empty());
  EXPECT_GT(plan_digests_by_key(parse_profile(text)).size(),
            plan_digests_by_key(parse_profile(test::kSmallProfile)).size());
}

// Runs fn in a forked child and says whether it ended (exit 0) within `seconds`; a child that
// hangs (a FIFO opened for reading) is killed, so the test fails instead of hanging.
bool finishes_within(double seconds, const std::function<void()>& fn) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    try {
      fn();
    } catch (...) {
      ::_exit(3);
    }
    ::_exit(0);
  }
  int status = 0;
  for (int waited = 0; waited < int(seconds * 100); ++waited) {
    if (::waitpid(pid, &status, WNOHANG) == pid)
      return WIFEXITED(status) && WEXITSTATUS(status) == 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return false;
}

// FIFOs planted in runs/ and locks/ (issue 65: they hung gc and runs) are not locks: gc skips and
// keeps them, and a claim of a task whose lock name is a FIFO ends with a line.
TEST(TaskCache, FifosInRunsAndLocksNeitherHangNorAreRemoved) {
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "c";
  { TaskCache cache(dir); }
  ASSERT_EQ(::mkfifo((dir / "runs" / "host.123").c_str(), 0644), 0);
  ASSERT_EQ(::mkfifo((dir / "locks" / (kDigestA + ".lock")).c_str(), 0644), 0);
  // At a commit's name, a dead writer's temporary name and in checkpoints/ too.
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  fs::create_directories(dir / "checkpoints");
  for (const fs::path& p : {dir / "0123456789abcdef.h5",
                            dir / ("0123456789abcdee.h5." + std::string(host) + ".999999999.tmp"),
                            dir / "checkpoints" / "0123456789abcdef.h5"})
    ASSERT_EQ(::mkfifo(p.c_str(), 0644), 0) << p;
  EXPECT_TRUE(finishes_within(10, [&] {
    TaskStore store(dir);
    TaskStore::ids_in(dir);
    TaskStore::ids_in(dir / "checkpoints");
    TaskStore checkpoints(dir / "checkpoints");
  }));
  EXPECT_TRUE(fs::is_fifo(dir / "0123456789abcdef.h5"));
  EXPECT_TRUE(finishes_within(10, [&] { collect_garbage(dir, {}, true); }));
  EXPECT_TRUE(finishes_within(10, [&] { collect_garbage(dir, {}, false); }));
  EXPECT_TRUE(fs::is_fifo(dir / "runs" / "host.123"));
  EXPECT_TRUE(fs::is_fifo(dir / "locks" / (kDigestA + ".lock")));
  EXPECT_TRUE(finishes_within(10, [&] {
    TaskCache cache(dir);
    try {
      cache.claim(kDigestA);
    } catch (const std::runtime_error& e) {
      if (std::string(e.what()).find("not a regular file") != std::string::npos) return;
    }
    throw std::logic_error("a FIFO was taken for a lock");
  }));
}

// gc sweeps only a task cache: a folder without the cache's gate is refused, and a dry run
// leaves no gc.lock behind in it (issue 65: it created one in any folder).
TEST(TaskCache, GcRefusesAFolderThatIsNotACacheAndLeavesNothingInIt) {
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "not-a-cache";
  fs::create_directories(dir);
  std::ofstream(dir / "notes.txt") << "mine";
  for (bool dry : {true, false}) {
    try {
      collect_garbage(dir, {}, dry);
      ADD_FAILURE() << "gc swept a folder that is not a cache (dry run: " << dry << ")";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("is not a task cache"), std::string::npos) << e.what();
    }
  }
  EXPECT_FALSE(fs::exists(dir / "gc.lock"));
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));
}

}  // namespace
}  // namespace sirl
