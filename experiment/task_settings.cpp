#include "experiment/task_settings.h"

#include <algorithm>
#include <sstream>

#include "datasets/environments.h"
#include "datasets/exact_text.h"
#include "experiment/profile_settings.h"

namespace sirl {

// A field added to one of these structs must be added to its describe_* below (and then the
// size here updated): a setting the digest does not see would let a stale task be reused.
static_assert(sizeof(QueryBundleConfig) == 96, "describe the new field in describe_queries");
static_assert(sizeof(Teacher) == 56, "describe the new Teacher field in describe_queries");
static_assert(sizeof(CohortConfig) == 88, "describe the new CohortConfig field in describe_study");
static_assert(sizeof(StudyPlan) == 120, "describe the new StudyPlan field in describe_study");
static_assert(sizeof(ActiveRounds) == 40,
              "declare the new ActiveRounds field in kActiveSettings (profile_settings.h)");
static_assert(sizeof(ExternalMethod) == 152, "describe the new field in describe_external");

// Settings added after results were stored, as their describe() line at the default every earlier
// result ran with: left out of a digest at that value, so those results are still found.
constexpr std::string_view kOmittedAtDefault[] = {"tpa.shadow_rel_tol = 0"};

std::string hyper_lines(const Hyper& h, std::initializer_list<std::string_view> prefixes) {
  std::istringstream in(describe(h));
  std::string out, line;
  while (std::getline(in, line)) {
    if (std::find(std::begin(kOmittedAtDefault), std::end(kOmittedAtDefault), line) !=
        std::end(kOmittedAtDefault))
      continue;
    for (std::string_view p : prefixes)
      if (line.starts_with(p)) {
        out += line + "\n";
        break;
      }
  }
  return out;
}

std::string describe_data(const Profile& p, const std::string& env) {
  const EnvSpec& spec = env_spec(env);
  return spec.describe_data ? spec.describe_data(p.data) : std::string();
}

std::string describe_queries(const QueryBundleConfig& q) {
  std::string mask;
  for (uint8_t m : q.teacher.mask) mask += char('0' + (m != 0));
  return "queries" + settings_text(q, kQueriesSettings) + " attend=" + exact_number(q.attend) +
         " teacher beta=" + exact_number(q.teacher.beta) +
         " mistake=" + exact_number(q.teacher.mistake) + " skip=" + exact_number(q.teacher.skip) +
         " equal=" + exact_number(q.teacher.equal) + " mask=" + mask + "\n";
}

std::string describe_active(const ActiveRounds& a) {
  return "active" + settings_text(a, kActiveSettings) + "\n";
}

std::string describe_study(const StudyPlan& s) {
  const CohortConfig& c = s.cohort;
  return "study enabled=" + exact_number(s.enabled) + " epochs=" + exact_number(s.epochs) +
         " tpa_epochs=" + exact_number(s.tpa_epochs) + " seeds=" + exact_number(s.seeds) +
         " splits=" + exact_number(s.splits) + " random_frozen=" + exact_number(s.random_frozen) +
         "\ncohort env=" + c.env + " trajectories=" + exact_number(double(c.trajectories)) +
         " users=" + exact_number(c.users) + " similarity=" + exact_number(double(c.similarity)) +
         " preference=" + exact_number(double(c.preference)) + " beta=" + exact_number(c.beta) +
         " mistake=" + exact_number(c.mistake) + " seed=" + exact_number(double(c.seed)) + "\n" +
         // A cohort on an environment from a file depends on the file's bytes, not its name (a
         // built-in environment's Ξ is set by the cohort's own fields above).
         (s.enabled && env_spec(c.env).from_file ? env_spec(c.env).describe_data(EnvConfig{})
                                                 : std::string());
}

std::string describe_external(const ExternalMethod& m) {
  // The description and environment list change no embedding: left out.
  return "external name=" + m.name + " embeddings=" + m.embeddings + " xxh3=" + m.xxh3 + "\n";
}

}  // namespace sirl
