#include "engine/method_catalog.h"

#include <stdexcept>

#include "datasets/enum_names.h"
#include "datasets/query_bundle.h"

namespace sirl {

namespace {
constexpr EnumName<MethodRole> kRoleNames[] = {
    {MethodRole::sirl, "sirl"},
    {MethodRole::baseline, "baseline"},
    {MethodRole::reference, "reference"},
    {MethodRole::external, "external"},
};
}  // namespace

const char* role_name(MethodRole r) {
  return name_in(kRoleNames, r);
}

namespace {

MethodTraining preference_training(PreferenceSet QueryBundle::*answers,
                                   RewardSet RewardSets::*humans) {
  return {.train = train_preferences,
          .schedule = &Hyper::pref,
          .hyper_prefix = "pref.",
          .rows_per_answer = 2,
          .rate_class = "rep_pref",
          .preferences = answers,
          .humans = humans};
}

}  // namespace

const std::vector<MethodSpec>& method_catalog() {
  // The colours are matplotlib's tab10/tab20 ones the paper's figures resemble.
  static const std::vector<MethodSpec> c = {
      {.method = Method::sirl,
       .name = "sirl",
       .label = "SIRL",
       .colour = "#d62728",
       .role = MethodRole::sirl,
       .queries = "similarity",
       .uses_queries = true,
       .accepts_vae = true,
       .best_frozen = true,
       .vae_colour = "#ff9896",
       .training = {.train = train_sirl,
                    .schedule = &Hyper::sirl,
                    .hyper_prefix = "sirl.",
                    .rows_per_answer = 3,
                    .stops_at_fixed_point = true,
                    .rate_class = "rep_sirl"}},
      {.method = Method::vae, .name = "vae", .label = "VAE", .colour = "#2ca02c"},
      {.method = Method::multipref10,
       .name = "multipref10",
       .label = "MultiPref-10",
       .colour = "#1f77b4",
       .queries = "preference",
       .uses_queries = true,
       .accepts_vae = true,
       .training = preference_training(&QueryBundle::multipref10, &RewardSets::multipref10)},
      {.method = Method::multipref50,
       .name = "multipref50",
       .label = "MultiPref-50",
       .colour = "#17becf",
       .queries = "preference",
       .uses_queries = true,
       .accepts_vae = true,
       .training = preference_training(&QueryBundle::multipref50, &RewardSets::multipref50)},
      {.method = Method::singlepref,
       .name = "singlepref",
       .label = "SinglePref",
       .colour = "#9467bd",
       .queries = "preference",
       .uses_queries = true,
       .accepts_vae = true,
       .training = preference_training(&QueryBundle::singlepref, &RewardSets::singlepref)},
      {.method = Method::random, .name = "random", .label = "Random", .colour = "#7f7f7f"},
      // An external method's label and colour are its own (variant_style); it hands in one
      // embedding per N, so N is an axis of its cells.
      {.method = Method::external,
       .name = "external",
       .label = "external",
       .colour = "#8c564b",
       .role = MethodRole::external,
       .uses_queries = true,
       .best_frozen = true,
       .listable = false},
      {.method = Method::truth,
       .name = "truth",
       .label = "truth φ* (ceiling)",
       .colour = "#000000",
       .role = MethodRole::reference,
       .best_frozen = true,
       .dashes = "6 3",
       .listable = false},
      {.method = Method::raw,
       .name = "raw",
       .label = "raw input (floor)",
       .colour = "#555555",
       .role = MethodRole::reference,
       .best_frozen = true,
       .dashes = "1 1.5",
       .listable = false},
  };
  return c;
}

const MethodSpec& method_spec(Method m) {
  for (const MethodSpec& s : method_catalog())
    if (s.method == m) return s;
  throw std::logic_error("a Method without a catalog entry");
}

namespace {

// External methods, in the order the file lists them.
constexpr const char* kExternalColours[] = {"#8c564b", "#e377c2", "#bcbd22",
                                            "#000000", "#ff7f0e", "#aec7e8"};

struct SelectionStyle {
  Selection selection;
  const char* label;
  const char* colour;
};
constexpr SelectionStyle kSelections[] = {
    {Selection::uniform, "uniform (the paper)", "#d62728"},
    {Selection::vote, "active: vote entropy", "#1f77b4"},
    {Selection::infogain, "active: information gain", "#2ca02c"},
};

}  // namespace

VariantStyle variant_style(Method m, bool vae, Selection selection, const std::string& name,
                           int external_index) {
  const MethodSpec& s = method_spec(m);
  VariantStyle v;
  for (const MethodSpec& o : method_catalog()) {
    if (o.method == m) break;
    ++v.catalog_order;
  }
  v.name = name;
  v.method = s.name;
  v.role = role_name(s.role);
  v.queries = s.queries;
  v.best_frozen = s.best_frozen;
  v.accepts_vae = s.accepts_vae;
  v.vae = vae;
  v.selection = selection_name(selection);
  for (size_t i = 0; i < std::size(kSelections); ++i)
    if (kSelections[i].selection == selection) {
      v.selection_label = kSelections[i].label;
      v.selection_colour = kSelections[i].colour;
      v.selection_order = int(i);
    }
  if (s.dashes) v.dashes = s.dashes;
  if (m == Method::external) {
    v.label = name;
    v.colour = kExternalColours[size_t(external_index) % std::size(kExternalColours)];
    v.figure_order = 1000 + external_index;  // after every built-in method
    return v;
  }
  v.label = std::string(s.label) + (vae ? "+VAE" : "");
  v.colour = vae && s.vae_colour ? s.vae_colour : s.colour;
  if (selection != Selection::uniform) v.label += std::string(" (") + v.selection_label + ")";
  // Figs. 4 and 5 draw each listable method and the "+vae" variants the catalog gives a colour,
  // each right after its method; selection variants have figures of their own.
  if (s.listable && selection == Selection::uniform && (!vae || s.vae_colour)) {
    int order = 0;
    for (const MethodSpec& o : method_catalog()) {
      if (o.method == m) break;
      if (o.listable) order += o.vae_colour ? 2 : 1;
    }
    v.figure_order = order + (vae ? 1 : 0);
  }
  return v;
}

// Names and roles, read from the declarations above.
const char* method_name(Method m) {
  return method_spec(m).name;
}

Method parse_method(const std::string& name) {
  for (const MethodSpec& s : method_catalog())
    if (name == s.name) return s.method;
  std::string known;
  for (const MethodSpec& s : method_catalog())
    if (s.listable) known += (known.empty() ? "" : ", ") + std::string(s.name);
  throw std::invalid_argument("unknown method '" + name + "' (expected one of " + known + ")");
}

bool uses_queries(Method m) {
  return method_spec(m).uses_queries;
}
bool accepts_vae_pretrain(Method m) {
  return method_spec(m).accepts_vae;
}
bool is_reference(Method m) {
  return method_spec(m).role == MethodRole::reference;
}

}  // namespace sirl
