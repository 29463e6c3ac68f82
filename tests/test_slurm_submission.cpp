// The Slurm submission's parts that need no cluster (jobs/slurm_submission.h, jobs/stop_request.h,
// jobs/cluster_prediction.h): --time strings, the manifest's round trip and its errors, shard
// logs (torn lines included), the scripts' shell syntax and quoting, a checkpointer under a stop
// request, and the memory a node needs worked out by hand. tests/slurm_submit.py runs them on a
// real Slurm.
#include <gtest/gtest.h>

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>

#include "jobs/cluster_prediction.h"
#include "jobs/slurm_submission.h"
#include "jobs/stop_request.h"
#include "jobs/task_checkpoints.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {

using test::ScratchDir;

SlurmSubmission sample(const std::filesystem::path& dir) {
  SlurmSubmission s;
  s.profile = "smoke";
  s.dir = dir;
  s.sirl = "/opt/sirl bench/sirl";
  s.shards = 3;
  s.cpus = 4;
  s.time_minutes = 95;
  s.memory_mib = 2048;
  s.partition = "short";
  s.jobs = {"12", "15"};
  return s;
}

TEST(SlurmSubmission, TimeIsDaysHoursMinutesRoundedToAtLeastOneMinute) {
  EXPECT_EQ(slurm_time(0), "0-00:01:00");
  EXPECT_EQ(slurm_time(1), "0-00:01:00");
  EXPECT_EQ(slurm_time(61), "0-01:01:00");
  EXPECT_EQ(slurm_time(1441), "1-00:01:00");
  EXPECT_EQ(slurm_time(3 * 1440 + 23 * 60 + 59), "3-23:59:00");
}

TEST(SlurmSubmission, TheManifestRoundTrips) {
  ScratchDir d;
  const SlurmSubmission s = sample(d.path());
  write_submission(s);
  const SlurmSubmission r = read_submission(d.path());
  EXPECT_EQ(r.profile, s.profile);
  EXPECT_EQ(r.sirl, s.sirl);
  EXPECT_EQ(r.shards, 3);
  EXPECT_EQ(r.cpus, 4);
  EXPECT_EQ(r.time_minutes, 95);
  EXPECT_EQ(r.memory_mib, 2048);
  EXPECT_EQ(r.partition, "short");
  EXPECT_EQ(r.jobs, s.jobs);
  EXPECT_FALSE(r.mpi);
}

TEST(SlurmSubmission, AMissingOrDamagedManifestIsOneClearError) {
  ScratchDir d;
  try {
    read_submission(d.path());
    FAIL() << "no manifest";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("holds no submission"), std::string::npos) << e.what();
  }
  std::ofstream(d.path() / "submission.toml") << "profile = 'smoke'\nshards = [";
  EXPECT_THROW(read_submission(d.path()), std::runtime_error);
  std::ofstream(d.path() / "submission.toml", std::ios::trunc) << "profile = 'smoke'\n";
  try {
    read_submission(d.path());
    FAIL() << "a manifest without its fields";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("lacks 'sirl'"), std::string::npos) << e.what();
  }
  SlurmSubmission s = sample(d.path());
  s.profile = "../elsewhere";  // the profile names files in the folder: never a path
  write_submission(s);
  EXPECT_THROW(read_submission(d.path()), std::runtime_error);
  s = sample(d.path());
  s.shards = 0;
  write_submission(s);
  EXPECT_THROW(read_submission(d.path()), std::runtime_error);
}

