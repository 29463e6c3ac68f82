// Making a finished file survive a crash: its bytes (and then its directory entry) reach the disk
// before anyone is told it exists. Used by every atomic "write temporary, fsync, rename" here.
#pragma once
#include <cstdint>
#include <string>

namespace sirl {

// fsync of a file or a directory; silently does nothing if it cannot be opened. Every durable
// write here (write a temporary file, fsync it, rename, fsync the directory) goes through it, so
// it holds the crash points: one before the fsync (the bytes written, not yet durable), one after.
void fsync_path(const std::string& path);

// Test hook: with SIRL_CRASH_AT=k in the environment, the process ends as kill -9 would (exit
// code 137, no destructors, no flush) at its k-th crash point. tests/crash_walk.py walks k over
// every crash point of a run and checks that each resumes to the file an uninterrupted run writes.
void crash_point();

// A fast checksum of a file's bytes from `offset` on: FNV-1a over 64-bit little-endian words (the
// tail zero-padded). ~0.1 s per 100 MB here, and any flipped byte changes it. Throws
// std::runtime_error if the file cannot be read.
uint64_t file_checksum(const std::string& path, uint64_t offset = 0);
// 16 lowercase hex digits.
std::string hex64(uint64_t v);

}  // namespace sirl
