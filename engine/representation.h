// A learned embedding φ: trajectory → R^d, and the methods that produce one (paper §4.3).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/dataset.h"
#include "engine/hyperparams.h"
#include "engine/method_catalog.h"
#include "kernels/mlp.h"

namespace sirl {

struct Representation {
  MlpShape shape;             // input → hidden… → d
  std::vector<float> params;  // [P] flat, layer by layer (kernels/mlp.h)
  Method method = Method::random;
  bool vae_pretrain = false;
  int64_t queries = 0;            // N used for training (0 for VAE and Random)
  std::vector<float> loss_curve;  // mean training loss per epoch (empty for Random)
  // Preference methods: the K reward heads trained with φ, [K, d + 1] (w, c) per human. Kept in
  // memory for inspection; not part of a task's record (FPE and TPA use φ alone).
  std::vector<float> heads;
  double train_flops = 0;  // multiply-adds ×2 spent training (excluding VAE pre-training)
  // What the epochs not run would have cost (SIRL's exact skip at a fixed point,
  // engine/train_sirl.cpp; a preference φ stopped by pref.stop): train_flops + skipped_flops is
  // the protocol's count.
  double skipped_flops = 0;
  // φ(Ξ) [T, d] when it is known: a learned φ's embedding of Ξ as its task stored it, or an
  // external representation's as handed in (then params are empty and shape is {input width, d},
  // a placeholder for the sizes). FPE and frozen TPA look rows up here when it is not empty, so
  // they probe exactly the embedding the results file holds, and an external method's cells run
  // the same code as a built-in one's.
  std::vector<float> table;
  int dim() const { return shape.out(); }
  // No weights: φ(Ξ) is given (external: `table`; truth, raw: the dataset's features or inputs).
  bool is_table() const { return method == Method::external || is_reference(method); }
};

// A reference representation of dataset d (m = truth: φ(ξ) = d's normalised features [F];
// m = raw: φ(ξ) = d's input [input_dim]). It holds no copy: embed_rows reads d. Throws
// std::invalid_argument for a method that is not a reference.
Representation reference_representation(Method m, const Dataset& d);

// An external representation: φ(Ξ) given as the rows [T, d] of `table` for a dataset whose inputs
// are `input_dim` wide. Throws std::invalid_argument if table is not T·d floats, d < 1, or a value
// is NaN or ±Inf (naming the first).
Representation table_representation(std::vector<float> table, int64_t T, int d, int input_dim);

// φ's shape for an input width: in → phi_hidden… → embedding_dim.
MlpShape phi_shape(int in, const Hyper& h);

// out [n, d] = φ(X [n, in]), in chunks so memory stays bounded for any n. A learned φ only (an
// external one has no weights: std::logic_error).
void embed(const Representation& rep, const float* X, int64_t n, float* out, int threads = 1);

// φ over a whole trajectory space in one pass: the embedding out [n, d] and, for each hidden
// layer followed by a ReLU, the fraction of its units that are 0 on every one of the n rows
// ("dead": a φ whose last hidden layer is all dead is a constant map, and no gradient reaches
// the layers below it, so no head on it can learn).
struct EmbeddingPass {
  std::vector<float> embedding;      // [n, d]
  std::vector<float> dead_fraction;  // [hidden layers with a ReLU]
};
EmbeddingPass embed_all(const Representation& rep, const float* X, int64_t n, int threads = 1);

// φ(ξ) for the rows `rows` of Ξ = d, [rows, dim]: a reference's rows of d, the rows of rep.table
// when it holds φ(Ξ), else d's inputs of those rows embedded (in chunks, as embed). The two can
// differ in the last bits: the GEMM kernels pick their blocking by row count, so a row computed
// among 200 others need not equal the same row computed in embed_all's chunks of 1024.
std::vector<float> embed_rows(const Representation& rep, const Dataset& d,
                              const std::vector<int32_t>& rows, int threads = 1);

// Throws std::runtime_error naming `what` if any value is NaN or ±Inf.
void require_finite(const std::vector<float>& v, const std::string& what);

}  // namespace sirl
