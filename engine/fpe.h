// Feature Prediction Error (paper §4.3): how linearly recoverable the true features are from φ.
#pragma once
#include "datasets/dataset.h"
#include "datasets/queries.h"
#include "engine/representation.h"

namespace sirl {

struct FpeResult {
  double fpe = 0;           // test MSE over the 20 % split, mean over test rows × features
  double train_mse = 0;     // the probe's fit on its own 80 %
  double ridge_weight = 0;  // the raw reference's ridge weight (0: least squares)
};

// φ frozen; a linear probe (with bias) fitted from φ(ξ) to the normalised φ*(ξ) on split.train,
// scored on split.test. The probe is least squares (the paper's), but for the raw reference:
// ridge with its weight chosen by leave-one-out error on the training rows
// (kernels/linear_probe.h), as its input is wider than the rows.
FpeResult evaluate_fpe(const Representation& rep, const Dataset& d, const FpeSplit& split,
                       int threads = 1);

}  // namespace sirl
