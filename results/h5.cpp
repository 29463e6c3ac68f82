#include "results/h5.h"

#include "results/durable.h"

#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

namespace sirl {
namespace {

// Silences HDF5's own error printing once; we report errors ourselves.
struct QuietHdf5 {
  QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }
};
void quiet() {
  thread_local QuietHdf5 q;  // HDF5's error-printing switch is per thread (thread-safe build)
}

// HDF5 does not say why a write failed; the OS's errno does when storage is the cause (a full
// disk, a file-size limit, a read-only or failing device).
std::string os_reason() {
  const int e = errno;
  if (e == ENOSPC || e == EFBIG || e == EDQUOT || e == EIO || e == EROFS || e == EACCES)
    return std::string(" (") + std::strerror(e) + ")";
  return "";
}

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  throw H5Error(file + ": " + what + os_reason());
}

// HDF5 closes what is still open at exit; after a failed write (a full disk) that close crashed
// inside the library (H5F__close_cb). Files are closed by H5File's destructor; the OS does the
// rest at exit.
const int kNoAtexit = (H5dont_atexit(), 0);

// RAII for any hid_t.
struct Hid {
  hid_t id;
  herr_t (*close)(hid_t);
  Hid(hid_t i, herr_t (*c)(hid_t)) : id(i), close(c) {}
  Hid(const Hid&) = delete;
  Hid(Hid&& o) noexcept : id(o.id), close(o.close) { o.id = -1; }
  ~Hid() {
    if (id >= 0) close(id);
  }
  operator hid_t() const { return id; }
};

hid_t lcpl_intermediate() {
  hid_t p = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(p, 1);
  return p;
}

// Dataset creation properties: contiguous, or (compress, and big enough to pay for the chunk
// index) chunks of ≈256 KiB along the first dimension (at least one row) with byte-shuffle +
// deflate level 4.
hid_t dcpl_for(hid_t type, const std::vector<hsize_t>& d, bool compress) {
  size_t total = 1;
  for (auto x : d) total *= size_t(x);
  hid_t p = H5Pcreate(H5P_DATASET_CREATE);
  if (!compress || d.empty() || total < 4096 || H5Zfilter_avail(H5Z_FILTER_DEFLATE) <= 0) return p;
  const size_t row = H5Tget_size(type) * (total / std::max<size_t>(d[0], 1));
  std::vector<hsize_t> chunk = d;
  chunk[0] = std::clamp<hsize_t>((256 << 10) / std::max<size_t>(row, 1), 1, d[0]);
  H5Pset_chunk(p, int(chunk.size()), chunk.data());
  H5Pset_shuffle(p);
  H5Pset_deflate(p, 4);
  return p;
}

