// A task's outputs (φ, the VAE) through a record and a file, as the resume path reads them.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "experiment/task_outputs.h"
#include "results/h5.h"
#include "results/task_record.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {

// The resumed path rebuilds φ and the VAE from records with the same get_* the fresh path uses;
// everything a later task reads must survive the trip, including shape flags the profile does
// not determine (the VAE method's φ keeps a linear output even under phi.relu_output = true).
TEST(TaskOutputs, RepresentationAndVaeRoundTripThroughARecordAndAFile) {
  Representation r;
  r.shape.widths = {5, 7, 3};
  r.shape.relu_on_output = true;
  r.shape.linear_layers = {0};
  r.params.resize(r.shape.param_count());
  for (size_t i = 0; i < r.params.size(); ++i) r.params[i] = float(i) * 0.25f - 3;
  r.method = Method::multipref50;
  r.vae_pretrain = true;
  r.queries = 321;
  r.loss_curve = {3, 2, 1.5f};
  r.train_flops = 12345;
  TaskRecord rec;
  rec.key = "grid/s0/multipref50+vae/N321/rep";
  put_representation(r, rec);
  const test::ScratchDir scratch;
  const std::string path = scratch.file("outputs.h5");
  {
    H5File f = H5File::create(path);
    write_record(f, "/r", rec);
  }
  const TaskRecord back = read_record(H5File::open_read(path), "/r");
  const Representation g = get_representation(back);
  EXPECT_EQ(g.shape.widths, r.shape.widths);
  EXPECT_EQ(g.shape.relu_on_output, true);
  EXPECT_EQ(g.shape.linear_layers, r.shape.linear_layers);
  EXPECT_EQ(g.params, r.params);
  EXPECT_EQ(g.method, r.method);
  EXPECT_EQ(g.vae_pretrain, true);
  EXPECT_EQ(g.queries, 321);
  EXPECT_EQ(g.loss_curve, r.loss_curve);
  EXPECT_EQ(g.train_flops, 12345);

  VaeModel v;
  v.shape = make_vae_shape(5, {4}, 2);
  v.params.assign(v.shape.param_count(), 0.5f);
  v.elbo = VaeElbo::mean_over_inputs;
  v.loss_curve = {4, 3};
  v.reconstruction_curve = {3.5f, 2.5f};
  v.kl_curve = {50, 50};
  v.kl_per_dim = {0.002f, 1.5f};
  v.latent_mean = {0.5f, -2};
  v.latent_std = {3, 0.25f};
  v.standardize = false;
  v.reconstruction_mse = 0.125;
  v.train_flops = 99;
  TaskRecord vr;
  vr.key = "grid/s0/vae";
  put_vae(v, vr);
  const VaeModel w = get_vae(deserialize(serialize(vr)));
  EXPECT_EQ(w.shape.encoder.widths, v.shape.encoder.widths);
  EXPECT_EQ(w.shape.decoder.widths, v.shape.decoder.widths);
  EXPECT_EQ(w.params, v.params);
  EXPECT_EQ(w.elbo, VaeElbo::mean_over_inputs);
  EXPECT_EQ(w.loss_curve, v.loss_curve);
  EXPECT_EQ(w.reconstruction_curve, v.reconstruction_curve);
  EXPECT_EQ(w.kl_curve, v.kl_curve);
  EXPECT_EQ(w.kl_per_dim, v.kl_per_dim);
  EXPECT_EQ(w.latent_mean, v.latent_mean);
  EXPECT_EQ(w.latent_std, v.latent_std);
  EXPECT_FALSE(w.standardize);
  EXPECT_EQ(w.reconstruction_mse, 0.125);
  EXPECT_EQ(w.train_flops, 99);
  // The φ a VAE method task hands on keeps the VAE's curve (a resumed run's did not, once).
  EXPECT_EQ(vae_mean_encoder(w).loss_curve, v.loss_curve);

  // A record without weights (store_weights = false) names what is missing.
  vr.arrays.erase("params");
  try {
    get_vae(vr);
    ADD_FAILURE() << "a VAE without params was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("grid/s0/vae: the stored record has no 'params'"),
              std::string::npos)
        << e.what();
  }
}

// A record with an empty array (a task with nothing to keep in one of them) crosses between MPI
// ranks intact: the message carries its name and shape, no data (UBSan once caught a copy from
// the empty array's null pointer here).
TEST(TaskOutputs, AnEmptyArrayCrossesTheMessageFormat) {
  TaskRecord r;
  r.key = "grid/s0/x";
  r.kind = "tpa";
  r.num["seconds"] = 1.5;
  r.arrays["empty"].dims = {0, 6};
  r.arrays["full"].dims = {2};
  r.arrays["full"].data = {1.f, -2.f};
  const TaskRecord back = deserialize(serialize(r));
  EXPECT_EQ(back.key, r.key);
  EXPECT_EQ(back.num.at("seconds"), 1.5);
  EXPECT_EQ(back.arrays.at("empty").dims, (std::vector<uint64_t>{0, 6}));
  EXPECT_TRUE(back.arrays.at("empty").data.empty());
  EXPECT_EQ(back.arrays.at("full").data, r.arrays.at("full").data);
}

}  // namespace
}  // namespace sirl
