#include "jobs/stop_request.h"

#include <unistd.h>
#include <csignal>
#include <cstring>

#include <atomic>

namespace sirl {

namespace {

std::atomic<int> g_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "set from a signal handler");

void on_stop_signal(int sig) {
  // A second Ctrl-C means "now": the default action (commits are atomic, so nothing is lost).
  if (sig == SIGINT && g_signal.load() != 0) {
    std::signal(SIGINT, SIG_DFL);
    raise(SIGINT);
    return;
  }
  int expected = 0;
  if (!g_signal.compare_exchange_strong(expected, sig)) return;  // already stopping
  // write(2) only: nothing else is safe in a signal handler.
  const char* msg =
      sig == SIGTERM   ? "\nsirl: SIGTERM: saving every training in progress at its next epoch "
                         "end, then stopping (rerun to continue)\n"
      : sig == SIGUSR1 ? "\nsirl: SIGUSR1: saving every training in progress at its next epoch "
                         "end, then stopping (rerun to continue)\n"
                       : "\nsirl: interrupted: saving every training in progress at its next "
                         "epoch end, then stopping (rerun to continue; Ctrl-C again to quit now)\n";
  [[maybe_unused]] const ssize_t n = write(STDERR_FILENO, msg, std::strlen(msg));
}

}  // namespace

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;  // a read or write in progress finishes instead of failing
  for (int sig : {SIGTERM, SIGUSR1, SIGINT}) sigaction(sig, &sa, nullptr);
}

bool stop_requested() {
  return g_signal.load(std::memory_order_relaxed) != 0;
}

int stop_signal() {
  return g_signal.load();
}

const char* stop_signal_name() {
  switch (g_signal.load()) {
    case 0:
      return "";
    case SIGTERM:
      return "SIGTERM";
    case SIGUSR1:
      return "SIGUSR1";
    case SIGINT:
      return "SIGINT";
    default:
      return "a signal";
  }
}

void request_stop(int signal_number) {
  int expected = 0;
  g_signal.compare_exchange_strong(expected, signal_number);
}

void clear_stop_request() {
  g_signal.store(0);
}

}  // namespace sirl
