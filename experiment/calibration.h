// What `sirl plan` times a task with. A rate class is a short run of the real training code that
// a kind's tasks spend their FLOPs in; each kind names its class per task (TaskKindSpec::rate),
// declared beside the kind, and tasks of one class share one measurement. jobs/estimate.cpp times
// every class a plan's tasks name, on a small sample of each environment's Ξ, and knows none of
// them by name.
#pragma once
#include "datasets/dataset.h"
#include "datasets/query_bundle.h"
#include "engine/hyperparams.h"
#include "engine/representation.h"

namespace sirl {

// What a rate class trains on: a small Ξ of the environment, a query bundle of 200 similarity and
// 200 preference queries over it, the environment's hyper-parameters, and SIRL's φ after its
// shortest calibration length (what the probes and reward heads of a cell sit on).
struct CalibrationSample {
  const Dataset* data = nullptr;
  QueryBundle bundle;
  Hyper hyper;
  bool sampled = false;  // a sampled Ξ (JacoRobot): its GEMM-bound networks need few steps
  Representation phi;
};

// The sample for environment data d: the bundle from the profile's query settings (counts cut to
// 200 and Ξ's size), the φ trained at calibration length 1. One thread throughout, as tasks run.
CalibrationSample make_calibration_sample(const Dataset& d, const QueryBundleConfig& queries,
                                          const Hyper& hyper, bool sampled);

// The sample's hyper-parameters with every training `scale` × its calibration length (SIRL 10,
// preference pre-training 5, VAE 1, reward heads 5 epochs per unit; 1, 1, 1, 1 on a sampled Ξ).
Hyper calibration_lengths(const CalibrationSample& s, int scale);

struct RateClass {
  const char* name;  // "rep_sirl", …: `sirl plan` prints its rate as "<env>/<name>"
  // Runs the class's training on the sample at calibration length `scale` (1, then 3: the rate
  // is the difference's, so what a call costs once is not read as slow training); returns the
  // FLOPs it executed.
  double (*train)(const CalibrationSample& s, int scale);
  // The class's work has no epochs (a probe over Ξ): timed once at scale 1, its fixed cost folded
  // into the rate.
  bool one_length = false;
};

}  // namespace sirl
