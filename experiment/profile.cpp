#include "experiment/profile.h"

#include "experiment/file_environments.h"
#include "experiment/profile_settings.h"
#include "experiment/suggest.h"

#include "engine/convergence.h"
#include "engine/hyper_key_docs.h"
#include "engine/method_catalog.h"

#include "experiment/install_paths.h"

#include "datasets/environments.h"
#include "datasets/study.h"

#include <toml++/toml.h>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace sirl {

std::string Variant::name() const {
  if (method == Method::external) return external;
  return std::string(method_name(method)) + (vae ? "+vae" : "") +
         (selection == Selection::uniform ? "" : std::string("@") + selection_name(selection));
}

Variant parse_variant(const std::string& name) {
  Variant v;
  std::string base = name;
  if (const size_t at = base.find('@'); at != std::string::npos) {
    v.selection = parse_selection(base.substr(at + 1));
    base.resize(at);
    if (base != "sirl" && base != "sirl+vae")
      throw std::invalid_argument("'" + name +
                                  "': query selection (@vote, @infogain) applies only to sirl and "
                                  "sirl+vae, whose triplets it chooses");
  }
  const std::string suffix = "+vae";
  if (base.size() > suffix.size() &&
      base.compare(base.size() - suffix.size(), suffix.size(), suffix) == 0) {
    v.vae = true;
    base.resize(base.size() - suffix.size());
  }
  v.method = parse_method(base);
  if (v.method == Method::external)
    throw std::invalid_argument(
        "'external' is not a method name: declare a representation "
        "trained elsewhere as [external.<name>] (or use `sirl evaluate`)");
  if (is_reference(v.method))
    throw std::invalid_argument("'" + name +
                                "' is a reference every profile scores beside the methods (truth, "
                                "raw): it is not listed among them");
  if (v.vae && !accepts_vae_pretrain(v.method)) {
    std::string takes;
    for (const MethodSpec& m : method_catalog())
      if (m.accepts_vae) takes += (takes.empty() ? "" : ", ") + std::string(m.name);
    throw std::invalid_argument("'" + name + "': VAE pre-training applies only to " + takes);
  }
  return v;
}

std::vector<bool> frozen_settings(const TpaGrid& grid, const Variant& v) {
  if (v.method == Method::external || is_reference(v.method)) return {true};  // no weights
  if (!grid.frozen.empty()) return grid.frozen;
  return {is_best_mode(v, true)};
}

bool is_best_mode(const Variant& v, bool frozen) {
  return frozen == method_spec(v.method).best_frozen;
}

std::string external_name_problem(const std::string& name) {
  if (name.empty() || name.size() > 40 || !(name[0] >= 'a' && name[0] <= 'z'))
    return "an external method's name is 1 to 40 characters, starting with a-z";
  for (char c : name)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-'))
      return "an external method's name holds only a-z, 0-9, '_' and '-' (got '" + name + "')";
  try {
    parse_method(name);
    return "'" + name + "' is a built-in method's name; choose another for an external method";
  } catch (const std::invalid_argument&) {
  }
  return "";
}

bool Profile::runs_protocol(const std::string& protocol) const {
  return std::find(tpa_protocols.begin(), tpa_protocols.end(), protocol) != tpa_protocols.end();
}

bool runs_in(const Profile& p, const Variant& v, const std::string& env) {
  if (v.method != Method::external) return true;
  const auto& envs = external_method(p, v.external).envs;
  return std::find(envs.begin(), envs.end(), env) != envs.end();
}

const ExternalMethod& external_method(const Profile& p, const std::string& name) {
  for (const auto& e : p.external)
    if (e.name == name) return e;
  throw std::invalid_argument("profile " + p.name + " has no external method '" + name + "'");
}

namespace {

// The most values one list of a profile (seeds, N, M) may hold.
constexpr size_t kMaxListValues = 1024;
// The most hyper-parameter points (combinations of [hyper] axes' values) per environment.
constexpr size_t kMaxHyperPoints = 256;
// A profile's size (its file, or the resolved text a results file stores) and its description's:
// far above any real one, far below what would make `sirl plan` or the report a flood.
constexpr size_t kMaxProfileBytes = 1 << 20;
constexpr size_t kMaxDescriptionBytes = 4000;

// Reads a parsed TOML document, checking every key; errors carry "file:line: ".
class Reader {
 public:
  Reader(const toml::table& root, std::string path) : root_(root), path_(std::move(path)) {}

  [[noreturn]] void fail(const toml::node* n, const std::string& what) const {
    // The file that set the value: a parent profile's (extends) or "--set", not always this one.
    std::string where = n && n->source().path ? *n->source().path : path_;
    if (n && n->source().begin.line > 0) where += ":" + std::to_string(n->source().begin.line);
    throw ProfileError(where + ": " + what);
  }

  void only_keys(const toml::table& t, const std::string& table,
                 const std::set<std::string>& allowed) const {
    for (auto&& [k, v] : t)
      if (!allowed.count(std::string(k.str()))) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(&v, "unknown key '" + std::string(k.str()) + "' in " + table +
                     " (expected one of: " + list + ")");
      }
  }

  const toml::table* table(const toml::table& t, const char* key, bool required) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) fail(&t, std::string("missing table [") + key + "]");
      return nullptr;
    }
    if (!n->is_table()) fail(n, std::string(key) + " must be a table");
    return n->as_table();
  }

  std::string string(const toml::table& t, const char* key, const std::string& def,
                     bool required = false) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) fail(&t, std::string("missing key '") + key + "'");
      return def;
    }
    if (!n->is_string()) fail(n, std::string(key) + " must be a string");
    return std::string(*n->value<std::string>());
  }

  int64_t integer(const toml::table& t, const char* key, int64_t def, int64_t lo,
                  int64_t hi) const {
    const toml::node* n = t.get(key);
    if (!n) return def;
    if (!n->is_integer()) fail(n, std::string(key) + " must be an integer");
    const int64_t v = *n->value<int64_t>();
    if (v < lo || v > hi)
      fail(n, std::string(key) + " = " + std::to_string(v) + " is outside [" + std::to_string(lo) +
                  ", " + std::to_string(hi) + "]");
    return v;
  }

  double number(const toml::table& t, const char* key, double def, double lo, double hi) const {
    const toml::node* n = t.get(key);
    return n ? number_of(*n, n, key, lo, hi) : def;
  }

  // A number (or "inf") in [lo, hi]; `where` is the node errors point at.
  double number_of(const toml::node& n, const toml::node* where, const char* key, double lo,
                   double hi) const {
    double v = 0;
    if (n.is_integer())
      v = double(*n.value<int64_t>());
    else if (n.is_floating_point())
      v = *n.value<double>();
    else if (n.is_string() && (*n.value<std::string>() == "inf"))
      v = std::numeric_limits<double>::infinity();
    else
      fail(where, std::string(key) + " must be a number");
    if (!(v >= lo && v <= hi)) {
      auto g = [](double x) {
        std::ostringstream o;
        o << x;
        return o.str();
      };
      fail(where, std::string(key) + " = " + g(v) + " is outside [" + g(lo) + ", " + g(hi) + "]");
    }
    return v;
  }

  std::vector<int64_t> int_list(const toml::table& t, const char* key, int64_t lo, int64_t hi,
                                bool required) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) fail(&t, std::string("missing key '") + key + "'");
      return {};
    }
    if (!n->is_array()) fail(n, std::string(key) + " must be an array of integers");
    // A grid axis of more values than this is a typo, and planning it would take gigabytes.
    if (n->as_array()->size() > kMaxListValues)
      fail(n, std::string(key) + " lists " + std::to_string(n->as_array()->size()) +
                  " values; at most " + std::to_string(kMaxListValues));
    std::vector<int64_t> out;
    for (auto&& e : *n->as_array()) {
      if (!e.is_integer()) fail(n, std::string(key) + " must contain only integers");
      const int64_t v = *e.value<int64_t>();
      if (v < lo || v > hi)
        fail(n, std::string(key) + ": " + std::to_string(v) + " is outside [" + std::to_string(lo) +
                    ", " + std::to_string(hi) + "]");
      if (std::find(out.begin(), out.end(), v) != out.end())
        fail(n, std::string(key) + ": " + std::to_string(v) + " is listed twice");
      out.push_back(v);
    }
    if (required && out.empty()) fail(n, std::string(key) + " must not be empty");
    return out;
  }

  std::vector<std::string> string_list(const toml::table& t, const char* key, bool required) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) fail(&t, std::string("missing key '") + key + "'");
      return {};
    }
    if (!n->is_array()) fail(n, std::string(key) + " must be an array of strings");
    std::vector<std::string> out;
    for (auto&& e : *n->as_array()) {
      if (!e.is_string()) fail(n, std::string(key) + " must contain only strings");
      out.push_back(std::string(*e.value<std::string>()));
    }
    if (required && out.empty()) fail(n, std::string(key) + " must not be empty");
    return out;
  }

  std::vector<Variant> variants(const toml::table& t, const char* key) const {
    std::vector<Variant> out;
    for (const auto& s : string_list(t, key, true)) {
      try {
        out.push_back(parse_variant(s));
      } catch (const std::invalid_argument& e) {
        fail(t.get(key), std::string(key) + ": " + e.what());
      }
      for (size_t i = 0; i + 1 < out.size(); ++i)
        if (out[i].name() == out.back().name())
          fail(t.get(key), std::string(key) + ": '" + s + "' is listed twice");
    }
    return out;
  }

  const toml::table& root() const { return root_; }

 private:
  const toml::table& root_;
  std::string path_;
};

