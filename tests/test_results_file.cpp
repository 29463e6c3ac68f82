// results/results_file: the schema version. A file written by the previous engine (fixture
// tests/data/results_v1.h5, made by engine 0.1.0 from tests/data/results_v1.toml) stays readable;
// a file of a newer version is refused with one line naming both versions.
#include <gtest/gtest.h>

#include <limits>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <stdexcept>

#include "experiment/task_kinds.h"
#include "results/h5.h"
#include "results/results_file.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {

namespace fs = std::filesystem;

const std::string kFixture = std::string(SIRL_SOURCE_DIR) + "/tests/data/results_v1.h5";

// A copy of the fixture in this process's scratch directory (removed when the process ends).
std::string temp_copy(const std::string& name) {
  static const test::ScratchDir scratch("sirl_results_file");
  const fs::path p = scratch.path() / name;
  fs::copy_file(kFixture, p, fs::copy_options::overwrite_existing);
  return p.string();
}

TEST(ResultsFile, AVersionOneFileFromThePreviousEngineIsRead) {
  const RunInfo info = read_run_info(kFixture);
  EXPECT_EQ(info.schema_version, 1);
  EXPECT_EQ(info.profile_name, "fixture-v1");
  EXPECT_EQ(info.engine_version, "0.1.0");
  EXPECT_TRUE(info.complete);
  const auto records = read_results_records(kFixture);
  // The fixture's profile: 2 representations (sirl N50, random), 2 FPE cells, 1 TPA cell.
  std::multiset<std::string> kinds;
  for (const auto& r : records) kinds.insert(r.kind);
  EXPECT_EQ(kinds.count("rep"), 2u);
  EXPECT_EQ(kinds.count("fpe"), 2u);
  EXPECT_EQ(kinds.count("tpa"), 1u);
  const ResultTables t = result_tables(records);
  EXPECT_EQ(t.at("fpe").rows(), 2u);
  EXPECT_EQ(t.at("tpa").rows(), 1u);
}

TEST(ResultsFile, ANewerVersionIsRefusedNamingBothVersions) {
  const std::string p = temp_copy("future.h5");
  {
    H5File f = H5File::open_rw(p);
    f.set_attr("/", "schema_version", int64_t(99));
  }
  try {
    read_run_info(p);
    ADD_FAILURE() << "a version-99 file was read";
  } catch (const H5Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("results schema version 99"), std::string::npos) << m;
    EXPECT_NE(m.find("reads versions 1 to " + std::to_string(kResultsSchemaVersion)),
              std::string::npos)
        << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << "one line: " << m;
  }
  EXPECT_THROW(read_results_records(p), H5Error);
  fs::remove(p);
}

TEST(ResultsFile, TheCurrentEngineWritesItsVersionAndReadsItBack) {
  const std::string p = temp_copy("rewritten.h5");
  const RunInfo old = read_run_info(kFixture);
  const auto records = read_results_records(kFixture);
  write_results_file(p, old, {}, records, result_tables(records));
  {
    const H5File f = H5File::open_read(p);
    EXPECT_EQ(f.attr_int("/", "schema_version"), kResultsSchemaVersion);
  }
  const RunInfo back = read_run_info(p);
  EXPECT_EQ(back.schema_version, kResultsSchemaVersion);
  EXPECT_EQ(back.profile_name, old.profile_name);
  const auto again = read_results_records(p);
  ASSERT_EQ(again.size(), records.size());
  for (size_t i = 0; i < records.size(); ++i) {
    EXPECT_EQ(again[i].key, records[i].key);
    EXPECT_EQ(again[i].num, records[i].num);
  }
  fs::remove(p);
}

