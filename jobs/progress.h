// Progress of a run: a live status line on a terminal (done/total, GFLOP/s, ETA), plain log lines
// (at most one every few seconds) when stderr is not a terminal, e.g. in CI logs.
#pragma once
#include <chrono>
#include <cstdio>
#include <map>
#include <mutex>
#include <set>
#include <string>

namespace sirl {

class Progress {
 public:
  Progress(int total, double total_flops, bool quiet = false);
  // Tasks that continue a training checkpoint: part of their work was done before this process
  // started, so they count toward the share done but not toward the rate the ETA divides by
  // (else a large cell finishing soon after a restart reads as an absurd rate).
  void set_resumed(std::set<std::string> keys);
  // A resumed task's training continued from a checkpoint that had executed flops_before: when
  // it finishes, what it ran here (its FLOPs less those) counts toward the rate, so a restarted
  // long run has an ETA before a task it started afresh finishes. 0: not known, the task stays
  // out of the rate (thread-safe).
  void resumed_from(const std::string& key, double flops_before);
  // One task finished (thread-safe): task_flops is the plan's estimate of its work (the unit of
  // the share done and the ETA), executed_flops what it ran (its record's FLOPs; < 0: unknown,
  // taken as the estimate). They differ when a task stops by a rule whose stopping epochs the
  // plan does not know.
  void task_done(const std::string& key, double task_flops, double seconds,
                 double executed_flops = -1);
  // A task another process computed while this one waited for it: done, but not run here.
  void done_elsewhere(const std::string& key, double task_flops);
  void finish();

  // What the status line is computed from: tasks and estimated FLOPs done, the estimated FLOPs
  // of the work finished tasks ran in this process (the ETA's rate), and the FLOPs they executed
  // here (the GFLOP/s shown).
  struct Counts {
    int done = 0;
    double done_flops = 0, rate_flops = 0, executed_flops = 0;
  };
  Counts counts();

 private:
  void print(const std::string& last, bool force);
  std::mutex mu_;
  int total_, done_ = 0;
  double total_flops_, done_flops_ = 0;
  double rate_flops_ = 0, executed_flops_ = 0;  // of the work run in this process
  std::set<std::string> resumed_;
  std::map<std::string, double> flops_before_;  // of resumed tasks whose checkpoint counted them
  bool tty_, quiet_;
  std::chrono::steady_clock::time_point start_, last_print_;
};

// The status line: tasks done of total, the share of the estimated FLOPs done, the speed (the
// FLOPs finished tasks executed in this process over the elapsed time) and the ETA (the estimated
// FLOPs left at the rate rate_flops, the estimated FLOPs of that work, was done; "?" before any
// such task finished).
std::string progress_line(int done, int total, double done_flops, double rate_flops,
                          double executed_flops, double total_flops, double elapsed);

// "1h02m", "3m05s", "12s".
std::string format_duration(double seconds);

}  // namespace sirl
