#include "results/results_file.h"

#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "results/dataset_store.h"
#include "results/durable.h"
#include "results/file_lock.h"
#include "results/isolated_read.h"

namespace sirl {

namespace fs = std::filesystem;

namespace {

using C = H5Table::Column;

double num_or(const TaskRecord& r, const char* k, double fallback) {
  auto it = r.num.find(k);
  return it == r.num.end() ? fallback : it->second;
}

double need_num(const TaskRecord& r, const char* k) {
  auto it = r.num.find(k);
  if (it == r.num.end()) throw H5Error("task " + r.key + ": its record has no number '" + k + "'");
  return it->second;
}
const std::string& need_text(const TaskRecord& r, const char* k) {
  auto it = r.text.find(k);
  if (it == r.text.end()) throw H5Error("task " + r.key + ": its record has no text '" + k + "'");
  return it->second;
}

H5Table cell_table(const std::vector<TaskRecord>& records, const CellTableSpec& spec) {
  H5Table t;
  for (const auto& c : spec.columns) t.add(c.name, c.type);
  for (const auto& r : records) {
    if (r.kind != spec.kind &&
        std::find(spec.more_kinds.begin(), spec.more_kinds.end(), r.kind) == spec.more_kinds.end())
      continue;
    const int64_t rows = spec.rows_key ? int64_t(need_num(r, spec.rows_key)) : 1;
    for (int64_t i = 0; i < rows; ++i)
      for (size_t k = 0; k < spec.columns.size(); ++k) {
        const TableColumn& c = spec.columns[k];
        std::string key = c.key;
        if (spec.rows_key)
          if (std::string own = key + "/" + std::to_string(i);
              r.text.count(own) || r.num.count(own))
            key = std::move(own);
        if (c.optional && !r.text.count(key) && !r.num.count(key)) {
          if (c.type == C::String)
            t.columns[k].strings.push_back(c.absent);
          else if (c.type == C::Int)
            t.columns[k].ints.push_back(0);
          else
            t.columns[k].doubles.push_back(0);
        } else if (c.type == C::String) {
          t.columns[k].strings.push_back(need_text(r, key.c_str()));
        } else if (c.type == C::Int) {
          t.columns[k].ints.push_back(int64_t(need_num(r, key.c_str())));
        } else {
          t.columns[k].doubles.push_back(need_num(r, key.c_str()));
        }
      }
  }
  return t;
}

// The last finite value of a curve row (a reward head that stopped early has NaN after its
// stop; tpa.stop), or NaN when it has none.
double last_finite(const float* row, int64_t n) {
  for (int64_t i = n - 1; i >= 0; --i)
    if (row[i] == row[i]) return row[i];
  return std::numeric_limits<double>::quiet_NaN();
}

// The final loss and epoch count of a record's curve: loss_curves is [heads, epochs] (the mean of
// the heads' last trained epochs), loss_curve [epochs].
std::pair<int64_t, double> final_loss_of(const TaskRecord& r) {
  const TaskRecord::Array* curve = nullptr;
  for (const char* c : {"loss_curve", "loss_curves"})
    if (auto it = r.arrays.find(c); it != r.arrays.end()) curve = &it->second;
  if (!curve || curve->data.empty()) return {0, 0.0};
  const uint64_t rows = curve->dims.size() == 2 ? curve->dims[0] : 1;
  const int64_t E = int64_t(curve->data.size() / rows);
  double last = 0;
  for (uint64_t k = 0; k < rows; ++k)
    last += last_finite(curve->data.data() + k * E, E) / double(rows);
  return {E, last};
}

// The cell fields a per-training table carries beside each row's own values, written from the
// record (never from its key): the method, its VAE pre-training and query selection, and whether
// a TPA cell is in the paper's best mode (Fig. 5: SIRL frozen, every other method unfrozen; 0 for
// a training that is not a TPA cell).
struct CellFieldColumns {
  H5Table::Column *method, *vae, *selection, *best_mode, *hyper_point;
  explicit CellFieldColumns(H5Table& t)
      : method(&t.add("method", C::String)),
        vae(&t.add("vae", C::Int)),
        selection(&t.add("selection", C::String)),
        best_mode(&t.add("best_mode", C::Int)),
        hyper_point(&t.add("hyper_point", C::String)) {}
  void push(const TaskRecord& r) {
    auto m = r.text.find("method"), s = r.text.find("selection"), h = r.text.find("hyper_point");
    hyper_point->strings.push_back(h != r.text.end() ? h->second : "");  // "" = the base point
    method->strings.push_back(m != r.text.end() ? m->second : "");
    vae->ints.push_back(int64_t(num_or(r, "vae", 0)));
    selection->strings.push_back(s != r.text.end() ? s->second : "uniform");
    best_mode->ints.push_back(int64_t(num_or(r, "best_mode", 0)));
  }
};

// One row per TPA reward head (every TPA record, of the main grid or [robustness]): its held-out
// and training accuracy, the epochs it trained and whether it stopped before the schedule's end by
// the stopping rule (tpa.stop = "converged"; `stop` names the cell's rule), its final loss and how
// far its copy of φ moved (0 when frozen).
H5Table tpa_heads_table(const std::vector<TaskRecord>& records) {
  H5Table t;
  auto &key = t.add("key", C::String), &env = t.add("env", C::String),
       &variant = t.add("variant", C::String), &N = t.add("N", C::Int), &M = t.add("M", C::Int),
       &frozen = t.add("frozen", C::Int), &seed = t.add("seed", C::Int),
       &teacher = t.add("teacher", C::String), &head = t.add("head", C::Int),
       &acc = t.add("accuracy", C::Double), &train = t.add("train_accuracy", C::Double),
       &epochs = t.add("epochs", C::Int), &cap = t.add("max_epochs", C::Int),
       &stopped = t.add("stopped", C::Int), &stop = t.add("stop", C::String),
       &loss = t.add("final_loss", C::Double), &drift = t.add("phi_drift", C::Double);
  CellFieldColumns cell(t);
  for (const auto& r : records) {
    auto a = r.arrays.find("accuracy"), tr = r.arrays.find("train_accuracy"),
         lc = r.arrays.find("loss_curves");
    if (a == r.arrays.end() || tr == r.arrays.end() || lc == r.arrays.end() || !r.num.count("M"))
      continue;
    const size_t R = a->second.data.size();
    if (lc->second.dims.size() != 2 || lc->second.dims[0] != R || tr->second.data.size() != R)
      throw H5Error("task " + r.key + ": its per-head arrays disagree in size");
    const int64_t E = int64_t(lc->second.dims[1]);
    auto he = r.arrays.find("head_epochs"), pd = r.arrays.find("phi_drift");
    auto tt = r.text.find("teacher"), st = r.text.find("stop");
    for (size_t k = 0; k < R; ++k) {
      key.strings.push_back(r.key);
      env.strings.push_back(need_text(r, "env"));
      variant.strings.push_back(need_text(r, "variant"));
      N.ints.push_back(int64_t(num_or(r, "N", 0)));
      M.ints.push_back(int64_t(need_num(r, "M")));
      frozen.ints.push_back(int64_t(num_or(r, "frozen", 0)));
      seed.ints.push_back(int64_t(need_num(r, "seed")));
      teacher.strings.push_back(tt == r.text.end() ? "" : tt->second);
      head.ints.push_back(int64_t(k));
      acc.doubles.push_back(a->second.data[k]);
      train.doubles.push_back(tr->second.data[k]);
      const int64_t e = he != r.arrays.end() && he->second.data.size() == R
                            ? int64_t(he->second.data[k])
                            : E;  // records before the stopping rule trained every epoch
      epochs.ints.push_back(e);
      cap.ints.push_back(E);
      stopped.ints.push_back(e < E);
      stop.strings.push_back(st == r.text.end() ? "fixed" : st->second);
      loss.doubles.push_back(last_finite(lc->second.data.data() + k * size_t(E), E));
      drift.doubles.push_back(
          pd != r.arrays.end() && pd->second.data.size() == R ? double(pd->second.data[k]) : 0.0);
      cell.push(r);
    }
  }
  return t;
}

// Every training's convergence (engine/convergence.h) and its final loss; dead_fraction is the
// share of φ's last hidden layer that is 0 on all of Ξ (−1 where not measured); teacher is ""
// for the main teacher, a noisy teacher's tag for robustness cells. Columns a kind
// does not have (N, M, frozen of a VAE) are 0.
H5Table training_table(const std::vector<TaskRecord>& records) {
  H5Table t;
  auto &kind = t.add("kind", C::String), &key = t.add("key", C::String),
       &env = t.add("env", C::String), &variant = t.add("variant", C::String),
       &N = t.add("N", C::Int), &M = t.add("M", C::Int), &frozen = t.add("frozen", C::Int),
       &seed = t.add("seed", C::Int), &epochs = t.add("epochs", C::Int),
       &final_loss = t.add("final_loss", C::Double),
       &rel = t.add("loss_relative_change", C::Double), &conv = t.add("converged", C::Int),
       &frac = t.add("converged_fraction", C::Double), &dead = t.add("dead_fraction", C::Double),
       &teacher = t.add("teacher", C::String);
  CellFieldColumns cell(t);
  for (const auto& r : records) {
    if (!r.num.count("converged")) continue;  // FPE, Random and the VAE method train nothing
    const auto [E, last] = final_loss_of(r);
    kind.strings.push_back(r.kind);
    key.strings.push_back(r.key);
    env.strings.push_back(need_text(r, "env"));
    variant.strings.push_back(need_text(r, "variant"));
    N.ints.push_back(int64_t(num_or(r, "N", 0)));
    M.ints.push_back(int64_t(num_or(r, "M", 0)));
    frozen.ints.push_back(int64_t(num_or(r, "frozen", 0)));
    seed.ints.push_back(int64_t(need_num(r, "seed")));
    epochs.ints.push_back(E);
    final_loss.doubles.push_back(last);
    rel.doubles.push_back(need_num(r, "loss_relative_change"));
    conv.ints.push_back(int64_t(need_num(r, "converged")));
    frac.doubles.push_back(num_or(r, "converged_fraction", need_num(r, "converged")));
    auto df = r.arrays.find("dead_fraction");
    dead.doubles.push_back(df != r.arrays.end() && !df->second.data.empty() ? df->second.data.back()
                                                                            : -1.0);
    auto tt = r.text.find("teacher");  // "" = the main teacher ([robustness] cells name theirs)
    teacher.strings.push_back(tt == r.text.end() ? "" : tt->second);
    cell.push(r);
  }
  return t;
}

// The VAE's posterior per latent dimension: KL ≈ 0 nats means the dimension carries no
// information about the trajectory (posterior collapse).
H5Table vae_latents_table(const std::vector<TaskRecord>& records) {
  H5Table t;
  auto &env = t.add("env", C::String), &seed = t.add("seed", C::Int),
       &elbo = t.add("elbo", C::String), &dim = t.add("dim", C::Int), &kl = t.add("kl", C::Double),
       &mse = t.add("reconstruction_mse", C::Double);
  for (const auto& r : records) {
    auto it = r.arrays.find("kl_per_dim");  // a VAE's record
    if (it == r.arrays.end()) continue;
    for (size_t k = 0; k < it->second.data.size(); ++k) {
      env.strings.push_back(need_text(r, "env"));
      seed.ints.push_back(int64_t(need_num(r, "seed")));
      elbo.strings.push_back(need_text(r, "elbo"));
      dim.ints.push_back(int64_t(k));
      kl.doubles.push_back(it->second.data[k]);
      mse.doubles.push_back(need_num(r, "reconstruction_mse"));
    }
  }
  return t;
}

// precision: "bf16" for a task whose matrix products ran in bf16 (its record's bf16_products),
// else "fp32". compute_roof_gflops: the roof of that precision's unit on the cores it ran on
// (`threads`, 1 unless the scheduler gave it more): the bf16 roof where the run measured one, else
// the fp32 roof (emulated bf16 products are fp32 arithmetic). roof_percent: its GFLOP/s as a share
// of that roof; 0 when the roof is unknown (engines before 0.3.0).
// memory_roof_gflops: for a task that streams its weights and Adam state from main memory (the
// cost model's stream_bytes), its FLOPs per byte × the measured bandwidth × its cores; 0 for a
// task that works in cache. attainable_percent: its GFLOP/s as a share of the lower of the two
// roofs, the relevant one (= roof_percent when it does not stream).
H5Table timings_table(const std::vector<TaskRecord>& records, const Roofs& roofs) {
  H5Table t;
  auto &kind = t.add("kind", C::String), &key = t.add("key", C::String),
       &sec = t.add("seconds", C::Double), &fl = t.add("flops", C::Double),
       &gf = t.add("gflops", C::Double), &pct = t.add("roof_percent", C::Double),
       &th = t.add("threads", C::Int), &mem = t.add("memory_roof_gflops", C::Double),
       &att = t.add("attainable_percent", C::Double), &prec = t.add("precision", C::String),
       &croof = t.add("compute_roof_gflops", C::Double), &pfl = t.add("protocol_flops", C::Double);
  // The task's cell, from its record ("" and -1 where a kind has no such field).
  auto &env = t.add("env", C::String), &seed = t.add("seed", C::Int),
       &teacher = t.add("teacher", C::String), &variant = t.add("variant", C::String);
  // Which CPU class computed it (a reused result may come from another class) and its content
  // digest (experiment/task_digest.h); "" in files of engines before 0.10.0.
  auto &cls = t.add("cpu_class", C::String), &digest = t.add("task_digest", C::String);
  CellFieldColumns cell(t);
  auto text_or = [](const TaskRecord& r, const char* k) {
    auto it = r.text.find(k);
    return it == r.text.end() ? std::string() : it->second;
  };
  for (const auto& r : records) {
    env.strings.push_back(text_or(r, "env"));
    seed.ints.push_back(int64_t(num_or(r, "seed", -1)));
    teacher.strings.push_back(text_or(r, "teacher"));
    variant.strings.push_back(text_or(r, "variant"));
    cls.strings.push_back(text_or(r, "cpu_class"));
    digest.strings.push_back(text_or(r, "task_digest"));
    cell.push(r);
    kind.strings.push_back(r.kind);
    key.strings.push_back(r.key);
    const double s = num_or(r, "seconds", 0), f = num_or(r, "flops", 0);
    sec.doubles.push_back(s);
    fl.doubles.push_back(f);
    // What the protocol's full schedule would have cost (≠ flops where training stopped early).
    pfl.doubles.push_back(num_or(r, "protocol_flops", f));
    gf.doubles.push_back(s > 0 ? f / s * 1e-9 : 0.0);
    const double cores = std::max(1.0, num_or(r, "threads", 1));
    th.ints.push_back(int64_t(cores));
    const bool bf16 = num_or(r, "bf16_products", 0) != 0;
    prec.strings.push_back(bf16 ? "bf16" : "fp32");
    const double compute_roof =
        (bf16 && roofs.bf16_gflops > 0 ? roofs.bf16_gflops : roofs.fp32_gflops) * cores;
    croof.doubles.push_back(compute_roof);
    pct.doubles.push_back(compute_roof > 0 ? 100 * gf.doubles.back() / compute_roof : 0.0);
    const double bytes = num_or(r, "stream_bytes", 0);
    const double mem_roof =
        bytes > 0 && roofs.stream_gbs > 0 ? f / bytes * roofs.stream_gbs * cores : 0.0;
    mem.doubles.push_back(mem_roof);
    double roof = compute_roof;
    if (mem_roof > 0 && (roof <= 0 || mem_roof < roof)) roof = mem_roof;
    att.doubles.push_back(roof > 0 ? 100 * gf.doubles.back() / roof : 0.0);
  }
  return t;
}

}  // namespace

const H5Table& ResultTables::at(const std::string& name) const {
  for (const auto& t : tables)
    if (t.name == name) return t.table;
  throw std::out_of_range("no table '" + name + "'");
}

ResultTables build_tables(const std::vector<TaskRecord>& records,
                          const std::vector<CellTableSpec>& cells, const Roofs& roofs) {
  ResultTables t;
  for (const auto& spec : cells) t.tables.push_back({spec.name, cell_table(records, spec)});
  t.tables.push_back({"timings", timings_table(records, roofs)});
  t.tables.push_back({"training", training_table(records)});
  t.tables.push_back({"vae_latents", vae_latents_table(records)});
  t.tables.push_back({"tpa_heads", tpa_heads_table(records)});
  return t;
}

namespace {

// Every results file from engine 0.8.0 on starts with a userblock HDF5 leaves alone, holding the
// file's own digest, so a copied .h5 verifies without its .sum (files of older engines start with
// HDF5's signature and are verified by their .sum alone):
//   "SIRLRESULTS2\nxxh3-128 " <file_digest of bytes [kResultsFrameBytes, end)> "\n" NUL…
constexpr uint64_t kResultsFrameBytes = 1024;
constexpr std::string_view kResultsMagic = "SIRLRESULTS2\nxxh3-128 ";

std::string results_frame(const std::string& digest) {
  std::string head = std::string(kResultsMagic) + digest + "\n";
  head.resize(kResultsFrameBytes, '\0');
  return head;
}

std::string digest_of(const std::string& path, uint64_t offset = 0) {
  try {
    return file_digest(path, offset);
  } catch (const std::runtime_error& e) {
    throw H5Error(e.what());
  }
}

// A finished, framed `partial` made the file at `path`: fsynced, renamed over it, the folder
// fsynced, its .sum rewritten. The old checksum goes first: a crash from here on leaves a file
// without one (read as unverified), never a file with another file's checksum.
void move_into_place(const std::string& partial, const std::string& path);

void write_frame(const std::string& path) {
  try {
    overwrite_head(path, results_frame(digest_of(path, kResultsFrameBytes)));
  } catch (const std::runtime_error& e) {
    throw H5Error(e.what());
  }
}

void move_into_place(const std::string& partial, const std::string& path) {
  fsync_path(partial);
  std::error_code ec;
  fs::remove(path + ".sum", ec);
  fs::rename(partial, path, ec);
  if (ec) throw H5Error(path + ": cannot move the finished file into place: " + ec.message());
  fsync_path(fs::path(path).parent_path().empty() ? "." : fs::path(path).parent_path().string());
  write_checksum(path);
}

}  // namespace

void write_results_file(const std::string& path, const RunInfo& info,
                        const std::vector<RunDataset>& datasets,
                        const std::vector<TaskRecord>& records, const ResultTables& tables) {
  const std::string partial = path + ".partial";
  try {
    {
      H5File f = H5File::create(partial, kResultsFrameBytes);
      f.set_compression(true);  // regenerable datasets, embeddings and curves: shuffle + deflate
      f.set_attr("/", "schema_version", kResultsSchemaVersion);
      f.set_attr("/", "profile_name", info.profile_name);
      f.set_attr("/", "profile_text", info.profile_text);
      f.set_attr("/", "engine_version", info.engine_version);
      if (!info.hyper_points.empty()) f.set_attr("/", "hyper_points", info.hyper_points);
      if (!info.missing_tasks.empty()) f.set_attr("/", "missing_tasks", info.missing_tasks);
      if (!info.unverified_inputs.empty())
        f.set_attr("/", "unverified_inputs", info.unverified_inputs);
      f.set_attr("/", "git_commit", info.git_commit);
      f.set_attr("/", "host", info.host);
      f.set_attr("/", "cpu_class", info.cpu_class);
      f.set_attr("/", "libraries", info.libraries);
      f.set_attr("/", "kernel_paths", info.kernel_paths);
      f.set_attr("/", "roof_fp32_gflops_per_core", info.roof_fp32_gflops);
      if (info.roof_bf16_gflops > 0)  // a bf16 run on a CPU with a bf16 unit
        f.set_attr("/", "roof_bf16_gflops_per_core", info.roof_bf16_gflops);
      f.set_attr("/", "stream_gbs_per_core", info.stream_gbs);
      f.set_attr("/", "started", info.started);
      f.set_attr("/", "finished", info.finished);
      f.set_attr("/", "shard", info.shard);
      f.set_attr("/", "threads", info.threads);
      f.set_attr("/", "tasks_total", info.tasks_total);
      f.set_attr("/", "tasks_done", info.tasks_done);
      f.set_attr("/", "wall_seconds", info.wall_seconds);
      f.set_attr("/", "complete", int64_t(info.complete));
      for (const auto& d : datasets) write_dataset(f, *d.dataset, *d.bundle, info.engine_version);
      std::vector<std::string> keys;
      for (const auto& r : records) {
        write_record(f, "/runs/" + r.key, r);
        keys.push_back(r.key);
      }
      f.write_strings("/runs_index", keys);
      for (const auto& t : tables.tables) f.write_table("/tables/" + t.name, t.table);
      for (const MethodAttributes& m : tables.methods) {
        const std::string g = "/methods/" + m.name;
        f.group(g);
        for (const auto& [k, v] : m.text) f.set_attr(g, k, v);
        for (const auto& [k, v] : m.integers) f.set_attr(g, k, v);
      }
      f.flush();  // a full disk shows here, not silently in the destructor
    }
    write_frame(partial);
  } catch (const std::exception& e) {
    // Nothing half-written stays behind (a full disk would keep failing on a stale .partial).
    std::error_code ec;
    fs::remove(partial, ec);
    throw H5Error(path + ": the results file could not be written: " + e.what());
  }
  move_into_place(partial, path);
}

// The sidecar FILE.sum: the whole file's digest, in the format `xxh128sum -c` checks.
void write_checksum(const std::string& path) {
  const std::string tmp = path + ".sum.tmp";
  try {
    refuse_symlink(tmp);
  } catch (const std::runtime_error& e) {
    throw H5Error(e.what());
  }
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << digest_of(path) << "  " << fs::path(path).filename().string() << "\n";
    if (!out) throw H5Error(tmp + ": cannot write the checksum");
  }
  fsync_path(tmp);
  std::error_code ec;
  fs::rename(tmp, path + ".sum", ec);
  if (ec) throw H5Error(path + ".sum: cannot write the checksum: " + ec.message());
}

