// Making a finished file survive a crash: its bytes (and then its directory entry) reach the disk
// before anyone is told it exists. Used by every atomic "write temporary, fsync, rename" here.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace sirl {

// Throws std::runtime_error if `path` is a symbolic link. Every file and folder sirl creates
// beside an output (OUT.partial, OUT.lock, OUT.sum.tmp, OUT.tasks, a commit's .tmp) is checked
// first: a link planted there would make sirl write, lock or delete whatever it points to.
void refuse_symlink(const std::string& path);

// Overwrites the first bytes of a closed file with `head` (a checksum frame in an HDF5 userblock:
// results files and task commits). Throws std::runtime_error naming the file if it cannot.
void overwrite_head(const std::string& path, const std::string& head);

// fsync of a file or a directory; silently does nothing if it cannot be opened. Every durable
// write here (write a temporary file, fsync it, rename, fsync the directory) goes through it, so
// it holds the crash points: one before the fsync (the bytes written, not yet durable), one after.
void fsync_path(const std::string& path);

// Replaces `path` with `text` atomically (a temporary file named by the process, fsync, rename,
// fsync of the folder): a reader sees the old file or the new one, never half of either. Throws
// std::runtime_error naming the file when it cannot (a full disk, a read-only folder).
void write_text_atomically(const std::string& path, const std::string& text);

// Test hook: with SIRL_CRASH_AT=k in the environment, the process ends as kill -9 would (exit
// code 137, no destructors, no flush) at its k-th crash point. tests/crash_walk.py walks k over
// every crash point of a run and checks that each resumes to the file an uninterrupted run writes.
void crash_point();

// The digest every file written from engine 0.8.0 on carries: XXH3-128 (xxHash, a hash designed
// to catch corruption: every single and paired bit flip changes it) of the file's bytes from
// `offset` on, as 32 lowercase hex digits in xxHash's canonical order (what `xxh128sum` prints
// for offset 0). Throws std::runtime_error if the file cannot be read.
std::string file_digest(const std::string& path, uint64_t offset = 0);
// The same over bytes in memory.
std::string bytes_digest(const void* data, size_t n);

// The checksum of engines up to 0.7.0, still read to verify their files: FNV-1a over 64-bit
// little-endian words (the tail zero-padded). Blind to some paired bit flips (two flips of one
// bit position in words of equal offset mod 8 can cancel); never written any more.
uint64_t file_checksum(const std::string& path, uint64_t offset = 0);
// 16 lowercase hex digits.
std::string hex64(uint64_t v);

// xxHash's version at run time, for provenance.
std::string xxhash_version();
}  // namespace sirl
