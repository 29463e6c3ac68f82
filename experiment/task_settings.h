// What a task reads of its profile, as canonical text: the settings half of its content digest
// (experiment/task_digest.h). Each task kind's `settings` (experiment/task_kinds.h) is built from
// these, so that two profiles that differ only where a task does not look (a comment, key order,
// another environment's or another method's hyper-parameters, one more seed) give it the same
// digest. Omitting something a task's result depends on would let a stale result be reused: each
// describe_* below covers every field of its struct (static_asserts on the structs' sizes make
// adding a field without describing it a compile error).
#pragma once
#include <initializer_list>
#include <string>
#include <string_view>

#include "experiment/profile.h"

namespace sirl {

// "key = value" lines of describe(h) whose key starts with one of `prefixes` ("sirl.", "phi.",
// "precision"): the hyper-parameters a task reads, what its digest hashes and what a
// representation's record states it was trained with.
std::string hyper_lines(const Hyper& h, std::initializer_list<std::string_view> prefixes);

// Ξ's settings for environment `env` ([jaco]'s trajectories, data seed, deformations, …).
std::string describe_data(const Profile& p, const std::string& env);
// The query budgets and the teacher who answers them.
std::string describe_queries(const QueryBundleConfig& q);
// [active.<env>].
std::string describe_active(const ActiveRounds& a);
// [study]: the simulated cohort and its pipeline's settings.
std::string describe_study(const StudyPlan& s);
// [external.<name>]: where its embeddings are and their digest.
std::string describe_external(const ExternalMethod& m);

}  // namespace sirl
