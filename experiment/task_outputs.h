// A task's outputs as a TaskRecord and back. The fresh path stores what it computed with put_*
// and hands later tasks the object get_* rebuilds from that record; a resumed run calls the same
// get_* on the committed record. So a resumed run's inputs and file equal a fresh run's exactly.
#pragma once
#include <string>

#include "datasets/queries.h"
#include "engine/representation.h"
#include "engine/train_vae.h"
#include "results/task_record.h"

namespace sirl {

// φ: params, loss_curve, the whole network shape (widths, output ReLU, linear layers), method,
// VAE pre-training, N and training FLOPs.
void put_representation(const Representation& r, TaskRecord& rec);
// Throws std::runtime_error naming the record if a field is missing or inconsistent.
Representation get_representation(const TaskRecord& rec);

// The VAE: params, the loss curve and its two terms, the ELBO form, the shapes, the posterior's
// per-latent KL and the reconstruction error.
void put_vae(const VaeModel& v, TaskRecord& rec);
VaeModel get_vae(const TaskRecord& rec);

// Similarity triplets: "queries" [count, 3] row indices (exact in float up to 2^24 rows) and the
// skipped count. Throws std::runtime_error naming the record if malformed.
void put_triplets(const TripletSet& q, TaskRecord& rec);
TripletSet get_triplets(const TaskRecord& rec);

// "19,128,128,6" and back (throws std::runtime_error on a malformed list).
std::string int_list_text(const std::vector<int>& v);
std::vector<int> parse_int_list(const std::string& text, const std::string& what);

}  // namespace sirl
