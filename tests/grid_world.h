// The GridRobot world, the fast hyper-parameters and the trained representations that the
// methods, TPA and FPE tests share (each test is its own process, so each builds them once).
#pragma once

#include <algorithm>
#include <vector>

#include "datasets/grid_robot.h"
#include "datasets/query_bundle.h"
#include "engine/hyperparams.h"
#include "engine/methods.h"
#include "engine/train_vae.h"

namespace sirl::test {

// One GridRobot world shared by the tests (built once: the enumeration is deterministic).
struct World {
  Dataset d = make_grid_dataset();
  QueryBundle bundle;
  World() {
    QueryBundleConfig qc;
    qc.similarity = 500;
    qc.preference = 500;
    qc.tpa_pairs = 250;
    qc.fpe_trajectories = 1000;
    bundle = make_query_bundle(d, qc, 7);
  }
};
inline const World& world() {
  static const World w;
  return w;
}

// The paper's grid hyper-parameters with fewer epochs, so each training run is well under a
// second; everything else (widths, learning rates, batch sizes, L2) stays the paper's.
inline Hyper fast_hyper() {
  Hyper h = paper_hyper("grid");
  h.sirl.epochs = 150;
  h.vae.epochs = 20;
  h.pref.epochs = 100;
  h.tpa.epochs = 150;
  return h;
}

// fast_hyper with the reward heads capped at `epochs` and stopping by `stop` ("converged",
// "converged-unfrozen") from a minimum of 30 epochs, so Grid heads stop well inside the cap.
inline Hyper stopping_hyper(int epochs, const char* stop) {
  Hyper h = fast_hyper();
  h.tpa.epochs = epochs;
  h.tpa_stop = stop;
  h.tpa_stop_min_epochs = 30;
  return h;
}

inline double tail_mean(const std::vector<float>& c) {
  double s = 0;
  const size_t n = std::max<size_t>(1, c.size() / 10);
  for (size_t i = c.size() - n; i < c.size(); ++i) s += c[i];
  return s / double(n);
}

// Trained once and shared: SIRL N=500, VAE and Random.
struct Trained {
  VaeModel vae;
  Representation sirl, vae_rep, random;
  Trained() {
    const World& w = world();
    const Hyper h = fast_hyper();
    vae = train_vae(w.d, h, 11);
    MethodConfig c{Method::sirl, 500, false, h};
    sirl = train_representation(w.d, w.bundle, c, 11);
    c.method = Method::vae;
    vae_rep = train_representation(w.d, w.bundle, c, 11, &vae);
    c.method = Method::random;
    random = train_representation(w.d, w.bundle, c, 11);
  }
};
inline const Trained& trained() {
  static const Trained t;
  return t;
}

// φ = identity on a world whose inputs are the normalised true features: the head sees φ*.
inline Representation true_feature_phi(Dataset& d) {
  d.inputs = d.features;
  d.input_dim = d.feature_count();
  Representation r;
  r.shape = MlpShape{{4, 4}};
  r.params = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0};
  return r;
}

}  // namespace sirl::test
