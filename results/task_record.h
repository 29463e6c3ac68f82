// One finished task's results, the unit that is committed, resumed, sharded and merged.
// Schema-light on purpose: named numbers, texts and float arrays, so every task kind (VAE,
// representation, FPE, TPA) shares one commit path.
#pragma once
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <vector>

namespace sirl {

class H5File;

struct TaskRecord {
  struct Array {
    std::vector<uint64_t> dims;
    std::vector<float> data;
    // Bit for bit: a reward head that stopped early has NaN epochs in its curve, and two
    // records of one task are the same results only when every bit agrees.
    bool operator==(const Array& o) const {
      return dims == o.dims && data.size() == o.data.size() &&
             (data.empty() ||
              std::memcmp(data.data(), o.data.data(), data.size() * sizeof(float)) == 0);
    }
    // A float array of the given shape; a vector when dims is empty.
    static Array of(std::vector<float> data, std::vector<uint64_t> dims = {}) {
      if (dims.empty()) dims = {uint64_t(data.size())};
      return Array{std::move(dims), std::move(data)};
    }
  };
  std::string key;   // e.g. "grid/s0/sirl/N100/rep"
  std::string kind;  // "vae", "rep", "fpe", "tpa"
  std::map<std::string, std::string> text;
  std::map<std::string, double> num;
  std::map<std::string, Array> arrays;
  bool operator==(const TaskRecord&) const = default;
};

// The record as the group `group` (created): attrs for key, kind, text and numbers, one dataset
// per array, and index attributes listing the names so it reads back exactly.
// A byte string for messages between processes (MPI); deserialize(serialize(r)) == r.
std::string serialize(const TaskRecord& r);
TaskRecord deserialize(const std::string& bytes);  // throws std::runtime_error if malformed

void write_record(H5File& f, const std::string& group, const TaskRecord& r);
TaskRecord read_record(const H5File& f, const std::string& group);

}  // namespace sirl
