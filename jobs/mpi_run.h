// Scale-out over MPI: the same `sirl run` under `mpirun -np K`. Rank 0 is the dispatcher and the
// only writer — it hands ready tasks to whichever worker asks next (dynamic pulling, costliest
// chains first) and commits the records the workers send back; ranks 1..K−1 compute. Results
// are identical to a single-process run because every task depends only on its key and inputs.
#pragma once
#include <functional>
#include <vector>

#include "experiment/plan.h"
#include "experiment/task_runner.h"
#include "results/task_record.h"

namespace sirl {

// True when started by mpirun/srun with more than one rank (Open MPI, PMI or PMIx environment).
bool launched_under_mpi();
// This process's rank as the launcher's environment tells it (0 when not under MPI).
int mpi_rank_from_env();
// MPI_Init (once); returns {rank, size}.
std::pair<int, int> mpi_start();
void mpi_stop();
// Rank 0, on an error before or during dispatch: tells every worker to exit (idempotent).
void mpi_release_workers();
// Rank 0 ends every rank with this exit code after printing its own error (no hung workers).
[[noreturn]] void mpi_abort(int code);

// Rank 0: runs the pending tasks on the workers; `on_result` (called on rank 0, one at a time)
// commits each record. Rethrows the first worker error after the running tasks finish. Returns
// the tasks each rank ran ([size]; rank 0 runs none).
// Each worker's task runs on `threads_per_worker` cores, times the workers it borrows: a big
// task alone in the ready queue or on a critical chain (task_threads, counted in workers) also
// takes idle workers of its node, which sleep until it ends, when its process may run threads
// on their cores (ranks not bound to single cores: `mpirun --bind-to none`).
std::vector<int> mpi_dispatch(const Plan& plan, const std::vector<char>& pending,
                              int threads_per_worker,
                              const std::function<void(int, const TaskRecord&)>& on_result);
// Ranks > 0: computes the tasks rank 0 sends, on the cores it says (results do not depend on
// them), or lends its core to another worker's task, until told to stop.
void mpi_work(const Plan& plan, RunContext& ctx);

}  // namespace sirl