// One declared key of table t (experiment/profile_settings.h) into its field, its type and range
// checked; an absent key leaves the field as it is (its struct's default, or the value a wider
// table gave: [active] under [active.<env>]).
void read_setting(const Reader& r, const toml::table& t, const std::string&, const SettingInfo& k,
                  int& v) {
  v = int(r.integer(t, k.key, v, int64_t(k.lo), int64_t(k.hi)));
}
void read_setting(const Reader& r, const toml::table& t, const std::string&, const SettingInfo& k,
                  int64_t& v) {
  v = r.integer(t, k.key, v, int64_t(k.lo), int64_t(k.hi));
}
void read_setting(const Reader& r, const toml::table& t, const std::string&, const SettingInfo& k,
                  double& v) {
  v = r.number(t, k.key, v, k.lo, k.hi);
}
void read_setting(const Reader& r, const toml::table& t, const std::string&, const SettingInfo& k,
                  std::string& v) {
  v = r.string(t, k.key, v, k.required);
}
// A list of strings (names checked by the caller).
void read_setting(const Reader& r, const toml::table& t, const std::string&, const SettingInfo& k,
                  std::vector<std::string>& v) {
  if (t.get(k.key) || k.required) v = r.string_list(t, k.key, k.required);
}
void read_setting(const Reader& r, const toml::table& t, const std::string& table,
                  const SettingInfo& k, bool& v) {
  if (!k.words[0]) {  // a TOML true/false
    if (const toml::node* n = t.get(k.key)) {
      if (!n->is_boolean()) r.fail(n, std::string(k.key) + " must be true or false");
      v = *n->value<bool>();
    }
    return;
  }
  const std::string w = r.string(t, k.key, k.words[v ? 1 : 0]);
  if (w != k.words[0] && w != k.words[1])
    r.fail(t.get(k.key),
           table + " " + k.key + " must be \"" + k.words[0] + "\" or \"" + k.words[1] + "\"");
  v = w == k.words[1];
}
// A list of integers, each in the declared range; an empty list is allowed unless required.
void read_setting(const Reader& r, const toml::table& t, const std::string&, const SettingInfo& k,
                  std::vector<int64_t>& v) {
  if (t.get(k.key) || k.required)
    v = r.int_list(t, k.key, int64_t(k.lo), int64_t(k.hi), k.required);
}
// Variant names ("sirl+vae", "sirl@vote"), each once; always required.
void read_setting(const Reader& r, const toml::table& t, const std::string&, const SettingInfo& k,
                  std::vector<Variant>& v) {
  v = r.variants(t, k.key);
}
// Method names (the ablation's).
void read_setting(const Reader& r, const toml::table& t, const std::string&, const SettingInfo& k,
                  std::vector<Method>& v) {
  v.clear();
  for (const auto& s : r.string_list(t, k.key, k.required)) {
    try {
      v.push_back(parse_method(s));
    } catch (const std::invalid_argument& e) {
      r.fail(t.get(k.key), std::string(k.key) + ": " + e.what());
    }
  }
}
// "best" (empty: the paper's best mode per method) or a non-empty list of booleans.
void read_setting(const Reader& r, const toml::table& t, const std::string&, const SettingInfo& k,
                  std::vector<bool>& v) {
  const toml::node* f = t.get(k.key);
  if (!f) return;
  const std::string expect = std::string(k.key) + " must be \"best\" or an array of booleans";
  if (f->is_string()) {
    if (*f->value<std::string>() != "best") r.fail(f, expect);
    v.clear();
  } else if (f->is_array()) {
    v.clear();
    for (auto&& e : *f->as_array()) {
      if (!e.is_boolean()) r.fail(f, expect);
      v.push_back(*e.value<bool>());
    }
    if (v.empty()) r.fail(f, std::string(k.key) + " must not be empty");
  } else {
    r.fail(f, expect);
  }
}

// Every key of a declared section, for only_keys.
template <class Settings, class S>
std::set<std::string> setting_keys(Settings settings, const S& s) {
  std::set<std::string> keys;
  settings(s, [&](const SettingInfo& k, const auto&) { keys.insert(k.key); });
  return keys;
}

// Every declared key of `table` (named `name` in errors) into s.
template <class Settings, class S>
void read_settings(const Reader& r, const toml::table& t, const std::string& name,
                   Settings settings, S& s) {
  settings(s, [&](const SettingInfo& k, auto& field) { read_setting(r, t, name, k, field); });
}

// ---- the reference of the declared sections (`sirl plan --keys`) ----

// A value as a reader writes it: 10000000, 0.05, 1e-09, ∞ (the digest's exact text is for
// machines).
std::string plain(double v) {
  if (std::isinf(v)) return "∞";
  std::ostringstream o;
  o.precision(15);
  o << v;
  return o.str();
}

// One row per key: | key | type | accepted | default | what it sets |
template <class Settings, class S>
std::string key_rows(Settings settings, const S& defaults) {
  std::string out;
  settings(defaults, [&](const SettingInfo& k, const auto& field) {
    using T = std::decay_t<decltype(field)>;
    std::string type, accepted, def;
    if constexpr (std::is_same_v<T, std::vector<std::string>>) {
      type = "string list";
      accepted = "—";
    } else if constexpr (std::is_same_v<T, std::vector<int64_t>>) {
      type = "integer list";
      accepted = "each " + plain(k.lo) + " – " + plain(k.hi);
    } else if constexpr (std::is_same_v<T, std::vector<Variant>>) {
      type = "string list";
      accepted = "variants: a method, `+vae`, `@<selection>` (methods.md)";
    } else if constexpr (std::is_same_v<T, std::vector<Method>>) {
      type = "string list";
      accepted = "method names (methods.md)";
    } else if constexpr (std::is_same_v<T, std::vector<bool>>) {
      type = "string or boolean list";
      accepted = "`\"best\"`, `[true]`, `[false]`, `[true, false]`";
    } else if constexpr (std::is_same_v<T, std::string>) {
      type = "string";
      accepted = "—";
      def = "`\"" + field + "\"`";
    } else if constexpr (std::is_same_v<T, bool>) {
      if (!k.words[0]) {
        type = "boolean";
        accepted = "`true`, `false`";
        def = field ? "`true`" : "`false`";
      } else {
        type = "string";
        accepted = std::string("`\"") + k.words[0] + "\"`, `\"" + k.words[1] + "\"`";
        def = std::string("`\"") + k.words[field ? 1 : 0] + "\"`";
      }
    } else {
      type = std::is_integral_v<T> ? "integer" : "number";
      accepted = plain(k.lo) + " – " + plain(k.hi);
      def = "`" + plain(double(field)) + "`";
      if (k.axis) type += " or list";
    }
    if (k.default_text) def = k.default_text;
    if (k.required) def = "required";
    out += "| `" + std::string(k.key) + "` | " + type + " | " + accepted + " | " + def + " | " +
           k.doc + " |\n";
  });
  return out;
}

