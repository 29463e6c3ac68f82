#include "results/task_record.h"

#include <cstring>
#include <stdexcept>

#include "results/h5.h"

namespace sirl {

namespace {
void put_u64(std::string& out, uint64_t v) {
  out.append(reinterpret_cast<const char*>(&v), 8);
}
void put_str(std::string& out, const std::string& s) {
  put_u64(out, s.size());
  out += s;
}
struct Cursor {
  const std::string& s;
  size_t pos = 0;
  const char* take(size_t n) {
    if (n > s.size() - pos) throw std::runtime_error("task record message is truncated");
    const char* p = s.data() + pos;
    pos += n;
    return p;
  }
  uint64_t u64() {
    uint64_t v;
    std::memcpy(&v, take(8), 8);
    return v;
  }
  std::string str() {
    const uint64_t n = u64();
    return std::string(take(n), n);
  }
};
}  // namespace

std::string serialize(const TaskRecord& r) {
  std::string out;
  put_str(out, r.key);
  put_str(out, r.kind);
  put_u64(out, r.text.size());
  for (const auto& [k, v] : r.text) {
    put_str(out, k);
    put_str(out, v);
  }
  put_u64(out, r.num.size());
  for (const auto& [k, v] : r.num) {
    put_str(out, k);
    out.append(reinterpret_cast<const char*>(&v), 8);
  }
  put_u64(out, r.arrays.size());
  for (const auto& [k, a] : r.arrays) {
    put_str(out, k);
    put_u64(out, a.dims.size());
    for (uint64_t d : a.dims) put_u64(out, d);
    put_u64(out, a.data.size());
    out.append(reinterpret_cast<const char*>(a.data.data()), a.data.size() * sizeof(float));
  }
  return out;
}

TaskRecord deserialize(const std::string& bytes) {
  Cursor c{bytes};
  TaskRecord r;
  r.key = c.str();
  r.kind = c.str();
  for (uint64_t n = c.u64(); n > 0; --n) {
    std::string k = c.str();
    r.text[k] = c.str();
  }
  for (uint64_t n = c.u64(); n > 0; --n) {
    std::string k = c.str();
    double v;
    std::memcpy(&v, c.take(8), 8);
    r.num[k] = v;
  }
  for (uint64_t n = c.u64(); n > 0; --n) {
    std::string k = c.str();
    TaskRecord::Array a;
    a.dims.resize(c.u64());
    for (auto& d : a.dims) d = c.u64();
    const uint64_t count = c.u64();
    if (count > bytes.size()) throw std::runtime_error("task record message is malformed");
    a.data.resize(count);
    const void* src = c.take(count * sizeof(float));
    if (count > 0)
      std::memcpy(a.data.data(), src, count * sizeof(float));  // an empty array: no data
    r.arrays[k] = std::move(a);
  }
  if (c.pos != bytes.size()) throw std::runtime_error("task record message has trailing bytes");
  return r;
}

void write_record(H5File& f, const std::string& g, const TaskRecord& r) {
  f.group(g);
  f.set_attr(g, "task_key", r.key);
  f.set_attr(g, "task_kind", r.kind);
  std::vector<std::string> tnames, nnames, anames;
  for (const auto& [k, v] : r.text) {
    f.set_attr(g, k, v);
    tnames.push_back(k);
  }
  for (const auto& [k, v] : r.num) {
    f.set_attr(g, k, v);
    nnames.push_back(k);
  }
  for (const auto& [k, a] : r.arrays) {
    f.write(g + "/" + k, a.data.data(), a.dims);
    anames.push_back(k);
  }
  f.set_attr(g, "record_texts", tnames);
  f.set_attr(g, "record_numbers", nnames);
  f.set_attr(g, "record_arrays", anames);
}

TaskRecord read_record(const H5File& f, const std::string& g) {
  TaskRecord r;
  r.key = f.attr_string(g, "task_key");
  r.kind = f.attr_string(g, "task_kind");
  for (const auto& k : f.attr_strings(g, "record_texts")) r.text[k] = f.attr_string(g, k);
  for (const auto& k : f.attr_strings(g, "record_numbers")) r.num[k] = f.attr_double(g, k);
  for (const auto& k : f.attr_strings(g, "record_arrays")) {
    TaskRecord::Array a;
    a.data = f.read_f32(g + "/" + k, kAnyShape, &a.dims);
    r.arrays[k] = std::move(a);
  }
  return r;
}

}  // namespace sirl
