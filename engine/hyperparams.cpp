#include "engine/hyperparams.h"

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <type_traits>
#include <variant>

#include "datasets/enum_names.h"
#include "datasets/environments.h"
#include "engine/hyper_key_docs.h"

namespace sirl {

Hyper paper_hyper(const std::string& env) {
  // The engine's defaults are GridRobot's; each environment's registration lists what differs
  // (JacoRobot: 1024-wide networks, its preference and VAE rates, its L2 weights).
  Hyper h;
  for (const auto& [key, value] : env_spec(env).hyper) set_hyper(h, key, value);
  validate(h);
  return h;
}

namespace {

// The doc lines of the four training schedules' keys (epochs, batch, lr, lr_decay), built once:
// for_each_field runs for every key set and every task described.
enum Schedule { kSirl, kVae, kPref, kTpa };
const std::array<std::string, 4>& schedule_docs(Schedule which) {
  static const auto docs = [] {
    const char* what[] = {"SIRL's φ", "the VAE", "a preference φ (SinglePref, MultiPref-K)",
                          "the TPA reward heads"};
    const char* items[] = {"triplets", "trajectories", "answered pairs", "answered pairs"};
    std::array<std::array<std::string, 4>, 4> d;
    for (int i = 0; i < 4; ++i)
      d[i] = {std::string("epochs of ") + what[i],
              std::string(items[i]) + " per step of " + what[i],
              std::string("Adam's learning rate for ") + what[i],
              std::string("the learning rate's factor per step for ") + what[i] + " (1: constant)"};
    return d;
  }();
  return docs[which];
}
const std::string& tpa_stop_doc() {
  static const std::string doc =
      "when a reward head stops: " + tpa_stop_rule_list() + " ([tpa] stop sets one per method)";
  return doc;
}

// Visits every field with its name and what it sets (f(name, field, doc), doc a string_view):
// the one table set_hyper, describe and the keys page (hyper_key_docs) read.
template <typename H, typename F>
void for_each_field(H& h, F&& f) {
  f("phi.hidden", h.phi_hidden, "φ's hidden layer widths (a ReLU after each)");
  f("phi.embedding_dim", h.embedding_dim, "φ's output: the embedding's dimension");
  f("phi.relu_output", h.phi_relu_output,
    "a ReLU on φ's embedding layer too (the lineage code leaves it linear)");
  auto schedule = [&](const std::string& p, auto& s, Schedule which) {
    const std::array<std::string, 4>& doc = schedule_docs(which);
    f(p + ".epochs", s.epochs, doc[0]);
    f(p + ".batch", s.batch, doc[1]);
    f(p + ".lr", s.adam.lr, doc[2]);
    f(p + ".lr_decay", s.adam.decay, doc[3]);
  };
  schedule("sirl", h.sirl, kSirl);
  f("sirl.margin", h.triplet_margin, "the triplet loss's margin");
  schedule("vae", h.vae, kVae);
  f("vae.kl_weight", h.vae_kl_weight, "the KL term's weight λ in the VAE's loss");
  f("vae.elbo", h.vae_elbo,
    "\"sum\" (squared error summed over inputs, KL over latents) or \"mean\" (averaged over "
    "inputs)");
  f("vae.standardize", h.vae_standardize,
    "φ is the encoder's mean standardised per latent over Ξ (folded into its last layer)");
  schedule("pref", h.pref, kPref);
  f("pref.l2", h.pref_l2, "the L2 penalty on a preference φ's predicted rewards");
  f("pref.stop", h.pref_stop,
    "when a preference φ ends: \"fixed\" (pref.epochs, the paper's) or \"converged\" (its "
    "loss has converged; pref.epochs the cap)");
  f("pref.stop_min_epochs", h.pref_stop_min_epochs, "the fewest epochs \"converged\" runs a φ");
  f("pref.stop_rel_tol", h.pref_stop_rel_tol,
    "the relative change below which a φ's loss counts as converged");
  schedule("tpa", h.tpa, kTpa);
  f("tpa.hidden", h.tpa_hidden, "a reward head's hidden layer widths");
  f("tpa.l2", h.tpa_l2, "the L2 penalty on a reward head's predicted rewards");
  f("tpa.stop", h.tpa_stop, tpa_stop_doc());
  f("tpa.stop_min_epochs", h.tpa_stop_min_epochs, "the fewest epochs a stop rule runs a head");
  f("tpa.stop_rel_tol", h.tpa_stop_rel_tol, "the convergence tolerance for unfrozen cells' heads");
  f("tpa.stop_frozen_rel_tol", h.tpa_stop_frozen_rel_tol,
    "the convergence tolerance for frozen cells' heads");
  f("tpa.shadow_rel_tol", h.tpa_shadow_rel_tol,
    "above 0: each head that runs every epoch is also scored where \"converged\" at this "
    "tolerance would have stopped it");
  f("precision", h.precision,
    "\"fp32\" (the paper's) or \"bf16\" matrix products (fp32 accumulation)");
}

[[noreturn]] void bad(const std::string& key, const HyperValue& value, const char* expected) {
  throw std::invalid_argument("hyper-parameter " + key + ": '" + hyper_value_text(value) +
                              "' is not " + expected);
}

// A value into its field, refused unless it is of the field's kind (an integer for an integer,
// an integer or a number for a number, one width or a list of them for widths).
void assign(const std::string& key, const HyperValue& v, int& out) {
  const int64_t* i = std::get_if<int64_t>(&v);
  if (!i || *i < std::numeric_limits<int>::min() || *i > std::numeric_limits<int>::max())
    bad(key, v, "an integer");
  out = int(*i);
}
void assign(const std::string& key, const HyperValue& v, double& out) {
  if (const int64_t* i = std::get_if<int64_t>(&v))
    out = double(*i);
  else if (const double* d = std::get_if<double>(&v); d && std::isfinite(*d))
    out = *d;
  else
    bad(key, v, "a finite number");
}
void assign(const std::string& key, const HyperValue& v, bool& out) {
  const bool* b = std::get_if<bool>(&v);
  if (!b) bad(key, v, "true or false");
  out = *b;
}
void assign(const std::string& key, const HyperValue& v, std::vector<int>& out) {
  if (std::holds_alternative<int64_t>(v)) {
    int w = 0;
    assign(key, v, w);
    out = {w};
  } else if (const auto* l = std::get_if<std::vector<int>>(&v); l && !l->empty()) {
    out = *l;
  } else {
    bad(key, v, "a list of widths");
  }
}
void assign(const std::string& key, const HyperValue& v, std::string& out) {
  const std::string* s = std::get_if<std::string>(&v);
  if (!s) bad(key, v, "a word");
  out = *s;  // its words are checked by validate()
}

HyperValue value_of(int v) {
  return int64_t{v};
}
HyperValue value_of(double v) {
  return v;
}
HyperValue value_of(bool v) {
  return v;
}
HyperValue value_of(const std::string& v) {
  return v;
}
HyperValue value_of(const std::vector<int>& v) {
  return v;
}

std::string show(const std::string& v) {
  return v;
}
std::string show(int64_t v) {
  return std::to_string(v);
}
std::string show(int v) {
  return std::to_string(v);
}
std::string show(bool v) {
  return v ? "true" : "false";
}
std::string show(double v) {
  std::ostringstream o;
  o.precision(17);
  o << v;
  return o.str();
}
std::string show(const std::vector<int>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + std::to_string(v[i]);
  return s;
}

[[noreturn]] void unknown_key(const std::string& key) {
  std::string keys;
  for (const auto& k : hyper_keys()) keys += (keys.empty() ? "" : ", ") + k;
  throw std::invalid_argument("unknown hyper-parameter '" + key + "' (known: " + keys + ")");
}

}  // namespace

std::string hyper_value_text(const HyperValue& v) {
  return std::visit([](const auto& x) { return show(x); }, v);
}

void set_hyper(Hyper& h, const std::string& key, const HyperValue& value) {
  bool found = false;
  for_each_field(h, [&](const std::string& name, auto& field, std::string_view) {
    if (name != key) return;
    found = true;
    assign(key, value, field);
  });
  if (!found) unknown_key(key);
}

HyperValue hyper_value(const Hyper& h, const std::string& key) {
  std::optional<HyperValue> out;
  for_each_field(h, [&](const std::string& name, const auto& field, std::string_view) {
    if (name == key) out = value_of(field);
  });
  if (!out) unknown_key(key);
  return *out;
}

HyperType hyper_type(const std::string& key) {
  Hyper h;
  std::optional<HyperType> type;
  for_each_field(h, [&](const std::string& name, auto& field, std::string_view) {
    if (name != key) return;
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_same_v<T, bool>)
      type = HyperType::boolean;
    else if constexpr (std::is_integral_v<T>)
      type = HyperType::integer;
    else if constexpr (std::is_floating_point_v<T>)
      type = HyperType::number;
    else if constexpr (std::is_same_v<T, std::vector<int>>)
      type = HyperType::integer_list;
    else
      type = HyperType::word;
  });
  if (!type) throw std::invalid_argument("unknown hyper-parameter '" + key + "'");
  return *type;
}

