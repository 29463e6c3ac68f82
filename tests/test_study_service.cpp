// The study server's request handlers (app/study_service.h) without HTTP: strict parsing, the
// token check, and an answer that is acknowledged exactly when its commit succeeded.
#include "app/study_service.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <memory>
#include <stdexcept>

#include "datasets/driver.h"
#include "datasets/study.h"

namespace sirl::app {
namespace {

using nlohmann::json;

struct StudyRequests : ::testing::Test {
  void SetUp() override {
    study.env = "grid";
    data = std::make_shared<const Dataset>(study_dataset(study));
    for (const char* id : {"ann", "bob"}) {
      StudyParticipant p = plan_participant(*data, id, 2, 1, 5);
      p.token = std::string("tok-") + id;
      study.participants.push_back(std::move(p));
    }
    service = std::make_unique<StudyService>(study, data, "ann", 1, [this](const Study& s) {
      if (disk_full) throw std::runtime_error("No space left on device");
      committed.push_back(*s.find("ann"));
    });
  }
  RequestParams ask(RequestParams extra) const {
    extra.insert({{"p", "ann"}, {"t", "tok-ann"}});
    return extra;
  }
  Reply post(const std::string& kind, const std::string& index, const std::string& answer,
             const std::string& ms = "1200") {
    return service->answer(
        ask({{"kind", kind}, {"index", index}, {"answer", answer}, {"response_ms", ms}}));
  }

