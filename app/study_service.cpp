#include "app/study_service.h"

#include <nlohmann/json.hpp>

#include <charconv>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace sirl::app {

namespace {

using nlohmann::json;

// Serialised text; invalid UTF-8 (a hostile request echoed in an error) becomes U+FFFD instead of
// an exception.
std::string text(const json& j) {
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

// Rows of Ξ as a JSON array.
json ids(const int32_t* v, int64_t n) {
  return json(std::vector<int32_t>(v, v + n));
}

// The first value of `key` (as httplib's get_param_value: a multimap keeps equal keys in
// insertion order, and find() may return any of them), or nullptr when the request has none.
const std::string* param(const RequestParams& r, const char* key) {
  const auto it = r.lower_bound(key);
  return it == r.end() || it->first != key ? nullptr : &it->second;
}
std::string param_or_empty(const RequestParams& r, const char* key) {
  const std::string* v = param(r, key);
  return v ? *v : std::string();
}

double now_unix() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

Reply error_reply(int status, const std::string& message) {
  return {status, text(json{{"error", message}})};
}

bool parse_index(const std::string& text, int64_t& out) {
  if (text.empty() || text.size() > 18) return false;  // 18 digits always fit in int64
  for (char c : text)
    if (c < '0' || c > '9') return false;
  out = std::stoll(text);
  return true;
}

bool parse_decimal(const std::string& text, double& out) {
  if (text.empty() || text.size() > 32) return false;
  for (char c : text)
    if (!((c >= '0' && c <= '9') || c == '.' || c == '-' || c == 'e' || c == 'E' || c == '+'))
      return false;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && ptr == text.data() + text.size() && std::isfinite(out);
}

StudyService::StudyService(Study study, std::shared_ptr<const Dataset> data,
                           std::string participant, int practice, Commit commit)
    : study_(std::move(study)),
      data_(std::move(data)),
      id_(std::move(participant)),
      view_(env_spec(study_.env).view),
      commit_(std::move(commit)) {
  if (!study_.find(id_)) throw std::invalid_argument("participant " + id_ + " is not in the study");
  practice_ = plan_participant(*data_, "practice", practice, practice, 12345);
}

StudyParticipant StudyService::participant() const {
  std::lock_guard lock(mu_);
  return *study_.find(id_);
}

bool StudyService::authorised(const RequestParams& r, Reply& refused) const {
  const std::string p = param_or_empty(r, "p"), t = param_or_empty(r, "t");
  const StudyParticipant* who = study_.find(p);  // participants are fixed once serving
  if (!who || who->token != t) {
    refused = error_reply(403, "unknown participant or wrong token");
    return false;
  }
  if (p != id_) {
    refused = error_reply(403, "this server records participant " + id_ + " only");
    return false;
  }
  return true;
}

std::string StudyService::state_json() const {
  const StudyParticipant& p = *study_.find(id_);
  const bool sim_left = p.similarity_done() < p.similarity_count();
  const bool pref_left = p.preference_done() < p.preference_count();
  json o;
  o["participant"] = p.id;
  o["env"] = study_.env;
  o["view"] = view_name(view_);
  o["title"] = env_spec(study_.env).title;
  o["features_gloss"] = env_spec(study_.env).study_features;
  o["features"] = data_->feature_names;
  o["scenario"] = p.scenario;
  o["stage"] = sim_left ? "similarity" : pref_left ? "preference" : "done";
  o["similarity"] = {{"done", p.similarity_done()}, {"total", p.similarity_count()}};
  o["preference"] = {{"done", p.preference_done()}, {"total", p.preference_count()}};
  if (sim_left)
    o["next"] = {{"kind", "similarity"},
                 {"index", p.similarity_done()},
                 {"trajectories", ids(p.similarity.data() + 3 * p.similarity_done(), 3)}};
  else if (pref_left)
    o["next"] = {{"kind", "preference"},
                 {"index", p.preference_done()},
                 {"trajectories", ids(p.preference.data() + 2 * p.preference_done(), 2)}};
  else
    o["next"] = nullptr;
  json sim = json::array(), pref = json::array();
  for (int64_t i = 0; i < practice_.similarity_count(); ++i)
    sim.push_back(ids(practice_.similarity.data() + 3 * i, 3));
  for (int64_t i = 0; i < practice_.preference_count(); ++i)
    pref.push_back(ids(practice_.preference.data() + 2 * i, 2));
  o["practice"] = {{"similarity", sim}, {"preference", pref}};
  return text(o);
}

Reply StudyService::state(const RequestParams& r) {
  Reply reply;
  if (!authorised(r, reply)) return reply;
  std::lock_guard lock(mu_);
  return {200, state_json()};
}

// An arm view's end-effector path [21, 3] (m), the arm's pose at each waypoint [21, 8, 3] and
// the objects; a plane view's cells [9, 2] and end angle.
Reply StudyService::trajectory(const RequestParams& r) {
  Reply reply;
  if (!authorised(r, reply)) return reply;
  int64_t id = -1;
  if (!parse_index(param_or_empty(r, "id"), id) || id >= data_->count)
    return error_reply(400,
                       "id must be a trajectory row in [0, " + std::to_string(data_->count) + ")");
  const Dataset& d = *data_;
  json objects = json::array();
  for (size_t k = 0; k < d.object_names.size(); ++k) {
    const float* pos = d.object_positions.data() + k * d.object_dim;
    objects.push_back(
        {{"name", d.object_names[k]}, {"pos", std::vector<float>(pos, pos + d.object_dim)}});
  }
  const TrajectoryView v = env_spec(study_.env).draw(d, id);
  json points = json::array();
  for (const auto& q : v.points)
    points.push_back(view_ == EnvView::arm ? json{q[0], q[1], q[2]} : json{q[0], q[1]});
  json o = {{"id", id}, {"objects", objects}, {"points", points}};
  if (view_ == EnvView::plane) o["angle"] = v.end_angle_deg;
  if (!v.links.empty()) {  // [waypoints][base + links][3]: the arm posed at each waypoint
    json arm = json::array();
    for (const auto& pose : v.links) {
      json p = json::array();
      for (const auto& q : pose) p.push_back({q[0], q[1], q[2]});
      arm.push_back(p);
    }
    o["arm"] = arm;
  }
  return {200, text(o)};
}

Reply StudyService::answer(const RequestParams& r) {
  Reply reply;
  if (!authorised(r, reply)) return reply;
  return commit_answer(r);
}

Reply StudyService::commit_answer(const RequestParams& r) {
  for (const char* f : {"kind", "index", "answer", "response_ms"})
    if (!param(r, f)) return error_reply(400, std::string("missing field '") + f + "'");
  const std::string kind = *param(r, "kind");
  if (kind != "similarity" && kind != "preference")
    return error_reply(400, "kind must be similarity or preference, got '" + kind + "'");
  int64_t index = 0;
  double value = 0, ms = 0;
  if (!parse_index(*param(r, "index"), index))
    return error_reply(400, "index must be a query number (0, 1, 2, ...)");
  if (!parse_decimal(*param(r, "answer"), value) || !parse_decimal(*param(r, "response_ms"), ms))
    return error_reply(400, "answer and response_ms must be decimal numbers");
  if (ms < 0 || ms > 3.6e6)
    return error_reply(400, "response_ms must be a time in [0, 3600000] ms");
  std::lock_guard lock(mu_);
  StudyParticipant& p = *study_.find(id_);
  const bool sim = kind == "similarity";
  const int64_t done = sim ? p.similarity_done() : p.preference_done();
  const int64_t total = sim ? p.similarity_count() : p.preference_count();
  if (!sim && p.similarity_done() < p.similarity_count())
    return error_reply(400, "preference queries come after the similarity queries");
  if (index < done)
    return error_reply(400, kind + " query " + std::to_string(index) + " is already answered");
  if (index >= total)
    return error_reply(400, kind + " query " + std::to_string(index) + " does not exist");
  if (index > done)
    return error_reply(400, "out of order: the next " + kind + " query is " + std::to_string(done));
  if (sim && !(value == 0 || value == 1 || value == 2))
    return error_reply(400, "a similarity answer is the position (0, 1 or 2) of the odd one out");
  if (!sim && !(value == 0 || value == 0.5 || value == 1))
    return error_reply(400, "a preference answer is 1 (first), 0 (second) or 0.5 (equal)");
  // Only the answer vectors change (authorised() reads id and token without the mutex).
  if (sim) {
    p.similarity_answer.push_back(int32_t(value));
    p.similarity_ms.push_back(float(ms));
    p.similarity_time.push_back(now_unix());
  } else {
    p.preference_answer.push_back(float(value));
    p.preference_ms.push_back(float(ms));
    p.preference_time.push_back(now_unix());
  }
  try {
    commit_(study_);
  } catch (const std::exception& e) {
    if (sim) {  // not durable: not accepted
      p.similarity_answer.pop_back(), p.similarity_ms.pop_back(), p.similarity_time.pop_back();
    } else {
      p.preference_answer.pop_back(), p.preference_ms.pop_back(), p.preference_time.pop_back();
    }
    return error_reply(500, std::string("could not save the answer: ") + e.what());
  }
  return {200, state_json()};
}

}  // namespace sirl::app
