// How a computation runs, as opposed to what it computes (MethodConfig, TpaConfig, ActiveConfig,
// Hyper): the threads its kernels use and where its training saves and resumes. Nothing here
// changes a result's bits: every kernel gives the same bits on any thread count, and a resumed
// training continues bit for bit (tests/test_checkpoint.cpp).
#pragma once

namespace sirl {

class Checkpointer;

// Steps a model takes in a row before the next model's, when models train one after another
// (engine/epochs.h, run_model_epochs): long enough that its weights stay in cache.
inline constexpr int kStretchSteps = 32;

struct Execution {
  int threads = 1;
  Checkpointer* checkpointer = nullptr;  // saves / resumes the training (engine/checkpoint.h)
  // TPA: the heads train one after another, each this many steps in a row (rounded up to whole
  // epochs) before the next; checkpoints fall between.
  int stretch_steps = kStretchSteps;
};

}  // namespace sirl