// A hyper-parameter's value as a profile writes it: 3000, 0.004, [128, 128], true, "fixed".
std::string toml_text(const HyperValue& v) {
  if (const auto* d = std::get_if<double>(&v)) return plain(*d);
  if (const auto* s = std::get_if<std::string>(&v)) return "\"" + *s + "\"";
  if (const auto* w = std::get_if<std::vector<int>>(&v)) {
    std::string out = "[";
    for (size_t i = 0; i < w->size(); ++i) out += (i ? ", " : "") + std::to_string((*w)[i]);
    return out + "]";
  }
  return hyper_value_text(v);  // an integer or a boolean
}

// [hyper.<env>]: one row per engine hyper-parameter (engine/hyperparams.cpp declares them), with
// the environments that set a default of their own.
std::string hyper_section() {
  std::string out =
      "## [hyper.<env>]\n\n"
      "The training hyper-parameters of one environment's tasks (the paper's Appendix B-C). A list "
      "of values makes an axis of the grid (running.md); a value of the wrong type, or out of "
      "its range, is refused with the key and the range when the profile is read.\n\n"
      "| key | type | accepted | default | an environment's own default | what it sets |\n"
      "|---|---|---|---|---|---|\n";
  for (const HyperKeyDoc& k : hyper_key_docs()) {
    const HyperType t = hyper_type(k.key);
    const char* type = t == HyperType::integer        ? "integer"
                       : t == HyperType::number       ? "number"
                       : t == HyperType::boolean      ? "boolean"
                       : t == HyperType::integer_list ? "integer list (widths)"
                                                      : "string";
    std::string accepted;
    if (!k.accept.words.empty()) {
      for (const auto& w : k.accept.words)
        accepted += (accepted.empty() ? "`\"" : ", `\"") + w.first + "\"`";
    } else if (t == HyperType::integer_list) {
      accepted = "widths " + range_text(k.accept) + ", at most " +
                 std::to_string(kMaxHiddenLayers) + " of them";
    } else if (t != HyperType::boolean) {
      accepted = range_text(k.accept);
    }
    std::string own;
    for (const EnvSpec& e : environments())
      for (const HyperDefault& d : e.hyper)
        if (d.key == k.key)
          own += (own.empty() ? "" : ", ") + e.name + ": `" + toml_text(d.value) + "`";
    out += "| `" + k.key + "` | " + type + " | " + (accepted.empty() ? "—" : accepted) + " | `" +
           toml_text(k.value) + "` | " + (own.empty() ? "—" : own) + " | " + k.doc + " |\n";
  }
  return out + "\n";
}

std::string keys_section(const char* title, const char* note, const std::string& rows) {
  return std::string("## ") + title + "\n\n" + note + "\n\n" +
         "| key | type | accepted | default | what it sets |\n|---|---|---|---|---|\n" + rows +
         "\n";
}

// A TOML scalar or array as the typed value set_hyper takes, refused unless its TOML type is the
// key's (an integer key takes 30, not 30.0, "30" or [30]; a number key takes 30 or 0.5).
HyperValue hyper_value(const Reader& r, const toml::node& n, const std::string& key) {
  HyperType want{};
  try {
    want = hyper_type(key);
  } catch (const std::invalid_argument&) {
    r.fail(
        &n, "unknown hyper-parameter '" + key + "' (known: " + [] {
          std::string keys;
          for (const auto& k : hyper_keys()) keys += (keys.empty() ? "" : ", ") + k;
          return keys;
        }() + ")");
  }
  const bool ok = want == HyperType::integer        ? n.is_integer()
                  : want == HyperType::number       ? n.is_integer() || n.is_floating_point()
                  : want == HyperType::boolean      ? n.is_boolean()
                  : want == HyperType::integer_list ? n.is_array() || n.is_integer()
                                                    : n.is_string();
  if (!ok) r.fail(&n, key + " must be " + hyper_type_name(want));
  // A profile trains what it names: 0 epochs would score an untrained network under its name.
  if (key.ends_with(".epochs") && n.is_integer() && *n.value<int64_t>() < 1)
    r.fail(&n, key + " must be >= 1 (0 epochs would leave the network untrained)");
  if (n.is_integer()) return *n.value<int64_t>();
  if (n.is_floating_point()) return *n.value<double>();
  if (n.is_boolean()) return *n.value<bool>();
  if (n.is_string()) return *n.value<std::string>();
  // Bounded before anything is built from it (a 10⁶-layer list once cost 1 GB in `sirl plan`).
  if (n.as_array()->size() > kMaxHiddenLayers)
    r.fail(&n, key + " lists " + std::to_string(n.as_array()->size()) + " hidden layers; at most " +
                   std::to_string(kMaxHiddenLayers));
  std::vector<int> widths;
  for (auto&& e : *n.as_array()) {
    const std::optional<int64_t> w = e.is_integer() ? e.value<int64_t>() : std::nullopt;
    if (!w || *w < std::numeric_limits<int>::min() || *w > std::numeric_limits<int>::max())
      r.fail(&n, key + " must be an array of integers");
    widths.push_back(int(*w));
  }
  return widths;
}

// [tpa] or [robustness] (the caller checks the table's keys): methods, N, M and which of
// frozen/unfrozen to run.
void parse_tpa(const Reader& r, const toml::table& tpa, const std::string& name, TpaGrid& g) {
  read_settings(r, tpa, name, kTpaSettings, g);
}

// stop = { sirl = "fixed", jaco = { "sirl+vae" = "converged" } } in `table` ("[tpa]", "[pref]"):
// a rule per variant, in every environment or (under an environment's name) in that one, into
// `out` (keys: tpa_stop_key). `why_not(name)` says why a variant may not have one ("" if it may);
// `rule_field` is the Hyper field the rule sets (tpa_stop, pref_stop): validate() names the rules.
template <class WhyNot>
void parse_stop_rules(const Reader& r, const toml::table& t, const std::string& table,
                      const Profile& p, WhyNot why_not, std::string Hyper::*rule_field,
                      std::map<std::string, std::string>& out) {
  const toml::node* n = t.get("stop");
  if (!n) return;
  const toml::table* rules = n->as_table();
  if (!rules)
    r.fail(n, table + " stop must be a table of method = rule, e.g. stop = { sirl = \"fixed\" }");
  const auto one = [&](const std::string& env, const std::string& name, const toml::node& value) {
    const std::string where = table + " stop." + (env.empty() ? "" : env + ".") + name;
    if (const std::string why = why_not(name); !why.empty())
      r.fail(&value, table + " stop" + (env.empty() ? "" : "." + env) + ": '" + name + "' " + why);
    if (!value.is_string()) r.fail(&value, where + " must be a string: a rule");
    try {
      Hyper check;
      check.*rule_field = *value.value<std::string>();
      validate(check);
    } catch (const std::invalid_argument& e) {
      r.fail(&value, where + ": " + e.what());
    }
    out[tpa_stop_key(env, name)] = *value.value<std::string>();
  };
  for (auto&& [key, value] : *rules) {
    const std::string name(key.str());
    if (const toml::table* per_env = value.as_table()) {
      if (std::find(p.envs.begin(), p.envs.end(), name) == p.envs.end()) {
        std::string envs;
        for (const std::string& e : p.envs) envs += (envs.empty() ? "" : ", ") + e;
        r.fail(&value, table + " stop." + name +
                           ": a table here must be named after one of envs (" + envs +
                           "), with method = rule inside");
      }
      for (auto&& [k, v] : *per_env) one(name, std::string(k.str()), v);
    } else {
      one("", name, value);
    }
  }
}

// [tpa] stop: a tpa.stop rule per variant listed in [tpa] methods, or for the reference truth
// (its paper-protocol cells are frozen heads on the true features) when the profile has
// references.
void parse_tpa_stop(const Reader& r, const toml::table& tpa, Profile& p) {
  parse_stop_rules(
      r, tpa, "[tpa]", p,
      [&](const std::string& name) {
        const bool listed = std::any_of(p.tpa.methods.begin(), p.tpa.methods.end(),
                                        [&](const Variant& v) { return v.name() == name; });
        if (listed || (p.references && name == Variant{Method::truth}.name())) return std::string();
        return std::string("is not one of [tpa] methods") +
               (p.references ? " nor the reference truth" : "");
      },
      &Hyper::tpa_stop, p.tpa_stop_by_method);
}

