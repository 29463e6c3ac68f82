// libFuzzer target: the study server's request handlers (app/study_service.h) on any sequence of
// requests. Each line of the input is one request: its first byte picks the endpoint (state,
// trajectory or answer), its second byte '!' makes the commit fail (a full disk), and the rest is
// a query string decoded by cpp-httplib as the server decodes it. After every request the
// handler's contract is checked, and a broken one aborts:
//   - the status is 200, 400, 403 or 500 and the body is JSON ({"error": ...} unless 200);
//   - an answer changes the participant only with 200, by exactly the posted answer;
//   - 500 only when the commit failed, and then nothing changed (never acknowledged, never kept).
#include <httplib.h>

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#include "app/study_service.h"
#include "datasets/study.h"

namespace {

using sirl::StudyParticipant;
using sirl::app::Reply;
using sirl::app::RequestParams;
using sirl::app::StudyService;

struct Fixture {
  std::shared_ptr<const sirl::Dataset> data;
  sirl::Study study;
};

// A GridRobot study with one participant "ann" (token "tok", 3 similarity and 2 preference
// queries, so a short input can reach the end).
const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture f;
    f.study.env = "grid";
    f.data = std::make_shared<const sirl::Dataset>(sirl::study_dataset(f.study));
    StudyParticipant p = sirl::plan_participant(*f.data, "ann", 3, 2, 7);
    p.token = "tok";
    f.study.participants.push_back(std::move(p));
    return f;
  }();
  return f;
}

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "contract broken: %s\n", what);
    std::abort();
  }
}

bool same_answers(const StudyParticipant& a, const StudyParticipant& b) {
  return a.similarity_answer == b.similarity_answer && a.preference_answer == b.preference_answer &&
         a.similarity_ms == b.similarity_ms && a.preference_ms == b.preference_ms &&
         a.similarity_time.size() == b.similarity_time.size() &&
         a.preference_time.size() == b.preference_time.size();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const Fixture& f = fixture();
  bool fail_commit = false, committed = false;
  StudyService service(f.study, f.data, "ann", 1, [&](const sirl::Study&) {
    if (fail_commit) throw std::runtime_error("No space left on device");
    committed = true;
  });
  const std::string input(reinterpret_cast<const char*>(data), size);
  size_t at = 0;
  for (int requests = 0; at < input.size() && requests < 64; ++requests) {
    size_t end = input.find('\n', at);
    if (end == std::string::npos) end = input.size();
    const std::string line = input.substr(at, end - at);
    at = end + 1;
    if (line.size() < 2) continue;
    fail_commit = line[1] == '!';
    committed = false;
    RequestParams params;
    httplib::detail::parse_query_text(line.substr(2), params);
    const StudyParticipant before = service.participant();
    Reply r;
    switch (uint8_t(line[0]) % 3) {
      case 0:
        r = service.state(params);
        break;
      case 1:
        r = service.trajectory(params);
        break;
      default:
        r = service.answer(params);
        break;
    }
    check(r.status == 200 || r.status == 400 || r.status == 403 || r.status == 500, "status");
    const nlohmann::json body = nlohmann::json::parse(r.body, nullptr, false);
    check(!body.is_discarded(), "the body is JSON");
    check(r.status == 200 || (body.contains("error") && body["error"].is_string()),
          "an error reply says why");
    const StudyParticipant after = service.participant();
    if (r.status != 200 || uint8_t(line[0]) % 3 != 2) {
      check(same_answers(before, after), "only an accepted answer changes the participant");
      check(r.status != 500 || fail_commit, "500 only when the commit failed");
      continue;
    }
    check(committed, "an accepted answer was committed");
    const auto grew = [](const auto& b, const auto& a) { return a.size() == b.size() + 1; };
    check(grew(before.similarity_answer, after.similarity_answer) !=
              grew(before.preference_answer, after.preference_answer),
          "an accepted answer adds exactly one answer of one kind");
    const double answer = std::strtod(params.lower_bound("answer")->second.c_str(), nullptr);
    if (grew(before.similarity_answer, after.similarity_answer))
      check(after.similarity_answer.back() == answer, "the posted similarity answer");
    else
      check(after.preference_answer.back() == answer, "the posted preference answer");
  }
  return 0;
}