namespace {
constexpr EnumName<HyperType> kHyperTypeNames[] = {
    {HyperType::integer, "an integer"},    {HyperType::number, "a number"},
    {HyperType::boolean, "true or false"}, {HyperType::integer_list, "an array of integers"},
    {HyperType::word, "a string"},
};
}  // namespace

const char* hyper_type_name(HyperType t) {
  return name_in(kHyperTypeNames, t);
}

std::vector<std::string> hyper_keys() {
  Hyper h;
  std::vector<std::string> keys;
  for_each_field(h,
                 [&](const std::string& name, auto&, std::string_view) { keys.push_back(name); });
  return keys;
}

std::string describe(const Hyper& h) {
  std::string s;
  for_each_field(h, [&](const std::string& name, const auto& field, std::string_view) {
    s += name + " = " + show(field) + "\n";
  });
  return s;
}

std::vector<HyperKeyDoc> hyper_key_docs() {
  Hyper h;
  std::vector<HyperKeyDoc> out;
  for_each_field(h, [&](const std::string& name, const auto& field, std::string_view doc) {
    out.push_back({name, value_of(field), std::string(doc)});
  });
  return out;
}

StopRule tpa_shadow_rule(const Hyper& h, bool frozen) {
  StopRule r;
  r.converged = h.tpa_shadow_rel_tol > 0 && !tpa_stop_rule(h, frozen).converged;
  r.min_epochs = h.tpa_stop_min_epochs;
  r.rel_tol = h.tpa_shadow_rel_tol;
  return r;
}

