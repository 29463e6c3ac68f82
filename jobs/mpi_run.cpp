#include "jobs/mpi_run.h"

// The C API only: Open MPI's deprecated C++ bindings need a library we do not link.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>

#include <algorithm>
#include <cstdlib>
#include <deque>
#include <stdexcept>
#include <string>

#include "jobs/ready_queue.h"

namespace sirl {

namespace {
enum Tag { kReady = 1, kTask = 2, kResult = 3, kError = 4, kStop = 5 };
bool g_released = false;

void send_bytes(const std::string& s, int dest, int tag) {
  MPI_Send(s.data(), int(s.size()), MPI_BYTE, dest, tag, MPI_COMM_WORLD);
}
std::string recv_bytes(const MPI_Status& st) {
  int n = 0;
  MPI_Get_count(&st, MPI_BYTE, &n);
  std::string s(size_t(n), '\0');
  MPI_Recv(s.data(), n, MPI_BYTE, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return s;
}
}  // namespace

bool launched_under_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"})
    if (const char* s = std::getenv(v); s && std::atoi(s) > 1) return true;
  return false;
}

int mpi_rank_from_env() {
  if (!launched_under_mpi()) return 0;
  for (const char* v : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"})
    if (const char* s = std::getenv(v)) return std::atoi(s);
  return 0;
}

std::pair<int, int> mpi_start() {
  int inited = 0;
  MPI_Initialized(&inited);
  if (!inited) MPI_Init(nullptr, nullptr);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return {rank, size};
}

void mpi_stop() {
  int fin = 0;
  MPI_Finalized(&fin);
  if (!fin) MPI_Finalize();
}

void mpi_release_workers() {
  if (g_released) return;
  g_released = true;
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  for (int w = 1; w < size; ++w) MPI_Send(nullptr, 0, MPI_BYTE, w, kStop, MPI_COMM_WORLD);
}

void mpi_abort(int code) {
  MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

std::vector<int> mpi_dispatch(const Plan& plan, const std::vector<char>& pending,
                              const std::function<void(int, const TaskRecord&)>& on_result) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::vector<int> ran(size, 0);  // results received per rank
  ReadyQueue queue(plan, pending);
  std::deque<int> idle;
  std::vector<int> running(size, -1);
  int busy = 0;
  std::string error;
  while (true) {
    while (error.empty() && !idle.empty() && !queue.empty()) {
      const int w = idle.front(), i = queue.pop();
      idle.pop_front();
      MPI_Send(&i, 1, MPI_INT, w, kTask, MPI_COMM_WORLD);
      running[w] = i;
      ++busy;
    }
    if (busy == 0 && (queue.remaining() == 0 || !error.empty())) break;
    MPI_Status st;
    MPI_Probe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &st);
    const std::string msg = recv_bytes(st);
    const int w = st.MPI_SOURCE;
    if (st.MPI_TAG == kReady) {
      idle.push_back(w);
    } else if (st.MPI_TAG == kResult || st.MPI_TAG == kError) {
      const int i = running[w];
      running[w] = -1;
      --busy;
      idle.push_back(w);
      if (st.MPI_TAG == kError) {
        if (error.empty()) error = "rank " + std::to_string(w) + ": " + msg;
        continue;
      }
      const TaskRecord rec = deserialize(msg);
      if (rec.key != plan.tasks[i].key)
        throw std::runtime_error("rank " + std::to_string(w) + " returned " + rec.key +
                                 " for task " + plan.tasks[i].key);
      on_result(i, rec);
      queue.finish(i);
      ++ran[w];
    }
  }
  mpi_release_workers();
  if (!error.empty()) throw std::runtime_error(error);
  return ran;
}

void mpi_work(const Plan& plan, RunContext& ctx, int task_threads) {
  MPI_Send(nullptr, 0, MPI_BYTE, 0, kReady, MPI_COMM_WORLD);
  while (true) {
    MPI_Status st;
    MPI_Probe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &st);
    if (st.MPI_TAG == kStop) {
      MPI_Recv(nullptr, 0, MPI_BYTE, 0, kStop, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      return;
    }
    int i = -1;
    MPI_Recv(&i, 1, MPI_INT, 0, kTask, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    try {
      Task t = plan.tasks.at(size_t(i));
      t.threads = std::max(1, task_threads);
      send_bytes(serialize(run_task(t, ctx)), 0, kResult);
    } catch (const std::exception& e) {
      send_bytes(e.what(), 0, kError);
    }
  }
}

}  // namespace sirl
