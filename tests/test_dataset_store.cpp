// The dataset file: round trips of Ξ, features and the query bundle, determinism with a
// different-seed contrast, and refusing files of the wrong shape or truncated.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "datasets/grid_robot.h"
#include "results/dataset_store.h"
#include "results/h5.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {
namespace fs = std::filesystem;

// A file in this process's scratch directory (removed with it when the process ends).
fs::path temp(const std::string& name) {
  static const test::ScratchDir scratch("sirl_dataset_store");
  return scratch.path() / (name + ".h5");
}

QueryBundle small_bundle(const Dataset& d, uint64_t seed = 42) {
  QueryBundleConfig c;
  c.similarity = 100;
  c.preference = 100;
  c.tpa_pairs = 50;
  c.fpe_trajectories = 300;
  c.teacher.beta = 20;
  c.teacher.mask = {1, 0, 1, 0};
  return make_query_bundle(d, c, seed);
}

TEST(DatasetStore, RoundTripIsExact) {
  const Dataset d = make_grid_dataset();
  const QueryBundle q = small_bundle(d);
  const auto path = temp("roundtrip");
  {
    H5File f = H5File::create(path);
    write_dataset(f, d, q, "test-version");
  }
  const H5File f = H5File::open_read(path);
  const StoredDataset s = read_dataset(f, "grid");
  EXPECT_EQ(s.engine_version, "test-version");
  EXPECT_EQ(s.data.inputs, d.inputs);
  EXPECT_EQ(s.data.features, d.features);
  EXPECT_EQ(s.data.features_raw, d.features_raw);
  EXPECT_EQ(s.data.feature_names, d.feature_names);
  EXPECT_EQ(s.data.feature_units, d.feature_units);
  EXPECT_EQ(s.data.feature_min, d.feature_min);
  EXPECT_EQ(s.data.object_positions, d.object_positions);
  EXPECT_EQ(s.data.object_names, d.object_names);
  EXPECT_EQ(s.queries.seed, 42u);
  EXPECT_EQ(s.queries.config.teacher.mask, q.config.teacher.mask);
  EXPECT_EQ(s.queries.config.teacher.beta, 20);
  EXPECT_EQ(s.queries.rewards.test.weights, q.rewards.test.weights);
  EXPECT_EQ(s.queries.rewards.multipref50.weights, q.rewards.multipref50.weights);
  EXPECT_EQ(s.queries.similarity.idx, q.similarity.idx);
  EXPECT_EQ(s.queries.multipref10.pairs, q.multipref10.pairs);
  EXPECT_EQ(s.queries.multipref10.label, q.multipref10.label);
  EXPECT_EQ(s.queries.multipref10.human, q.multipref10.human);
  ASSERT_EQ(s.queries.tpa.size(), 20u);
  for (int r = 0; r < 20; ++r) {
    EXPECT_EQ(s.queries.tpa[r].pairs.pairs, q.tpa[r].pairs.pairs);
    EXPECT_EQ(s.queries.tpa[r].pairs.label, q.tpa[r].pairs.label);
    EXPECT_EQ(s.queries.tpa[r].train, 40);
  }
  EXPECT_EQ(s.queries.fpe.train, q.fpe.train);
  EXPECT_EQ(s.queries.fpe.test, q.fpe.test);
  fs::remove(path);
}

TEST(DatasetStore, SameSeedSameBundleAnotherSeedAnotherBundle) {
  const Dataset d = make_grid_dataset();
  const auto a = small_bundle(d), b = small_bundle(d), c = small_bundle(d, 43);
  EXPECT_EQ(a.similarity.idx, b.similarity.idx);
  EXPECT_EQ(a.tpa[3].pairs.pairs, b.tpa[3].pairs.pairs);
  EXPECT_EQ(a.tpa[3].pairs.label, b.tpa[3].pairs.label);
  EXPECT_EQ(a.rewards.test.weights, b.rewards.test.weights);
  EXPECT_EQ(a.fpe.train, b.fpe.train);
  // Every query set and reward set changes with the seed (a stream ignoring it would not).
  EXPECT_NE(a.similarity.idx, c.similarity.idx);
  EXPECT_NE(a.singlepref.pairs, c.singlepref.pairs);
  EXPECT_NE(a.multipref10.pairs, c.multipref10.pairs);
  EXPECT_NE(a.multipref50.pairs, c.multipref50.pairs);
  EXPECT_NE(a.tpa[3].pairs.pairs, c.tpa[3].pairs.pairs);
  EXPECT_NE(a.rewards.test.weights, c.rewards.test.weights);
  EXPECT_NE(a.rewards.multipref10.weights, c.rewards.multipref10.weights);
  EXPECT_NE(a.fpe.train, c.fpe.train);
}

TEST(DatasetStore, WrongShapeIsAClearError) {
  const auto path = temp("wrongshape");
  {
    H5File f = H5File::create(path);
    const Dataset d = make_grid_dataset();
    write_dataset(f, d, small_bundle(d), "v");
    std::vector<float> bad(10 * 3);
    f.write("/datasets/grid/features_raw", bad.data(), {10, 3});  // replace with a mis-shaped array
  }
  const H5File f = H5File::open_read(path);
  try {
    read_dataset(f, "grid");
    FAIL() << "expected H5Error";
  } catch (const H5Error& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "/datasets/grid/features_raw has shape [10, 3], expected [1960, 4]"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(read_dataset(f, "jaco"), H5Error);
  fs::remove(path);
}

TEST(DatasetStore, TruncatedOrForeignFilesAreRefused) {
  const auto path = temp("trunc"), junk = temp("junk");
  {
    H5File f = H5File::create(path);
    const Dataset d = make_grid_dataset();
    write_dataset(f, d, small_bundle(d), "v");
  }
  fs::resize_file(path, fs::file_size(path) / 2);
  EXPECT_THROW(
      {
        const H5File f = H5File::open_read(path);
        read_dataset(f, "grid");
      },
      H5Error);
  std::ofstream(junk) << "this is not HDF5";
  EXPECT_THROW(H5File::open_read(junk), H5Error);
  EXPECT_THROW(H5File::open_read("/nonexistent/file.h5"), H5Error);
  fs::remove(path);
  fs::remove(junk);
}

}  // namespace
}  // namespace sirl
