// The run's results file (docs/ARCHITECTURE.md §5): root attributes describing the run, the
// datasets, every task's record under /runs/<task key>, and long tables that pandas reads directly
// (fpe and tpa are the FPE and TPA task kinds' tables, declared with them:
// experiment/simulation_tasks.cpp):
//   /tables/fpe      env, method, variant, vae, N, seed, fpe, train_mse
//   /tables/tpa      env, method, variant, vae, frozen, N, M, seed, tpa, tpa_std, tpa_train,
//                    in_main (a Fig. 5 cell), in_ablation (a Fig. 7 cell)
//   /tables/timings  kind, key, seconds, flops (executed), gflops, …, protocol_flops (the full
//                    schedule's: more than flops where reward heads stopped early)
//   /tables/training kind, key, env, variant, N, M, frozen, seed, epochs, final_loss,
//                    loss_relative_change, converged, converged_fraction, dead_fraction
//   /tables/vae_latents  env, seed, elbo, dim, kl, reconstruction_mse
//   /tables/tpa_heads    key, env, variant, N, M, frozen, seed, teacher, head, accuracy,
//                        train_accuracy, epochs, max_epochs, stopped, stop, final_loss, phi_drift
// Written atomically (a .partial file renamed into place), so the file on disk is always whole.
#pragma once
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "datasets/dataset.h"
#include "datasets/query_bundle.h"
#include "results/h5.h"
#include "results/task_record.h"

