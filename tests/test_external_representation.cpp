// An external representation (φ(Ξ) handed in as a table, `sirl evaluate`): FPE and frozen TPA look
// its rows up, and feeding the engine's own φ(Ξ) through that path reproduces φ's cells bit for
// bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include "engine/fpe.h"
#include "engine/tpa.h"
#include "tests/grid_world.h"

namespace sirl {
namespace {

using namespace test;

Representation as_table(const Representation& phi, const Dataset& d) {
  return table_representation(embed_all(phi, d.inputs.data(), d.count).embedding, d.count,
                              phi.dim(), d.input_dim);
}

bool identical_floats(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(ExternalRepresentation, ALearnedPhiWithItsEmbeddingOfXiReadsRowsFromIt) {
  // A rep task hands later tasks φ with its stored embedding of Ξ: embed_rows returns those rows
  // bit for bit, in the order asked (the GEMM kernels choose their blocking by row count, so
  // recomputing a row among a few others need not give the same last bits).
  const World& w = world();
  Representation phi = trained().sirl;
  phi.table = embed_all(phi, w.d.inputs.data(), w.d.count).embedding;
  const int d = phi.dim();
  const std::vector<int32_t> rows{5, 1959, 0, 1024, 1023, 5};
  const std::vector<float> e = embed_rows(phi, w.d, rows);
  for (size_t i = 0; i < rows.size(); ++i)
    EXPECT_EQ(0, std::memcmp(e.data() + i * d, phi.table.data() + size_t(rows[i]) * d, d * 4))
        << "row " << rows[i];
  // ... and FPE reads them: another φ's table under the same weights changes the result.
  Representation other = phi;
  other.table = embed_all(trained().random, w.d.inputs.data(), w.d.count).embedding;
  EXPECT_NE(evaluate_fpe(phi, w.d, w.bundle.fpe).fpe, evaluate_fpe(other, w.d, w.bundle.fpe).fpe);
  // A table of the wrong number of rows is refused, not read past its end.
  other.table.resize(other.table.size() - size_t(d));
  EXPECT_THROW(embed_rows(other, w.d, rows), std::invalid_argument);
}

TEST(ExternalRepresentation, TheEnginesOwnEmbeddingGivesBitIdenticalFpeAndFrozenTpa) {
  const World& w = world();
  for (const Representation* learned : {&trained().sirl, &trained().random}) {
    Representation built_in = *learned;  // as a rep task hands it on: with its embedding of Ξ
    built_in.table = embed_all(*learned, w.d.inputs.data(), w.d.count).embedding;
    const Representation* phi = &built_in;
    const Representation ext = as_table(*learned, w.d);
    const FpeResult a = evaluate_fpe(*phi, w.d, w.bundle.fpe),
                    b = evaluate_fpe(ext, w.d, w.bundle.fpe);
    EXPECT_EQ(a.fpe, b.fpe);
    EXPECT_EQ(a.train_mse, b.train_mse);
    const TpaConfig c{10, true, fast_hyper()};
    const TpaResult ta = evaluate_tpa(*phi, w.d, w.bundle.tpa, c, 3);
    const TpaResult tb = evaluate_tpa(ext, w.d, w.bundle.tpa, c, 3);
    EXPECT_EQ(ta.accuracy, tb.accuracy);
    EXPECT_EQ(ta.train_accuracy, tb.train_accuracy);
    EXPECT_TRUE(identical_floats(ta.loss_curves, tb.loss_curves));
    EXPECT_EQ(ta.mean, tb.mean);
  }
}

TEST(ExternalRepresentation, ATableIsLookedUpNotComputed) {
  // A table that is not any φ's output: FPE on the true features themselves is a linear probe
  // of the targets on themselves, so its error is ~0 (within float rounding), and any row order
  // mistake in the lookup would show.
  const World& w = world();
  const Representation ext =
      table_representation(w.d.features, w.d.count, w.d.feature_count(), w.d.input_dim);
  EXPECT_LT(evaluate_fpe(ext, w.d, w.bundle.fpe).fpe, 1e-9);
  std::vector<float> shuffled = w.d.features;  // rows rotated by one: the probe cannot fit
  std::rotate(shuffled.begin(), shuffled.begin() + w.d.feature_count(), shuffled.end());
  const Representation bad =
      table_representation(shuffled, w.d.count, w.d.feature_count(), w.d.input_dim);
  EXPECT_GT(evaluate_fpe(bad, w.d, w.bundle.fpe).fpe, 1e-3);
}

TEST(ExternalRepresentation, RefusesBadTablesAndUnfrozenCells) {
  const World& w = world();
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(message([&] {
              table_representation(std::vector<float>(10), 3, 3, 19);
            }).find("needs 9 values, got 10"),
            std::string::npos);
  EXPECT_NE(message([&] { table_representation({}, 3, 0, 19); }).find("d >= 1"), std::string::npos);
  std::vector<float> t(6, 1.f);
  t[4] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(message([&] { table_representation(t, 3, 2, 19); }).find("row 2, column 0"),
            std::string::npos);
  const Representation ext = as_table(trained().sirl, w.d);
  EXPECT_NE(message([&] {
              evaluate_tpa(ext, w.d, w.bundle.tpa, TpaConfig{10, false, fast_hyper()}, 3);
            }).find("frozen cells only"),
            std::string::npos);
  std::vector<float> out(6);
  EXPECT_THROW(embed(ext, w.d.inputs.data(), 1, out.data()), std::logic_error);
}

}  // namespace
}  // namespace sirl