bool verify_checksum(const std::string& path, bool* is_framed) {
  auto mismatch = [&](const std::string& what, const std::string& got, const std::string& want) {
    return H5Error(path + ": " + what + " mismatch (" + got + ", recorded " + want +
                   "): the file changed after it was written (corrupted?); restore it, or rerun "
                   "with --force to recompute");
  };
  constexpr std::string_view kHdf5Signature = "\x89HDF\r\n\x1a\n";
  std::string head(kResultsFrameBytes + kHdf5Signature.size(), '\0');
  {
    // Opening a FIFO would block until a writer comes: only a regular file is read.
    std::error_code ec;
    if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
      throw H5Error(path + ": not a regular file (a pipe, socket, device or folder)");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw H5Error(path + ": cannot read");
    in.read(head.data(), std::streamsize(head.size()));
    head.resize(size_t(in.gcount()));
  }
  // Only a file starting with HDF5's own signature is an older engine's unframed file: a file
  // whose first bytes are neither that nor the frame (one flipped bit in "SIRLRESULTS") is a
  // damaged frame, never a reason to stop checking (HDF5 would still find its superblock at 1024).
  const bool framed = !head.starts_with(kHdf5Signature);
  const bool hdf5_after_frame = head.size() > kResultsFrameBytes &&
                                head.substr(kResultsFrameBytes).starts_with(kHdf5Signature);
  if (framed && !hdf5_after_frame && !head.starts_with("SIRLRESULTS"))
    throw H5Error(path + ": not an HDF5 file (neither a sirl results file nor a dataset file)");
  head.resize(std::min<size_t>(head.size(), kResultsFrameBytes));
  if (is_framed) *is_framed = framed;
  if (framed) {
    const size_t d = kResultsMagic.size();
    const std::string want = head.size() > d + 32 ? head.substr(d, 32) : "";
    if (!head.starts_with(kResultsMagic) || head.size() != kResultsFrameBytes ||
        results_frame(want) != head)
      throw H5Error(path + ": its checksum frame (the first " + std::to_string(kResultsFrameBytes) +
                    " bytes) is damaged (corrupted or truncated), or it is not a sirl results "
                    "file; restore it, or rerun with --force to recompute");
    const std::string got = digest_of(path, kResultsFrameBytes);
    if (got != want) throw mismatch("checksum", got, want);
  }
  // A .sum that is not a regular file (a FIFO would block the open forever) is no checksum.
  std::error_code sum_ec;
  if (std::filesystem::exists(path + ".sum", sum_ec) &&
      !std::filesystem::is_regular_file(path + ".sum", sum_ec))
    throw H5Error(path + ".sum: not a regular file (a pipe, socket, device or folder)");
  std::ifstream sum(path + ".sum");
  if (!sum) return framed;  // a file of engine ≤ 0.7.0 without its .sum cannot be verified
  std::string want;
  sum >> want;
  if (want.size() == 32) {
    const std::string got = digest_of(path);
    if (got != want) throw mismatch(".sum checksum", got, want);
  } else if (want.size() == 16) {  // engines up to 0.7.0
    std::string got;
    try {
      got = hex64(file_checksum(path));
    } catch (const std::runtime_error& e) {
      throw H5Error(e.what());
    }
    if (got != want) throw mismatch(".sum checksum", got, want);
  } else {
    throw H5Error(path + ".sum: not a checksum file");
  }
  return true;
}