void write_any(hid_t file, const std::string& path, const std::string& name, hid_t type,
               const void* data, const std::vector<uint64_t>& dims, bool compress = false) {
  std::vector<hsize_t> d(dims.begin(), dims.end());
  Hid space(H5Screate_simple(int(d.size()), d.data(), nullptr), H5Sclose);
  if (H5Lexists(file, name.c_str(), H5P_DEFAULT) > 0) H5Ldelete(file, name.c_str(), H5P_DEFAULT);
  Hid lcpl(lcpl_intermediate(), H5Pclose);
  Hid dcpl(dcpl_for(type, d, compress), H5Pclose);
  Hid ds(H5Dcreate2(file, name.c_str(), type, space, lcpl, dcpl, H5P_DEFAULT), H5Dclose);
  if (ds < 0) fail(path, "cannot create dataset " + name);
  size_t total = 1;
  for (auto x : d) total *= size_t(x);
  if (total > 0 && H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
    fail(path, "cannot write dataset " + name);
}

// The engine stores every dataset's bytes inside its file. A dataset whose bytes live elsewhere
// (HDF5 external raw storage, or a virtual dataset mapping other files) is refused before it is
// read: a file's checksum would not cover them, and they could point at any file on the machine.
bool storage_outside(hid_t ds, const std::string& path, const std::string& name) {
  Hid dcpl(H5Dget_create_plist(ds), H5Pclose);
  if (dcpl < 0) fail(path, "cannot read the storage of dataset " + name + " (file corrupt?)");
  return H5Pget_external_count(dcpl) != 0 || H5Pget_layout(dcpl) == H5D_VIRTUAL;
}

void refuse_storage_outside(hid_t ds, const std::string& path, const std::string& name) {
  if (storage_outside(ds, path, name))
    throw H5Error(path + ": " + name +
                  " keeps its values outside the file (external or virtual storage), which no "
                  "checksum of the file covers: refused");
}

template <typename T>
std::vector<T> read_any(hid_t file, const std::string& path, const std::string& name,
                        hid_t mem_type, H5T_class_t cls, const std::vector<int64_t>& expect,
                        std::vector<uint64_t>* dims_out, const char* type_name) {
  if (H5Lexists(file, name.c_str(), H5P_DEFAULT) <= 0) fail(path, "missing dataset " + name);
  Hid ds(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (ds < 0) fail(path, "cannot open dataset " + name + " (file corrupt?)");
  refuse_storage_outside(ds, path, name);
  Hid ftype(H5Dget_type(ds), H5Tclose);
  if (H5Tget_class(ftype) != cls || H5Tget_size(ftype) != sizeof(T))
    // What the file holds, not a failed system call: no errno reason (a stale one misleads).
    throw H5Error(path + ": " + name + " has the wrong element type (expected " + type_name + ")");
  Hid space(H5Dget_space(ds), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space);
  std::vector<hsize_t> d(std::max(rank, 0));
  H5Sget_simple_extent_dims(space, d.data(), nullptr);
  auto shape_str = [](const auto& v) {
    std::string s = "[";
    for (size_t i = 0; i < v.size(); ++i)
      s += (i ? ", " : "") + (int64_t(v[i]) < 0 ? std::string("*") : std::to_string(v[i]));
    return s + "]";
  };
  const bool any_shape = expect.size() == 1 && expect[0] == kAnyShape[0];
  bool ok = any_shape || size_t(rank) == expect.size();
  for (size_t i = 0; ok && !any_shape && i < d.size(); ++i)
    ok = expect[i] < 0 || hsize_t(expect[i]) == d[i];
  if (!ok)
    throw H5Error(path + ": " + name + " has shape " + shape_str(d) + ", expected " +
                  shape_str(expect));
  size_t n = 1;
  for (auto x : d) n *= x;
  std::vector<T> out(n);
  if (n && H5Dread(ds, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
    fail(path, "cannot read " + name + " (file truncated or corrupt?)");
  if (dims_out) dims_out->assign(d.begin(), d.end());
  return out;
}

Hid open_object(hid_t file, const std::string& path, const std::string& object) {
  if (object != "/" && H5Lexists(file, object.c_str(), H5P_DEFAULT) <= 0)
    fail(path, "missing object " + object);
  hid_t o = H5Oopen(file, object.c_str(), H5P_DEFAULT);
  if (o < 0) fail(path, "cannot open " + object);
  return Hid(o, H5Oclose);
}

Hid open_attr(hid_t file, const std::string& path, const std::string& object,
              const std::string& attr) {
  Hid o = open_object(file, path, object);
  if (H5Aexists(o, attr.c_str()) <= 0) fail(path, "missing attribute " + object + "@" + attr);
  return Hid(H5Aopen(o, attr.c_str(), H5P_DEFAULT), H5Aclose);
}

void write_attr(hid_t file, const std::string& path, const std::string& object,
                const std::string& attr, hid_t type, const void* data, hsize_t n, bool scalar) {
  Hid o = open_object(file, path, object);
  if (H5Aexists(o, attr.c_str()) > 0) H5Adelete(o, attr.c_str());
  Hid space(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr), H5Sclose);
  Hid a(H5Acreate2(o, attr.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  const char* empty[1] = {""};  // HDF5 rejects a null buffer even for zero elements
  if (a < 0 || H5Awrite(a, type, n == 0 ? static_cast<const void*>(empty) : data) < 0)
    fail(path, "cannot write attribute " + object + "@" + attr);
}

Hid vlen_string_type() {
  hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, H5T_VARIABLE);
  H5Tset_cset(t, H5T_CSET_UTF8);
  return Hid(t, H5Tclose);
}

}  // namespace

H5File H5File::create(const std::string& path, uint64_t userblock_bytes) {
  quiet();
  try {
    refuse_symlink(path);  // H5Fcreate would truncate the link's target
  } catch (const std::runtime_error& e) {
    throw H5Error(e.what());
  }
  errno = 0;
  hid_t fcpl = H5P_DEFAULT;
  if (userblock_bytes > 0) {
    fcpl = H5Pcreate(H5P_FILE_CREATE);
    if (fcpl < 0 || H5Pset_userblock(fcpl, hsize_t(userblock_bytes)) < 0) {
      if (fcpl >= 0) H5Pclose(fcpl);
      fail(path, "bad userblock size " + std::to_string(userblock_bytes));
    }
  }
  hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl, H5P_DEFAULT);
  if (fcpl != H5P_DEFAULT) H5Pclose(fcpl);
  if (f < 0)
    fail(path,
         errno == ENOENT ? "cannot create file (its folder does not exist)" : "cannot create file");
  return H5File(f, path);
}

H5File H5File::open_read(const std::string& path) {
  quiet();
  {
    // Opening a FIFO would block until a writer comes (never): only a regular file is read.
    std::error_code ec;
    if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
      throw H5Error(path + ": not a regular file (a pipe, socket, device or folder)");
  }
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    errno = 0;
    FILE* probe = std::fopen(path.c_str(), "rb");
    if (!probe) fail(path, "no such file or not readable");
    std::fclose(probe);
    // About the content, not the OS: an errno left by HDF5's probing would only mislead.
    throw H5Error(path + ": not an HDF5 file, or truncated/corrupt");
  }
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) fail(path, "cannot open (truncated or corrupt HDF5 file?)");
  H5File file(f, path);
  // A link to another file (external or user-defined) would pull values no checksum of this
  // file covers: a file holding one is refused whole, before any object is read.
  std::string foreign;
  const herr_t visited = H5Lvisit(
      f, H5_INDEX_NAME, H5_ITER_NATIVE,
      [](hid_t, const char* name, const H5L_info_t* info, void* out) -> herr_t {
        if (info->type == H5L_TYPE_HARD || info->type == H5L_TYPE_SOFT) return 0;
        *static_cast<std::string*>(out) = name;
        return 1;
      },
      &foreign);
  if (visited < 0) fail(path, "cannot list its objects (corrupt HDF5 file?)");
  if (!foreign.empty())
    throw H5Error(path + ": /" + foreign +
                  " is a link to another file (an HDF5 external link), which no checksum of this "
                  "file covers; sirl reads no such file");
  return file;
}