// A results file carries its checksum (in its first 1024 bytes, and FILE.sum beside it): one
// flipped byte anywhere, and reading it is one clear error before HDF5 parses anything (a flipped
// byte in a string heap used to crash the HDF5 library), with or without FILE.sum; a file of
// engine 0.1.0 (neither) is read unverified.
TEST(ResultsFile, AFlippedByteIsRefusedByTheChecksumBeforeHdf5ReadsIt) {
  const std::string p = temp_copy("checksummed.h5");
  const auto records = read_results_records(kFixture);
  write_results_file(p, read_run_info(kFixture), {}, records, result_tables(records));
  ASSERT_TRUE(fs::exists(p + ".sum"));
  EXPECT_NO_THROW(read_run_info(p));
  {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(fs::file_size(p) / 2));
    char c = 0;
    f.read(&c, 1);
    f.seekp(std::streamoff(fs::file_size(p) / 2));
    c = char(c ^ 0x10);
    f.write(&c, 1);
  }
  for (int k = 0; k < 2; ++k) {
    try {
      k == 0 ? (void)read_run_info(p) : (void)read_results_records(p);
      ADD_FAILURE() << "a corrupted file was read";
    } catch (const H5Error& e) {
      EXPECT_NE(std::string(e.what()).find("checksum mismatch"), std::string::npos) << e.what();
    }
  }
  // Without its .sum (a copied .h5) the digest inside the file refuses it just the same.
  fs::remove(p + ".sum");
  try {
    (void)read_run_info(p);
    ADD_FAILURE() << "a corrupted copy without its .sum was read";
  } catch (const H5Error& e) {
    EXPECT_NE(std::string(e.what()).find("checksum mismatch"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(kFixture + ".sum"));  // the v1 fixture has none and still reads
  EXPECT_NO_THROW(read_run_info(kFixture));
  fs::remove(p);
  fs::remove(p + ".sum");
}

// One flipped bit in the frame's magic ("SIRLRESULTS") must not make a file look like an older
// engine's unframed one, which is read unverified: only HDF5's own signature at byte 0 means that.
TEST(ResultsFile, AFlippedBitInTheFramesMagicIsRefusedNotReadUnverified) {
  const std::string p = temp_copy("magic.h5");
  const auto records = read_results_records(kFixture);
  write_results_file(p, read_run_info(kFixture), {}, records, result_tables(records));
  fs::remove(p + ".sum");  // a copied .h5: the frame is all that vouches for it
  for (std::streamoff at = 0; at < 11; ++at) {
    const auto flip = [&] {
      std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
      f.seekg(at);
      char c = 0;
      f.read(&c, 1);
      c = char(c ^ 0x01);
      f.seekp(at);
      f.write(&c, 1);
    };
    flip();
    try {
      (void)read_run_info(p);
      ADD_FAILURE() << "a file with byte " << at << " of its frame flipped was read";
    } catch (const H5Error& e) {
      EXPECT_NE(std::string(e.what()).find("checksum frame"), std::string::npos) << e.what();
    }
    EXPECT_THROW(read_results_records(p), H5Error) << "byte " << at;
    flip();  // restored: it reads again
    EXPECT_NO_THROW(read_run_info(p)) << "byte " << at;
  }
  fs::remove(p);
}

// The report's verdicts kept in the file: stored, read back by the summary, replaced by a second
// store, the file still verifying by its frame and its .sum; a file that does not verify (one
// flipped byte) or has no frame (engine 0.1.0's) is refused and left byte for byte as it was.
TEST(ResultsFile, VerdictsAreStoredInAVerifiedFileAndNeverLaunderAnUnverifiedOne) {
  const std::string p = temp_copy("verdicts.h5");
  const auto records = read_results_records(kFixture);
  write_results_file(p, read_run_info(kFixture), {}, records, result_tables(records));
  EXPECT_EQ(read_results_summary(p).verdicts, "");
  const std::string first = R"([{"env":"grid","claim":"H1","verdict":"held"}])";
  store_verdicts(p, first, "test");
  EXPECT_EQ(read_results_summary(p).verdicts, first);
  EXPECT_TRUE(verify_checksum(p));
  EXPECT_EQ(read_results_records(p).size(), records.size());
  const std::string second = R"([{"env":"grid","claim":"H1","verdict":"not held"}])";
  store_verdicts(p, second, "test");
  EXPECT_EQ(read_results_summary(p).verdicts, second);
  fs::remove(p + ".sum");
  EXPECT_TRUE(verify_checksum(p)) << "the frame alone vouches for the rewritten file";
  EXPECT_FALSE(fs::exists(p + ".partial"));

  const auto bytes = [](const std::string& f) {
    std::ifstream in(f, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(fs::file_size(p) / 2));
    char c = 0;
    f.read(&c, 1);
    f.seekp(std::streamoff(fs::file_size(p) / 2));
    c = char(c ^ 0x04);
    f.write(&c, 1);
  }
  const std::string corrupted = bytes(p);
  EXPECT_THROW(store_verdicts(p, first, "test"), H5Error);
  EXPECT_EQ(bytes(p), corrupted) << "a file that does not verify was rewritten";
  EXPECT_FALSE(fs::exists(p + ".sum")) << "a corrupted file was given a checksum";
  EXPECT_FALSE(fs::exists(p + ".partial"));

  const std::string old = temp_copy("unframed.h5");  // engine 0.1.0's: no frame, no .sum
  const std::string before = bytes(old);
  try {
    store_verdicts(old, first, "test");
    ADD_FAILURE() << "verdicts stored in an unframed file";
  } catch (const H5Error& e) {
    EXPECT_NE(std::string(e.what()).find("no checksum frame"), std::string::npos) << e.what();
  }
  EXPECT_EQ(bytes(old), before);
  EXPECT_FALSE(fs::exists(old + ".sum"));
  fs::remove(p);
  fs::remove(old);
}

TaskRecord fpe_record(const std::string& key, double fpe) {
  TaskRecord r;
  r.key = key;
  r.kind = "fpe";
  r.text = {{"env", "grid"}, {"method", "sirl"}, {"variant", "sirl+vae"}};
  r.num = {{"vae", 1},         {"N", 100},     {"seed", 3},   {"fpe", fpe},
           {"train_mse", 0.5}, {"seconds", 2}, {"flops", 4e9}};
  return r;
}

const H5Table::Column& column(const H5Table& t, const std::string& name) {
  for (const auto& c : t.columns)
    if (c.name == name) return c;
  throw std::runtime_error("no column " + name);
}

TEST(ResultsFile, TablesHoldOneRowPerCellWithTheRecordsValues) {
  std::vector<TaskRecord> records{fpe_record("a/fpe", 0.25), fpe_record("b/fpe", 0.75)};
  TaskRecord v;  // a VAE with a 3-epoch curve and 2 latents
  v.key = "grid/s3/vae";
  v.kind = "vae";
  v.text = {{"env", "grid"}, {"elbo", "sum"}};
  v.num = {{"seed", 3},
           {"converged", 1},
           {"loss_relative_change", 0.001},
           {"reconstruction_mse", 0.2},
           {"seconds", 0},
           {"flops", 1}};
  v.arrays["loss_curve"] = {{3}, {9, 8, 7}};
  v.arrays["kl_per_dim"] = {{2}, {0.5f, 0.0f}};
  records.push_back(v);
  const ResultTables t = result_tables(records);

  ASSERT_EQ(t.at("fpe").rows(), 2u);
  EXPECT_EQ(column(t.at("fpe"), "variant").strings,
            (std::vector<std::string>{"sirl+vae", "sirl+vae"}));
  EXPECT_EQ(column(t.at("fpe"), "N").ints, (std::vector<int64_t>{100, 100}));
  EXPECT_EQ(column(t.at("fpe"), "fpe").doubles, (std::vector<double>{0.25, 0.75}));
  EXPECT_EQ(t.at("tpa").rows(), 0u);
  // timings: every record; GFLOP/s = flops / seconds, 0 when no time was measured.
  ASSERT_EQ(t.at("timings").rows(), 3u);
  EXPECT_EQ(column(t.at("timings"), "gflops").doubles, (std::vector<double>{2, 2, 0}));
  // training: only what trained (the VAE); final loss = the curve's last epoch.
  ASSERT_EQ(t.at("training").rows(), 1u);
  EXPECT_EQ(column(t.at("training"), "epochs").ints, (std::vector<int64_t>{3}));
  EXPECT_EQ(column(t.at("training"), "final_loss").doubles, (std::vector<double>{7}));
  EXPECT_EQ(column(t.at("training"), "variant").strings, (std::vector<std::string>{"vae"}));
  EXPECT_EQ(column(t.at("training"), "dead_fraction").doubles, (std::vector<double>{-1}));
  // vae_latents: one row per latent dimension.
  ASSERT_EQ(t.at("vae_latents").rows(), 2u);
  EXPECT_EQ(column(t.at("vae_latents"), "dim").ints, (std::vector<int64_t>{0, 1}));
  EXPECT_EQ(column(t.at("vae_latents"), "kl").doubles, (std::vector<double>{0.5, 0.0}));
}

// /tables/tpa_heads: one row per reward head, worked out by hand for a cell of 2 heads under the
// converged rule, head 0 stopped after 2 of 4 epochs (its curve NaN after), head 1 ran all 4.
TEST(ResultsFile, TpaHeadsTableHasOneRowPerHeadWithItsStopAndLastTrainedLoss) {
  TaskRecord r;
  r.key = "jaco/s1/random/tpa/M10/unfrozen";
  r.kind = "tpa";
  r.text = {{"env", "jaco"}, {"method", "random"}, {"variant", "random"}, {"stop", "converged"}};
  r.num = {{"N", 0},       {"M", 10},          {"frozen", 0},    {"seed", 1},
           {"vae", 0},     {"tpa", 0.625},     {"tpa_std", 0.2}, {"tpa_train", 0.95},
           {"in_main", 1}, {"in_ablation", 0}, {"flops", 6},     {"protocol_flops", 8},
           {"seconds", 1}};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  r.arrays["accuracy"] = {{2}, {0.75f, 0.5f}};
  r.arrays["train_accuracy"] = {{2}, {1.0f, 0.9f}};
  r.arrays["loss_curves"] = {{2, 4}, {0.7f, 0.6f, nan, nan, 0.7f, 0.5f, 0.4f, 0.3f}};
  r.arrays["head_epochs"] = {{2}, {2, 4}};
  r.arrays["phi_drift"] = {{2}, {0.25f, 0.125f}};
  const ResultTables t = result_tables({r});
  const H5Table& h = t.at("tpa_heads");
  ASSERT_EQ(h.rows(), 2u);
  EXPECT_EQ(column(h, "head").ints, (std::vector<int64_t>{0, 1}));
  EXPECT_EQ(column(h, "epochs").ints, (std::vector<int64_t>{2, 4}));
  EXPECT_EQ(column(h, "max_epochs").ints, (std::vector<int64_t>{4, 4}));
  EXPECT_EQ(column(h, "stopped").ints, (std::vector<int64_t>{1, 0}));
  EXPECT_EQ(column(h, "stop").strings, (std::vector<std::string>{"converged", "converged"}));
  EXPECT_EQ(column(h, "final_loss").doubles, (std::vector<double>{0.6f, 0.3f}));
  EXPECT_EQ(column(h, "accuracy").doubles, (std::vector<double>{0.75, 0.5}));
  EXPECT_EQ(column(h, "phi_drift").doubles, (std::vector<double>{0.25, 0.125}));
  EXPECT_EQ(column(h, "M").ints, (std::vector<int64_t>{10, 10}));
  // The training table's final loss: the mean of each head's last trained epoch, not NaN.
  ASSERT_EQ(t.at("training").rows(), 0u);  // no convergence fields in this record
  // timings: executed and protocol FLOPs side by side.
  EXPECT_EQ(column(t.at("timings"), "flops").doubles, (std::vector<double>{6}));
  EXPECT_EQ(column(t.at("timings"), "protocol_flops").doubles, (std::vector<double>{8}));
  // A record from before the stopping rule (no head_epochs, no stop): every epoch, "fixed".
  r.arrays.erase("head_epochs");
  r.text.erase("stop");
  r.arrays["loss_curves"] = {{2, 4}, {0.7f, 0.6f, 0.5f, 0.4f, 0.7f, 0.5f, 0.4f, 0.3f}};
  const ResultTables before = result_tables({r});
  const H5Table& old = before.at("tpa_heads");
  EXPECT_EQ(column(old, "epochs").ints, (std::vector<int64_t>{4, 4}));
  EXPECT_EQ(column(old, "stopped").ints, (std::vector<int64_t>{0, 0}));
  EXPECT_EQ(column(old, "stop").strings, (std::vector<std::string>{"fixed", "fixed"}));
}

// Two records of one task are the same results when every bit agrees: a stopped head's NaN
// epochs must not make a record differ from itself (sirl merge compares records of one task).
TEST(ResultsFile, ARecordWithNaNEpochsEqualsItsRoundTripAndNothingElse) {
  TaskRecord r;
  r.key = "jaco/s0/random/tpa/M10/unfrozen";
  r.kind = "tpa";
  const float nan = std::numeric_limits<float>::quiet_NaN();
  r.arrays["loss_curves"] = {{1, 3}, {0.5f, nan, nan}};
  EXPECT_TRUE(deserialize(serialize(r)) == r);
  TaskRecord other = r;
  other.arrays["loss_curves"].data[0] = 0.25f;
  EXPECT_FALSE(other == r);
  other = r;
  other.arrays["loss_curves"].data[2] = -0.0f;  // a value where the other has none
  EXPECT_FALSE(other == r);
}

// /tables/timings' roofs, worked out by hand with a 200 GFLOP/s fp32 roof per core:
//  - in cache (no stream_bytes): 100 GFLOP in 1 s on 1 core → 50 % of the roof, no memory roof;
//  - streaming: 100 GFLOP over 10 GB at 20 GB/s per core, on 2 cores, in 2 s → 50 GFLOP/s;
//    memory roof 10 FLOP/B × 20 GB/s × 2 = 400 GFLOP/s, fp32 400 → 12.5 % of either;
//  - streaming harder: 100 GFLOP over 50 GB at 20 GB/s, 1 core, 4 s → 25 GFLOP/s; memory roof
//    2 × 20 = 40 GFLOP/s, below the fp32 200 → attainable 62.5 %, roof_percent 12.5 %.
TEST(ResultsFile, TimingsGiveEachTaskItsShareOfTheLowerRoof) {
  auto rec = [](const std::string& key, double seconds, double threads, double bytes) {
    TaskRecord r;
    r.key = key;
    r.kind = "rep";
    r.num = {{"seconds", seconds}, {"flops", 100e9}, {"threads", threads}};
    if (bytes > 0) r.num["stream_bytes"] = bytes;
    return r;
  };
  const ResultTables t =
      result_tables({rec("a", 1, 1, 0), rec("b", 2, 2, 10e9), rec("c", 4, 1, 50e9)}, {200, 0, 20});
  const H5Table& tm = t.at("timings");
  EXPECT_EQ(column(tm, "gflops").doubles, (std::vector<double>{100, 50, 25}));
  EXPECT_EQ(column(tm, "roof_percent").doubles, (std::vector<double>{50, 12.5, 12.5}));
  EXPECT_EQ(column(tm, "memory_roof_gflops").doubles, (std::vector<double>{0, 400, 40}));
  EXPECT_EQ(column(tm, "attainable_percent").doubles, (std::vector<double>{50, 12.5, 62.5}));
  EXPECT_EQ(column(tm, "compute_roof_gflops").doubles, (std::vector<double>{200, 400, 200}));
  EXPECT_EQ(column(tm, "precision").strings, (std::vector<std::string>{"fp32", "fp32", "fp32"}));
}

// A bf16 task against the bf16 roof, by hand: 100 GFLOP in 0.5 s = 200 GFLOP/s, with a 200 fp32
// and an 800 bf16 roof per core → 25 % on 1 core, 12.5 % on 2; an fp32 task of the same run stays
// against the fp32 roof (100 %); with no bf16 unit (bf16 roof 0: emulated products, fp32
// arithmetic) the bf16 task is held to the fp32 roof too (100 %). Streaming 100 GB at 20 GB/s
// gives the first a memory roof of 20, which is then its attainable roof (1000 %).
TEST(ResultsFile, Bf16TasksAreMeasuredAgainstTheBf16Roof) {
  auto rec = [](const std::string& key, bool bf16, double threads, double bytes) {
    TaskRecord r;
    r.key = key;
    r.kind = "rep";
    r.num = {{"seconds", 0.5}, {"flops", 100e9}, {"threads", threads}};
    if (bf16) r.num["bf16_products"] = 1;
    if (bytes > 0) r.num["stream_bytes"] = bytes;
    return r;
  };
  const std::vector<TaskRecord> records = {rec("a", true, 1, 100e9), rec("b", true, 2, 0),
                                           rec("c", false, 1, 0)};
  const ResultTables with_unit = result_tables(records, {200, 800, 20});
  const H5Table& tm = with_unit.at("timings");
  EXPECT_EQ(column(tm, "precision").strings, (std::vector<std::string>{"bf16", "bf16", "fp32"}));
  EXPECT_EQ(column(tm, "compute_roof_gflops").doubles, (std::vector<double>{800, 1600, 200}));
  EXPECT_EQ(column(tm, "roof_percent").doubles, (std::vector<double>{25, 12.5, 100}));
  EXPECT_EQ(column(tm, "attainable_percent").doubles, (std::vector<double>{1000, 12.5, 100}));
  const ResultTables emulated = result_tables(records, {200, 0, 20});
  EXPECT_EQ(column(emulated.at("timings"), "roof_percent").doubles,
            (std::vector<double>{100, 50, 100}));
}

TEST(ResultsFile, ARecordMissingAColumnsKeyIsAnErrorNotAZero) {
  TaskRecord r = fpe_record("grid/s3/sirl+vae/N100/fpe", 0.25);
  r.num.erase("train_mse");
  try {
    result_tables({r});
    ADD_FAILURE() << "a record without train_mse made a table";
  } catch (const H5Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("grid/s3/sirl+vae/N100/fpe"), std::string::npos) << m;
    EXPECT_NE(m.find("train_mse"), std::string::npos) << m;
  }
}

