#include "results/h5.h"

#include <hdf5.h>

#include <cstring>

namespace sirl {
namespace {

// Silences HDF5's own error printing once; we report errors ourselves.
struct QuietHdf5 {
  QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }
};
void quiet() {
  static QuietHdf5 q;
}

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  throw H5Error(file + ": " + what);
}

// RAII for any hid_t.
struct Hid {
  hid_t id;
  herr_t (*close)(hid_t);
  Hid(hid_t i, herr_t (*c)(hid_t)) : id(i), close(c) {}
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

void write_any(hid_t file, const std::string& path, const std::string& name, hid_t type,
               const void* data, const std::vector<uint64_t>& dims) {
  std::vector<hsize_t> d(dims.begin(), dims.end());
  Hid space(H5Screate_simple(int(d.size()), d.data(), nullptr), H5Sclose);
  if (H5Lexists(file, name.c_str(), H5P_DEFAULT) > 0) H5Ldelete(file, name.c_str(), H5P_DEFAULT);
  Hid lcpl(lcpl_intermediate(), H5Pclose);
  Hid ds(H5Dcreate2(file, name.c_str(), type, space, lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
  if (ds < 0) fail(path, "cannot create dataset " + name);
  if (H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
    fail(path, "cannot write dataset " + name);
}

template <typename T>
std::vector<T> read_any(hid_t file, const std::string& path, const std::string& name,
                        hid_t mem_type, H5T_class_t cls, const std::vector<int64_t>& expect,
                        std::vector<uint64_t>* dims_out, const char* type_name) {
  if (H5Lexists(file, name.c_str(), H5P_DEFAULT) <= 0) fail(path, "missing dataset " + name);
  Hid ds(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (ds < 0) fail(path, "cannot open dataset " + name + " (file corrupt?)");
  Hid ftype(H5Dget_type(ds), H5Tclose);
  if (H5Tget_class(ftype) != cls || H5Tget_size(ftype) != sizeof(T))
    fail(path, name + " has the wrong element type (expected " + type_name + ")");
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
  bool ok = size_t(rank) == expect.size();
  for (size_t i = 0; ok && i < d.size(); ++i) ok = expect[i] < 0 || hsize_t(expect[i]) == d[i];
  if (!ok) fail(path, name + " has shape " + shape_str(d) + ", expected " + shape_str(expect));
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
  if (a < 0 || H5Awrite(a, type, data) < 0)
    fail(path, "cannot write attribute " + object + "@" + attr);
}

Hid vlen_string_type() {
  hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, H5T_VARIABLE);
  H5Tset_cset(t, H5T_CSET_UTF8);
  return Hid(t, H5Tclose);
}

}  // namespace

H5File H5File::create(const std::string& path) {
  quiet();
  hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (f < 0) fail(path, "cannot create file (directory missing or not writable?)");
  return H5File(f, path);
}

H5File H5File::open_read(const std::string& path) {
  quiet();
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    FILE* probe = std::fopen(path.c_str(), "rb");
    if (!probe) fail(path, "no such file or not readable");
    std::fclose(probe);
    fail(path, "not an HDF5 file, or truncated/corrupt");
  }
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) fail(path, "cannot open (truncated or corrupt HDF5 file?)");
  return H5File(f, path);
}

H5File H5File::open_rw(const std::string& path) {
  quiet();
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (f < 0) fail(path, "cannot open for writing (missing, locked, or corrupt?)");
  return H5File(f, path);
}

H5File::H5File(H5File&& o) noexcept : id_(o.id_), path_(std::move(o.path_)) {
  o.id_ = -1;
}
H5File::~H5File() {
  if (id_ >= 0) H5Fclose(id_);
}
void H5File::flush() {
  if (H5Fflush(id_, H5F_SCOPE_GLOBAL) < 0) fail(path_, "flush failed");
}

bool H5File::exists(const std::string& object) const {
  // Check every prefix: H5Lexists fails on a path whose parent is missing.
  size_t pos = 0;
  while ((pos = object.find('/', pos + 1)) != std::string::npos)
    if (H5Lexists(id_, object.substr(0, pos).c_str(), H5P_DEFAULT) <= 0) return false;
  return H5Lexists(id_, object.c_str(), H5P_DEFAULT) > 0;
}

void H5File::write(const std::string& n, const float* d, const std::vector<uint64_t>& dims) {
  write_any(id_, path_, n, H5T_NATIVE_FLOAT, d, dims);
}
void H5File::write(const std::string& n, const int32_t* d, const std::vector<uint64_t>& dims) {
  write_any(id_, path_, n, H5T_NATIVE_INT32, d, dims);
}
void H5File::write(const std::string& n, const double* d, const std::vector<uint64_t>& dims) {
  write_any(id_, path_, n, H5T_NATIVE_DOUBLE, d, dims);
}
std::vector<float> H5File::read_f32(const std::string& n, const std::vector<int64_t>& e,
                                    std::vector<uint64_t>* d) const {
  return read_any<float>(id_, path_, n, H5T_NATIVE_FLOAT, H5T_FLOAT, e, d, "float32");
}
std::vector<int32_t> H5File::read_i32(const std::string& n, const std::vector<int64_t>& e,
                                      std::vector<uint64_t>* d) const {
  return read_any<int32_t>(id_, path_, n, H5T_NATIVE_INT32, H5T_INTEGER, e, d, "int32");
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
int64_t H5File::attr_int(const std::string& o, const std::string& a) const {
  Hid attr = open_attr(id_, path_, o, a);
  int64_t v = 0;
  if (H5Aread(attr, H5T_NATIVE_INT64, &v) < 0) fail(path_, "cannot read attribute " + o + "@" + a);
  return v;
}

}  // namespace sirl
