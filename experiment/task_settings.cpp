#include "experiment/task_settings.h"

#include <cstdio>
#include <sstream>

namespace sirl {

// A field added to one of these structs must be added to its describe_* below (and then the
// size here updated): a setting the digest does not see would let a stale task be reused.
static_assert(sizeof(GridConfig) == 28, "describe the new GridConfig field in describe_data");
static_assert(sizeof(JacoConfig) == 104, "describe the new JacoConfig field in describe_data");
static_assert(sizeof(QueryBundleConfig) == 96, "describe the new field in describe_queries");
static_assert(sizeof(Teacher) == 56, "describe the new Teacher field in describe_queries");
static_assert(sizeof(CohortConfig) == 88, "describe the new CohortConfig field in describe_study");
static_assert(sizeof(StudyPlan) == 120, "describe the new StudyPlan field in describe_study");
static_assert(sizeof(ActiveRounds) == 40, "describe the new ActiveRounds field in describe_active");
static_assert(sizeof(ExternalMethod) == 152, "describe the new field in describe_external");

namespace {

// Round-trip exact: two values print alike only if they are the same double.
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

template <typename T, size_t K>
std::string triple(const std::array<T, K>& a) {
  std::string s;
  for (size_t i = 0; i < K; ++i) {
    if (i) s.push_back(',');
    s.append(num(double(a[i])));
  }
  return s;
}

}  // namespace

std::string hyper_lines(const Hyper& h, std::initializer_list<std::string_view> prefixes) {
  std::istringstream in(describe(h));
  std::string out, line;
  while (std::getline(in, line))
    for (std::string_view p : prefixes)
      if (line.starts_with(p)) {
        out += line + "\n";
        break;
      }
  return out;
}

std::string describe_data(const Profile& p, const std::string& env) {
  const GridConfig& g = p.data.grid;
  std::string s = "grid size=" + num(g.size) + " obstacle1=" + triple(g.obstacle1) +
                  " obstacle2=" + triple(g.obstacle2) + " laptop=" + triple(g.laptop) + "\n";
  if (!env_spec(env).data_table.empty()) {
    // Every field but `threads` (the result never depends on it).
    const JacoConfig& j = p.data.jaco;
    s += "jaco trajectories=" + num(double(j.trajectories)) + " waypoints=" + num(j.waypoints) +
         " max_deformations=" + num(j.max_deformations) +
         " max_deformation=" + num(j.max_deformation) + " laptop=" + triple(j.laptop) +
         " human=" + triple(j.human) + " table_z=" + num(j.table_z) +
         " with_human=" + num(j.with_human) + " seed=" + num(double(j.seed)) + "\n";
  }
  return s;
}

std::string describe_queries(const QueryBundleConfig& q) {
  std::string mask;
  for (uint8_t m : q.teacher.mask) mask += char('0' + (m != 0));
  return "queries similarity=" + num(double(q.similarity)) +
         " preference=" + num(double(q.preference)) + " tpa_pairs=" + num(double(q.tpa_pairs)) +
         " fpe_trajectories=" + num(double(q.fpe_trajectories)) + " attend=" + num(q.attend) +
         " teacher beta=" + num(q.teacher.beta) + " mistake=" + num(q.teacher.mistake) +
         " skip=" + num(q.teacher.skip) + " equal=" + num(q.teacher.equal) + " mask=" + mask + "\n";
}

std::string describe_active(const ActiveRounds& a) {
  return "active members=" + num(a.members) + " pool=" + num(double(a.pool)) +
         " batch=" + num(double(a.batch)) + " round_epochs=" + num(a.round_epochs) +
         " mu=" + num(a.mu) + "\n";
}

std::string describe_study(const StudyPlan& s) {
  const CohortConfig& c = s.cohort;
  return "study enabled=" + num(s.enabled) + " epochs=" + num(s.epochs) +
         " tpa_epochs=" + num(s.tpa_epochs) + " seeds=" + num(s.seeds) +
         " splits=" + num(s.splits) + " random_frozen=" + num(s.random_frozen) +
         "\ncohort env=" + c.env + " trajectories=" + num(double(c.trajectories)) +
         " users=" + num(c.users) + " similarity=" + num(double(c.similarity)) +
         " preference=" + num(double(c.preference)) + " beta=" + num(c.beta) +
         " mistake=" + num(c.mistake) + " seed=" + num(double(c.seed)) + "\n";
}

std::string describe_external(const ExternalMethod& m) {
  // The description and environment list change no embedding: left out.
  return "external name=" + m.name + " embeddings=" + m.embeddings + " xxh3=" + m.xxh3 + "\n";
}

}  // namespace sirl