// [pref] stop: a pref.stop rule per preference-trained variant the profile runs.
void parse_pref(const Reader& r, const toml::table& root, Profile& p) {
  const toml::node* n = root.get("pref");
  if (!n) return;
  if (!n->is_table()) r.fail(n, "pref must be a table");
  r.only_keys(*n->as_table(), "[pref]", {"stop"});
  parse_stop_rules(
      r, *n->as_table(), "[pref]", p,
      [&](const std::string& name) {
        Variant v;
        try {
          v = parse_variant(name);
        } catch (const std::invalid_argument& e) {
          return std::string("is not a method: ") + e.what();
        }
        if (!method_spec(v.method).training.preferences)
          return std::string(
              "is not trained on preferences (singlepref, multipref10, multipref50 and their "
              "+vae variants are)");
        const auto named = [&](const std::vector<Variant>& vs) {
          return std::any_of(vs.begin(), vs.end(),
                             [&](const Variant& u) { return u.name() == name; });
        };
        const bool ablation = std::find(p.ablation_methods.begin(), p.ablation_methods.end(),
                                        v.method) != p.ablation_methods.end();
        if (!named(p.fpe_methods) && !named(p.tpa.methods) && !named(p.robustness.methods) &&
            !ablation)
          return std::string("is not run by this profile ([fpe], [tpa], [ablation], [robustness])");
        return std::string();
      },
      &Hyper::pref_stop, p.pref_stop_by_method);
}

// [tpa] protocols = ["paper", "linear"]: one or more of kTpaProtocols, each once.
void parse_tpa_protocols(const Reader& r, const toml::table& tpa, Profile& p) {
  const toml::node* n = tpa.get("protocols");
  if (!n) return;
  std::string expect = "[tpa] protocols must be a non-empty array of ";
  for (size_t i = 0; i < kTpaProtocols.size(); ++i)
    expect += std::string(i == 0                          ? ""
                          : i + 1 == kTpaProtocols.size() ? " and "
                                                          : ", ") +
              "\"" + kTpaProtocols[i].name + "\" (" + kTpaProtocols[i].doc + ")";
  expect += ", each at most once";
  const toml::array* a = n->as_array();
  if (!a || a->empty()) r.fail(n, expect);
  p.tpa_protocols.clear();
  for (auto&& e : *a) {
    const std::optional<std::string> s = e.value<std::string>();
    const bool known = s && std::any_of(kTpaProtocols.begin(), kTpaProtocols.end(),
                                        [&](const ProtocolInfo& c) { return *s == c.name; });
    if (!known || p.runs_protocol(*s)) r.fail(&e, expect);
    p.tpa_protocols.push_back(*s);
  }
}

}  // namespace

namespace {

// Each environment's table takes the axis keys; the table named by an environment's data_table
// ([jaco] for both JacoRobot variants) also sets Ξ.
// A profile table through the Reader's checks, for an environment reading its own keys.
struct TomlDataTable : DataTableReader {
  TomlDataTable(const Reader& r, const toml::table& t) : r_(r), t_(t) {}
  int64_t integer(const char* key, int64_t def, int64_t lo, int64_t hi) const override {
    return r_.integer(t_, key, def, lo, hi);
  }
  double number(const char* key, double def, double lo, double hi) const override {
    return r_.number(t_, key, def, lo, hi);
  }
  const Reader& r_;
  const toml::table& t_;
};

// Each environment's table ([grid], [jaco], …): the grid's axes, and where the environment owns
// a data table, the keys it reads itself (EnvSpec::read_data).
void parse_data_tables(Reader& r, const toml::table& root, EnvConfig& data) {
  const std::set<std::string> axis_keys = setting_keys(kEnvTableSettings, EnvAxes{});
  for (const auto& e : environments()) {
    const auto* t = r.table(root, e.name.c_str(), false);
    if (!t) continue;
    const bool owns_data = e.read_data && e.data_table == e.name;
    std::set<std::string> keys = axis_keys;
    if (owns_data) keys.insert(e.data_keys.begin(), e.data_keys.end());
    r.only_keys(*t, "[" + e.name + "]", keys);
    if (owns_data) e.read_data(TomlDataTable(r, *t), data);
  }
  data.jaco.threads = 1;  // generated inside one task; the data never depends on it
}

bool env_is_study(const std::string& name) {
  for (const auto& e : environments())
    if (e.name == name) return e.in_study;
  return false;
}

}  // namespace

