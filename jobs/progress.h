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
  // One task finished (thread-safe).
  void task_done(const std::string& key, double task_flops, double seconds);
  void finish();

  // What the status line is computed from: tasks and FLOPs done, and the FLOPs finished tasks
  // ran in this process (the rate's numerator).
  struct Counts {
    int done = 0;
    double done_flops = 0, rate_flops = 0;
  };
  Counts counts();

 private:
  void print(const std::string& last, bool force);
  std::mutex mu_;
  int total_, done_ = 0;
  double total_flops_, done_flops_ = 0, rate_flops_ = 0;  // rate_flops_: run in this process
  std::set<std::string> resumed_;
  std::map<std::string, double> flops_before_;  // of resumed tasks whose checkpoint counted them
  bool tty_, quiet_;
  std::chrono::steady_clock::time_point start_, last_print_;
};

// The status line: tasks done of total, the share of the estimated FLOPs done, the rate (the FLOPs
// finished tasks ran in this process over the elapsed time) and the ETA (the FLOPs left at that
// rate; "?" before any such task finished).
std::string progress_line(int done, int total, double done_flops, double rate_flops,
                          double total_flops, double elapsed);

// "1h02m", "3m05s", "12s".
std::string format_duration(double seconds);

}  // namespace sirl
