// The representation methods, declared once each: the name profiles, task keys and tables use,
// what the method learns from, its role in the report, and how every figure labels and colours
// it. Code that needs a method's name or role reads it here, and the results file carries the
// presentation of every variant it holds (/methods/<variant>, written from `variant_style`), so
// the figure and report scripts hold no list of methods. Adding a method is one entry in
// method_catalog.cpp beside its training function (docs/ARCHITECTURE.md, "Adding a method").
#pragma once
#include <string>
#include <vector>

#include "engine/hyperparams.h"
#include "engine/method_trainers.h"
#include "engine/selection.h"

namespace sirl {

// `external`: a representation learned outside the engine and handed in as its embedding of Ξ
// (a profile's [external.<name>], `sirl evaluate`); it has no weights, so its TPA cells are frozen.
// `truth` and `raw`: the references every profile scores beside the methods (never a baseline of
// the paper's claims): φ*(ξ) itself, the normalised true features (the ceiling), and the
// trajectory's network input itself (the floor a learned representation must beat). Both are
// functions of Ξ alone: no training, no weights, frozen cells only.
enum class Method { sirl, vae, multipref10, multipref50, singlepref, random, external, truth, raw };

// "sirl", "vae", "multipref10", "multipref50", "singlepref", "random", "external".
const char* method_name(Method m);
// Inverse of method_name; throws std::invalid_argument listing the valid names (the built-in
// six; "external" is accepted too, as records of external methods carry it).
Method parse_method(const std::string& name);
// Methods whose φ is trained on human queries (N matters). An external method hands in one
// embedding per N, so N matters for it too.
bool uses_queries(Method m);
// Methods that accept VAE pre-training as a switch (SIRL+VAE, MultiPref+VAE, SinglePref+VAE).
bool accepts_vae_pretrain(Method m);
// truth and raw: the reference representations (see Method).
bool is_reference(Method m);

// A method's part in the paper's claims and the report's tables.
enum class MethodRole {
  sirl,       // the paper's method (H1, H2 are about it)
  baseline,   // a baseline the claims compare SIRL with
  reference,  // a ceiling or floor scored beside the methods, never a baseline (truth, raw)
  external,   // a representation trained elsewhere (`sirl evaluate`, [external.<name>])
};
const char* role_name(MethodRole r);  // "sirl", "baseline", "reference", "external"

struct PreferenceSet;
struct RewardSet;
struct RewardSets;

// How a method obtains φ: the function that trains it, the settings it reads, and what one
// training answer costs (the plan's FLOP model and its calibration class read these).
struct MethodTraining {
  // null: φ is not trained by the method's own task (Random: its seeded initialisation; VAE: the
  // VAE task's encoder; external, truth, raw: φ(Ξ) is given).
  TrainFn train = nullptr;
  // The schedule (epochs, batch, Adam) it trains with, and the prefix of every setting of its
  // own it reads ("sirl.": sirl.epochs, sirl.lr, sirl.margin, …).
  TrainSchedule Hyper::*schedule = nullptr;
  const char* hyper_prefix = "";
  int rows_per_answer = 0;  // trajectories one answer feeds through φ: 3 (triplet), 2 (pair)
  // Training may end at an exact fixed point (SIRL's hinge), so the plan expects fewer epochs
  // than the schedule's (experiment/expected_epochs.h).
  bool stops_at_fixed_point = false;
  // The calibration class that times it on this machine (experiment/calibration.h).
  const char* rate_class = "";
  // Preference methods: the bundle's answers they train on and the humans (heads) behind them.
  PreferenceSet QueryBundle::*preferences = nullptr;
  RewardSet RewardSets::*humans = nullptr;
};

struct MethodSpec {
  Method method = Method::sirl;
  const char* name = "";    // "sirl", "multipref10", …: profiles, task keys, tables
  const char* label = "";   // figures and report: "SIRL", "MultiPref-10", …
  const char* colour = "";  // one matplotlib colour per method, the same in every figure
  MethodRole role = MethodRole::baseline;
  // The human answers φ learns from: "similarity" (triplets), "preference" (pairs), "" (none:
  // Ξ alone, or nothing). Those that learn from answers have N as an axis of their cells.
  const char* queries = "";
  bool uses_queries = false;  // N is an axis of its cells (an external method: one φ per N)
  bool accepts_vae = false;   // "+vae": φ starts from the VAE encoder
  // The paper's best TPA mode (frozen = "best"): φ frozen (true) or fine-tuned (false).
  bool best_frozen = false;
  // The "+vae" variant as a line of its own in Figs. 4 and 5 (the paper draws SIRL+VAE only);
  // null: its cells are drawn only where the ablation draws them, by the method's own colour.
  const char* vae_colour = nullptr;
  // References: the matplotlib dash pattern of their reference line ("6 3"); null otherwise.
  const char* dashes = nullptr;
  // Whether a profile may list it among its methods (external: [external.<name>]; references:
  // every profile scores them).
  bool listable = true;
  MethodTraining training;
};

// Every method, in the order figures draw them.
const std::vector<MethodSpec>& method_catalog();
const MethodSpec& method_spec(Method m);

// How figures and the report show one variant (a method with "+vae" and "@selection"), as the
// results file stores it under /methods/<name>.
struct VariantStyle {
  std::string name;     // the variant's name: "sirl+vae", "sirl@vote", an external's name
  std::string method;   // its method's name ("external" for an external one)
  std::string label;    // "SIRL+VAE", "SIRL (active: vote entropy)", …
  std::string colour;   // matplotlib colour
  std::string role;     // role_name of its method
  std::string queries;  // MethodSpec::queries
  bool best_frozen = false;
  bool accepts_vae = false;
  int figure_order = -1;  // position among the method lines of Figs. 4, 5 and the curves; -1: none
  int catalog_order = 0;  // its method's position in method_catalog()
  bool vae = false;
  std::string selection;        // "uniform", "vote", "infogain"
  std::string selection_label;  // the active-query figures' legend: "uniform (the paper)", …
  std::string selection_colour;
  int selection_order = 0;  // uniform 0, then the active rules
  std::string dashes;       // references: the dash pattern of their line
};
// external_index: an external variant's position among the externals of the file (its colour).
VariantStyle variant_style(Method m, bool vae, Selection selection, const std::string& name,
                           int external_index = 0);

}  // namespace sirl
