#include "results/environment_file.h"

#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "results/durable.h"
#include "results/h5.h"
#include "results/isolated_read.h"

namespace sirl {

namespace {

using u64 = uint64_t;

[[noreturn]] void fail(const EnvironmentFileSpec& s, const std::string& what) {
  throw std::invalid_argument(s.path + ": " + what);
}

// A 2-D or 3-D array of float32, or float64 rounded to float32 (numpy's default), after its
// shape was checked against `expect` (-1: any extent).
std::vector<float> read_floats(const H5File& f, const std::string& name,
                               const std::vector<int64_t>& expect) {
  try {
    return f.read_f32(name, expect);
  } catch (const H5Error&) {
    const std::vector<double> v = f.read_f64(name, expect);
    return std::vector<float>(v.begin(), v.end());
  }
}

std::string shape_text(const std::vector<u64>& dims) {
  std::string s = "[";
  for (size_t i = 0; i < dims.size(); ++i) s += (i ? ", " : "") + std::to_string(dims[i]);
  return s + "]";
}

Dataset read_unsandboxed(const EnvironmentFileSpec& s) {
  const H5File f = H5File::open_read(s.path);
  const std::string g = "/datasets/" + s.group;
  if (!f.exists(g))
    fail(s, "no group " + g +
                " (an environment file holds /datasets/<name>/inputs and "
                "features_raw; name the group with `dataset = \"...\"`)");
  const std::string in = g + "/inputs", feat = g + "/features_raw", pts = g + "/points";
  for (const std::string& name : {in, feat})
    if (!f.exists(name)) fail(s, "no array " + name);
  for (const std::string& name : {in, feat, pts})
    if (f.exists(name) && f.stored_outside(name))
      fail(s, name +
                  " keeps its values outside the file (external or virtual storage), which "
                  "its XXH3-128 does not cover: write the values into the file itself");
  // Every shape before any value is read: a crafted extent allocates nothing.
  const std::vector<u64> di = f.dims(in), df = f.dims(feat);
  if (di.size() != 2) fail(s, in + " is " + shape_text(di) + "; inputs are [T, D]");
  if (df.size() != 2) fail(s, feat + " is " + shape_text(df) + "; true features are [T, F]");
  const u64 T = di[0], D = di[1], F = df[1];
  if (df[0] != T)
    fail(s, feat + " has " + std::to_string(df[0]) + " rows; inputs have " + std::to_string(T));
  if (T < u64(kMinFileTrajectories))
    fail(s, std::to_string(T) + " trajectories; a similarity query needs at least " +
                std::to_string(kMinFileTrajectories));
  if (T > kMaxFileTrajectories)
    fail(s, std::to_string(T) + " trajectories; at most " + std::to_string(kMaxFileTrajectories));
  if (D < 1 || D > kMaxFileInputDim)
    fail(s, "inputs of " + std::to_string(D) + " floats per trajectory; 1 to " +
                std::to_string(kMaxFileInputDim));
  if (T * D > kMaxFileValues)
    fail(s, "inputs of " + std::to_string(T) + " x " + std::to_string(D) + " values; at most " +
                std::to_string(kMaxFileValues) + " in all");
  if (F < 1 || F > kMaxFileFeatures)
    fail(s, std::to_string(F) + " true features; 1 to " + std::to_string(kMaxFileFeatures));
  u64 L = 0, P = 0;
  if (f.exists(pts)) {
    const std::vector<u64> dp = f.dims(pts);
    if (dp.size() != 3 || dp[0] != T || (dp[2] != 2 && dp[2] != 3) || dp[1] < 1 ||
        dp[1] > kMaxFilePointsPerTrajectory)
      fail(s, pts + " is " + shape_text(dp) +
                  "; points are [T, L, 2 or 3] with T = " + std::to_string(T) +
                  " and 1 <= L <= " + std::to_string(kMaxFilePointsPerTrajectory));
    L = dp[1];
    P = dp[2];
  }

  Dataset d;
  d.env = s.env;
  d.count = int64_t(T);
  d.input_dim = int(D);
  try {
    d.inputs = read_floats(f, in, {-1, -1});
    d.features_raw = read_floats(f, feat, {-1, -1});
    if (L > 0) d.points = read_floats(f, pts, {-1, -1, -1});
  } catch (const H5Error& e) {
    fail(s, std::string("an array is neither float32 nor float64 (") + e.what() + ")");
  }
  if (!f.has_attr(feat, "feature_names"))
    fail(s, feat + " has no @feature_names (one name per column)");
  d.feature_names = f.attr_strings(feat, "feature_names");
  if (d.feature_names.size() != F)
    fail(s, feat + "@feature_names has " + std::to_string(d.feature_names.size()) + " names for " +
                std::to_string(F) + " columns");
  std::set<std::string> seen;
  for (const std::string& n : d.feature_names) {
    bool ok = !n.empty() && n.size() <= 64;
    for (char c : n) ok = ok && c >= 0x20 && c != 0x7f;
    if (!ok) fail(s, "a feature name must be 1-64 printable characters");
    if (!seen.insert(n).second) fail(s, "the feature name '" + n + "' appears twice");
  }
  d.feature_units =
      f.has_attr(feat, "units") ? f.attr_strings(feat, "units") : std::vector<std::string>(F, "");
  if (d.feature_units.size() != F)
    fail(s, feat + "@units has " + std::to_string(d.feature_units.size()) + " entries for " +
                std::to_string(F) + " features");
  d.input_description =
      f.has_attr(in, "description") ? f.attr_string(in, "description") : "read from " + s.path;

  const auto finite = [&](const std::vector<float>& v, const std::string& name, u64 row_len) {
    for (size_t i = 0; i < v.size(); ++i)
      if (!std::isfinite(v[i]))
        fail(s, name + " has a non-finite value (" + std::to_string(v[i]) + ") in row " +
                    std::to_string(i / row_len));
  };
  finite(d.inputs, in, D);
  finite(d.features_raw, feat, F);
  if (L > 0) {
    finite(d.points, pts, L * P);
    d.point_len = int(L);
    d.point_dim = int(P);
  }
  normalise_features(d);
  for (u64 k = 0; k < F; ++k)
    if (!(d.feature_max[k] > d.feature_min[k]))
      fail(s, "the feature '" + d.feature_names[k] + "' is the same (" +
                  std::to_string(d.feature_min[k]) + ") for all " + std::to_string(T) +
                  " trajectories: the simulated humans could not tell any two apart by it");
  return d;
}

}  // namespace

Dataset read_environment_file(const EnvironmentFileSpec& s) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(s.path, ec))
    fail(s, std::filesystem::exists(s.path, ec) ? "not a regular file" : "no such file");
  std::string digest;
  try {
    digest = file_digest(s.path);
  } catch (const std::runtime_error& e) {
    fail(s, e.what());
  }
  if (digest != s.xxh3)
    fail(s, "its XXH3-128 is " + digest + ", not the " + s.xxh3 +
                " the profile names (the file changed since it was declared: check it, then put "
                "its new digest in the profile)");
  try {
    // Untrusted HDF5: a crafted file may crash the library itself, so a child reads it first.
    read_in_child_first(s.path, [&] { read_unsandboxed(s); });
    return read_unsandboxed(s);
  } catch (const H5Error& e) {
    throw std::invalid_argument(e.what());
  }
}

}  // namespace sirl