std::string unverified_note(const std::string& path) {
  return "warning: " + path + " cannot be verified: it carries no checksum (a file of engine " +
         "0.7.0 or older, without its .sum beside it); its numbers are read as they are";
}

int64_t check_results_schema(const H5File& f) {
  const int64_t v = f.has_attr("/", "schema_version") ? f.attr_int("/", "schema_version") : 1;
  if (v < 1 || v > kResultsSchemaVersion)
    throw H5Error(f.path() + ": results schema version " + std::to_string(v) +
                  ", but this engine reads versions 1 to " + std::to_string(kResultsSchemaVersion) +
                  " (written by engine " +
                  (f.has_attr("/", "engine_version") ? f.attr_string("/", "engine_version")
                                                     : std::string("unknown")) +
                  "; use that engine, or a newer one)");
  return v;
}

namespace {
// Engines from 0.8.0 on (schema 3) frame every results file they write: one of theirs without a
// frame was rewritten (h5repack, h5py) or had its frame cut off, and nothing covers what it holds.
void refuse_unframed(const std::string& path, bool framed, int64_t schema_version) {
  if (!framed && schema_version >= 3)
    throw H5Error(
        path + ": a schema-" + std::to_string(schema_version) +
        " results file (engines from 0.8.0 frame every file they write) without its "
        "checksum frame: it was rewritten (h5repack, h5py) or its first 1024 bytes were "
        "cut off, so nothing vouches for its values; use the file as the engine wrote it");
}

RunInfo read_run_info_unsandboxed(const std::string& path, bool verified, bool framed) {
  H5File f = H5File::open_read(path);
  RunInfo i;
  i.verified = verified;
  i.schema_version = check_results_schema(f);
  i.profile_name = f.attr_string("/", "profile_name");
  i.profile_text = f.attr_string("/", "profile_text");
  i.engine_version = f.attr_string("/", "engine_version");
  i.git_commit = f.attr_string("/", "git_commit");
  i.host = f.attr_string("/", "host");
  if (f.has_attr("/", "cpu_class")) i.cpu_class = f.attr_string("/", "cpu_class");
  if (f.has_attr("/", "libraries")) i.libraries = f.attr_string("/", "libraries");
  if (f.has_attr("/", "kernel_paths")) i.kernel_paths = f.attr_string("/", "kernel_paths");
  if (f.has_attr("/", "hyper_points")) i.hyper_points = f.attr_string("/", "hyper_points");
  if (f.has_attr("/", "missing_tasks")) i.missing_tasks = f.attr_string("/", "missing_tasks");
  if (f.has_attr("/", "unverified_inputs"))
    i.unverified_inputs = f.attr_string("/", "unverified_inputs");
  if (f.has_attr("/", "roof_fp32_gflops_per_core"))
    i.roof_fp32_gflops = f.attr_double("/", "roof_fp32_gflops_per_core");
  if (f.has_attr("/", "roof_bf16_gflops_per_core"))
    i.roof_bf16_gflops = f.attr_double("/", "roof_bf16_gflops_per_core");
  if (f.has_attr("/", "stream_gbs_per_core"))
    i.stream_gbs = f.attr_double("/", "stream_gbs_per_core");
  i.started = f.attr_string("/", "started");
  i.finished = f.attr_string("/", "finished");
  i.shard = f.attr_string("/", "shard");
  i.threads = f.attr_int("/", "threads");
  i.tasks_total = f.attr_int("/", "tasks_total");
  i.tasks_done = f.attr_int("/", "tasks_done");
  i.wall_seconds = f.attr_double("/", "wall_seconds");
  i.complete = f.attr_int("/", "complete") != 0;
  refuse_unframed(path, framed, i.schema_version);
  return i;
}

std::map<std::string, int64_t> read_kinds_unsandboxed(const std::string& path) {
  H5File f = H5File::open_read(path);
  std::map<std::string, int64_t> kinds;
  for (const auto& k : f.read_strings("/runs_index"))
    ++kinds[f.attr_string("/runs/" + k, "task_kind")];
  return kinds;
}

std::vector<TaskRecord> read_records_unsandboxed(const std::string& path, bool framed) {
  H5File f = H5File::open_read(path);
  refuse_unframed(path, framed, check_results_schema(f));
  std::vector<TaskRecord> out;
  for (const auto& k : f.read_strings("/runs_index")) out.push_back(read_record(f, "/runs/" + k));
  return out;
}
}  // namespace