namespace {

// [queries] and [teacher]: the budgets and the simulated human.
void parse_queries(Reader& r, const toml::table& root, Profile& p) {
  if (const auto* q = r.table(root, "queries", false)) {
    r.only_keys(*q, "[queries]", setting_keys(kQueriesSettings, p.queries));
    read_settings(r, *q, "[queries]", kQueriesSettings, p.queries);
  }
  const auto* t = r.table(root, "teacher", false);
  if (!t) return;
  r.only_keys(*t, "[teacher]", setting_keys(kTeacherSettings, p.queries));
  // A scalar sets the main teacher; a list (for an axis key) keeps the main teacher's default for
  // that key and makes each listed value one teacher of a noise axis (its cells: [robustness]).
  struct NoiseAxis {
    const char* key;
    double main;  // the main teacher's value: the axis's reference point, not a noisy teacher
    std::vector<double> values;
  };
  std::vector<NoiseAxis> axes;
  kTeacherSettings(p.queries, [&](const SettingInfo& k, double& field) {
    const toml::node* n = t->get(k.key);
    if (!n) return;
    if (!k.axis || !n->is_array()) {
      field = r.number_of(*n, n, k.key, k.lo, k.hi);
      return;
    }
    std::vector<double> values;
    for (auto&& e : *n->as_array()) {
      const double v = r.number_of(e, n, k.key, k.lo, k.hi);
      if (std::find(values.begin(), values.end(), v) != values.end())
        r.fail(n, std::string(k.key) + ": a value is listed twice");
      values.push_back(v);
    }
    if (values.empty()) r.fail(n, std::string(k.key) + " must not be an empty list");
    axes.push_back({k.key, field, values});
  });
  for (const NoiseAxis& a : axes)
    for (double v : a.values) {
      if (v == a.main) continue;
      TeacherPoint tp;
      tp.axis = a.key;
      tp.level = v;
      std::ostringstream o;
      o << a.key << "=" << v;
      tp.tag = o.str();
      tp.queries = p.queries;
      kTeacherSettings(tp.queries, [&](const SettingInfo& k, double& field) {
        if (tp.axis == k.key) field = v;
      });
      p.robustness.teachers.push_back(tp);
    }
}

// [active] and [active.<env>]: the active variants' selection settings.
void parse_active(Reader& r, const toml::table& root, Profile& p) {
  for (const auto& env : p.envs) p.active[env] = ActiveRounds{};
  const auto* at = r.table(root, "active", false);
  if (!at) return;
  const std::set<std::string> keys = setting_keys(kActiveSettings, ActiveRounds{});
  auto read = [&](const toml::table& t, const std::string& name, ActiveRounds& a) {
    read_settings(r, t, name, kActiveSettings, a);
    if (a.pool < a.batch)
      r.fail(&t, name + ": pool = " + std::to_string(a.pool) + " is below batch = " +
                     std::to_string(a.batch) + " (a round picks its batch from the pool)");
  };
  std::set<std::string> allowed = keys;
  for (const auto& env : p.envs) allowed.insert(env);
  r.only_keys(*at, "[active]", allowed);
  ActiveRounds all;
  read(*at, "[active]", all);
  for (const auto& env : p.envs) {
    p.active[env] = all;
    if (const auto* et = r.table(*at, env.c_str(), false)) {
      r.only_keys(*et, "[active." + env + "]", keys);
      read(*et, "[active." + env + "]", p.active[env]);
    }
  }
}

// [robustness]: which cells the noisy teachers of [teacher]'s lists run.
void parse_robustness(Reader& r, const toml::table& root, Profile& p) {
  const auto* rb = r.table(root, "robustness", false);
  const bool lists = !p.robustness.teachers.empty();
  if (!rb) {
    if (lists)
      r.fail(root.get("teacher"),
             "[teacher] lists noisy teachers but there is no [robustness] table saying which "
             "cells they run (methods, N, M)");
    return;
  }
  if (!lists)
    r.fail(rb,
           "[robustness] needs noisy teachers: give a list for beta, mistake or attend in "
           "[teacher] (e.g. beta = [10, 1, 0])");
  r.only_keys(*rb, "[robustness]", setting_keys(kTpaSettings, TpaGrid{}));
  parse_tpa(r, *rb, "[robustness]", p.robustness);  // its cells, as a [tpa] table's
}

// [fpe], [tpa], [ablation]: which cells run.
void parse_cells(Reader& r, const toml::table& root, Profile& p) {
  // A profile runs any part of the grid: [fpe], [tpa] and [ablation] are each optional, but at
  // least one must be there.
  const auto* fpe = r.table(root, "fpe", false);
  const auto* tpa = r.table(root, "tpa", false);
  if (!fpe && !tpa && !r.table(root, "ablation", false) && !r.table(root, "study", false) &&
      !r.table(root, "robustness", false))
    r.fail(&root,
           "nothing to run: give at least one of [fpe], [tpa], [ablation], [robustness] or "
           "[study]");
  if (fpe) {
    r.only_keys(*fpe, "[fpe]", setting_keys(kFpeSettings, p));
    read_settings(r, *fpe, "[fpe]", kFpeSettings, p);
  }
  if (tpa) {
    std::set<std::string> keys = setting_keys(kTpaSettings, p.tpa);
    keys.insert({"stop", "protocols"});
    r.only_keys(*tpa, "[tpa]", keys);
    parse_tpa(r, *tpa, "[tpa]", p.tpa);
    parse_tpa_stop(r, *tpa, p);
    parse_tpa_protocols(r, *tpa, p);
  }
  if (const auto* ab = r.table(root, "ablation", false)) {
    r.only_keys(*ab, "[ablation]", setting_keys(kAblationSettings, p));
    read_settings(r, *ab, "[ablation]", kAblationSettings, p);
  }
}

// [external.<name>]: representations trained elsewhere, each joining [fpe] and [tpa] (frozen).
void parse_external(Reader& r, const toml::table& root, Profile& p) {
  const auto* ext = r.table(root, "external", false);
  if (!ext) return;
  namespace fs = std::filesystem;
  const fs::path base =
      p.path.empty() || p.path[0] == '<' ? fs::current_path() : fs::absolute(p.path).parent_path();
  for (auto&& [k, node] : *ext) {
    const std::string name(k.str());
    if (!node.is_table()) r.fail(&node, "[external." + name + "] must be a table");
    const toml::table& t = *node.as_table();
    if (const std::string why = external_name_problem(name); !why.empty()) r.fail(&node, why);
    r.only_keys(t, "[external." + name + "]", setting_keys(kExternalSettings, ExternalMethod{}));
    ExternalMethod m;
    m.name = name;
    m.envs = p.envs;
    read_settings(r, t, "[external." + name + "]", kExternalSettings, m);
    if (m.embeddings.empty()) r.fail(t.get("embeddings"), "embeddings must name a file");
    if (t.get("envs") && m.envs.empty()) r.fail(t.get("envs"), "envs must not be empty");
    m.embeddings = (base / m.embeddings).lexically_normal().string();
    if (m.xxh3.size() != 32 || m.xxh3.find_first_not_of("0123456789abcdef") != std::string::npos)
      r.fail(t.get("xxh3"),
             "xxh3 must be the file's XXH3-128 as 32 lowercase hex digits (`xxh128sum " +
                 m.embeddings + "` prints it)");
    for (const auto& e : m.envs)
      if (std::find(p.envs.begin(), p.envs.end(), e) == p.envs.end())
        r.fail(t.get("envs"), "envs: '" + e + "' is not one of the profile's envs");
    Variant v;
    v.method = Method::external;
    v.external = name;
    if (!p.fpe_N.empty()) p.fpe_methods.push_back(v);
    if (!p.tpa.N.empty()) p.tpa.methods.push_back(v);
    p.external.push_back(std::move(m));
  }
}

// [environments.<name>]: environments read from files (experiment/file_environments.h), each
// registered before `envs` and the environments' own tables are read.
void parse_file_environments(Reader& r, const toml::table& root, const std::string& path,
                             const std::set<std::string>& sections) {
  const auto* envs = r.table(root, "environments", false);
  if (!envs) return;
  namespace fs = std::filesystem;
  const fs::path base =
      path.empty() || path[0] == '<' ? fs::current_path() : fs::absolute(path).parent_path();
  for (auto&& [k, node] : *envs) {
    FileEnvironment e;
    e.name = std::string(k.str());
    if (!node.is_table()) r.fail(&node, "[environments." + e.name + "] must be a table");
    const toml::table& t = *node.as_table();
    const std::string where = "[environments." + e.name + "]";
    // An environment's own table is [<name>] and its hyper-parameters [hyper.<name>]: a name
    // that is a profile section, or [hyper.all], would be read as the wrong table.
    if (sections.count(e.name) || e.name == "all")
      r.fail(&node, where + ": '" + e.name + "' names a profile section; choose another name");
    r.only_keys(t, where, setting_keys(kFileEnvironmentSettings, FileEnvironment{}));
    read_settings(r, t, where, kFileEnvironmentSettings, e);
    if (e.path.empty()) r.fail(t.get("file"), "file must name an environment file");
    e.path = (base / e.path).lexically_normal().string();
    if (e.xxh3.size() != 32 || e.xxh3.find_first_not_of("0123456789abcdef") != std::string::npos)
      r.fail(t.get("xxh3"),
             "xxh3 must be the file's XXH3-128 as 32 lowercase hex digits (`xxh128sum " + e.path +
                 "` prints it)");
    for (const std::string* text : {&e.group, &e.title, &e.description})
      for (char c : *text)
        if ((c >= 0 && c < 0x20) || c == 0x7f)
          r.fail(&node, where + ": dataset, title and description are one line of printable text");
    if (e.title.size() > 64 || e.description.size() > 400 || e.group.size() > 256)
      r.fail(&node, where + ": title ≤ 64, description ≤ 400, dataset ≤ 256 characters");
    try {
      declare_file_environment(e);
    } catch (const std::invalid_argument& err) {
      r.fail(&node, err.what());
    }
  }
}

// Per environment: the top-level axes unless its own table overrides them.
void parse_env_axes(Reader& r, const toml::table& root, Profile& p) {
  for (const auto& env : p.envs) {
    EnvAxes g{p.seeds, p.fpe_N, p.tpa.N, p.tpa.M, p.ablation_N, p.ablation_M};
    g.store_weights = !env_spec(env).sampled;  // JacoRobot's 3.1 M-float networks: off
    if (const auto* t = r.table(root, env.c_str(), false)) {
      read_settings(r, *t, "[" + env + "]", kEnvTableSettings, g);
      if (g.seeds.empty()) r.fail(t->get("seeds"), "seeds must not be empty");
    }
    p.axes[env] = g;
  }
}

// [study]: the simulated cohort of the user-study pipeline.
void parse_study(Reader& r, const toml::table& root, Profile& p) {
  if (const auto* st = r.table(root, "study", false)) {
    r.only_keys(*st, "[study]", setting_keys(kStudySettings, p.study));
    p.study.enabled = true;
    read_settings(r, *st, "[study]", kStudySettings, p.study);
    if (!env_is_study(p.study.cohort.env))
      r.fail(st->get("env"), "[study] env must be " + study_env_names() +
                                 " (an environment from a file, if its file has 2-D points)");
  }
}

// Whether a [hyper] value is an axis: a list of values for a key that takes one (a list of
// lists for a width list).
bool is_hyper_axis(const toml::node& v, const std::string& key) {
  const auto* a = v.as_array();
  if (!a) return false;
  HyperType want{};
  try {
    want = hyper_type(key);
  } catch (const std::invalid_argument&) {
    return false;  // hyper_value names the unknown key
  }
  return want != HyperType::integer_list || (!a->empty() && (*a)[0].is_array());
}

// An axis's values; refuses an empty list and a repeated value.
std::vector<HyperValue> hyper_axis_values(const Reader& r, const toml::node& v,
                                          const std::string& key) {
  // An axis holds at most kMaxHyperPoints values (the product of all axes does too): refused
  // before any value is read, so a pasted list of thousands costs nothing.
  if (v.as_array()->size() > kMaxHyperPoints)
    r.fail(&v, key + ": an axis of " + std::to_string(v.as_array()->size()) +
                   " values; a profile runs at most " + std::to_string(kMaxHyperPoints) +
                   " hyper-parameter points per environment");
  std::vector<HyperValue> out;
  std::set<std::string> seen;
  for (auto&& e : *v.as_array()) {
    HyperValue value = hyper_value(r, e, key);  // fails with file:line itself
    // Two values are one when their texts are (1 and 1.0 for a number): a point's name is its text.
    const std::string text = hyper_value_text(value);
    if (!seen.insert(text).second) r.fail(&e, key + ": the value " + text + " is listed twice");
    out.push_back(std::move(value));
  }
  if (out.empty()) r.fail(&v, key + ": an axis needs at least one value");
  return out;
}

struct HyperAxis {
  std::string key;
  std::vector<HyperValue> values;
  const toml::node* node;
};

using HyperAxes = std::map<std::string, std::vector<HyperAxis>>;  // per environment

// [hyper.all] then [hyper.<env>], each table's keys in toml++ order: a single value sets the
// environment's base point, a list makes (or replaces) an axis.
HyperAxes read_hyper_tables(Reader& r, const toml::table& hy, Profile& p) {
  HyperAxes axes;
  std::set<std::string> allowed{"all"};
  for (const auto& e : p.envs) allowed.insert(e);
  r.only_keys(hy, "[hyper] (one sub-table per environment, or 'all')", allowed);
  std::vector<std::string> scopes{"all"};
  scopes.insert(scopes.end(), p.envs.begin(), p.envs.end());
  for (const std::string& scope : scopes) {
    const auto* t = r.table(hy, scope.c_str(), false);
    if (!t) continue;
    for (auto&& [k, v] : *t) {
      const std::string key(k.str());
      for (auto& [env, h] : p.hyper) {
        if (scope != "all" && env != scope) continue;
        auto& env_axes = axes[env];
        std::erase_if(env_axes, [&](const HyperAxis& a) { return a.key == key; });
        if (is_hyper_axis(v, key)) {
          env_axes.push_back({key, hyper_axis_values(r, v, key), &v});
          continue;
        }
        const HyperValue value = hyper_value(r, v, key);  // fails with file:line itself
        try {
          set_hyper(h, key, value);
        } catch (const std::invalid_argument& e) {
          r.fail(&v, e.what());
        }
      }
    }
  }
  return axes;
}

// Every combination of an environment's axes (p.hyper_points), the first values' being the base
// point (p.hyper).
void expand_hyper_points(Reader& r, const HyperAxes& axes, Profile& p) {
  for (const auto& [env, env_axes] : axes) {
    if (env_axes.empty()) continue;
    // The product is bounded before any point is built (each factor is ≤ kMaxHyperPoints, so the
    // running product cannot overflow before it passes the bound).
    size_t product = 1;
    for (const HyperAxis& a : env_axes) {
      product *= a.values.size();
      if (product > kMaxHyperPoints)
        r.fail(a.node, "[hyper." + env + "]: the axes up to '" + a.key + "' already make " +
                           std::to_string(product) +
                           " combinations of hyper-parameter values (at most " +
                           std::to_string(kMaxHyperPoints) + ")");
    }
    std::vector<std::vector<std::pair<std::string, HyperValue>>> points{{}};
    for (const HyperAxis& a : env_axes) {
      std::vector<std::vector<std::pair<std::string, HyperValue>>> next;
      for (const auto& pt : points)
        for (const HyperValue& value : a.values) {
          next.push_back(pt);
          next.back().push_back({a.key, value});
        }
      points = std::move(next);
    }
    const Hyper base = p.hyper[env];
    for (size_t i = 0; i < points.size(); ++i) {
      HyperPoint hp{"", base};
      for (const auto& kv : points[i]) {
        const std::string& key = kv.first;  // (a structured binding cannot be captured in C++20)
        hp.tag += (hp.tag.empty() ? "" : ";") + key + "=" + hyper_value_text(kv.second);
        try {
          set_hyper(hp.hyper, key, kv.second);
        } catch (const std::invalid_argument& e) {
          const auto it = std::find_if(env_axes.begin(), env_axes.end(),
                                       [&](const HyperAxis& a) { return a.key == key; });
          r.fail(it->node, e.what());
        }
      }
      if (i == 0) p.hyper[env] = hp.hyper;
      p.hyper_points[env].push_back(std::move(hp));
    }
  }
}

// Every point's values valid. (Whether its networks fit this machine's memory is the run's
// question, not the profile's: `sirl run` checks each task's working set before it starts.)
void check_hyper_points(Reader& r, const toml::table& hy, Profile& p) {
  std::vector<std::pair<std::string, Hyper*>> all;  // every point's values
  for (auto& [env, h] : p.hyper) all.push_back({env, &h});
  for (auto& [env, pts] : p.hyper_points)
    for (auto& pt : pts) all.push_back({env, &pt.hyper});
  for (auto& [env, hp] : all) {
    const Hyper& h = *hp;
    try {
      validate(h);
    } catch (const std::invalid_argument& e) {
      r.fail(&hy, std::string("[hyper.") + env + "]: " + e.what());
    }
  }
}

// The paper's hyper-parameters per environment, then [hyper.all] and [hyper.<env>] overrides. A
// key given a list of values is an axis: the environment's cells run at every combination of its
// axes' values, the first value of each being the base point (p.hyper, tasks without a point).
void parse_hyper(Reader& r, const toml::table& root, Profile& p) {
  for (const auto& env : p.envs) {
    p.hyper[env] = paper_hyper(env);
    p.hyper[env].precision = p.precision;
  }
  const auto* hy = r.table(root, "hyper", false);
  if (!hy) return;
  const HyperAxes axes = read_hyper_tables(r, *hy, p);
  expand_hyper_points(r, axes, p);
  check_hyper_points(r, *hy, p);
}

// Cross-checks: budgets must cover the grid.
void check_budgets(Reader& r, const toml::table& root, const Profile& p) {
  auto check_n = [&](const std::vector<int64_t>& Ns, const char* table, bool has_mp50) {
    for (int64_t N : Ns) {
      if (N > p.queries.similarity || N > p.queries.preference)
        r.fail(root.get(table), std::string("[") + table + "] N = " + std::to_string(N) +
                                    " exceeds the query budget ([queries] similarity = " +
                                    std::to_string(p.queries.similarity) +
                                    ", preference = " + std::to_string(p.queries.preference) + ")");
      if (has_mp50 && N < 50)
        r.fail(root.get(table),
               std::string("[") + table + "] N = " + std::to_string(N) +
                   " is below 50, the MultiPref-50 minimum of one query per human");
    }
  };
  auto has_mp50 = [](const std::vector<Variant>& vs) {
    for (const auto& v : vs)
      if (v.method == Method::multipref50) return true;
    return false;
  };
  const int64_t tpa_train = tpa_train_count(p.queries.tpa_pairs);
  for (const auto& [env, g] : p.axes) {
    check_n(g.fpe_N, "fpe", has_mp50(p.fpe_methods));
    check_n(g.tpa_N, "tpa", has_mp50(p.tpa.methods));
    check_n(g.ablation_N, "ablation",
            std::find(p.ablation_methods.begin(), p.ablation_methods.end(), Method::multipref50) !=
                p.ablation_methods.end());
    check_n(p.robustness.N, "robustness", has_mp50(p.robustness.methods));
    for (const auto* Ms : {&g.tpa_M, &g.ablation_M, &p.robustness.M})
      for (int64_t M : *Ms)
        if (M > tpa_train)
          r.fail(
              root.get(Ms == &g.tpa_M ? "tpa" : (Ms == &g.ablation_M ? "ablation" : "robustness")),
              "M = " + std::to_string(M) + " exceeds the " + std::to_string(tpa_train) +
                  " training pairs per test reward (80 % of [queries] tpa_pairs = " +
                  std::to_string(p.queries.tpa_pairs) + ")");
  }
}

}  // namespace

