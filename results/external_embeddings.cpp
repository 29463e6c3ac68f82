#include "results/external_embeddings.h"

#include <filesystem>
#include <stdexcept>

#include "results/durable.h"
#include "results/h5.h"

namespace sirl {

std::string external_embedding_name(const std::string& env, int64_t seed, int64_t N) {
  return "/" + env + "/s" + std::to_string(seed) + "/N" + std::to_string(N);
}

ExternalEmbedding read_external_embedding(const std::string& file, const std::string& xxh3,
                                          const std::string& env, int64_t seed, int64_t N,
                                          int64_t T) {
  auto fail = [&](const std::string& what) { throw std::invalid_argument(file + ": " + what); };
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) fail("no such file");
  std::string digest;
  try {
    digest = file_digest(file);
  } catch (const std::runtime_error& e) {
    fail(e.what());
  }
  if (digest != xxh3)
    fail("its XXH3-128 is " + digest + ", not the " + xxh3 +
         " the profile names (the file changed since; evaluate it again to use it)");
  const std::string name = external_embedding_name(env, seed, N);
  try {
    const H5File f = H5File::open_read(file);
    if (!f.exists(name))
      fail("no array " + name + " (the embedding of Ξ for env " + env + ", seed " +
           std::to_string(seed) + ", N " + std::to_string(N) + ")");
    // Values in another file (external or virtual storage) escape the digest checked above.
    if (f.stored_outside(name))
      fail(name +
           " keeps its values outside the file (external or virtual storage), which its "
           "XXH3-128 does not cover: write the values into the file itself");
    // The shape first, so a file of the wrong size is refused before anything is allocated.
    std::vector<uint64_t> dims = f.dims(name);
    if (dims.size() != 2)
      fail(name + " has " + std::to_string(dims.size()) + " dimensions; an embedding is [T, d]");
    if (dims[0] != uint64_t(T))
      fail(name + " has " + std::to_string(dims[0]) + " rows; Ξ of " + env + " has " +
           std::to_string(T) + " trajectories");
    if (dims[1] > uint64_t(kMaxExternalDim))
      fail(name + " has d = " + std::to_string(dims[1]) + " columns; an embedding has at most " +
           std::to_string(kMaxExternalDim));
    ExternalEmbedding e;
    try {
      e.values = f.read_f32(name, {-1, -1}, &dims);
    } catch (const H5Error&) {  // numpy's default float64 is welcome too: rounded to float32
      std::vector<double> v;
      try {
        v = f.read_f64(name, {-1, -1}, &dims);
      } catch (const H5Error&) {
        fail(name + " is not a 2-D float32 or float64 array [T, d]");
      }
      e.values.assign(v.begin(), v.end());
    }
    e.rows = int64_t(dims[0]);
    e.dim = int(dims[1]);
    if (e.rows != T)
      fail(name + " has " + std::to_string(e.rows) + " rows; Ξ of " + env + " has " +
           std::to_string(T) + " trajectories");
    if (e.dim < 1) fail(name + " has no columns");

    return e;
  } catch (const H5Error& e) {
    throw std::invalid_argument(e.what());
  }
}

}  // namespace sirl
