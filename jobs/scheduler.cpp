#include "jobs/scheduler.h"

#include "jobs/ready_queue.h"

#include <tbb/info.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>
#include <tbb/version.h>

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <mutex>
#include <string>

namespace sirl {

double task_speedup(int k, double serial_fraction) {
  return k <= 1 ? 1.0 : double(k) / (1.0 + serial_fraction * double(k - 1));
}

double serial_fraction_from_speedup(int k, double speedup) {
  if (k < 2 || !(speedup > 0)) return 1.0;
  return std::clamp((double(k) / speedup - 1.0) / double(k - 1), 0.0, 1.0);
}

int usable_cores() {
  return std::max(1, tbb::info::default_concurrency());
}

namespace {

// A cgroup limit file's value in bytes; 0 when absent, unreadable or "max" (no limit).
double cgroup_limit(const char* path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text) || text == "max") return 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return end && *end == '\0' && v > 0 ? v : 0;
}

}  // namespace

double usable_memory_bytes() {
  double bytes = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
  // The process's own cgroup is mounted at /sys/fs/cgroup inside a container (where these
  // limits are set); a v1 "no limit" is a huge number, which the minimum ignores.
  for (const char* f : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"})
    if (const double limit = cgroup_limit(f); limit > 0) bytes = std::min(bytes, limit);
  return bytes;
}

int task_threads(const Task& t, const CoreOffer& o) {
  const int cap = std::max(1, std::min(o.free_cores, o.max_task_threads));
  if (cap == 1 || t.flops < kThreadedTaskFlops || t.bytes < kThreadedTaskBytes) return 1;
  if (o.ready_after == 0) return cap;
  const double share = std::max(
      o.remaining_flops / double(std::max(1, o.total_cores)),
      o.longest_chain / task_speedup(std::max(1, o.max_task_threads), kAssumedSerialFraction));
  int k = 1;
  while (k < cap && o.chain_flops / task_speedup(k, kAssumedSerialFraction) > share) ++k;
  return k;
}

void run_dag(const Plan& plan, const std::vector<char>& pending, int threads, int max_task_threads,
             const std::function<void(int, int)>& work, double memory_bytes) {
  ReadyQueue queue(plan, pending);
  std::mutex mu;
  std::exception_ptr error;
  bool stop = false;
  threads = std::max(1, threads);
  int free_cores = threads;
  double used_bytes = 0;  // Σ working sets of the running tasks
  int running = 0;
  const auto fits = [&](int i) {
    return memory_bytes <= 0 || running == 0 ||
           used_bytes + plan.tasks[size_t(i)].bytes <= memory_bytes;
  };
  tbb::task_arena arena(threads);
  tbb::task_group group;
  // Under the lock: start ready tasks while cores are free (each decides its own width).
  std::function<void()> dispatch;
  dispatch = [&] {
    while (!stop && free_cores > 0 && !queue.empty() && fits(queue.top())) {
      const int i = queue.pop();
      const int k = task_threads(plan.tasks[size_t(i)],
                                 {free_cores, threads, max_task_threads, queue.size(),
                                  queue.rank(i), queue.remaining_flops(), queue.longest_chain()});
      free_cores -= k;
      used_bytes += plan.tasks[size_t(i)].bytes;
      ++running;
      group.run([&, i, k] {
        // Take the lock the dispatcher held while starting this task: it orders everything the
        // starting thread wrote before this task's reads (oneTBB's own hand-off does too, but
        // inside uninstrumented libtbb, where ThreadSanitizer cannot see it).
        { std::lock_guard start(mu); }
        bool failed = false;
        try {
          work(i, k);
        } catch (...) {
          std::lock_guard lock(mu);
          if (!error) error = std::current_exception();
          stop = failed = true;
        }
        std::lock_guard lock(mu);
        free_cores += k;
        used_bytes -= plan.tasks[size_t(i)].bytes;
        --running;
        if (!failed) queue.finish(i);
        dispatch();
      });
    }
  };
  arena.execute([&] {
    {
      std::lock_guard lock(mu);
      dispatch();
    }
    group.wait();
  });
  if (error) std::rethrow_exception(error);
}

void run_dag(const Plan& plan, const std::vector<char>& pending, int threads,
             const std::function<void(int)>& work) {
  run_dag(plan, pending, threads, 1, [&](int i, int) { work(i); });
}

std::string tbb_version() {
  return TBB_runtime_version();
}
}  // namespace sirl
