#include "experiment/calibration.h"

#include <algorithm>

#include "engine/methods.h"

namespace sirl {

CalibrationSample make_calibration_sample(const Dataset& d, const QueryBundleConfig& queries,
                                          const Hyper& hyper, bool sampled) {
  CalibrationSample s;
  s.data = &d;
  s.hyper = hyper;
  s.sampled = sampled;
  QueryBundleConfig qc = queries;
  qc.similarity = qc.preference = 200;
  qc.fpe_trajectories = std::min<int64_t>(qc.fpe_trajectories, d.count);
  s.bundle = make_query_bundle(d, qc, 1);
  s.phi = train_representation(
      d, s.bundle, MethodConfig{Method::sirl, 200, false, calibration_lengths(s, 1)}, 1);
  return s;
}

Hyper calibration_lengths(const CalibrationSample& s, int scale) {
  Hyper x = s.hyper;
  x.sirl.epochs = (s.sampled ? 1 : 10) * scale;
  x.pref.epochs = (s.sampled ? 1 : 5) * scale;
  x.vae.epochs = scale;
  x.tpa.epochs = (s.sampled ? 1 : 5) * scale;
  return x;
}

}  // namespace sirl
