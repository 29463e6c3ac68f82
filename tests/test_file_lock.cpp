// The output lock (results/file_lock.h): removed when its holder is done, a stale one taken over,
// a file that is not a sirl lock never touched, and one writer at a time even while holders keep
// removing the file that others have open.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "results/file_lock.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(FileLock, IsRemovedWhenItsHolderIsDoneAndAStaleOneIsTakenOver) {
  const test::ScratchDir scratch;
  const std::string out = scratch.file("r.h5");
  {
    const FileLock lock(out, "sirl run", "wait");
    EXPECT_TRUE(fs::exists(out + ".lock"));
    EXPECT_NE(read(out + ".lock").find(" sirl run"), std::string::npos);
    EXPECT_THROW(FileLock(out, "sirl merge", "wait"), FileBusy);
  }
  EXPECT_FALSE(fs::exists(out + ".lock")) << "the lock outlived its holder";
  // A process killed while holding it leaves its file: the next takes it over and removes it.
  std::ofstream(out + ".lock") << "12345 sirl run";
  { const FileLock lock(out, "sirl merge", "wait"); }
  EXPECT_FALSE(fs::exists(out + ".lock"));
  // Not a sirl lock: refused, left as it was.
  std::ofstream(out + ".lock") << "[[package]]\nname = \"x\"\n";
  EXPECT_THROW(FileLock(out, "sirl merge", "wait"), FileBusy);  // exit 2, as a held one
  EXPECT_EQ(read(out + ".lock"), "[[package]]\nname = \"x\"\n");
}

// Eight threads (flock conflicts between open() calls of one process as between processes) take
// the lock over and over, each holder removing the file as it leaves: never two inside at once.
// Without the taker's check that the path still names the file it locked, a thread holding the
// removed file and one holding its replacement would both be inside.
TEST(FileLock, OneHolderAtATimeWhileHoldersKeepRemovingTheFile) {
  const test::ScratchDir scratch;
  const std::string out = scratch.file("r.h5");
  std::atomic<int> inside{0}, most{0}, entries{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&] {
      for (int got = 0; got < 200;) {
        try {
          const FileLock lock(out, "sirl run", "wait");
          const int now = ++inside;
          int m = most.load();
          while (now > m && !most.compare_exchange_weak(m, now)) {
          }
          std::this_thread::yield();
          --inside;
          ++got;
          ++entries;
        } catch (const FileBusy&) {
          std::this_thread::yield();
        }
      }
    });
  for (auto& th : threads) th.join();
  EXPECT_EQ(entries.load(), 1600);
  EXPECT_EQ(most.load(), 1) << "two holders of one output at once";
  EXPECT_FALSE(fs::exists(out + ".lock"));
}

}  // namespace
}  // namespace sirl
