// The file a representation trained outside the engine hands in (`sirl evaluate`, a profile's
// [external.<name>]): its embedding of Ξ for every environment × seed × N the profile runs,
//   /<env>/s<seed>/N<N>   float32 [T, d]   row i = φ(ξ_i), Ξ in the engine's order (the rows of
//                                          /datasets/<env>/inputs of `sirl dataset --profile`)
// (float64 is read too and rounded to float32, the precision every embedding has in the engine).
// d is the method's own (any d ≥ 1, the same for every array of one environment). The file is
// identified by its XXH3-128 digest (what `xxh128sum FILE` prints), checked before HDF5 reads it.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace sirl {

// The widest embedding accepted (a reward head's first layer is d × its width, per test reward).
inline constexpr int kMaxExternalDim = 4096;

// "/grid/s0/N100".
std::string external_embedding_name(const std::string& env, int64_t seed, int64_t N);

struct ExternalEmbedding {
  std::vector<float> values;  // [T, d]
  int64_t rows = 0;
  int dim = 0;
};

// Reads one array of `file` after checking that the file's digest is `xxh3`. Throws
// std::invalid_argument with one line naming the file and what is wrong: another digest (the file
// changed since the profile named it), a missing array, another type than float32 or float64,
// another shape than [T, d ≥ 1]. Values are not checked here (table_representation refuses NaN and
// ±Inf).
ExternalEmbedding read_external_embedding(const std::string& file, const std::string& xxh3,
                                          const std::string& env, int64_t seed, int64_t N,
                                          int64_t T);

}  // namespace sirl