RunInfo read_run_info(const std::string& path) {
  bool framed = false;
  const bool verified = verify_checksum(path, &framed);
  read_in_child_first(path, [&] { read_run_info_unsandboxed(path, verified, framed); });
  return read_run_info_unsandboxed(path, verified, framed);
}

ResultsSummary read_results_summary(const std::string& path) {
  bool framed = false;
  const bool verified = verify_checksum(path, &framed);
  const auto read = [&] {
    ResultsSummary s{read_run_info_unsandboxed(path, verified, framed), {}, {}};
    s.records_by_kind = read_kinds_unsandboxed(path);
    const H5File f = H5File::open_read(path);
    if (f.exists("/verdicts") && f.has_attr("/verdicts", "claims"))
      s.verdicts = f.attr_string("/verdicts", "claims");
    return s;
  };
  read_in_child_first(path, [&] { read(); });
  return read();
}

namespace {
std::string utc_now_iso() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}
}  // namespace

void store_verdicts(const std::string& path, const std::string& claims_json,
                    const std::string& writer) {
  const FileLock lock(path, "sirl reproduce (storing verdicts)",
                      "wait for it to finish, or choose another --out");
  const std::string partial = path + ".partial";
  try {
    refuse_symlink(partial);
    if (!fs::is_regular_file(path)) throw H5Error(path + ": not a regular file");
    fs::copy_file(path, partial, fs::copy_options::overwrite_existing);
    // The copy is what gets a new digest, so the copy is what must verify by its own frame (a
    // .sum beside the original could vouch for bytes that changed since).
    bool framed = false;
    verify_checksum(partial, &framed);
    if (!framed)
      throw H5Error(path +
                    ": no checksum frame (an engine before 0.8.0 wrote it, or it was "
                    "altered): verdicts are stored only in a file whose digest verifies");
    read_in_child_first(partial, [&] { read_run_info_unsandboxed(partial, true, true); });
    {
      H5File f = H5File::open_rw(partial);
      if (!f.exists("/verdicts")) f.group("/verdicts");
      f.set_attr("/verdicts", "claims", claims_json);
      f.set_attr("/verdicts", "written", utc_now_iso());
      f.set_attr("/verdicts", "writer", writer);
      f.flush();
    }
    write_frame(partial);
  } catch (const std::exception& e) {
    std::error_code ec;
    fs::remove(partial, ec);
    throw H5Error(path + ": the verdicts could not be stored: " + e.what());
  }
  move_into_place(partial, path);
}