H5File H5File::open_rw(const std::string& path) {
  quiet();
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (f < 0) fail(path, "cannot open for writing (missing, locked, or corrupt?)");
  return H5File(f, path);
}

H5File::H5File(H5File&& o) noexcept
    : id_(o.id_), compress_(o.compress_), path_(std::move(o.path_)) {
  o.id_ = -1;
}
H5File::~H5File() {
  if (id_ >= 0) H5Fclose(id_);
}
void H5File::flush() {
  errno = 0;
  if (H5Fflush(id_, H5F_SCOPE_GLOBAL) < 0) fail(path_, "cannot write (flush failed)");
}
void H5File::close() {
  flush();
  errno = 0;
  const herr_t rc = H5Fclose(id_);
  id_ = -1;
  if (rc < 0) fail(path_, "cannot write (close failed)");
}

bool H5File::exists(const std::string& object) const {
  // Check every prefix: H5Lexists fails on a path whose parent is missing.
  size_t pos = 0;
  while ((pos = object.find('/', pos + 1)) != std::string::npos)
    if (H5Lexists(id_, object.substr(0, pos).c_str(), H5P_DEFAULT) <= 0) return false;
  return H5Lexists(id_, object.c_str(), H5P_DEFAULT) > 0;
}

void H5File::write(const std::string& n, const float* d, const std::vector<uint64_t>& dims) {
  write_any(id_, path_, n, H5T_NATIVE_FLOAT, d, dims, compress_);
}
void H5File::write(const std::string& n, const int32_t* d, const std::vector<uint64_t>& dims) {
  write_any(id_, path_, n, H5T_NATIVE_INT32, d, dims, compress_);
}
void H5File::write(const std::string& n, const double* d, const std::vector<uint64_t>& dims) {
  write_any(id_, path_, n, H5T_NATIVE_DOUBLE, d, dims, compress_);
}
std::vector<uint64_t> H5File::dims(const std::string& name) const {
  quiet();
  if (H5Lexists(id_, name.c_str(), H5P_DEFAULT) <= 0) fail(path_, "missing dataset " + name);
  Hid ds(H5Dopen2(id_, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (ds < 0) fail(path_, "cannot open dataset " + name + " (file corrupt?)");
  Hid space(H5Dget_space(ds), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space);
  std::vector<hsize_t> d(std::max(rank, 0));
  if (rank > 0) H5Sget_simple_extent_dims(space, d.data(), nullptr);
  return {d.begin(), d.end()};
}

bool H5File::stored_outside(const std::string& name) const {
  quiet();
  if (H5Lexists(id_, name.c_str(), H5P_DEFAULT) <= 0) fail(path_, "missing dataset " + name);
  Hid ds(H5Dopen2(id_, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (ds < 0) fail(path_, "cannot open dataset " + name + " (file corrupt?)");
  return storage_outside(ds, path_, name);
}

std::vector<float> H5File::read_f32(const std::string& n, const std::vector<int64_t>& e,
                                    std::vector<uint64_t>* d) const {
  return read_any<float>(id_, path_, n, H5T_NATIVE_FLOAT, H5T_FLOAT, e, d, "float32");
}
std::vector<double> H5File::read_f64(const std::string& n, const std::vector<int64_t>& e,
                                     std::vector<uint64_t>* d) const {
  return read_any<double>(id_, path_, n, H5T_NATIVE_DOUBLE, H5T_FLOAT, e, d, "float64");
}
std::vector<int32_t> H5File::read_i32(const std::string& n, const std::vector<int64_t>& e,
                                      std::vector<uint64_t>* d) const {
  return read_any<int32_t>(id_, path_, n, H5T_NATIVE_INT32, H5T_INTEGER, e, d, "int32");
}

size_t H5Table::rows() const {
  if (columns.empty()) return 0;
  const Column& c = columns.front();
  return c.type == Column::Int      ? c.ints.size()
         : c.type == Column::Double ? c.doubles.size()
                                    : c.strings.size();
}

void H5File::write_strings(const std::string& name, const std::vector<std::string>& v) {
  Hid t = vlen_string_type();
  std::vector<const char*> p;
  for (const auto& x : v) p.push_back(x.c_str());
  write_any(id_, path_, name, t, p.data(), {uint64_t(v.size())});
}

std::vector<std::string> H5File::read_strings(const std::string& name) const {
  if (!exists(name)) fail(path_, "missing dataset " + name);
  Hid ds(H5Dopen2(id_, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (ds < 0) fail(path_, "cannot open dataset " + name + " (file corrupt?)");
  refuse_storage_outside(ds, path_, name);
  Hid ftype(H5Dget_type(ds), H5Tclose);
  if (H5Tget_class(ftype) != H5T_STRING || H5Tis_variable_str(ftype) <= 0)
    fail(path_, name + " is not a string dataset");
  Hid space(H5Dget_space(ds), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  std::vector<char*> raw(n);
  Hid t = vlen_string_type();
  if (n && H5Dread(ds, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data()) < 0)
    fail(path_, "cannot read " + name);
  std::vector<std::string> out;
  for (char* c : raw) out.emplace_back(c ? c : "");
  if (n) H5Dvlen_reclaim(t, space, H5P_DEFAULT, raw.data());
  return out;
}

void H5File::write_table(const std::string& name, const H5Table& table) {
  using C = H5Table::Column;
  const size_t rows = table.rows();
  std::vector<size_t> offset, width;
  size_t row_bytes = 0;
  for (const C& c : table.columns) {
    const size_t n = c.type == C::Int      ? c.ints.size()
                     : c.type == C::Double ? c.doubles.size()
                                           : c.strings.size();
    if (n != rows) fail(path_, "table " + name + ": column " + c.name + " has a different length");
    size_t w = 8;
    if (c.type == C::String) {
      w = 1;
      for (const auto& x : c.strings) w = std::max(w, x.size());
    }
    offset.push_back(row_bytes);
    width.push_back(w);
    row_bytes += w;
  }
  Hid type(H5Tcreate(H5T_COMPOUND, std::max<size_t>(row_bytes, 1)), H5Tclose);
  std::vector<Hid> str_types;
  str_types.reserve(table.columns.size());
  for (size_t k = 0; k < table.columns.size(); ++k) {
    const C& c = table.columns[k];
    hid_t member = c.type == C::Int ? H5T_NATIVE_INT64 : H5T_NATIVE_DOUBLE;
    if (c.type == C::String) {
      str_types.emplace_back(H5Tcopy(H5T_C_S1), H5Tclose);
      H5Tset_size(str_types.back(), width[k]);
      H5Tset_strpad(str_types.back(), H5T_STR_NULLPAD);
      member = str_types.back();
    }
    if (H5Tinsert(type, c.name.c_str(), offset[k], member) < 0)
      fail(path_, "table " + name + ": bad column " + c.name);
  }
  std::vector<char> buf(rows * row_bytes, 0);
  for (size_t r = 0; r < rows; ++r)
    for (size_t k = 0; k < table.columns.size(); ++k) {
      const C& c = table.columns[k];
      char* dst = buf.data() + r * row_bytes + offset[k];
      if (c.type == C::Int)
        std::memcpy(dst, &c.ints[r], 8);
      else if (c.type == C::Double)
        std::memcpy(dst, &c.doubles[r], 8);
      else
        std::memcpy(dst, c.strings[r].data(), c.strings[r].size());
    }
  write_any(id_, path_, name, type, buf.data(), {uint64_t(rows)});
}

void H5File::group(const std::string& name) {
  if (exists(name)) return;
  Hid lcpl(lcpl_intermediate(), H5Pclose);
  Hid g(H5Gcreate2(id_, name.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (g < 0) fail(path_, "cannot create group " + name);
}

void H5File::set_attr(const std::string& o, const std::string& a, const std::string& v) {
  Hid t = vlen_string_type();
  const char* p = v.c_str();
  write_attr(id_, path_, o, a, t, &p, 1, true);
}
void H5File::set_attr(const std::string& o, const std::string& a, double v) {
  write_attr(id_, path_, o, a, H5T_NATIVE_DOUBLE, &v, 1, true);
}
void H5File::set_attr(const std::string& o, const std::string& a, int64_t v) {
  write_attr(id_, path_, o, a, H5T_NATIVE_INT64, &v, 1, true);
}
void H5File::set_attr(const std::string& o, const std::string& a,
                      const std::vector<std::string>& v) {
  Hid t = vlen_string_type();
  std::vector<const char*> p;
  for (const auto& s : v) p.push_back(s.c_str());
  write_attr(id_, path_, o, a, t, p.data(), p.size(), false);
}

std::string H5File::attr_string(const std::string& o, const std::string& a) const {
  auto v = attr_strings(o, a);
  if (v.size() != 1) fail(path_, "attribute " + o + "@" + a + " is not a single string");
  return v[0];
}

std::vector<std::string> H5File::attr_strings(const std::string& o, const std::string& a) const {
  Hid attr = open_attr(id_, path_, o, a);
  Hid ftype(H5Aget_type(attr), H5Tclose);
  if (H5Tget_class(ftype) != H5T_STRING || H5Tis_variable_str(ftype) <= 0)
    fail(path_, "attribute " + o + "@" + a + " is not a string");
  Hid space(H5Aget_space(attr), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  if (n == 0) return {};
  std::vector<char*> raw(n);
  Hid t = vlen_string_type();
  if (H5Aread(attr, t, raw.data()) < 0) fail(path_, "cannot read attribute " + o + "@" + a);
  std::vector<std::string> out(raw.begin(), raw.end());
  H5Dvlen_reclaim(t, space, H5P_DEFAULT, raw.data());
  return out;
}

double H5File::attr_double(const std::string& o, const std::string& a) const {
  Hid attr = open_attr(id_, path_, o, a);
  double v = 0;
  if (H5Aread(attr, H5T_NATIVE_DOUBLE, &v) < 0) fail(path_, "cannot read attribute " + o + "@" + a);
  return v;
}
bool H5File::has_attr(const std::string& o, const std::string& a) const {
  Hid obj = open_object(id_, path_, o);
  return H5Aexists(obj, a.c_str()) > 0;
}

int64_t H5File::attr_int(const std::string& o, const std::string& a) const {
  Hid attr = open_attr(id_, path_, o, a);
  int64_t v = 0;
  if (H5Aread(attr, H5T_NATIVE_INT64, &v) < 0) fail(path_, "cannot read attribute " + o + "@" + a);
  return v;
}

std::string hdf5_version() {
  unsigned major = 0, minor = 0, release = 0;
  H5get_libversion(&major, &minor, &release);
  return std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(release);
}
}  // namespace sirl
