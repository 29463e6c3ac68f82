#include "results/task_record.h"

#include "results/h5.h"

namespace sirl {

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
