// Importing a study's answers from CSV and JSON, and the errors for bad records.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "datasets/study.h"
#include "datasets/study_import.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {

// Writes `text` to a file of the test's scratch directory (removed when the process ends).
std::string write_temp(const std::string& name, const std::string& text) {
  static const test::ScratchDir scratch("sirl_import");
  const std::string p = scratch.file(name);
  std::ofstream(p) << text;
  return p;
}

std::string import_error(bool json, const std::string& text, const Dataset& d) {
  Study s;
  s.env = "grid";
  try {
    const std::string p = write_temp(json ? "sirl_bad.json" : "sirl_bad.csv", text);
    json ? import_study_json(p, d, s) : import_study_csv(p, d, s);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(StudyImport, CsvAndJsonGiveTheSameStudy) {
  Study base;
  base.env = "grid";
  const Dataset d = study_dataset(base);
  const std::string csv = write_temp(
      "sirl_import.csv",
      "participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,scenario_features\n"
      "ann,similarity,1,2,3,2,1500,1700000000.5,\"Stay away, please\",laptop_distance;abs_angle\n"
      "ann,similarity,4,5,6,0,900,1700000001,,\n"
      "ann,preference,7,8,,1,700,1700000002,,\n"
      "ben,preference,9,10,,0.5,1100,1700000003,Anything,\n");
  const std::string json = write_temp("sirl_import.json",
                                      R"({"answers": [
        {"participant": "ann", "kind": "similarity", "trajectories": [1, 2, 3], "answer": 2,
         "response_ms": 1500, "timestamp": 1700000000.5, "scenario": "Stay away, please",
         "scenario_features": ["laptop_distance", "abs_angle"]},
        {"participant": "ann", "kind": "similarity", "trajectories": [4, 5, 6], "answer": 0,
         "response_ms": 900, "timestamp": 1700000001},
        {"participant": "ann", "kind": "preference", "trajectories": [7, 8], "answer": 1,
         "response_ms": 700, "timestamp": 1700000002},
        {"participant": "ben", "kind": "preference", "trajectories": [9, 10], "answer": 0.5,
         "response_ms": 1100, "timestamp": 1700000003, "scenario": "Anything"}]})");
  Study a = base, b = base;
  import_study_csv(csv, d, a);
  import_study_json(json, d, b);
  ASSERT_EQ(a.participants.size(), 2u);
  ASSERT_EQ(b.participants.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const auto &x = a.participants[i], &y = b.participants[i];
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.scenario, y.scenario);
    EXPECT_EQ(x.scenario_features, y.scenario_features);
    EXPECT_EQ(x.similarity, y.similarity);
    EXPECT_EQ(x.similarity_answer, y.similarity_answer);
    EXPECT_EQ(x.preference, y.preference);
    EXPECT_EQ(x.preference_answer, y.preference_answer);
    EXPECT_EQ(x.similarity_ms, y.similarity_ms);
    EXPECT_EQ(x.preference_time, y.preference_time);
  }
  const auto& ann = a.participants[0];
  EXPECT_EQ(ann.scenario, "Stay away, please");
  EXPECT_EQ(ann.similarity, (std::vector<int32_t>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(ann.similarity_answer, (std::vector<int32_t>{2, 0}));
  EXPECT_EQ(ann.preference_answer, (std::vector<float>{1.f}));
  EXPECT_EQ(a.participants[1].preference_answer, (std::vector<float>{0.5f}));
  EXPECT_DOUBLE_EQ(ann.similarity_time[0], 1700000000.5);
  // Every imported participant gets a capability of their own (not a shared fixed token).
  std::set<std::string> tokens;
  for (const Study* st : {&a, &b})
    for (const auto& p : st->participants) {
      EXPECT_EQ(p.token.size(), 32u);
      EXPECT_EQ(p.token.find_first_not_of("0123456789abcdef"), std::string::npos) << p.token;
      tokens.insert(p.token);
    }
  EXPECT_EQ(tokens.size(), a.participants.size() + b.participants.size());
}

// A spreadsheet's UTF-8 export starts with a byte-order mark: the same study as without it. A NUL
// byte in a field is refused with its line (it used to cut the field short silently).
TEST(StudyImport, ByteOrderMarkIsAcceptedAndNulIsRefused) {
  Study base;
  base.env = "grid";
  const Dataset d = study_dataset(base);
  const std::string body =
      "participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,scenario_features\n"
      "ann,similarity,1,2,3,2,1500,1700000000.5,Stay away,laptop_distance\n"
      "ann,preference,7,8,,1,700,1700000002,,\n";
  Study plain = base, bom = base;
  import_study_csv(write_temp("plain.csv", body), d, plain);
  import_study_csv(write_temp("bom.csv", "\xEF\xBB\xBF" + body), d, bom);
  ASSERT_EQ(plain.participants.size(), 1u);
  EXPECT_EQ(bom.participants.size(), 1u);
  EXPECT_EQ(bom.participants[0].id, "ann");
  EXPECT_EQ(bom.participants[0].similarity, plain.participants[0].similarity);
  EXPECT_EQ(bom.participants[0].preference_answer, plain.participants[0].preference_answer);
  EXPECT_EQ(bom.participants[0].scenario_features, plain.participants[0].scenario_features);
  std::string with_nul = body;
  with_nul.insert(with_nul.find("Stay away") + 4, 1, '\0');  // line 2
  const std::string m = import_error(false, with_nul, d);
  EXPECT_NE(m.find("sirl_bad.csv:2: a NUL byte"), std::string::npos) << m;
}

TEST(StudyImport, BadRecordsNameTheLineAndTheProblem) {
  Study base;
  base.env = "grid";
  const Dataset d = study_dataset(base);
  const std::string h =
      "participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,scenario_features\n";
  auto has = [](const std::string& msg, const std::string& part) {
    return msg.find(part) != std::string::npos;
  };
  std::string m = import_error(false, "who,what\n", d);
  EXPECT_TRUE(has(m, ":1: the header must be")) << m;
  m = import_error(false, h + "ann,similarity,1,2,3,2,10,0,,\nann,similarity,1,2,99999,2,10,0,,\n",
                   d);
  EXPECT_TRUE(has(m, "sirl_bad.csv:3: trajectory")) << m;
  m = import_error(false, h + "ann,similarity,1,2,3,5,10,0,,\n", d);
  EXPECT_TRUE(has(m, ":2: a similarity answer")) << m;
  m = import_error(false, h + "ann,preference,1,1,,1,10,0,,\n", d);
  EXPECT_TRUE(has(m, "same trajectory twice")) << m;
  m = import_error(false, h + "a b,preference,1,2,,1,10,0,,\n", d);
  EXPECT_TRUE(has(m, "participant id")) << m;
  m = import_error(false, h + "ann,preference,1,2,,1,fast,0,,\n", d);
  EXPECT_TRUE(has(m, "response_ms 'fast' is not a number")) << m;
  m = import_error(false, h + "ann,opinion,1,2,,1,10,0,,\n", d);
  EXPECT_TRUE(has(m, "kind must be similarity or preference")) << m;
  m = import_error(false, h + "ann,preference,1,2,,1,10,0,,colour\n", d);
  EXPECT_TRUE(has(m, "unknown feature 'colour'")) << m;
  m = import_error(true, R"({"answers": [{"participant": "ann", "kind": "preference",
      "trajectories": [1, 2], "answer": 1}]})",
                   d);
  EXPECT_TRUE(has(m, "record 0: missing \"response_ms\"")) << m;
  m = import_error(true, R"({"answers": [{"participant": "ann", )", d);
  EXPECT_TRUE(has(m, "sirl_bad.json: parse error at line 1, column 37")) << m;
  m = import_error(true, R"({"answers": []} trailing)", d);
  EXPECT_TRUE(has(m, "parse error")) << m;
  m = import_error(true, R"({"answers": [{"participant": "ann", "answer": 1e400}]})", d);
  EXPECT_TRUE(has(m, "1e400")) << m;
  // A hostile file of 100,000 '[' (issue 17): one clear line, no stack overflow.
  m = import_error(true, std::string(100000, '['), d);
  EXPECT_TRUE(has(m, "nested deeper than 16 levels")) << m;
  m = import_error(true, R"([{"participant": 7}])", d);
  EXPECT_TRUE(has(m, "\"participant\" has the wrong type")) << m;
}

