// The study server's request handlers without the HTTP layer: each takes a request's decoded
// parameters (query string or form body) and returns a status and a JSON body. The server
// (app/study_server.cpp) only routes; tests and fuzz/fuzz_study_requests.cpp call these directly.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "datasets/dataset.h"
#include "datasets/environments.h"
#include "datasets/study.h"

namespace sirl::app {

// A request's decoded parameters, as cpp-httplib hands them over (a key may repeat; the first
// value counts).
using RequestParams = std::multimap<std::string, std::string>;

struct Reply {
  int status = 200;
  std::string body;  // JSON: the answer, or {"error": "..."} for a status other than 200
};

// One participant's side of a study. Answers are appended under a mutex and committed (made
// durable) before the reply; an answer whose commit throws is rolled back and answered 500, so
// an acknowledged answer is never lost and a lost one is never acknowledged.
class StudyService {
 public:
  using Commit = std::function<void(const Study&)>;  // makes the study durable, or throws

  // `participant` must be in `study`; `data` is study_dataset(study).
  StudyService(Study study, std::shared_ptr<const Dataset> data, std::string participant,
               int practice, Commit commit);

  // GET /api/state: stage, progress, the next query, the practice queries, the scenario.
  Reply state(const RequestParams& r);
  // GET /api/trajectory: what the page draws for row `id` of Ξ.
  Reply trajectory(const RequestParams& r);
  // POST /api/answer: kind, index, answer, response_ms; validated strictly, then committed.
  Reply answer(const RequestParams& r);

  // A copy of the served participant as it stands (for tests).
  StudyParticipant participant() const;

 private:
  bool authorised(const RequestParams& r, Reply& refused) const;
  std::string state_json() const;  // mu_ held
  Reply commit_answer(const RequestParams& r);

  Study study_;
  std::shared_ptr<const Dataset> data_;
  std::string id_;
  StudyParticipant practice_;
  EnvView view_ = EnvView::plane;
  Commit commit_;
  mutable std::mutex mu_;
};

// An error reply: status and {"error": message}.
Reply error_reply(int status, const std::string& message);

// Strict request numbers: the whole field, plain decimal, nothing else ("5abc", "1e3" for an
// integer, " 1", "0x1", "-1" for an index are all refused).
bool parse_index(const std::string& text, int64_t& out);
bool parse_decimal(const std::string& text, double& out);

}  // namespace sirl::app