StopRule tpa_stop_rule(const Hyper& h, bool frozen) {
  StopRule r;
  const TpaStopRule* rule = find_tpa_stop_rule(h.tpa_stop);
  r.converged = rule && (frozen ? rule->stops_frozen : rule->stops_unfrozen);
  r.min_epochs = h.tpa_stop_min_epochs;
  r.rel_tol = frozen ? h.tpa_stop_frozen_rel_tol : h.tpa_stop_rel_tol;
  return r;
}

void validate_precision(const std::string& precision) {
  if (precision != "fp32" && precision != "bf16")
    throw std::invalid_argument(
        "precision must be \"fp32\" or \"bf16\" (bf16 matrix products, fp32 accumulation), got \"" +
        precision + "\"");
}

void validate(const Hyper& h) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("hyper-parameter " + what);
  };
  auto widths = [&](const char* name, const std::vector<int>& w) {
    if (w.size() > kMaxHiddenLayers)
      fail(std::string(name) + ": at most " + std::to_string(kMaxHiddenLayers) +
           " hidden layers, got " + std::to_string(w.size()));
    for (int x : w)
      if (x < 1) fail(std::string(name) + ": widths must be >= 1");
  };
  widths("phi.hidden", h.phi_hidden);
  widths("tpa.hidden", h.tpa_hidden);
  if (h.embedding_dim < 1) fail("phi.embedding_dim must be >= 1");
  auto schedule = [&](const std::string& p, const TrainSchedule& s) {
    if (s.epochs < 0) fail(p + ".epochs must be >= 0");
    if (s.batch < 1) fail(p + ".batch must be >= 1");
    if (!(s.adam.lr > 0)) fail(p + ".lr must be > 0");
    if (!(s.adam.decay > 0 && s.adam.decay <= 1)) fail(p + ".lr_decay must be in (0, 1]");
  };
  schedule("sirl", h.sirl);
  schedule("vae", h.vae);
  schedule("pref", h.pref);
  schedule("tpa", h.tpa);
  if (h.triplet_margin < 0) fail("sirl.margin must be >= 0");
  if (h.vae_kl_weight < 0) fail("vae.kl_weight must be >= 0");
  if (h.vae_elbo != "sum" && h.vae_elbo != "mean")
    fail(
        "vae.elbo must be \"sum\" (the standard ELBO) or \"mean\" (reconstruction averaged "
        "over inputs), got \"" +
        h.vae_elbo + "\"");
  if (h.pref_l2 < 0) fail("pref.l2 must be >= 0");
  if (h.pref_stop != "fixed" && h.pref_stop != "converged")
    fail(
        "pref.stop must be \"fixed\" (every epoch, the paper's) or \"converged\" (the "
        "training ends once its loss has converged), got \"" +
        h.pref_stop + "\"");
  if (h.pref_stop_min_epochs < 2) fail("pref.stop_min_epochs must be >= 2");
  if (!(h.pref_stop_rel_tol > 0 && h.pref_stop_rel_tol < 1))
    fail("pref.stop_rel_tol must be in (0, 1)");
  if (h.tpa_l2 < 0) fail("tpa.l2 must be >= 0");
  if (!find_tpa_stop_rule(h.tpa_stop))
    fail("tpa.stop must be " + tpa_stop_rule_list() + ", got \"" + h.tpa_stop + "\"");
  if (h.tpa_stop_min_epochs < 2) fail("tpa.stop_min_epochs must be >= 2");
  if (!(h.tpa_stop_rel_tol > 0 && h.tpa_stop_rel_tol < 1))
    fail("tpa.stop_rel_tol must be in (0, 1)");
  if (!(h.tpa_stop_frozen_rel_tol > 0 && h.tpa_stop_frozen_rel_tol < 1))
    fail("tpa.stop_frozen_rel_tol must be in (0, 1)");
  if (!(h.tpa_shadow_rel_tol >= 0 && h.tpa_shadow_rel_tol < 1))
    fail("tpa.shadow_rel_tol must be in [0, 1) (0: no shadow rule)");
  try {
    validate_precision(h.precision);
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
}

}  // namespace sirl