namespace {

toml::table parse_toml(const std::string& text, const std::string& path) {
  try {
    return toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw ProfileError(path + ":" + std::to_string(e.source().begin.line) + ": " +
                       std::string(e.description()));
  }
}

Profile parse_profile_table(const toml::table& root, const std::string& text,
                            const std::string& path);

}  // namespace

Profile parse_profile(const std::string& text, const std::string& path) {
  if (text.size() > kMaxProfileBytes)  // a stored profile text is anyone's
    throw ProfileError(path + ": a profile text of " + std::to_string(text.size()) +
                       " bytes; a profile is at most " + std::to_string(kMaxProfileBytes));
  const toml::table root = parse_toml(text, path);
  if (root.contains("extends"))
    throw ProfileError(path +
                       ": `extends` needs the profile's file (load_profile resolves it); "
                       "a stored profile text is always resolved");
  return parse_profile_table(root, text, path);
}

namespace {

Profile parse_profile_table(const toml::table& root, const std::string& text,
                            const std::string& path) {
  Reader r(root, path);
  Profile p;
  // The top level: its declared keys and the tables.
  std::set<std::string> top = setting_keys(kProfileSettings, p);
  top.insert({"queries", "teacher", "fpe", "tpa", "ablation", "hyper", "study", "robustness",
              "active", "external", "environments", "pref"});
  parse_file_environments(r, root, path, top);
  for (const auto& e : environments()) top.insert(e.name);  // each environment's own table
  r.only_keys(root, "the profile", top);
  p.path = path;
  p.text = text;
  read_settings(r, root, "the profile", kProfileSettings, p);
  if (p.description.size() > kMaxDescriptionBytes)
    r.fail(root.get("description"), "description: " + std::to_string(p.description.size()) +
                                        " characters; at most " +
                                        std::to_string(kMaxDescriptionBytes) +
                                        " (a few lines: it heads `sirl plan` and the report)");
  for (const auto& e : p.envs) {
    try {
      env_spec(e);
    } catch (const std::invalid_argument& err) {
      r.fail(root.get("envs"), err.what());
    }
  }
  try {
    validate_precision(p.precision);
  } catch (const std::invalid_argument& e) {
    r.fail(root.get("precision"), e.what());
  }
  parse_data_tables(r, root, p.data);
  parse_queries(r, root, p);
  parse_cells(r, root, p);
  parse_external(r, root, p);
  parse_robustness(r, root, p);
  parse_pref(r, root, p);
  parse_active(r, root, p);
  parse_env_axes(r, root, p);
  parse_study(r, root, p);
  parse_hyper(r, root, p);
  check_budgets(r, root, p);
  return p;
}

}  // namespace

