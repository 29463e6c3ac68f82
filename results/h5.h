// A thin, checked layer over the HDF5 C API: the only place in sirl-bench that includes hdf5.h.
// Every failure becomes an sirl::H5Error naming the file and object, never an HDF5 error stack
// on stderr or a crash.
#pragma once
#include <cstdint>
#include <deque>
#include <stdexcept>
#include <string>
#include <vector>

namespace sirl {

struct H5Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Pass as `expect` to accept an array of any rank and shape.
inline const std::vector<int64_t> kAnyShape{INT64_MIN};

// Columns of equal length; each column holds one of ints, doubles or strings.
struct H5Table {
  struct Column {
    std::string name;
    enum Type { Int, Double, String } type = Double;
    std::vector<int64_t> ints;
    std::vector<double> doubles;
    std::vector<std::string> strings;
  };
  std::deque<Column> columns;  // a deque: add() keeps references to earlier columns valid
  Column& add(const std::string& name, Column::Type t) {
    columns.push_back(Column{name, t, {}, {}, {}});
    return columns.back();
  }
  size_t rows() const;
};

class H5File {
 public:
  // Truncates an existing file. A userblock (a power of two ≥ 512 bytes) reserves the file's
  // first bytes for the caller; HDF5 neither reads nor writes them.
  static H5File create(const std::string& path, uint64_t userblock_bytes = 0);
  static H5File open_read(const std::string& path);  // throws H5Error: missing, not HDF5, truncated
  static H5File open_rw(const std::string& path);
  H5File(H5File&& o) noexcept;
  H5File& operator=(H5File&&) = delete;
  ~H5File();
  const std::string& path() const { return path_; }
  int64_t id() const { return id_; }
  void flush();
  // Flushes and closes now, throwing H5Error if a byte could not be written (the destructor
  // closes silently: a writer must close() or flush() to learn that its file is whole).
  void close();

  bool exists(const std::string& object) const;
  // From now on, numeric arrays of ≥ 4096 elements are written chunked with shuffle + deflate
  // (h5py and pandas read them transparently). Off by default: task commits stay fast.
  void set_compression(bool on) { compress_ = on; }
  // Arrays: row-major, dims as given; parent groups are created as needed.
  void write(const std::string& name, const float* data, const std::vector<uint64_t>& dims);
  void write(const std::string& name, const int32_t* data, const std::vector<uint64_t>& dims);
  void write(const std::string& name, const double* data, const std::vector<uint64_t>& dims);
  // A 1-D dataset of variable-length UTF-8 strings (h5py reads it as bytes objects).
  void write_strings(const std::string& name, const std::vector<std::string>& values);
  std::vector<std::string> read_strings(const std::string& name) const;
  // A "long" table as a 1-D compound dataset, one field per column (strings fixed-length, so
  // pandas.DataFrame(h5py.File(f)[name][:]) reads it directly).
  void write_table(const std::string& name, const struct H5Table& table);
  // A dataset's extents (without reading it); throws H5Error if it is missing.
  std::vector<uint64_t> dims(const std::string& name) const;
  // Whether a dataset keeps its values outside the file (HDF5 external or virtual storage, which
  // no checksum of the file covers). Every read refuses such a dataset.
  bool stored_outside(const std::string& name) const;
  // Reads and checks the element type and shape; a dim of -1 in `expect` matches any extent.
  std::vector<float> read_f32(const std::string& name, const std::vector<int64_t>& expect,
                              std::vector<uint64_t>* dims = nullptr) const;
  std::vector<double> read_f64(const std::string& name, const std::vector<int64_t>& expect,
                               std::vector<uint64_t>* dims = nullptr) const;
  std::vector<int32_t> read_i32(const std::string& name, const std::vector<int64_t>& expect,
                                std::vector<uint64_t>* dims = nullptr) const;
  // Attributes on a group or dataset (created if missing).
  void group(const std::string& name);
  void set_attr(const std::string& object, const std::string& attr, const std::string& value);
  void set_attr(const std::string& object, const std::string& attr, double value);
  void set_attr(const std::string& object, const std::string& attr, int64_t value);
  void set_attr(const std::string& object, const std::string& attr,
                const std::vector<std::string>& values);
  bool has_attr(const std::string& object, const std::string& attr) const;
  std::string attr_string(const std::string& object, const std::string& attr) const;
  double attr_double(const std::string& object, const std::string& attr) const;
  int64_t attr_int(const std::string& object, const std::string& attr) const;
  std::vector<std::string> attr_strings(const std::string& object, const std::string& attr) const;

 private:
  H5File(int64_t id, std::string path) : id_(id), path_(std::move(path)) {}
  int64_t id_;
  bool compress_ = false;
  std::string path_;
};

// The HDF5 library's version at run time, for provenance.
std::string hdf5_version();
}  // namespace sirl
