#include "experiment/task_outputs.h"

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace sirl {

namespace {

const std::vector<float>& need_array(const TaskRecord& rec, const std::string& name) {
  auto it = rec.arrays.find(name);
  if (it == rec.arrays.end())
    throw std::runtime_error(rec.key + ": the stored record has no '" + name +
                             "' (written by an older engine, or without weights: rerun with "
                             "--force to recompute)");
  return it->second.data;
}
double need_num(const TaskRecord& rec, const std::string& name) {
  auto it = rec.num.find(name);
  if (it == rec.num.end()) throw std::runtime_error(rec.key + ": the stored record has no " + name);
  return it->second;
}
const std::string& need_text(const TaskRecord& rec, const std::string& name) {
  auto it = rec.text.find(name);
  if (it == rec.text.end())
    throw std::runtime_error(rec.key + ": the stored record has no " + name);
  return it->second;
}

void put_shape(const MlpShape& s, const std::string& prefix, TaskRecord& rec) {
  rec.text[prefix + "widths"] = int_list_text(s.widths);
  rec.text[prefix + "linear_layers"] = int_list_text(s.linear_layers);
  rec.num[prefix + "relu_output"] = s.relu_on_output;
  if (s.bf16_products) rec.num[prefix + "bf16_products"] = 1;  // fp32 records stay as before
}
MlpShape get_shape(const TaskRecord& rec, const std::string& prefix) {
  MlpShape s;
  s.widths = parse_int_list(need_text(rec, prefix + "widths"), rec.key + " " + prefix + "widths");
  s.linear_layers = parse_int_list(need_text(rec, prefix + "linear_layers"),
                                   rec.key + " " + prefix + "linear_layers");
  s.relu_on_output = need_num(rec, prefix + "relu_output") != 0;
  const auto bf16 = rec.num.find(prefix + "bf16_products");  // absent before engine 0.7.0: fp32
  s.bf16_products = bf16 != rec.num.end() && bf16->second != 0;
  try {
    validate(s);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(rec.key + ": stored network shape: " + e.what());
  }
  return s;
}

void check_size(const TaskRecord& rec, size_t have, size_t want, const char* what) {
  if (have != want)
    throw std::runtime_error(rec.key + ": stored " + what + " has " + std::to_string(have) +
                             " parameters, its shape needs " + std::to_string(want));
}

}  // namespace

std::string int_list_text(const std::vector<int>& v) {
  std::string s;
  for (int x : v) s += (s.empty() ? "" : ",") + std::to_string(x);
  return s;
}

std::vector<int> parse_int_list(const std::string& text, const std::string& what) {
  std::vector<int> out;
  size_t i = 0;
  while (i < text.size()) {
    const size_t j = std::min(text.find(',', i), text.size());
    int x = 0;
    auto [p, ec] = std::from_chars(text.data() + i, text.data() + j, x);
    if (ec != std::errc() || p != text.data() + j)
      throw std::runtime_error(what + ": '" + text + "' is not a list of integers");
    out.push_back(x);
    i = j + 1;
  }
  return out;
}

void put_representation(const Representation& r, TaskRecord& rec) {
  rec.arrays["params"] = TaskRecord::Array::of(r.params);
  rec.arrays["loss_curve"] = TaskRecord::Array::of(r.loss_curve);
  put_shape(r.shape, "", rec);
  rec.text["method"] = method_name(r.method);
  rec.num["vae"] = r.vae_pretrain;
  rec.num["queries"] = double(r.queries);
  rec.num["train_flops"] = r.train_flops;
}

Representation get_representation(const TaskRecord& rec) {
  Representation r;
  r.shape = get_shape(rec, "");
  // An external representation has no weights, only its embedding of Ξ; a learned φ has both
  // (records of any engine version store the embedding: FPE and frozen TPA read its rows).
  if (auto e = rec.arrays.find("embedding"); e != rec.arrays.end()) r.table = e->second.data;
  if (need_text(rec, "method") != method_name(Method::external)) {
    r.params = need_array(rec, "params");
    check_size(rec, r.params.size(), r.shape.param_count(), "φ");
  }
  r.loss_curve = need_array(rec, "loss_curve");
  try {
    r.method = parse_method(need_text(rec, "method"));
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(rec.key + ": " + e.what());
  }
  r.vae_pretrain = need_num(rec, "vae") != 0;
  r.queries = int64_t(need_num(rec, "queries"));
  r.train_flops = need_num(rec, "train_flops");
  return r;
}

void put_vae(const VaeModel& v, TaskRecord& rec) {
  rec.arrays["params"] = TaskRecord::Array::of(v.params);
  rec.arrays["loss_curve"] = TaskRecord::Array::of(v.loss_curve);
  rec.arrays["reconstruction_curve"] = TaskRecord::Array::of(v.reconstruction_curve);
  rec.arrays["kl_curve"] = TaskRecord::Array::of(v.kl_curve);
  rec.arrays["kl_per_dim"] = TaskRecord::Array::of(v.kl_per_dim);
  rec.arrays["latent_mean"] = TaskRecord::Array::of(v.latent_mean);
  rec.arrays["latent_std"] = TaskRecord::Array::of(v.latent_std);
  rec.num["standardize"] = v.standardize;
  put_shape(v.shape.encoder, "encoder_", rec);
  put_shape(v.shape.decoder, "decoder_", rec);
  rec.num["latent"] = v.shape.latent;
  rec.text["elbo"] = v.elbo == VaeElbo::sum_over_inputs ? "sum" : "mean";
  rec.num["reconstruction_mse"] = v.reconstruction_mse;
  rec.num["train_flops"] = v.train_flops;
}

VaeModel get_vae(const TaskRecord& rec) {
  VaeModel v;
  v.shape.encoder = get_shape(rec, "encoder_");
  v.shape.decoder = get_shape(rec, "decoder_");
  v.shape.latent = int(need_num(rec, "latent"));
  if (v.shape.encoder.out() != 2 * v.shape.latent || v.shape.decoder.in() != v.shape.latent)
    throw std::runtime_error(rec.key + ": stored VAE shapes do not match its latent width");
  v.params = need_array(rec, "params");
  check_size(rec, v.params.size(), v.shape.param_count(), "VAE");
  v.loss_curve = need_array(rec, "loss_curve");
  v.reconstruction_curve = need_array(rec, "reconstruction_curve");
  v.kl_curve = need_array(rec, "kl_curve");
  v.kl_per_dim = need_array(rec, "kl_per_dim");
  v.latent_mean = need_array(rec, "latent_mean");
  v.latent_std = need_array(rec, "latent_std");
  v.standardize = need_num(rec, "standardize") != 0;
  const std::string& elbo = need_text(rec, "elbo");
  if (elbo != "sum" && elbo != "mean")
    throw std::runtime_error(rec.key + ": unknown ELBO form '" + elbo + "'");
  v.elbo = elbo == "sum" ? VaeElbo::sum_over_inputs : VaeElbo::mean_over_inputs;
  v.reconstruction_mse = need_num(rec, "reconstruction_mse");
  v.train_flops = need_num(rec, "train_flops");
  return v;
}

void put_triplets(const TripletSet& q, TaskRecord& rec) {
  rec.arrays["queries"] =
      TaskRecord::Array::of(std::vector<float>(q.idx.begin(), q.idx.end()), {uint64_t(q.count), 3});
  rec.num["skipped"] = double(q.skipped);
}

TripletSet get_triplets(const TaskRecord& rec) {
  const std::vector<float>& a = need_array(rec, "queries");
  if (a.size() % 3 != 0)
    throw std::runtime_error(rec.key + ": its 'queries' do not come in triplets");
  TripletSet q;
  q.count = int64_t(a.size() / 3);
  q.skipped = int64_t(need_num(rec, "skipped"));
  q.idx.reserve(a.size());
  for (float v : a) {
    if (!(v >= 0) || v != std::floor(v) || v > float(1 << 24))
      throw std::runtime_error(rec.key + ": its 'queries' hold a value that is not a row index");
    q.idx.push_back(int32_t(v));
  }
  return q;
}

}  // namespace sirl