namespace {

// [tpa] protocols and [tpa] stop: the names each accepts (kTpaProtocols, kTpaStopRules).
std::string protocols_section() {
  std::string out =
      "## [tpa] protocols, [tpa] stop\n\n"
      "`protocols` lists how TPA cells read out a reward (default: every one); `stop` maps a "
      "method of `[tpa] methods` (or, under an environment's name, a method there) to the rule "
      "its reward heads stop by (default: the `tpa.stop` hyper-parameter).\n\n"
      "| key | accepts | what it is |\n|---|---|---|\n";
  for (const ProtocolInfo& c : kTpaProtocols)
    out += std::string("| `protocols` | `\"") + c.name + "\"` | " + c.doc + " |\n";
  for (const TpaStopRule& rule : kTpaStopRules)
    out += std::string("| `stop` | `\"") + rule.name + "\"` | " + rule.doc + " |\n";
  out +=
      "\n## [pref] stop\n\n"
      "`stop` maps a preference-trained variant the profile runs (`singlepref`, `multipref10`, "
      "`multipref50`, their `+vae` variants), or under an environment's name a variant there, to "
      "the rule its φ trains by (default: the `pref.stop` hyper-parameter, `\"fixed\"`).\n\n"
      "| key | accepts | what it is |\n|---|---|---|\n"
      "| `stop` | `\"fixed\"` | every epoch of `pref.epochs`, the paper's |\n"
      "| `stop` | `\"converged\"` | φ stops once its training loss has converged "
      "(`pref.stop_min_epochs`, `pref.stop_rel_tol`) |\n";
  return out + "\n";
}

}  // namespace

std::string profile_keys_markdown() {
  return keys_section("the top level",
                      "What the profile is and runs on; `extends = \"P\"` (or a list) starts "
                      "from another profile's tables (running.md).",
                      key_rows(kProfileSettings, Profile{})) +
         keys_section("[queries]", "Each seed's query budgets.",
                      key_rows(kQueriesSettings, QueryBundleConfig{})) +
         keys_section("[fpe]", "Which FPE cells run (Fig. 4): every method at every N.",
                      key_rows(kFpeSettings, Profile{})) +
         keys_section("[tpa], [robustness]",
                      "Which TPA cells run (Fig. 5): every method at every N × M in the modes "
                      "`frozen` gives. `[robustness]` takes the same keys for the cells of the "
                      "noisy teachers `[teacher]` lists; `[tpa]` also takes `stop` and "
                      "`protocols` (below).",
                      key_rows(kTpaSettings, TpaGrid{})) +
         keys_section("[ablation]", "Fig. 7: the pre-training and fine-tuning ablation.",
                      key_rows(kAblationSettings, Profile{})) +
         keys_section("[teacher]",
                      "The simulated human who answers every query (the paper's: the perfect "
                      "oracle). A list for `beta`, `mistake` or `attend` keeps the main teacher's "
                      "default for that key and adds one noisy teacher per other listed value; "
                      "`[robustness]` (methods, N, M, frozen, as in `[tpa]`) names their cells.",
                      key_rows(kTeacherSettings, QueryBundleConfig{})) +
         keys_section("[<env>] ([grid], [jaco], a file environment's name)",
                      "The grid's lists for one environment alone (an empty list: no such cell "
                      "there). The table that holds an environment's data also takes the keys "
                      "that environment reads (`trajectories`, …; see running.md).",
                      key_rows(kEnvTableSettings, EnvAxes{})) +
         protocols_section() +
         keys_section("[external.<name>]",
                      "A representation trained elsewhere, read from its embeddings file; it joins "
                      "`[fpe]` and `[tpa]` (frozen) under its name (external-methods.md). A "
                      "relative path is the profile file's folder's.",
                      key_rows(kExternalSettings, ExternalMethod{})) +
         keys_section("[environments.<name>]",
                      "An environment read from a file (environment-files.md), then named in "
                      "`envs` like a built-in one. A relative path is the profile file's "
                      "folder's.",
                      key_rows(kFileEnvironmentSettings, FileEnvironment{})) +
         keys_section("[active], [active.<env>]",
                      "How an active variant's ensemble asks (`sirl@vote`, `sirl@infogain`); "
                      "`[active.<env>]` overrides `[active]` key by key; pool must be at least "
                      "batch.",
                      key_rows(kActiveSettings, ActiveRounds{})) +
         keys_section("[study]",
                      "The user study's simulated cohort and its analysis; the table's presence "
                      "runs the study.",
                      key_rows(kStudySettings, StudyPlan{})) +
         hyper_section();
}

const QueryBundleConfig& queries_for(const Profile& p, const std::string& teacher) {
  if (teacher.empty()) return p.queries;
  for (const auto& t : p.robustness.teachers)
    if (t.tag == teacher) return t.queries;
  throw std::invalid_argument("profile " + p.name + " has no teacher '" + teacher + "'");
}

std::vector<std::string> hyper_point_tags(const Profile& p, const std::string& env) {
  std::vector<std::string> tags{""};
  if (auto it = p.hyper_points.find(env); it != p.hyper_points.end())
    for (size_t i = 1; i < it->second.size(); ++i) tags.push_back(it->second[i].tag);
  return tags;
}

std::string hyper_points_text(const Profile& p) {
  std::string s;
  for (const auto& [env, pts] : p.hyper_points) {
    s += env;
    for (const HyperPoint& hp : pts) s += "\t" + hp.tag;
    s += "\n";
  }
  return s;
}

const Hyper& hyper_at(const Profile& p, const std::string& env, const std::string& tag) {
  if (tag.empty()) return p.hyper.at(env);
  if (auto it = p.hyper_points.find(env); it != p.hyper_points.end())
    for (const HyperPoint& hp : it->second)
      if (hp.tag == tag) return hp.hyper;
  throw std::invalid_argument("no hyper-parameter point '" + tag + "' in environment " + env);
}

std::string tpa_stop_key(const std::string& env, const std::string& variant) {
  return env.empty() ? variant : env + "/" + variant;
}

Hyper tpa_cell_hyper(const Profile& p, const std::string& env, const std::string& tag,
                     const Variant& v) {
  Hyper h = hyper_at(p, env, tag);
  // The environment's own entry first, then the one for every environment.
  for (const std::string& key : {tpa_stop_key(env, v.name()), tpa_stop_key("", v.name())})
    if (auto it = p.tpa_stop_by_method.find(key); it != p.tpa_stop_by_method.end()) {
      h.tpa_stop = it->second;
      break;
    }
  return h;
}

Hyper rep_task_hyper(const Profile& p, const std::string& env, const std::string& tag,
                     const Variant& v) {
  Hyper h = hyper_at(p, env, tag);
  for (const std::string& key : {tpa_stop_key(env, v.name()), tpa_stop_key("", v.name())})
    if (auto it = p.pref_stop_by_method.find(key); it != p.pref_stop_by_method.end()) {
      h.pref_stop = it->second;
      break;
    }
  return h;
}

