// Progress of a run: a live status line on a terminal (done/total, GFLOP/s, ETA), plain log lines
// (at most one every few seconds) when stderr is not a terminal, e.g. in CI logs.
#pragma once
#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>

namespace sirl {

class Progress {
 public:
  Progress(int total, double total_flops, bool quiet = false);
  // One task finished (thread-safe).
  void task_done(const std::string& key, double task_flops, double seconds);
  void finish();

 private:
  void print(const std::string& last, bool force);
  std::mutex mu_;
  int total_, done_ = 0;
  double total_flops_, done_flops_ = 0;
  bool tty_, quiet_;
  std::chrono::steady_clock::time_point start_, last_print_;
};

// "1h02m", "3m05s", "12s".
std::string format_duration(double seconds);

}  // namespace sirl
