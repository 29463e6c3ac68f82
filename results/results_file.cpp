#include "results/results_file.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "results/dataset_store.h"

namespace sirl {

namespace fs = std::filesystem;

ResultTables build_tables(const std::vector<TaskRecord>& records) {
  using C = H5Table::Column;
  ResultTables t;
  auto num = [](const TaskRecord& r, const char* k) {
    auto it = r.num.find(k);
    return it == r.num.end() ? 0.0 : it->second;
  };
  auto txt = [](const TaskRecord& r, const char* k) {
    auto it = r.text.find(k);
    return it == r.text.end() ? std::string() : it->second;
  };
  {
    auto &env = t.fpe.add("env", C::String), &method = t.fpe.add("method", C::String),
         &variant = t.fpe.add("variant", C::String), &vae = t.fpe.add("vae", C::Int),
         &N = t.fpe.add("N", C::Int), &seed = t.fpe.add("seed", C::Int),
         &fpe = t.fpe.add("fpe", C::Double), &tr = t.fpe.add("train_mse", C::Double);
    for (const auto& r : records) {
      if (r.kind != "fpe") continue;
      env.strings.push_back(txt(r, "env"));
      method.strings.push_back(txt(r, "method"));
      variant.strings.push_back(txt(r, "variant"));
      vae.ints.push_back(int64_t(num(r, "vae")));
      N.ints.push_back(int64_t(num(r, "N")));
      seed.ints.push_back(int64_t(num(r, "seed")));
      fpe.doubles.push_back(num(r, "fpe"));
      tr.doubles.push_back(num(r, "train_mse"));
    }
  }
  {
    auto &env = t.tpa.add("env", C::String), &method = t.tpa.add("method", C::String),
         &variant = t.tpa.add("variant", C::String), &vae = t.tpa.add("vae", C::Int),
         &frozen = t.tpa.add("frozen", C::Int), &N = t.tpa.add("N", C::Int),
         &M = t.tpa.add("M", C::Int), &seed = t.tpa.add("seed", C::Int),
         &tpa = t.tpa.add("tpa", C::Double), &sd = t.tpa.add("tpa_std", C::Double),
         &tr = t.tpa.add("tpa_train", C::Double), &in_main = t.tpa.add("in_main", C::Int),
         &in_ab = t.tpa.add("in_ablation", C::Int);
    for (const auto& r : records) {
      if (r.kind != "tpa") continue;
      env.strings.push_back(txt(r, "env"));
      method.strings.push_back(txt(r, "method"));
      variant.strings.push_back(txt(r, "variant"));
      vae.ints.push_back(int64_t(num(r, "vae")));
      frozen.ints.push_back(int64_t(num(r, "frozen")));
      N.ints.push_back(int64_t(num(r, "N")));
      M.ints.push_back(int64_t(num(r, "M")));
      seed.ints.push_back(int64_t(num(r, "seed")));
      tpa.doubles.push_back(num(r, "tpa"));
      sd.doubles.push_back(num(r, "tpa_std"));
      tr.doubles.push_back(num(r, "tpa_train"));
      in_main.ints.push_back(int64_t(num(r, "in_main")));
      in_ab.ints.push_back(int64_t(num(r, "in_ablation")));
    }
  }
  {
    // Every training's convergence (engine/convergence.h) and its final loss; dead_fraction is
    // the share of φ's last hidden layer that is 0 on all of Ξ (−1 where not measured).
    auto &kind = t.training.add("kind", C::String), &key = t.training.add("key", C::String),
         &env = t.training.add("env", C::String), &variant = t.training.add("variant", C::String),
         &N = t.training.add("N", C::Int), &M = t.training.add("M", C::Int),
         &frozen = t.training.add("frozen", C::Int), &seed = t.training.add("seed", C::Int),
         &epochs = t.training.add("epochs", C::Int),
         &final_loss = t.training.add("final_loss", C::Double),
         &rel = t.training.add("loss_relative_change", C::Double),
         &conv = t.training.add("converged", C::Int),
         &frac = t.training.add("converged_fraction", C::Double),
         &dead = t.training.add("dead_fraction", C::Double);
    for (const auto& r : records) {
      if (!r.num.count("converged")) continue;  // FPE, Random and the VAE method train nothing
      const TaskRecord::Array* curve = nullptr;
      for (const char* c : {"loss_curve", "loss_curves"})
        if (auto it = r.arrays.find(c); it != r.arrays.end()) curve = &it->second;
      int64_t E = 0;
      double last = 0;
      if (curve && !curve->data.empty()) {
        // loss_curves is [heads, epochs]: the mean of the heads' last epochs.
        const uint64_t rows = curve->dims.size() == 2 ? curve->dims[0] : 1;
        E = int64_t(curve->data.size() / rows);
        for (uint64_t k = 0; k < rows; ++k) last += curve->data[(k + 1) * E - 1] / double(rows);
      }
      kind.strings.push_back(r.kind);
      key.strings.push_back(r.key);
      env.strings.push_back(txt(r, "env"));
      variant.strings.push_back(r.kind == "vae" ? "vae" : txt(r, "variant"));
      N.ints.push_back(int64_t(num(r, "N")));
      M.ints.push_back(int64_t(num(r, "M")));
      frozen.ints.push_back(int64_t(num(r, "frozen")));
      seed.ints.push_back(int64_t(num(r, "seed")));
      epochs.ints.push_back(E);
      final_loss.doubles.push_back(last);
      rel.doubles.push_back(num(r, "loss_relative_change"));
      conv.ints.push_back(int64_t(num(r, "converged")));
      frac.doubles.push_back(r.num.count("converged_fraction") ? num(r, "converged_fraction")
                                                               : num(r, "converged"));
      auto df = r.arrays.find("dead_fraction");
      dead.doubles.push_back(
          df != r.arrays.end() && !df->second.data.empty() ? df->second.data.back() : -1.0);
    }
  }
  {
    // The VAE's posterior per latent dimension: KL ≈ 0 nats means the dimension carries no
    // information about the trajectory (posterior collapse).
    auto &env = t.vae_latents.add("env", C::String), &seed = t.vae_latents.add("seed", C::Int),
         &elbo = t.vae_latents.add("elbo", C::String), &dim = t.vae_latents.add("dim", C::Int),
         &kl = t.vae_latents.add("kl", C::Double),
         &mse = t.vae_latents.add("reconstruction_mse", C::Double);
    for (const auto& r : records) {
      if (r.kind != "vae") continue;
      auto it = r.arrays.find("kl_per_dim");
      if (it == r.arrays.end()) continue;
      for (size_t k = 0; k < it->second.data.size(); ++k) {
        env.strings.push_back(txt(r, "env"));
        seed.ints.push_back(int64_t(num(r, "seed")));
        elbo.strings.push_back(txt(r, "elbo"));
        dim.ints.push_back(int64_t(k));
        kl.doubles.push_back(it->second.data[k]);
        mse.doubles.push_back(num(r, "reconstruction_mse"));
      }
    }
  }
  {
    auto &kind = t.timings.add("kind", C::String), &key = t.timings.add("key", C::String),
         &sec = t.timings.add("seconds", C::Double), &fl = t.timings.add("flops", C::Double),
         &gf = t.timings.add("gflops", C::Double);
    for (const auto& r : records) {
      kind.strings.push_back(r.kind);
      key.strings.push_back(r.key);
      const double s = num(r, "seconds"), f = num(r, "flops");
      sec.doubles.push_back(s);
      fl.doubles.push_back(f);
      gf.doubles.push_back(s > 0 ? f / s * 1e-9 : 0.0);
    }
  }
  return t;
}

void write_results_file(const std::string& path, const RunInfo& info,
                        const std::vector<RunDataset>& datasets,
                        const std::vector<TaskRecord>& records) {
  const std::string partial = path + ".partial";
  {
    H5File f = H5File::create(partial);
    f.set_compression(true);  // regenerable datasets, embeddings and curves: shuffle + deflate
    f.set_attr("/", "schema_version", kResultsSchemaVersion);
    f.set_attr("/", "profile_name", info.profile_name);
    f.set_attr("/", "profile_text", info.profile_text);
    f.set_attr("/", "engine_version", info.engine_version);
    f.set_attr("/", "git_commit", info.git_commit);
    f.set_attr("/", "host", info.host);
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
    const ResultTables t = build_tables(records);
    f.write_table("/tables/fpe", t.fpe);
    f.write_table("/tables/tpa", t.tpa);
    f.write_table("/tables/timings", t.timings);
    f.write_table("/tables/training", t.training);
    f.write_table("/tables/vae_latents", t.vae_latents);
  }
  std::error_code ec;
  fs::rename(partial, path, ec);
  if (ec) throw H5Error(path + ": cannot move the finished file into place: " + ec.message());
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

RunInfo read_run_info(const std::string& path) {
  H5File f = H5File::open_read(path);
  RunInfo i;
  i.schema_version = check_results_schema(f);
  i.profile_name = f.attr_string("/", "profile_name");
  i.profile_text = f.attr_string("/", "profile_text");
  i.engine_version = f.attr_string("/", "engine_version");
  i.git_commit = f.attr_string("/", "git_commit");
  i.host = f.attr_string("/", "host");
  i.started = f.attr_string("/", "started");
  i.finished = f.attr_string("/", "finished");
  i.shard = f.attr_string("/", "shard");
  i.threads = f.attr_int("/", "threads");
  i.tasks_total = f.attr_int("/", "tasks_total");
  i.tasks_done = f.attr_int("/", "tasks_done");
  i.wall_seconds = f.attr_double("/", "wall_seconds");
  i.complete = f.attr_int("/", "complete") != 0;
  return i;
}

std::vector<TaskRecord> read_results_records(const std::string& path) {
  H5File f = H5File::open_read(path);
  check_results_schema(f);
  std::vector<TaskRecord> out;
  for (const auto& k : f.read_strings("/runs_index")) out.push_back(read_record(f, "/runs/" + k));
  return out;
}

void export_csv(const ResultTables& t, const std::string& dir) {
  fs::create_directories(dir);
  auto write = [&](const H5Table& tab, const char* name) {
    const fs::path p = fs::path(dir) / name;
    std::ofstream out(p);
    for (size_t k = 0; k < tab.columns.size(); ++k) out << (k ? "," : "") << tab.columns[k].name;
    out << "\n";
    out.precision(17);
    for (size_t r = 0; r < tab.rows(); ++r) {
      for (size_t k = 0; k < tab.columns.size(); ++k) {
        const auto& c = tab.columns[k];
        if (k) out << ",";
        if (c.type == H5Table::Column::Int)
          out << c.ints[r];
        else if (c.type == H5Table::Column::Double)
          out << c.doubles[r];
        else
          out << c.strings[r];  // keys and names never contain commas or quotes
      }
      out << "\n";
    }
    if (!out) throw H5Error(p.string() + ": cannot write");
  };
  write(t.fpe, "fpe.csv");
  write(t.tpa, "tpa.csv");
  write(t.timings, "timings.csv");
  write(t.training, "training.csv");
  write(t.vae_latents, "vae_latents.csv");
}

}  // namespace sirl