bool runs_bf16(const Profile& p) {
  if (p.precision == "bf16") return true;
  for (const auto& [env, h] : p.hyper)
    if (bf16_products(h)) return true;
  for (const auto& [env, pts] : p.hyper_points)
    for (const HyperPoint& hp : pts)
      if (bf16_products(hp.hyper)) return true;
  return false;
}

const std::string& precision_of(const Profile& p, const std::string& env) {
  const auto it = p.hyper.find(env);
  return it == p.hyper.end() ? p.precision : it->second.precision;
}

namespace {

// The profile names (stems of *.toml) in a folder, sorted.
std::vector<std::string> profile_names_in(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.path().extension() == ".toml") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

std::vector<std::string> bundled_profiles() {
  try {
    return profile_names_in(data_dir() / "configs");
  } catch (const std::runtime_error&) {
    return {};
  }
}

std::string bundled_profile_names() {
  namespace fs = std::filesystem;
  fs::path dir;
  try {
    dir = data_dir() / "configs";
  } catch (const std::runtime_error& e) {
    return std::string("none: ") + e.what();
  }
  const std::vector<std::string> names = profile_names_in(dir);
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "none found in " + dir.string() : s;
}

namespace {

// over's keys on top of base's: tables merge key by key, any other value (arrays included)
// replaces base's. Nodes keep their source (file and line), so errors still point at the file
// that set the value.
// (Nodes are moved, never copied: toml++ keeps a node's source only when it moves.)
void merge_into(toml::table& base, toml::table&& over) {
  for (auto&& [k, v] : over) {
    toml::node* b = base.get(k.str());
    if (b && b->is_table() && v.is_table())
      merge_into(*b->as_table(), std::move(*v.as_table()));
    else
      base.insert_or_assign(k, std::move(v));
  }
}

// The file of a profile named by path or bare name ("quick": configs/quick.toml here or among the
// installed profiles); `near` is the folder of the profile that names it (extends), searched first.
std::filesystem::path find_profile(const std::string& path_or_name,
                                   const std::filesystem::path& near = {});

// What resolving one profile's `extends` has seen: the chain being resolved (a cycle), and every
// file already resolved (a file reached twice, e.g. two parents sharing a grandparent, is read
// once: without this a chain where each file names the next twice costs 2^depth reads).
struct ResolveState {
  std::vector<std::string> chain;
  std::map<std::string, toml::table> resolved;
  bool composed = false;
};
// Deeper `extends` chains than this are refused (no honest profile comes near it).
constexpr size_t kMaxExtendsDepth = 32;

// A profile file with its parents (`extends = "quick"` or a list, merged left to right, then the
// file's own keys on top), resolved recursively.
toml::table resolve_profile(const std::filesystem::path& file, ResolveState& st) {
  namespace fs = std::filesystem;
  std::vector<std::string>& chain = st.chain;
  const std::string id = fs::weakly_canonical(file).string();
  if (std::find(chain.begin(), chain.end(), id) != chain.end())
    throw ProfileError(file.string() + ": `extends` makes a cycle (" + chain.front() + " → … → " +
                       id + ")");
  if (auto it = st.resolved.find(id); it != st.resolved.end()) return it->second;
  if (chain.size() >= kMaxExtendsDepth)
    throw ProfileError(file.string() + ": `extends` nests deeper than " +
                       std::to_string(kMaxExtendsDepth) + " profiles (from " + chain.front() + ")");
  chain.push_back(id);
  if (std::error_code ec; !fs::is_regular_file(file, ec))  // a FIFO would block the read forever
    throw ProfileError(file.string() + ": not a regular file");
  if (std::error_code ec; fs::file_size(file, ec) > kMaxProfileBytes)
    throw ProfileError(file.string() + ": " + std::to_string(fs::file_size(file, ec)) +
                       " bytes; a profile is at most " + std::to_string(kMaxProfileBytes));
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  if (!in && !in.eof()) throw ProfileError(file.string() + ": cannot read");
  toml::table own = parse_toml(ss.str(), file.string());
  const toml::node* ext = own.get("extends");
  if (!ext) {
    chain.pop_back();
    st.resolved.emplace(id, own);
    return own;
  }
  st.composed = true;
  std::vector<std::string> parents;
  auto bad = [&] {
    throw ProfileError(file.string() + ":" + std::to_string(ext->source().begin.line) +
                       ": extends must be a profile name or path, or a list of them");
  };
  if (ext->is_string()) {
    parents.push_back(*ext->value<std::string>());
  } else if (const auto* a = ext->as_array()) {
    for (auto&& e : *a) {
      if (!e.is_string()) bad();
      parents.push_back(*e.value<std::string>());
    }
  } else {
    bad();
  }
  if (parents.empty()) bad();
  toml::table merged;
  for (const auto& parent : parents)
    merge_into(merged, resolve_profile(find_profile(parent, file.parent_path()), st));
  own.erase("extends");
  merge_into(merged, std::move(own));
  chain.pop_back();
  st.resolved.emplace(id, merged);
  return merged;
}

// "KEY=VALUE" as a one-line TOML document (KEY may be dotted: hyper.grid."sirl.epochs").
toml::table parse_setting(const std::string& setting) {
  const size_t eq = setting.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ProfileError("--set " + setting + ": expected KEY=VALUE, e.g. seeds=[0,1] or " +
                       "hyper.grid.\"sirl.epochs\"=100");
  try {
    return toml::parse(setting.substr(0, eq) + " = " + setting.substr(eq + 1), "--set " + setting);
  } catch (const toml::parse_error& e) {
    throw ProfileError("--set " + setting + ": " + std::string(e.description()) +
                       " (VALUE is TOML: a number, true/false, a \"string\" or an [array])");
  }
}

}  // namespace

Profile load_profile(const std::string& path_or_name, const std::vector<std::string>& settings) {
  const std::filesystem::path file = find_profile(path_or_name);
  ResolveState st;
  toml::table root = resolve_profile(file, st);
  if (!st.composed && settings.empty()) {  // the file as written is the profile's text
    std::ifstream in(file);
    std::stringstream ss;
    ss << in.rdbuf();
    return parse_profile(ss.str(), file.string());
  }
  for (const auto& s : settings) merge_into(root, parse_setting(s));
  // The resolved profile is the one recorded (results, resume, merge): one self-contained text.
  std::ostringstream text;
  text << "# " << file.string() << (st.composed ? " with its parents (extends)" : "");
  for (const auto& s : settings) text << ", --set " << s;
  text << ", resolved\n" << root << "\n";
  return parse_profile_table(root, text.str(), file.string());
}

namespace {

std::filesystem::path find_profile(const std::string& path_or_name,
                                   const std::filesystem::path& near) {
  namespace fs = std::filesystem;
  std::vector<fs::path> candidates{path_or_name};
  fs::path bundled;
  std::string missing_data;
  if (fs::path(path_or_name).extension() != ".toml") {
    candidates.push_back(fs::path("configs") / (path_or_name + ".toml"));
    try {
      bundled = data_dir() / "configs";
      candidates.push_back(bundled / (path_or_name + ".toml"));
    } catch (const std::runtime_error& e) {  // no bundled profiles: said in the error below
      missing_data = e.what();
    }
  }
  if (!near.empty()) {
    const fs::path rel = near / path_or_name;
    candidates.insert(candidates.begin(), rel);
    if (rel.extension() != ".toml")
      candidates.insert(candidates.begin() + 1, rel.string() + ".toml");
  }
  for (const auto& c : candidates) {
    std::error_code ec;
    if (fs::is_regular_file(c, ec)) return c;
  }
  throw ProfileError(
      "profile '" + path_or_name + "' not found (looked for " + candidates.front().string() +
      (candidates.size() > 1
           ? ", configs/" + path_or_name + ".toml" +
                 (bundled.empty() ? std::string()
                                  : " and " + (bundled / path_or_name).string() + ".toml")
           : std::string()) +
      ")" + (missing_data.empty() ? std::string() : "; " + missing_data) + [&] {
        std::vector<std::string> known = profile_names_in("configs");
        if (!bundled.empty())
          for (auto& n : profile_names_in(bundled)) known.push_back(std::move(n));
        return did_you_mean(path_or_name, known);
      }());
}

}  // namespace

}  // namespace sirl
