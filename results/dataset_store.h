// The HDF5 layout of an environment's dataset and query sets, under /datasets/<env>/:
//   inputs [T, D] f32, features_raw / features [T, F] f32, feature_min / feature_max [F],
//   objects [O, 2|3], rewards/{test, multipref10, multipref50, singlepref} [K, F],
//   queries/similarity [N, 3] i32, queries/<set>/{pairs [N, 2] i32, label [N] f32, human [N] i32},
//   queries/tpa/{pairs [R, P, 2], label [R, P]} (+ @train), queries/fpe/{train, test} i32.
// Every array carries a `description` attribute (meaning, units, shape); the group carries the
// generator seed, engine version and the teacher. The reader checks every shape and type.
#pragma once
#include <cstdint>
#include <string>

#include "datasets/query_bundle.h"

namespace sirl {

class H5File;

void write_dataset(H5File& f, const Dataset& d, const QueryBundle& q,
                   const std::string& engine_version);

// One seed's query sets of an environment whose /datasets/<env> is written already:
// /datasets/<env>/seeds/s<seed>/{rewards, queries} in the layout above, with @query_seed (the
// training data a method trained elsewhere needs, per seed: `sirl dataset --profile`).
void write_seed_queries(H5File& f, const std::string& env, int64_t seed, const QueryBundle& q);

struct StoredDataset {
  Dataset data;
  QueryBundle queries;
  std::string engine_version;
};
// Throws sirl::H5Error naming the file and the object on a missing, mis-shaped or mistyped array.
StoredDataset read_dataset(const H5File& f, const std::string& env);

}  // namespace sirl