std::vector<TaskRecord> read_results_records(const std::string& path) {
  bool framed = false;
  verify_checksum(path, &framed);
  read_in_child_first(path, [&] { read_records_unsandboxed(path, framed); });
  return read_records_unsandboxed(path, framed);
}

void export_csv(const ResultTables& t, const std::string& dir) {
  // Every CSV is written in full into a folder of our own inside `dir` first, then each is renamed
  // into place (renames need no space): a full disk leaves the old CSVs as they were, never a
  // truncated one beside new ones. Other files in `dir` are left alone.
  // Named by our pid: two exports into one folder never share (or delete) each other's staging.
  const fs::path staging =
      fs::path(dir) / (".sirl-export." + std::to_string(::getpid()) + ".partial");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw H5Error(dir + ": cannot create the folder: " + ec.message());
  refuse_symlink(staging.string());
  fs::remove_all(staging, ec);
  fs::create_directory(staging, ec);
  if (ec) throw H5Error(staging.string() + ": cannot create: " + ec.message());
  auto write = [&](const H5Table& tab, const std::string& name) {
    const fs::path p = staging / (name + ".csv");
    std::FILE* out = std::fopen(p.c_str(), "w");
    if (!out) throw H5Error(p.string() + ": cannot write: " + std::strerror(errno));
    std::string line;
    char num[32];
    auto put = [&](const std::string& s) {
      if (std::fwrite(s.data(), 1, s.size(), out) != s.size()) {
        const int err = errno;
        std::fclose(out);
        throw H5Error((fs::path(dir) / (name + ".csv")).string() +
                      ": cannot write: " + std::strerror(err));
      }
    };
    for (size_t k = 0; k < tab.columns.size(); ++k) line += (k ? "," : "") + tab.columns[k].name;
    put(line + "\n");
    // A value the cell does not have is an empty field (what pandas, R and spreadsheets read as
    // missing), as the Python reader makes it <NA>: N and M of 0 (a method without queries, an
    // FPE cell without M), a seed of -1 (a task with no seed), `frozen` where there is no M, and
    // NaN.
    const H5Table::Column* m_col = nullptr;
    for (const auto& c : tab.columns)
      if (c.name == "M") m_col = &c;
    const auto number = [](const H5Table::Column& c, size_t r) {
      return c.type == H5Table::Column::Int ? double(c.ints[r]) : c.doubles[r];
    };
    const auto missing = [&](const H5Table::Column& c, size_t r) {
      if (c.type == H5Table::Column::String) return false;
      const double v = number(c, r);
      if (std::isnan(v)) return true;
      if (c.name == "N" || c.name == "M") return v == 0;
      if (c.name == "seed") return v < 0;
      if (c.name == "frozen" && m_col && m_col->type != H5Table::Column::String)
        return number(*m_col, r) == 0;
      return false;
    };
    for (size_t r = 0; r < tab.rows(); ++r) {
      line.clear();
      for (size_t k = 0; k < tab.columns.size(); ++k) {
        const auto& c = tab.columns[k];
        if (k) line += ',';
        if (missing(c, r)) {
          continue;
        } else if (c.type == H5Table::Column::Int) {
          line += std::to_string(c.ints[r]);
        } else if (c.type == H5Table::Column::Double) {
          std::snprintf(num, sizeof num, "%.17g", c.doubles[r]);
          line += num;
        } else {
          // RFC 4180: a field with a comma, quote or line break (a CPU class) is quoted, its
          // quotes doubled.
          const std::string& v = c.strings[r];
          if (v.find_first_of(",\"\r\n") == std::string::npos) {
            line += v;
          } else {
            line += '"';
            for (char ch : v) line += ch == '"' ? std::string("\"\"") : std::string(1, ch);
            line += '"';
          }
        }
      }
      put(line + "\n");
    }
    if (std::fflush(out) != 0 || ::fsync(::fileno(out)) != 0) {
      const int err = errno;
      std::fclose(out);
      throw H5Error((fs::path(dir) / (name + ".csv")).string() +
                    ": cannot write: " + std::strerror(err));
    }
    if (std::fclose(out) != 0)
      throw H5Error((fs::path(dir) / (name + ".csv")).string() +
                    ": cannot write: " + std::strerror(errno));
  };
  try {
    for (const auto& tab : t.tables) write(tab.table, tab.name);
    for (const auto& tab : t.tables) {
      fs::rename(staging / (tab.name + ".csv"), fs::path(dir) / (tab.name + ".csv"), ec);
      if (ec) throw H5Error(dir + "/" + tab.name + ".csv: cannot move into place: " + ec.message());
    }
  } catch (...) {
    fs::remove_all(staging, ec);
    throw;
  }
  fs::remove_all(staging, ec);
  fsync_path(dir);
}

}  // namespace sirl
