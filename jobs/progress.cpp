#include "jobs/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace sirl {

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  char buf[32];
  const long t = std::lround(s);
  if (t >= 3600)
    std::snprintf(buf, sizeof buf, "%ldh%02ldm", t / 3600, (t / 60) % 60);
  else if (t >= 60)
    std::snprintf(buf, sizeof buf, "%ldm%02lds", t / 60, t % 60);
  else
    std::snprintf(buf, sizeof buf, "%lds", t);
  return buf;
}

Progress::Progress(int total, double total_flops, bool quiet)
    : total_(total),
      total_flops_(total_flops),
      tty_(isatty(STDERR_FILENO)),
      quiet_(quiet),
      start_(std::chrono::steady_clock::now()),
      last_print_(start_) {}

void Progress::set_resumed(std::set<std::string> keys) {
  std::lock_guard lock(mu_);
  resumed_ = std::move(keys);
}

Progress::Counts Progress::counts() {
  std::lock_guard lock(mu_);
  return {done_, done_flops_, rate_flops_, executed_flops_};
}

void Progress::resumed_from(const std::string& key, double flops_before) {
  std::lock_guard lock(mu_);
  if (flops_before > 0) flops_before_[key] = flops_before;
}

void Progress::task_done(const std::string& key, double task_flops, double seconds,
                         double executed_flops) {
  std::lock_guard lock(mu_);
  const double ran = executed_flops < 0 ? task_flops : executed_flops;
  ++done_;
  done_flops_ += task_flops;
  if (!resumed_.count(key)) {
    rate_flops_ += task_flops;
    executed_flops_ += ran;
  } else if (const auto it = flops_before_.find(key); it != flops_before_.end()) {
    const double here = std::max(0.0, ran - it->second);  // the part run in this process
    executed_flops_ += here;
    if (ran > 0) rate_flops_ += task_flops * here / ran;  // that share of the estimate
  }
  print(key, done_ == total_);
}

void Progress::done_elsewhere(const std::string& key, double task_flops) {
  std::lock_guard lock(mu_);
  ++done_;
  done_flops_ += task_flops;
  print(key, done_ == total_);
}

std::string progress_line(int done, int total, double done_flops, double rate_flops,
                          double executed_flops, double total_flops, double elapsed) {
  // The share of estimated work done (tasks differ in cost by orders of magnitude).
  const double frac = total_flops > 0 ? done_flops / total_flops : double(done) / total;
  const double rate = elapsed > 0 ? rate_flops / elapsed : 0;       // estimated FLOPs per second
  const double speed = elapsed > 0 ? executed_flops / elapsed : 0;  // FLOP/s executed
  const double left = total_flops > 0 ? std::max(0.0, total_flops - done_flops) : 0;
  double eta = NAN;
  if (done == total)
    eta = 0;
  else if (total_flops > 0 && rate > 0)
    eta = left / rate;
  else if (total_flops <= 0 && frac > 0)
    eta = elapsed * (1 - frac) / frac;
  char line[256];
  std::snprintf(line, sizeof line, "[%d/%d tasks] %5.1f%% | %.1f GFLOP/s | elapsed %s | ETA %s",
                done, total, 100 * frac, speed * 1e-9, format_duration(elapsed).c_str(),
                format_duration(eta).c_str());
  return line;
}

void Progress::print(const std::string& last, bool force) {
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (!tty_ && !force && std::chrono::duration<double>(now - last_print_).count() < 5) return;
  last_print_ = now;
  const std::string line = progress_line(done_, total_, done_flops_, rate_flops_, executed_flops_,
                                         total_flops_, elapsed);
  if (tty_)
    std::fprintf(stderr, "\r\033[K%s | %s", line.c_str(), last.c_str());
  else
    std::fprintf(stderr, "%s | last: %s\n", line.c_str(), last.c_str());
  std::fflush(stderr);
}

void Progress::finish() {
  std::lock_guard lock(mu_);
  if (tty_ && !quiet_) std::fprintf(stderr, "\n");
}

}  // namespace sirl
