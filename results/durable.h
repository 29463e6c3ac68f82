// Making a finished file survive a crash: its bytes (and then its directory entry) reach the disk
// before anyone is told it exists. Used by every atomic "write temporary, fsync, rename" here.
#pragma once
#include <cstdint>
#include <string>

namespace sirl {

// fsync of a file or a directory; silently does nothing if it cannot be opened.
void fsync_path(const std::string& path);

// A fast checksum of a file's bytes from `offset` on: FNV-1a over 64-bit little-endian words (the
// tail zero-padded). ~0.1 s per 100 MB here, and any flipped byte changes it. Throws
// std::runtime_error if the file cannot be read.
uint64_t file_checksum(const std::string& path, uint64_t offset = 0);
// 16 lowercase hex digits.
std::string hex64(uint64_t v);

}  // namespace sirl
