#include "jobs/progress.h"

#include <unistd.h>

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

void Progress::task_done(const std::string& key, double task_flops, double seconds) {
  std::lock_guard lock(mu_);
  ++done_;
  done_flops_ += task_flops;
  print(key, done_ == total_);
}

void Progress::print(const std::string& last, bool force) {
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (!tty_ && !force && std::chrono::duration<double>(now - last_print_).count() < 5) return;
  last_print_ = now;
  // ETA from the share of estimated work done (tasks differ in cost by orders of magnitude).
  const double frac = total_flops_ > 0 ? done_flops_ / total_flops_ : double(done_) / total_;
  const double eta = frac > 0 ? elapsed * (1 - frac) / frac : NAN;
  const double gflops = elapsed > 0 ? done_flops_ / elapsed * 1e-9 : 0;
  char line[256];
  std::snprintf(line, sizeof line, "[%d/%d tasks] %5.1f%% | %.1f GFLOP/s | elapsed %s | ETA %s",
                done_, total_, 100 * frac, gflops, format_duration(elapsed).c_str(),
                done_ == total_ ? "0s" : format_duration(eta).c_str());
  if (tty_)
    std::fprintf(stderr, "\r\033[K%s | %s", line, last.c_str());
  else
    std::fprintf(stderr, "%s | last: %s\n", line, last.c_str());
  std::fflush(stderr);
}

void Progress::finish() {
  std::lock_guard lock(mu_);
  if (tty_ && !quiet_) std::fprintf(stderr, "\n");
}

}  // namespace sirl
