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

// The ranges and word lists the keys accept (HyperAccept), built once.
struct Accepts {
  HyperAccept any, non_negative, positive, at_least_1, at_least_2, fraction, decay, shadow_tol;
  HyperAccept elbo, pref_stop, tpa_stop, precision;
};
const Accepts& accepts() {
  static const Accepts a = [] {
    auto range = [](double lo, double hi, bool lo_open, bool hi_open) {
      return HyperAccept{lo, hi, lo_open, hi_open, {}};
    };
    Accepts x;
    x.non_negative = range(0, INFINITY, false, false);
    x.positive = range(0, INFINITY, true, false);
    x.at_least_1 = range(1, INFINITY, false, false);
    x.at_least_2 = range(2, INFINITY, false, false);
    x.fraction = range(0, 1, true, true);
    x.decay = range(0, 1, true, false);
    x.shadow_tol = range(0, 1, false, true);
    x.elbo.words = {{"sum", "the standard ELBO"}, {"mean", "reconstruction averaged over inputs"}};
    x.pref_stop.words = {{"fixed", "every epoch, the paper's"},
                         {"converged", "the training ends once its loss has converged"}};
    for (const TpaStopRule& r : kTpaStopRules) x.tpa_stop.words.push_back({r.name, r.doc});
    x.precision.words = {{"fp32", ""}, {"bf16", "bf16 matrix products, fp32 accumulation"}};
    return x;
  }();
  return a;
}

// Visits every field with its name, what it sets and what it accepts (f(name, field, doc,
// accept), doc a string_view, accept a HyperAccept): the one table set_hyper, validate, describe
// and the keys page (hyper_key_docs) read.
template <typename H, typename F>
void for_each_field(H& h, F&& f) {
  const Accepts& a = accepts();
  f("phi.hidden", h.phi_hidden, "φ's hidden layer widths (a ReLU after each)", a.at_least_1);
  f("phi.embedding_dim", h.embedding_dim, "φ's output: the embedding's dimension", a.at_least_1);
  f("phi.relu_output", h.phi_relu_output,
    "a ReLU on φ's embedding layer too (the lineage code leaves it linear)", a.any);
  auto schedule = [&](const std::string& p, auto& s, Schedule which) {
    const std::array<std::string, 4>& doc = schedule_docs(which);
    f(p + ".epochs", s.epochs, doc[0], a.non_negative);
    f(p + ".batch", s.batch, doc[1], a.at_least_1);
    f(p + ".lr", s.adam.lr, doc[2], a.positive);
    f(p + ".lr_decay", s.adam.decay, doc[3], a.decay);
  };
  schedule("sirl", h.sirl, kSirl);
  f("sirl.margin", h.triplet_margin, "the triplet loss's margin", a.non_negative);
  schedule("vae", h.vae, kVae);
  f("vae.kl_weight", h.vae_kl_weight, "the KL term's weight λ in the VAE's loss", a.non_negative);
  f("vae.elbo", h.vae_elbo,
    "\"sum\" (squared error summed over inputs, KL over latents) or \"mean\" (averaged over "
    "inputs)",
    a.elbo);
  f("vae.standardize", h.vae_standardize,
    "φ is the encoder's mean standardised per latent over Ξ (folded into its last layer)", a.any);
  schedule("pref", h.pref, kPref);
  f("pref.l2", h.pref_l2, "the L2 penalty on a preference φ's predicted rewards", a.non_negative);
  f("pref.stop", h.pref_stop,
    "when a preference φ ends: \"fixed\" (pref.epochs, the paper's) or \"converged\" (its "
    "loss has converged; pref.epochs the cap)",
    a.pref_stop);
  f("pref.stop_min_epochs", h.pref_stop_min_epochs, "the fewest epochs \"converged\" runs a φ",
    a.at_least_2);
  f("pref.stop_rel_tol", h.pref_stop_rel_tol,
    "the relative change below which a φ's loss counts as converged", a.fraction);
  schedule("tpa", h.tpa, kTpa);
  f("tpa.hidden", h.tpa_hidden, "a reward head's hidden layer widths", a.at_least_1);
  f("tpa.l2", h.tpa_l2, "the L2 penalty on a reward head's predicted rewards", a.non_negative);
  f("tpa.stop", h.tpa_stop, tpa_stop_doc(), a.tpa_stop);
  f("tpa.stop_min_epochs", h.tpa_stop_min_epochs, "the fewest epochs a stop rule runs a head",
    a.at_least_2);
  f("tpa.stop_rel_tol", h.tpa_stop_rel_tol, "the convergence tolerance for unfrozen cells' heads",
    a.fraction);
  f("tpa.stop_frozen_rel_tol", h.tpa_stop_frozen_rel_tol,
    "the convergence tolerance for frozen cells' heads", a.fraction);
  f("tpa.shadow_rel_tol", h.tpa_shadow_rel_tol,
    "above 0: each head that runs every epoch is also scored where \"converged\" at this "
    "tolerance would have stopped it (0: no shadow rule)",
    a.shadow_tol);
  f("precision", h.precision,
    "\"fp32\" (the paper's) or \"bf16\" matrix products (fp32 accumulation)", a.precision);
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
  for_each_field(h,
                 [&](const std::string& name, auto& field, std::string_view, const HyperAccept&) {
                   if (name != key) return;
                   found = true;
                   assign(key, value, field);
                 });
  if (!found) unknown_key(key);
}

