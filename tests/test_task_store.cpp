// The task store: commits round-trip, torn commits are swept, corrupted commits refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "results/durable.h"
#include "results/h5.h"
#include "results/task_store.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {

// The one commit file in a staging directory that holds one task.
std::filesystem::path the_commit(const std::filesystem::path& dir) {
  std::filesystem::path file;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".h5") file = e.path();
  return file;
}

std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// A byte flipped in a committed task's data (here a weight of a 4096-float array, which HDF5
// itself never checks) is caught by the commit's checksum: refused with the task's name, the
// file removed so that a rerun computes the task again.
TEST(TaskStore, ACorruptedCommitIsRefusedByNameAndRemoved) {
  namespace fs = std::filesystem;
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "tasks";
  TaskRecord r;
  r.key = "grid/s0/sirl/N100/rep";
  r.kind = "rep";
  r.text["env"] = "grid";
  std::vector<float> w(4096);
  for (size_t i = 0; i < w.size(); ++i) w[i] = 0.25f + float(i);
  r.arrays["params"] = {{4096}, w};
  TaskStore s(dir);
  s.commit(r);
  EXPECT_EQ(s.load(r.key), r);
  // Find weight 2000 (2000.25f) in the file and flip one bit of it.
  const fs::path file = the_commit(dir);
  std::string bytes = read_bytes(file);
  const float target = 2000.25f;
  const size_t at = bytes.find(std::string(reinterpret_cast<const char*>(&target), 4));
  ASSERT_NE(at, std::string::npos);
  bytes[at] = char(bytes[at] ^ 0x01);
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
  try {
    s.load(r.key);
    ADD_FAILURE() << "a corrupted task was loaded";
  } catch (const H5Error& e) {
    EXPECT_NE(std::string(e.what()).find("task grid/s0/sirl/N100/rep"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("corrupted"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(TaskStore(dir).has(r.key));  // a rerun computes it again
}

// Any byte of a commit flipped — HDF5's superblock, object headers and heaps included, which the
// HDF5 library may crash on — is refused before HDF5 opens the file, or (a flip in the frame's
// padding) harmless: the store never crashes and never returns another record.
TEST(TaskStore, EveryFlippedByteIsRefusedOrHarmlessNeverACrash) {
  namespace fs = std::filesystem;
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "tasks";
  TaskRecord r;
  r.key = "jaco/s1/sirl+vae/N1000/rep";
  r.kind = "rep";
  r.text["variant"] = "sirl+vae";
  r.num["N"] = 1000;
  r.arrays["params"] = {{3, 2}, {1, 2, 3, 4, 5, 6}};
  TaskStore(dir).commit(r);
  const fs::path file = the_commit(dir);
  const std::string original = read_bytes(file);
  ASSERT_GT(original.size(), 1024u);
  int refused = 0, harmless = 0;
  for (size_t at = 0; at < original.size(); at += 7) {
    std::string bytes = original;
    bytes[at] = char(bytes[at] ^ 0x10);
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
    try {
      const TaskStore s(dir);  // indexing reads the frame only
      EXPECT_EQ(s.load(r.key), r) << "byte " << at;
      ++harmless;
    } catch (const H5Error&) {
      ++refused;
    }
  }
  // Only the frame's NUL padding (after the key, before byte 1024) may change harmlessly.
  const size_t padding = 1024 - (10 + 17 + r.key.size() + 1);
  EXPECT_LE(harmless, int(padding / 7) + 1);
  EXPECT_GT(refused, int((original.size() - 1024) / 7));
}

// A commit of engine 0.2.0 (plain HDF5, no frame) is still read.
TEST(TaskStore, ACommitWithoutAFrameIsStillRead) {
  namespace fs = std::filesystem;
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "tasks";
  TaskRecord r;
  r.key = "grid/s0/vae";
  r.kind = "vae";
  r.num["seed"] = 0;
  TaskStore(dir).commit(r);
  const fs::path file = the_commit(dir);
  {
    H5File f = H5File::create(file.string());  // rewritten as engine 0.2.0 wrote it
    write_record(f, "/r", r);
    f.set_attr("/r", "record_checksum", record_checksum(r));
  }
  const TaskStore s(dir);
  ASSERT_TRUE(s.has(r.key));
  EXPECT_EQ(s.load(r.key), r);
  EXPECT_EQ(TaskStore::load_from(dir, r.key), r);
}

// A commit of engines 0.3.0-0.7.0 (frame SIRLTASK1 with the 16-digit FNV checksum, an FNV record
// checksum) is still read and still verified.
TEST(TaskStore, ACommitOfTheFnvFrameIsStillReadAndVerified) {
  namespace fs = std::filesystem;
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "tasks";
  TaskRecord r;
  r.key = "grid/s0/vae";
  r.kind = "vae";
  r.num["seed"] = 0;
  r.arrays["loss_curve"] = {{3}, {3, 2, 1}};
  TaskStore(dir).commit(r);
  const fs::path file = the_commit(dir);
  {
    H5File f = H5File::create(file.string(), 1024);  // rewritten as engine 0.7.0 wrote it
    write_record(f, "/r", r);
    f.set_attr("/r", "record_checksum", record_checksum_fnv(r));
  }
  std::string head =
      "SIRLTASK1\n" + hex64(file_checksum(file.string(), 1024)) + "\n" + r.key + "\n";
  head.resize(1024, '\0');
  {
    std::fstream out(file, std::ios::in | std::ios::out | std::ios::binary);
    out.write(head.data(), std::streamsize(head.size()));
  }
  EXPECT_EQ(TaskStore::load_from(dir, r.key), r);
  {
    std::fstream out(file, std::ios::in | std::ios::out | std::ios::binary);
    out.seekp(std::streamoff(fs::file_size(file) - 100));
    out.put('\x5a');
  }
  EXPECT_THROW(TaskStore::load_from(dir, r.key), H5Error);
}

// An edit that keeps the file well-formed — a record's value changed, and the frame's digest
// rewritten to match the edited bytes — is still refused: the record checksum beside the record
// covers its values.
TEST(TaskStore, AnEditedValueWithARewrittenFrameIsRefused) {
  namespace fs = std::filesystem;
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "tasks";
  TaskRecord r;
  r.key = "grid/s0/sirl/N100/tpa/M10/frozen";
  r.kind = "tpa";
  r.num["tpa"] = 0.61;
  TaskStore(dir).commit(r);
  const fs::path file = the_commit(dir);
  {
    H5File f = H5File::open_rw(file.string());
    f.set_attr("/r", "tpa", 0.99);  // a better number than the one computed
  }
  std::string head = "SIRLTASK2\n" + file_digest(file.string(), 1024) + "\n" + r.key + "\n";
  head.resize(1024, '\0');
  {
    std::fstream out(file, std::ios::in | std::ios::out | std::ios::binary);
    out.write(head.data(), std::streamsize(head.size()));
  }
  EXPECT_TRUE(TaskStore(dir).has(r.key)) << "the rewritten frame no longer reads as a commit";
  try {
    TaskStore::load_from(dir, r.key);
    ADD_FAILURE() << "an edited value was loaded";
  } catch (const H5Error& e) {
    EXPECT_NE(std::string(e.what()).find("record checksum mismatch"), std::string::npos)
        << e.what();
  }
}

// (Durability under a crash is batch_engine.py's kill -9 test; this one is the file format.)
TEST(TaskStore, CommitsRoundTripAndTornCommitsAreSwept) {
  namespace fs = std::filesystem;
  const test::ScratchDir scratch;
  const fs::path dir = scratch.path() / "tasks";
  TaskRecord r;
  r.key = "grid/s0/sirl/N100/tpa/M10/frozen";
  r.kind = "tpa";
  r.text["env"] = "grid";
  r.num["tpa"] = 0.8125;
  r.arrays["loss_curves"] = {{2, 3}, {1, 2, 3, 4, 5, 6}};
  r.arrays["empty"] = {{0}, {}};
  {
    TaskStore s(dir);
    s.commit(r);
    EXPECT_TRUE(s.has(r.key));
  }
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  // An interrupted commit: a dead writer of this host named, the store's bytes.
  const std::string torn = "0123456789abcdef.h5." + std::string(host) + ".999999999.tmp";
  std::ofstream(dir / torn) << "SIRLTASK torn";
  // Names that only look like the store's temporaries are the user's, whatever their pid field
  // holds (a 20-digit "pid" once ended every run with "stol"); an old-style name names no writer
  // and is left alone too.
  const std::string long_pid =
      "0123456789abcdef.h5." + std::string(host) + ".12345678901234567890.tmp";
  std::ofstream(dir / long_pid) << "mine";
  std::ofstream(dir / "fedcba9876543210.h5.tmp") << "my notes";
  TaskStore again(dir);
  EXPECT_EQ(again.keys(), std::vector<std::string>{r.key});
  EXPECT_EQ(again.load(r.key), r);
  EXPECT_FALSE(fs::exists(dir / torn));
  EXPECT_TRUE(fs::exists(dir / long_pid));
  EXPECT_TRUE(fs::exists(dir / "fedcba9876543210.h5.tmp"));
}

}  // namespace
}  // namespace sirl