TEST(SlurmSubmission, AShardsLogSaysWhatBecameOfItsLastJob) {
  ScratchDir d;
  const SlurmSubmission s = sample(d.path());
  EXPECT_EQ(read_shard_state(s, 0).phase, ShardState::kNotStarted);
  std::filesystem::create_directories(d.path() / "state");
  auto write = [&](const std::string& text) {
    std::ofstream(s.state_file(1), std::ios::trunc) << text;
  };
  write("start 12_1 nodeA 2026-01-01T00:00:00Z\nexit 75 2026-01-01T01:00:00Z\n");
  ShardState st = read_shard_state(s, 1);
  EXPECT_EQ(st.phase, ShardState::kStopped);
  EXPECT_EQ(st.exit_code, 75);
  write(
      "start 12_1 nodeA 2026-01-01T00:00:00Z\nexit 75 2026-01-01T01:00:00Z\n"
      "start 12_1 nodeB 2026-01-01T01:01:00Z\n");
  st = read_shard_state(s, 1);
  EXPECT_EQ(st.phase, ShardState::kRunning);
  EXPECT_EQ(st.host, "nodeB");
  EXPECT_EQ(st.starts, 2);
  write("start 15_1 nodeA 2026-01-01T00:00:00Z\nexit 2 2026-01-01T00:00:05Z\n");
  st = read_shard_state(s, 1);
  EXPECT_EQ(st.phase, ShardState::kFailed);
  EXPECT_EQ(st.exit_code, 2);
  EXPECT_EQ(st.job, "15_1");
  // A job killed while writing its exit line leaves it torn: the shard still reads as running.
  write("start 15_1 nodeA 2026-01-01T00:00:00Z\nex");
  EXPECT_EQ(read_shard_state(s, 1).phase, ShardState::kRunning);
  write("start 15_1 nodeA 2026-01-01T00:00:00Z\nexit 0 2026-01-01T00:09:00Z\n");
  EXPECT_EQ(read_shard_state(s, 1).phase, ShardState::kDone);
}

// bash -n: the script parses; and a folder with a quote in its name stays one word.
void expect_valid_shell(const SlurmSubmission& s, const std::filesystem::path& file) {
  std::ofstream(file) << slurm_script(s);
  EXPECT_EQ(std::system(("bash -n '" + file.string() + "'").c_str()), 0) << slurm_script(s);
}

TEST(SlurmSubmission, TheArrayScriptRunsOneShardPerTaskAndRequeuesOnTheWarning) {
  ScratchDir d;
  SlurmSubmission s = sample(d.path() / "it's here");
  const std::string text = slurm_script(s);
  for (const char* line :
       {"#SBATCH --array=0-2\n", "#SBATCH --cpus-per-task=4\n", "#SBATCH --mem=2048M\n",
        "#SBATCH --time=0-01:35:00\n", "#SBATCH --requeue\n", "#SBATCH --open-mode=append\n",
        "#SBATCH --signal=B:USR1@300\n", "#SBATCH --partition=short\n", "--shard \"$shard/3\"",
        "scontrol requeue \"$job\"", "'/opt/sirl bench/sirl' run"})
    EXPECT_NE(text.find(line), std::string::npos) << line << "\n" << text;
  EXPECT_NE(text.find("dir='" + d.path().string() + "/it'\\''s here'"), std::string::npos) << text;
  EXPECT_EQ(text.find("#SBATCH --account"), std::string::npos);
  expect_valid_shell(s, d.path() / "array.sh");
}

TEST(SlurmSubmission, TheMpiScriptAsksForNodesAndRanks) {
  ScratchDir d;
  SlurmSubmission s = sample(d.path());
  s.mpi = true;
  s.shards = 1;
  s.nodes = 8;
  s.cpus = 64;
  s.threads_per_worker = 4;
  const std::string text = slurm_script(s);
  for (const char* line :
       {"#SBATCH --nodes=8\n", "#SBATCH --ntasks-per-node=16\n", "#SBATCH --cpus-per-task=4\n",
        "mpirun --bind-to none", "--task-threads 4"})
    EXPECT_NE(text.find(line), std::string::npos) << line << "\n" << text;
  EXPECT_EQ(text.find("--array"), std::string::npos);
  EXPECT_EQ(s.shard_file(0), d.path() / "smoke.h5");
  expect_valid_shell(s, d.path() / "mpi.sh");
}

