#include "results/durable.h"

#include <xxhash.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <vector>

namespace sirl {

void crash_point() {
  static const long k = [] {
    const char* v = std::getenv("SIRL_CRASH_AT");
    return v ? std::strtol(v, nullptr, 10) : 0L;
  }();
  static std::atomic<long> points{0};
  if (k > 0 && ++points == k) std::_Exit(137);
}

void fsync_path(const std::string& path) {
  crash_point();
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
  crash_point();
}

void write_text_atomically(const std::string& path, const std::string& text) {
  refuse_symlink(path);
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw std::runtime_error(path + ": cannot write (" + std::strerror(errno) + ")");
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    const bool closed = std::fclose(f) == 0;
    if (!ok || !closed) {
      const int err = errno;
      std::remove(tmp.c_str());
      throw std::runtime_error(path + ": cannot write (" + std::strerror(err) + ")");
    }
  }
  fsync_path(tmp);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot replace (" + std::strerror(err) + ")");
  }
  const auto slash = path.rfind('/');
  fsync_path(slash == std::string::npos ? "." : path.substr(0, slash + 1));
}

uint64_t file_checksum(const std::string& path, uint64_t offset) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read");
  in.seekg(std::streamoff(offset));
  uint64_t h = 0xCBF29CE484222325ull;
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    const size_t n = size_t(in.gcount());
    for (size_t i = 0; i < n; i += 8) {
      uint64_t w = 0;
      std::memcpy(&w, buf.data() + i, std::min<size_t>(8, n - i));
      h = (h ^ w) * 0x100000001B3ull;
    }
  }
  return h;
}

void overwrite_head(const std::string& path, const std::string& head) {
  std::fstream out(path, std::ios::in | std::ios::out | std::ios::binary);
  out.seekp(0);
  out.write(head.data(), std::streamsize(head.size()));
  out.flush();
  if (!out) throw std::runtime_error(path + ": cannot write its checksum frame");
}

void refuse_symlink(const std::string& path) {
  struct stat st;
  if (::lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode))
    throw std::runtime_error(path +
                             " is a symbolic link; sirl creates this file itself and does "
                             "not write through links: remove it");
}

namespace {

std::string canonical_hex(XXH128_hash_t h) {
  XXH128_canonical_t c;
  XXH128_canonicalFromHash(&c, h);
  static const char* digits = "0123456789abcdef";
  std::string s(32, '0');
  for (int i = 0; i < 16; ++i) {
    s[2 * i] = digits[c.digest[i] >> 4];
    s[2 * i + 1] = digits[c.digest[i] & 15];
  }
  return s;
}

}  // namespace

std::string file_digest(const std::string& path, uint64_t offset) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read");
  in.seekg(std::streamoff(offset));
  std::unique_ptr<XXH3_state_t, XXH_errorcode (*)(XXH3_state_t*)> state(XXH3_createState(),
                                                                        XXH3_freeState);
  if (!state || XXH3_128bits_reset(state.get()) != XXH_OK)
    throw std::runtime_error(path + ": cannot start the digest");
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    XXH3_128bits_update(state.get(), buf.data(), size_t(in.gcount()));
  }
  if (in.bad()) throw std::runtime_error(path + ": read error");
  return canonical_hex(XXH3_128bits_digest(state.get()));
}

std::string bytes_digest(const void* data, size_t n) {
  return canonical_hex(XXH3_128bits(data, n));
}

std::string hex64(uint64_t v) {
  char b[17];
  std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
  return b;
}

std::string xxhash_version() {
  const unsigned v = XXH_versionNumber();  // major·10000 + minor·100 + release
  return std::to_string(v / 10000) + "." + std::to_string(v / 100 % 100) + "." +
         std::to_string(v % 100);
}
}  // namespace sirl