HyperValue hyper_value(const Hyper& h, const std::string& key) {
  std::optional<HyperValue> out;
  for_each_field(
      h, [&](const std::string& name, const auto& field, std::string_view, const HyperAccept&) {
        if (name == key) out = value_of(field);
      });
  if (!out) unknown_key(key);
  return *out;
}

HyperType hyper_type(const std::string& key) {
  Hyper h;
  std::optional<HyperType> type;
  for_each_field(h,
                 [&](const std::string& name, auto& field, std::string_view, const HyperAccept&) {
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
  for_each_field(h, [&](const std::string& name, auto&, std::string_view, const HyperAccept&) {
    keys.push_back(name);
  });
  return keys;
}

std::string describe(const Hyper& h) {
  std::string s;
  for_each_field(h, [&](const std::string& name, const auto& field, std::string_view,
                        const HyperAccept&) { s += name + " = " + show(field) + "\n"; });
  return s;
}

std::vector<HyperKeyDoc> hyper_key_docs() {
  Hyper h;
  std::vector<HyperKeyDoc> out;
  for_each_field(h, [&](const std::string& name, const auto& field, std::string_view doc,
                        const HyperAccept& accept) {
    out.push_back({name, value_of(field), std::string(doc), accept});
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
  const HyperAccept& a = accepts().precision;  // the words the hyper-parameter takes
  for (const auto& w : a.words)
    if (w.first == precision) return;
  throw std::invalid_argument("precision must be " + words_text(a) + ", got \"" + precision + "\"");
}

bool accepts(const HyperAccept& a, double x) {
  return (a.lo_open ? x > a.lo : x >= a.lo) && (a.hi_open ? x < a.hi : x <= a.hi);
}

std::string range_text(const HyperAccept& a) {
  auto num = [](double x) {
    std::ostringstream o;
    o << x;
    return o.str();
  };
  if (std::isinf(a.lo) && std::isinf(a.hi)) return "any value";
  if (std::isinf(a.hi)) return (a.lo_open ? "> " : ">= ") + num(a.lo);
  if (std::isinf(a.lo)) return (a.hi_open ? "< " : "<= ") + num(a.hi);
  return std::string("in ") + (a.lo_open ? "(" : "[") + num(a.lo) + ", " + num(a.hi) +
         (a.hi_open ? ")" : "]");
}

std::string words_text(const HyperAccept& a) {
  std::string s;
  for (size_t i = 0; i < a.words.size(); ++i) {
    if (i > 0) s += i + 1 == a.words.size() ? " or " : ", ";
    s += "\"" + a.words[i].first + "\"";
    if (!a.words[i].second.empty()) s += " (" + a.words[i].second + ")";
  }
  return s;
}

namespace {

[[noreturn]] void refuse(const std::string& what) {
  throw std::invalid_argument("hyper-parameter " + what);
}
void check_accepted(const std::string& key, double x, const HyperAccept& a) {
  if (!accepts(a, x)) refuse(key + " must be " + range_text(a) + ", got " + show(x));
}
void check_accepted(const std::string& key, int x, const HyperAccept& a) {
  if (!accepts(a, x)) refuse(key + " must be " + range_text(a) + ", got " + std::to_string(x));
}
void check_accepted(const std::string&, bool, const HyperAccept&) {}
void check_accepted(const std::string& key, const std::string& x, const HyperAccept& a) {
  for (const auto& w : a.words)
    if (w.first == x) return;
  refuse(key + " must be " + words_text(a) + ", got \"" + x + "\"");
}
void check_accepted(const std::string& key, const std::vector<int>& widths, const HyperAccept& a) {
  if (widths.size() > kMaxHiddenLayers)
    refuse(key + ": at most " + std::to_string(kMaxHiddenLayers) + " hidden layers, got " +
           std::to_string(widths.size()));
  for (int x : widths)
    if (!accepts(a, x))
      refuse(key + ": widths must be " + range_text(a) + ", got " + std::to_string(x));
}

}  // namespace

// Every key against what its declaration accepts (for_each_field).
void validate(const Hyper& h) {
  for_each_field(h, [](const std::string& name, const auto& field, std::string_view,
                       const HyperAccept& accept) { check_accepted(name, field, accept); });
}

}  // namespace sirl