TEST(StopRequest, ACheckpointerSavesAtOnceAndStopsTheTraining) {
  ScratchDir d;
  CheckpointStore store(d.path(), 3600);  // not due for an hour...
  auto cp = store.for_task("0123456789abcdef", "grid/s0/sirl/N10/rep");
  EXPECT_FALSE(cp->due());
  request_stop(SIGTERM);  // ...until a stop is requested
  EXPECT_TRUE(stop_requested());
  EXPECT_STREQ(stop_signal_name(), "SIGTERM");
  EXPECT_TRUE(cp->due());
  TrainingSnapshot s;
  s.epoch = 7;
  s.numbers["flops"] = 1;
  EXPECT_THROW(cp->save(s), StopRequested);
  clear_stop_request();
  TrainingSnapshot back;
  ASSERT_TRUE(cp->load(back));  // saved before it stopped
  EXPECT_EQ(back.epoch, 7);
  EXPECT_FALSE(stop_requested());
}

TEST(StopRequest, AResumedTrainingTellsTheRunWhatItHadExecuted) {
  ScratchDir d;
  CheckpointStore store(d.path(), 0);
  TrainingSnapshot s;
  s.epoch = 3;
  s.numbers["train_flops"] = 7e9;
  store.for_task("0123456789abcdef", "grid/s0/sirl/N10/rep")->save(s);
  std::string label;
  double flops = -1;
  store.on_resume([&](const std::string& l, double f) {
    label = l;
    flops = f;
  });
  TrainingSnapshot back;
  ASSERT_TRUE(store.for_task("0123456789abcdef", "grid/s0/sirl/N10/rep")->load(back));
  EXPECT_EQ(label, "grid/s0/sirl/N10/rep");
  EXPECT_DOUBLE_EQ(flops, 7e9);
  // A snapshot without the count: the hook hears 0 (not known).
  TrainingSnapshot t;
  t.epoch = 1;
  store.for_task("fedcba9876543210", "grid/s0/sirl/N10/tpa/M10/frozen")->save(t);
  ASSERT_TRUE(store.for_task("fedcba9876543210", "grid/s0/sirl/N10/tpa/M10/frozen")->load(back));
  EXPECT_EQ(label, "grid/s0/sirl/N10/tpa/M10/frozen");
  EXPECT_DOUBLE_EQ(flops, 0);
}

TEST(ClusterPrediction, ANodeHoldsItsProcessesDataAndTheLargestTasksThatRunThereAtOnce) {
  Plan plan;
  const double mib = 1024.0 * 1024.0;
  for (int i = 0; i < 5; ++i) {
    Task t;
    t.key = "t" + std::to_string(i);
    t.flops = 1e9;
    t.bytes = double(10 * (i + 1)) * mib;  // 10, 20, 30, 40, 50 MiB
    plan.index[t.key] = i;
    plan.tasks.push_back(t);
  }
  PlanEstimate e;
  e.task_seconds.assign(5, 1.0);
  e.data_bytes = 100 * mib;
  const std::vector<char> all(5, 1);
  ClusterModel threads;
  threads.cores_per_node = 2;
  threads.max_task_threads = 2;
  // One process: its data and the two largest tasks.
  EXPECT_DOUBLE_EQ(predict_cluster(plan, e, threads, all).memory_bytes_per_node,
                   (100 + 50 + 40) * mib);
  ClusterModel mpi;
  mpi.mpi = true;
  mpi.nodes = 1;
  mpi.cores_per_node = 4;  // rank 0 and three workers: four copies of the data, three tasks
  EXPECT_DOUBLE_EQ(predict_cluster(plan, e, mpi, all).memory_bytes_per_node,
                   (4 * 100 + 50 + 40 + 30) * mib);
  mpi.nodes = 2;  // the second node's four workers: four tasks
  EXPECT_DOUBLE_EQ(predict_cluster(plan, e, mpi, all).memory_bytes_per_node,
                   (4 * 100 + 50 + 40 + 30 + 20) * mib);
  // A shard's prediction counts only its tasks.
  const std::vector<char> two{1, 0, 0, 0, 1};
  EXPECT_DOUBLE_EQ(predict_cluster(plan, e, threads, two).memory_bytes_per_node,
                   (100 + 50 + 10) * mib);
}

}  // namespace
}  // namespace sirl