// The same answers imported twice (the file again, or a row repeated, CSV or JSON) are refused
// with the record's place, and the study is left as it was: an answer counted twice would weigh
// twice in the analysis. The same trajectories answered again at another time are a new answer.
TEST(StudyImport, AnAnswerAlreadyInTheStudyIsRefused) {
  Study s;
  s.env = "grid";
  const Dataset d = study_dataset(s);
  const std::string head =
      "participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,scenario_features\n";
  const std::string first =
      write_temp("sirl_once.csv", head +
                                      "ann,similarity,1,2,3,2,1500,1700000000,,\n"
                                      "ann,preference,7,8,,1,700,1700000002,,\n");
  import_study_csv(first, d, s);
  const Study before = s;
  try {
    import_study_csv(first, d, s);
    ADD_FAILURE() << "the same file was imported twice";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sirl_once.csv:2: this similarity answer of ann"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("already in the study"), std::string::npos) << e.what();
  }
  const std::string json = write_temp("sirl_again.json", R"({"answers": [
      {"participant": "ann", "kind": "preference", "trajectories": [7, 8], "answer": 1,
       "response_ms": 700, "timestamp": 1700000002}]})");
  EXPECT_THROW(import_study_json(json, d, s), std::invalid_argument);
  const std::string twice = write_temp("sirl_twice.csv", head +
                                                             "bob,similarity,4,5,6,0,900,5,,\n"
                                                             "bob,similarity,4,5,6,0,900,5,,\n");
  Study other = before;
  try {
    import_study_csv(twice, d, other);
    ADD_FAILURE() << "a repeated row was imported";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sirl_twice.csv:3:"), std::string::npos) << e.what();
  }
  // Asked again later, answered again: a new answer.
  const std::string later =
      write_temp("sirl_later.csv", head + "ann,similarity,1,2,3,2,1500,1700000100,,\n");
  Study again = before;
  import_study_csv(later, d, again);
  EXPECT_EQ(again.participants[0].similarity_answer, (std::vector<int32_t>{2, 2}));
}

// A participant whose server-planned queries are not all answered: an imported answer appended
// behind them would be read as the answer to the first open query, so it is refused.
TEST(StudyImport, AParticipantWithOpenQueriesTakesNoImportedAnswer) {
  Study s;
  s.env = "grid";
  const Dataset d = study_dataset(s);
  s.participants.push_back(plan_participant(d, "ann", 5, 2, 0));
  s.participants[0].similarity_answer = {1, 0};  // 2 of 5 answered
  s.participants[0].similarity_ms = {900, 800};
  s.participants[0].similarity_time = {1, 2};
  const std::string csv = write_temp(
      "sirl_open.csv",
      "participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,scenario_features\n"
      "ann,similarity,1,2,3,2,1500,1700000000,,\n");
  try {
    import_study_csv(csv, d, s);
    ADD_FAILURE() << "an answer went behind open queries";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("still open (3 similarity, 2 preference)"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace sirl
