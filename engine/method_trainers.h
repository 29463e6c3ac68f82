// The training functions the method catalog names (engine/method_catalog.cpp), one file each.
// Each trains rep in place: rep arrives with φ's shape and initial weights (seeded, or the VAE's
// encoder for "+vae") and leaves with its trained weights, loss curve and FLOP counts. The public
// entry point is train_representation (engine/methods.h), which checks the configuration first.
#pragma once
#include <cstdint>

namespace sirl {

struct Dataset;
struct QueryBundle;
struct MethodConfig;
struct Execution;
struct Representation;

// Signature of a method's training (MethodTraining::train).
using TrainFn = void (*)(const Dataset& d, const QueryBundle& bundle, const MethodConfig& cfg,
                         uint64_t seed, const Execution& ex, Representation& rep);

// engine/train_sirl.cpp: the symmetric triplet loss on the first N similarity answers.
void train_sirl(const Dataset& d, const QueryBundle& bundle, const MethodConfig& cfg, uint64_t seed,
                const Execution& ex, Representation& rep);
// engine/train_preferences.cpp: shared φ + K linear reward heads on N pairs of the method's
// preference set (MethodTraining::preferences).
void train_preferences(const Dataset& d, const QueryBundle& bundle, const MethodConfig& cfg,
                       uint64_t seed, const Execution& ex, Representation& rep);

}  // namespace sirl