// A long table (CellTableSpec::rows_key): a record gives num[rows_key] rows; row i reads
// "<key>/<i>" where the record has it and the record's own "<key>" otherwise; a missing row
// field is an error naming the task and the field.
TEST(ResultsFile, ALongTableGivesEachRecordItsRowsAndRepeatsItsOwnFields) {
  using C = H5Table::Column;
  const CellTableSpec spec{"long",
                           "thing",
                           {{"env", C::String, "env"},
                            {"unit", C::String, "unit"},
                            {"value", C::Double, "value"},
                            {"n", C::Int, "n"}},
                           "rows"};
  TaskRecord a;
  a.key = "t/a";
  a.kind = "thing";
  a.text = {{"env", "grid"}, {"unit/0", "p1"}, {"unit/1", "p2"}};
  a.num = {{"rows", 2}, {"value/0", 0.5}, {"value/1", 0.25}, {"n", 7}};
  TaskRecord b = a;  // one row, its own env; an empty record gives none
  b.key = "t/b";
  b.text = {{"env", "jaco"}, {"unit/0", "p9"}};
  b.num = {{"rows", 1}, {"value/0", 1.5}, {"n", 3}};
  TaskRecord none = a;
  none.key = "t/none";
  none.num["rows"] = 0;
  const ResultTables t = build_tables({a, none, b}, {spec});
  const H5Table& l = t.at("long");
  ASSERT_EQ(l.rows(), 3u);
  EXPECT_EQ(column(l, "env").strings, (std::vector<std::string>{"grid", "grid", "jaco"}));
  EXPECT_EQ(column(l, "unit").strings, (std::vector<std::string>{"p1", "p2", "p9"}));
  EXPECT_EQ(column(l, "value").doubles, (std::vector<double>{0.5, 0.25, 1.5}));
  EXPECT_EQ(column(l, "n").ints, (std::vector<int64_t>{7, 7, 3}));
  b.num.erase("value/0");
  try {
    build_tables({b}, {spec});
    ADD_FAILURE() << "a row without its value made a table";
  } catch (const H5Error& e) {
    EXPECT_NE(std::string(e.what()).find("t/b"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("value"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sirl