  Study study;
  std::shared_ptr<const Dataset> data;
  std::unique_ptr<StudyService> service;
  bool disk_full = false;
  std::vector<StudyParticipant> committed;
};

TEST(StudyService, ParsesRequestNumbersStrictly) {
  int64_t i = -1;
  EXPECT_TRUE(parse_index("0", i) && i == 0);
  EXPECT_TRUE(parse_index("123456789012345678", i) && i == 123456789012345678);
  for (const char* bad : {"", "-1", "+1", " 1", "1 ", "1e3", "5abc", "0x1", "1.0",
                          "1234567890123456789"})  // the last: 19 digits, may overflow int64
    EXPECT_FALSE(parse_index(bad, i)) << bad;
  double d = -1;
  EXPECT_TRUE(parse_decimal("0.5", d) && d == 0.5);
  EXPECT_TRUE(parse_decimal("1e3", d) && d == 1000);
  EXPECT_TRUE(parse_decimal("-2", d) && d == -2);
  for (const char* bad : {"", "0x1", " 1", "1 ", "nan", "inf", "1e999", "1..2", "--1", "+1", "1,5",
                          "123456789012345678901234567890123"})
    EXPECT_FALSE(parse_decimal(bad, d)) << bad;
}

TEST_F(StudyRequests, RefusesAWrongTokenAndAnotherParticipant) {
  Reply r = service->state({{"p", "ann"}, {"t", "tok-bob"}});
  EXPECT_EQ(r.status, 403);
  EXPECT_NE(r.body.find("wrong token"), std::string::npos) << r.body;
  r = service->state({{"p", "bob"}, {"t", "tok-bob"}});  // bob's own token, on ann's server
  EXPECT_EQ(r.status, 403);
  EXPECT_NE(r.body.find("records participant ann only"), std::string::npos) << r.body;
  r = service->answer({{"p", "bob"},
                       {"t", "tok-bob"},
                       {"kind", "similarity"},
                       {"index", "0"},
                       {"answer", "1"},
                       {"response_ms", "1"}});
  EXPECT_EQ(r.status, 403);
  EXPECT_TRUE(committed.empty());
}

TEST_F(StudyRequests, StateNamesTheNextQueryAndItsTrajectories) {
  const Reply r = service->state(ask({}));
  ASSERT_EQ(r.status, 200) << r.body;
  const json s = json::parse(r.body);
  const StudyParticipant& ann = *study.find("ann");
  EXPECT_EQ(s["stage"], "similarity");
  EXPECT_EQ(s["next"]["index"], 0);
  EXPECT_EQ(s["next"]["trajectories"],
            json({ann.similarity[0], ann.similarity[1], ann.similarity[2]}));
  EXPECT_EQ(s["similarity"]["total"], 2);
  EXPECT_EQ(s["preference"]["total"], 1);
}

TEST_F(StudyRequests, AnAnswerIsAcknowledgedExactlyWhenItsCommitSucceeds) {
  disk_full = true;
  Reply r = post("similarity", "0", "2");
  EXPECT_EQ(r.status, 500);
  EXPECT_NE(r.body.find("No space left on device"), std::string::npos) << r.body;
  EXPECT_TRUE(service->participant().similarity_answer.empty()) << "a lost answer was kept";
  EXPECT_EQ(json::parse(service->state(ask({})).body)["next"]["index"], 0);
  disk_full = false;  // space again: the same query is asked and accepted
  r = post("similarity", "0", "2", "950.5");
  ASSERT_EQ(r.status, 200) << r.body;
  ASSERT_EQ(committed.size(), 1u);
  EXPECT_EQ(committed[0].similarity_answer, std::vector<int32_t>{2});
  EXPECT_EQ(committed[0].similarity_ms, std::vector<float>{950.5f});
  EXPECT_EQ(json::parse(r.body)["next"]["index"], 1) << "the reply is the new state";
  disk_full = true;  // a failed second answer leaves the first one in place
  EXPECT_EQ(post("similarity", "1", "0").status, 500);
  EXPECT_EQ(service->participant().similarity_answer, std::vector<int32_t>{2});
  EXPECT_EQ(service->participant().similarity_ms.size(), 1u);
  EXPECT_EQ(service->participant().similarity_time.size(), 1u);
}

TEST_F(StudyRequests, RefusesMalformedAndOutOfOrderAnswersWithoutCommitting) {
  const struct {
    const char *kind, *index, *answer, *ms, *words;
  } bad[] = {
      {"opinion", "0", "1", "1", "kind must be"},
      {"similarity", "1e0", "1", "1", "index must be"},
      {"similarity", "-1", "1", "1", "index must be"},
      {"similarity", "0", "0x1", "1", "decimal numbers"},
      {"similarity", "0", "1", "nan", "decimal numbers"},
      {"similarity", "0", "1", "-3", "response_ms must be"},
      {"similarity", "0", "1", "3600001", "response_ms must be"},
      {"similarity", "0", "3", "1", "odd one out"},
      {"similarity", "0", "0.5", "1", "odd one out"},
      {"similarity", "1", "1", "1", "out of order"},
      {"similarity", "2", "1", "1", "does not exist"},
      {"preference", "0", "1", "1", "after the similarity"},
  };
  for (const auto& b : bad) {
    const Reply r = post(b.kind, b.index, b.answer, b.ms);
    EXPECT_EQ(r.status, 400) << b.words;
    EXPECT_NE(r.body.find(b.words), std::string::npos) << r.body;
  }
  EXPECT_EQ(service->answer(ask({{"kind", "similarity"}, {"index", "0"}, {"answer", "1"}})).status,
            400);  // response_ms missing
  EXPECT_TRUE(committed.empty());
  ASSERT_EQ(post("similarity", "0", "1").status, 200);
  const Reply again = post("similarity", "0", "1");
  EXPECT_EQ(again.status, 400);
  EXPECT_NE(again.body.find("already answered"), std::string::npos);
  ASSERT_EQ(post("similarity", "1", "0").status, 200);
  EXPECT_EQ(post("preference", "0", "2").status, 400);  // 1, 0 or 0.5 only
  ASSERT_EQ(post("preference", "0", "0.5").status, 200);
  const json done = json::parse(service->state(ask({})).body);
  EXPECT_EQ(done["stage"], "done");
  EXPECT_TRUE(done["next"].is_null());
  EXPECT_EQ(committed.size(), 3u);
  EXPECT_EQ(committed.back().preference_answer, std::vector<float>{0.5f});
}

TEST_F(StudyRequests, ARepeatedFieldCountsByItsFirstValue) {
  RequestParams r = ask({});
  r.insert({"kind", "similarity"});
  r.insert({"index", "0"});
  r.insert({"index", "1"});
  r.insert({"answer", "2"});
  r.insert({"answer", "0"});
  r.insert({"response_ms", "5"});
  ASSERT_EQ(service->answer(r).status, 200);
  EXPECT_EQ(service->participant().similarity_answer, std::vector<int32_t>{2});
}

TEST_F(StudyRequests, TrajectoryChecksItsRowAndDrawsTheGridPath) {
  const std::string last = std::to_string(data->count - 1);
  EXPECT_EQ(service->trajectory(ask({{"id", std::to_string(data->count)}})).status, 400);
  EXPECT_EQ(service->trajectory(ask({{"id", "-1"}})).status, 400);
  const Reply r = service->trajectory(ask({{"id", last}}));
  ASSERT_EQ(r.status, 200) << r.body;
  const json t = json::parse(r.body);
  EXPECT_EQ(t["id"], data->count - 1);
  ASSERT_FALSE(t["points"].empty());
  EXPECT_EQ(t["points"][0].size(), 2u) << "a plane view draws 2-D cells";
  EXPECT_EQ(t["objects"].size(), data->object_names.size());
}

// Driver on the study page: a "path" view (2-D points in road units, drawn to fit), its title for
// the welcome text, and each trajectory's start and 50 states with no end angle.
TEST(StudyService, DriverIsServedAsAPathOfRoadPoints) {
  Study study;
  study.env = "driver";
  study.trajectories = 60;
  auto data = std::make_shared<const Dataset>(study_dataset(study));
  StudyParticipant p = plan_participant(*data, "cy", 2, 1, 5);
  p.token = "tok";
  study.participants.push_back(std::move(p));
  StudyService service(study, data, "cy", 1, [](const Study&) {});
  const Reply st = service.state({{"p", "cy"}, {"t", "tok"}});
  ASSERT_EQ(st.status, 200) << st.body;
  const json state = json::parse(st.body);
  EXPECT_EQ(state["view"], "path");
  EXPECT_EQ(state["title"], "Driver");
  const Reply r = service.trajectory({{"p", "cy"}, {"t", "tok"}, {"id", "7"}});
  ASSERT_EQ(r.status, 200) << r.body;
  const json t = json::parse(r.body);
  ASSERT_EQ(t["points"].size(), size_t(kDriverSteps + 1));
  EXPECT_EQ(t["points"][0], json({0.f, -0.3f}));  // every car starts at (0, −0.3)
  for (int i = 0; i < kDriverSteps; ++i)          // then the (x, y) of each state of its input row
    EXPECT_EQ(t["points"][i + 1], json({data->input(7)[4 * i], data->input(7)[4 * i + 1]})) << i;
  EXPECT_FALSE(t.contains("angle"));
}

}  // namespace
}  // namespace sirl::app
