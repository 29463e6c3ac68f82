// A request to stop a run early and keep its work: SIGTERM (Slurm's pre-emption, `scontrol
// requeue`, a time limit, `kill`), SIGUSR1 (the warning a batch script asks for with
// `--signal=B:USR1@N`, forwarded to sirl) or a first Ctrl-C. Every training in progress saves
// its state at its next epoch end and stops; no new task starts; the run writes what finished
// and exits with kExitStopped, and rerunning the same command continues each training from its
// checkpoint. A second Ctrl-C ends the process at once (commits are atomic: nothing committed
// is lost).
#pragma once
#include "engine/checkpoint.h"  // StopRequested

namespace sirl {

// The exit status of a run stopped by such a request: EX_TEMPFAIL ("try again later").
// A batch script requeues the job when it sees it.
constexpr int kExitStopped = 75;

// Installs the handlers (SIGTERM, SIGUSR1, SIGINT). Idempotent.
void install_stop_handlers();

// Whether a stop was requested, and by which signal (0: none).
bool stop_requested();
int stop_signal();
// The signal's name ("SIGTERM"), or "" when none.
const char* stop_signal_name();

// Raises the request from code (tests, an MPI worker told by rank 0).
void request_stop(int signal_number);
// Clears it (tests only: a process normally stops once).
void clear_stop_request();

}  // namespace sirl