namespace sirl {

// The results file's layout version (docs/RESULTS.md), stored as /@schema_version. Version 1
// (engine 0.1.0, no attribute) lacks the environment attributes of /datasets/<env>; it is still
// read. Version 3 (engine 0.8.0) starts with its checksum frame and its tables carry each cell's
// fields (selection, teacher, best_mode). A file of a newer version is refused with one line
// naming both versions.
inline constexpr int64_t kResultsSchemaVersion = 3;
// The file's version (1 when the attribute is missing); throws H5Error for a version this engine
// cannot read.
int64_t check_results_schema(const H5File& f);

// One core's roofs as the writer of a results file measured them (probes/roofline.h; 0: unknown).
struct Roofs {
  double fp32_gflops = 0;  // peak fp32 FMA
  double bf16_gflops = 0;  // the unit bf16 products ran on (0: no bf16 run, or bf16 emulated)
  double stream_gbs = 0;   // main-memory bandwidth (STREAM triad)
};

struct RunInfo {
  std::string profile_name, profile_text, engine_version, git_commit, host;
  double roof_fp32_gflops = 0;  // one core's fp32 roof, measured by the writer (probes/roofline.h)
  double roof_bf16_gflops = 0;  // one core's bf16 roof, measured by a bf16 run's writer (else 0)
  double stream_gbs = 0;  // one core's main-memory bandwidth, measured by the writer (0: unknown)
  std::string cpu_class;  // probes/cpu_class.h ("" in files of engines before 0.3.0)
  bool verified = true;   // read_run_info: false when no checksum covered the file
  std::string libraries;  // compiler and library versions ("" in files before engine 0.8.0)
  std::string kernel_paths;  // the instruction sets and backends that ran (probes/cpu_class.h;
                             // "" in files before engine 0.9.0)
  // The hyper-parameter points of environments with axes ([hyper.<env>] lists), one line per
  // environment: "<env>\t<base tag>\t<tag>…"; a table row's hyper_point "" is the base tag. ""
  // when the profile has no axis.
  std::string hyper_points;
  std::string started, finished;  // ISO 8601 UTC
  std::string shard;              // "i/n" for a shard file, "" for a whole run
  // The keys of the plan's tasks a partial merge (`sirl merge --partial`) lacked, one per line;
  // "" otherwise (a partial run's missing tasks are those of its plan not in /runs_index).
  std::string missing_tasks;
  // The inputs of a merge that no checksum verified (`sirl merge --accept-unverified`), one per
  // line; "" otherwise.
  std::string unverified_inputs;
  int64_t threads = 0, tasks_total = 0, tasks_done = 0;
  double wall_seconds = 0;
  bool complete = false;
  int64_t schema_version = kResultsSchemaVersion;
  Roofs roofs() const { return {roof_fp32_gflops, roof_bf16_gflops, stream_gbs}; }
};

// A table of one kind's records (a task kind declares it: experiment/task_kinds.h): one row per
// record, each column read from one record field (`key`: text for String columns, a number for Int
// and Double). A record without the field is an error naming the task, never a silent 0.
struct TableColumn {
  const char* name;
  H5Table::Column::Type type;
  const char* key;
  bool optional = false;    // a record without the field gives "" (or 0) instead of an error
  const char* absent = "";  // what an optional String column gives a record without the field
};
struct CellTableSpec {
  std::string name;  // the table: /tables/<name>, <name>.csv
  std::string kind;  // the records it reads: those of this kind
  std::vector<TableColumn> columns;
  // Several rows per record (a long table): with rows_key set, a record gives num[rows_key] rows,
  // and row i's column reads the field "<key>/<i>" where the record has one, else the record's own
  // "<key>" (the same in each of its rows).
  const char* rows_key = nullptr;
  std::vector<std::string> more_kinds;  // records of these kinds too (rows with the same columns)
};

struct NamedTable {
  std::string name;
  H5Table table;
};
// /methods/<name>: how figures and the report show one variant of the file (its attributes:
// engine/method_catalog.h's VariantStyle, filled by the experiment layer).
struct MethodAttributes {
  std::string name;
  std::vector<std::pair<std::string, std::string>> text;
  std::vector<std::pair<std::string, int64_t>> integers;
};

struct ResultTables {
  std::vector<NamedTable> tables;         // in the file's order
  std::vector<MethodAttributes> methods;  // every variant the records hold
  // The table called `name`; throws std::out_of_range naming it.
  const H5Table& at(const std::string& name) const;
};
// The cell tables in the order given, then the tables every kind contributes to: timings,
// training (each training's convergence), vae_latents, tpa_heads (one row per reward head). The
// roofs give /tables/timings its roof_percent column (a task whose record says bf16_products
// against the bf16 roof where there is one, every other against the fp32 roof) and the memory roofs
// of the tasks that stream (their records' stream_bytes).
ResultTables build_tables(const std::vector<TaskRecord>& records,
                          const std::vector<CellTableSpec>& cells, const Roofs& roofs = {});

struct RunDataset {
  const Dataset* dataset;
  const QueryBundle* bundle;  // the queries of the run's first seed (the figures draw from them)
};

void write_results_file(const std::string& path, const RunInfo& info,
                        const std::vector<RunDataset>& datasets,
                        const std::vector<TaskRecord>& records, const ResultTables& tables);
// Both verify the file against its checksums before HDF5 reads a byte of it, and read it in a
// forked child first (results/isolated_read.h): a corrupted or crafted file is one clear H5Error,
// never a crash inside the HDF5 library. A file of a framing engine (schema 3) without its frame
// is refused. RunInfo::verified says whether it could
// be verified at all (a file of engine ≤ 0.7.0 copied without its .sum cannot).
RunInfo read_run_info(const std::string& path);
std::vector<TaskRecord> read_results_records(const std::string& path);
// read_run_info, and how many task records of each kind the file holds: verified and read in a
// child once, each record's kind attribute only (no arrays), for a summary (`sirl show`).
struct ResultsSummary {
  RunInfo info;
  std::map<std::string, int64_t> records_by_kind;
  std::string verdicts;  // /verdicts@claims (store_verdicts), "" when the file has none
};
ResultsSummary read_results_summary(const std::string& path);

// A results file carries its digest in its first 1024 bytes (an HDF5 userblock; engines from 0.8.0
// on); FILE.sum beside it holds the whole file's (`xxh128sum -c FILE.sum` checks it; a 16-digit
// .sum is an older engine's FNV checksum). verify_checksum throws H5Error on any mismatch or a
// damaged frame, and returns whether anything verified the file (false: an unframed file without
// its .sum).
void write_checksum(const std::string& path);
// `framed`: whether the file starts with a frame (engines from 0.8.0 on frame what they write).
bool verify_checksum(const std::string& path, bool* framed = nullptr);
// One line for a file verify_checksum could not verify.
std::string unverified_note(const std::string& path);

// The report's verdicts kept in the results file itself: /verdicts with attributes `claims` (the
// JSON list the report writes as claims.json: one object per claim × environment × protocol),
// `written` (ISO 8601 UTC) and `writer` (what wrote them). The file is rewritten as every write
// here is: a copy with the group (replacing one stored before) framed with its new digest, renamed
// into place, its .sum rewritten, under the file's lock. A file whose frame does not verify is
// refused (H5Error): storing would give a file no checksum vouches for a valid digest. A run that
// rewrites the file drops them (they describe the file the report read).
void store_verdicts(const std::string& path, const std::string& claims_json,
                    const std::string& writer);

// One CSV per table (<name>.csv: fpe.csv, tpa.csv, timings.csv, training.csv, …) in dir.
void export_csv(const ResultTables& t, const std::string& dir);

}  // namespace sirl
