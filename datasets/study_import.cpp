#include "datasets/study_import.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>

namespace sirl {

namespace {

// One answered query, whatever the file format.
struct Record {
  std::string participant, kind, scenario;
  std::vector<double> trajectories;
  std::vector<std::string> scenario_features;
  double answer = NAN, response_ms = NAN, timestamp = 0;
};

// Every answered record of the study, by its participant, kind, rows, answer, response time and
// timestamp: a record met again is the same answer imported twice (the same file imported again,
// or a row repeated), which would count that answer twice in the analysis.
class SeenRecords {
 public:
  explicit SeenRecords(const Study& s) {
    for (const StudyParticipant& p : s.participants) {
      for (int64_t i = 0; i < p.similarity_done(); ++i)
        keys_.insert(key(p.id, "similarity", p.similarity.data() + 3 * i, 3,
                         double(p.similarity_answer[size_t(i)]), p.similarity_ms[size_t(i)],
                         p.similarity_time[size_t(i)]));
      for (int64_t i = 0; i < p.preference_done(); ++i)
        keys_.insert(key(p.id, "preference", p.preference.data() + 2 * i, 2,
                         double(p.preference_answer[size_t(i)]), p.preference_ms[size_t(i)],
                         p.preference_time[size_t(i)]));
    }
  }
  // False if the record was there already.
  bool insert(const std::string& id, const std::string& kind, const std::vector<int32_t>& rows,
              double answer, float ms, double time) {
    return keys_.insert(key(id, kind.c_str(), rows.data(), int(rows.size()), answer, ms, time))
        .second;
  }

 private:
  static std::string key(const std::string& id, const char* kind, const int32_t* rows, int n,
                         double answer, float ms, double time) {
    std::string k = id + "/" + kind;
    char buf[96];  // 3 separators, two %.17g of up to 24 characters, one %.9g of up to 16
    for (int i = 0; i < n; ++i) k += "/" + std::to_string(rows[i]);
    std::snprintf(buf, sizeof buf, "/%.17g/%.9g/%.17g", answer, double(ms), time);
    return k + buf;
  }
  std::set<std::string> keys_;
};

void add(const Record& r, const Dataset& d, Study& s, SeenRecords& seen, const std::string& where) {
  auto bad = [&](const std::string& what) { return std::invalid_argument(where + ": " + what); };
  try {
    validate_participant_id(r.participant);
  } catch (const std::invalid_argument& e) {
    throw bad(e.what());
  }
  std::vector<int32_t> rows;
  for (double t : r.trajectories) {
    if (!(t == std::floor(t)) || t < 0 || t >= double(d.count))
      throw bad("trajectory " + std::to_string(t) + " is not a row of the " +
                std::to_string(d.count) + "-trajectory space");
    if (std::find(rows.begin(), rows.end(), int32_t(t)) != rows.end())
      throw bad("a query shows the same trajectory twice");
    rows.push_back(int32_t(t));
  }
  if (!(r.response_ms >= 0)) throw bad("response_ms must be a number >= 0");
  StudyParticipant* p = s.find(r.participant);
  if (!p) {
    StudyParticipant np;
    np.id = r.participant;
    np.token = new_participant_token();  // each participant their own capability
    np.scenario = r.scenario;
    for (const auto& f : r.scenario_features) {
      if (std::find(d.feature_names.begin(), d.feature_names.end(), f) == d.feature_names.end())
        throw bad("unknown feature '" + f + "'");
      np.scenario_features.push_back(f);
    }
    s.participants.push_back(std::move(np));
    p = &s.participants.back();
  }
  // Queries a server planned and the participant has not answered yet come before any imported
  // one: an answer appended behind them would be read as the answer to the first open query.
  if (p->similarity_done() < p->similarity_count() || p->preference_done() < p->preference_count())
    throw bad("participant " + r.participant + " has queries from `sirl study serve` still open (" +
              std::to_string(p->similarity_count() - p->similarity_done()) + " similarity, " +
              std::to_string(p->preference_count() - p->preference_done()) +
              " preference): finish serving them, or import these answers under another id");
  if ((r.kind == "similarity" || r.kind == "preference") &&
      !seen.insert(r.participant, r.kind == "similarity" ? "similarity" : "preference", rows,
                   r.answer, float(r.response_ms), r.timestamp))
    throw bad("this " + r.kind + " answer of " + r.participant +
              " (same trajectories, answer, response time and timestamp) is already in the study: "
              "the file imported before, or a repeated row");
  if (r.kind == "similarity") {
    if (rows.size() != 3) throw bad("a similarity record has 3 trajectories");
    if (!(r.answer == 0 || r.answer == 1 || r.answer == 2))
      throw bad("a similarity answer is the position (0, 1, 2) of the odd one out");
    p->similarity.insert(p->similarity.end(), rows.begin(), rows.end());
    p->similarity_answer.push_back(int32_t(r.answer));
    p->similarity_ms.push_back(float(r.response_ms));
    p->similarity_time.push_back(r.timestamp);
  } else if (r.kind == "preference") {
    if (rows.size() != 2) throw bad("a preference record has 2 trajectories");
    if (!(r.answer == 0 || r.answer == 0.5 || r.answer == 1))
      throw bad("a preference answer is 1 (first), 0 (second) or 0.5 (equal)");
    p->preference.insert(p->preference.end(), rows.begin(), rows.end());
    p->preference_answer.push_back(float(r.answer));
    p->preference_ms.push_back(float(r.response_ms));
    p->preference_time.push_back(r.timestamp);
  } else {
    throw bad("kind must be similarity or preference, got '" + r.kind + "'");
  }
}

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"')
        cur += '"', ++i;
      else if (c == '"')
        quoted = false;
      else
        cur += c;
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else if (c != '\r') {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

double number(const std::string& v, const std::string& where, const char* what) {
  try {
    size_t used = 0;
    const double x = std::stod(v, &used);
    if (used == v.size()) return x;
  } catch (const std::exception&) {
  }
  throw std::invalid_argument(where + ": " + what + " '" + v + "' is not a number");
}

std::string slurp(const std::string& path) {
  // Only a regular file: a FIFO would block the open until a writer comes (never).
  std::error_code ec;
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
    throw std::invalid_argument(path + ": not a regular file (a pipe, socket, device or folder)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot read");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

void import_study_csv(const std::string& path, const Dataset& d, Study& s) {
  std::string text = slurp(path);
  // A NUL byte would silently end a field where C code reads it: refuse the file, naming the line.
  if (const size_t nul = text.find('\0'); nul != std::string::npos)
    throw std::invalid_argument(
        path + ":" + std::to_string(1 + std::count(text.begin(), text.begin() + nul, '\n')) +
        ": a NUL byte (a binary file, or a broken export?)");
  // A spreadsheet saves UTF-8 CSV with a byte-order mark by default: accept it.
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  const std::string header =
      "participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,scenario_features";
  if (line.rfind(header, 0) != 0)
    throw std::invalid_argument(path + ":1: the header must be: " + header);
  int64_t row = 1;
  SeenRecords seen(s);
  while (std::getline(in, line)) {
    ++row;
    if (line.empty() || line == "\r") continue;
    const std::string where = path + ":" + std::to_string(row);
    const auto f = split_csv(line);
    if (f.size() != 10)
      throw std::invalid_argument(where + ": expected 10 fields, got " + std::to_string(f.size()));
    Record r;
    r.participant = f[0];
    r.kind = f[1];
    for (int k = 2; k <= 4; ++k)
      if (!f[k].empty()) r.trajectories.push_back(number(f[k], where, "trajectory"));
    r.answer = number(f[5], where, "answer");
    r.response_ms = number(f[6], where, "response_ms");
    r.timestamp = f[7].empty() ? 0 : number(f[7], where, "timestamp");
    r.scenario = f[8];
    std::stringstream ss(f[9]);
    std::string feat;
    while (std::getline(ss, feat, ';'))
      if (!feat.empty()) r.scenario_features.push_back(feat);
    add(r, d, s, seen, where);
  }
}

// The answers file parsed by nlohmann-json, nesting limited: the schema is 3 levels deep, and a
// hostile file of 100,000 '[' must be one clear error, not a stack overflow.
nlohmann::json parse_answers(const std::string& path) {
  constexpr int kMaxDepth = 16;
  const std::string text = slurp(path);
  auto limit = [&](int depth, nlohmann::json::parse_event_t e, nlohmann::json&) {
    if ((e == nlohmann::json::parse_event_t::object_start ||
         e == nlohmann::json::parse_event_t::array_start) &&
        depth >= kMaxDepth)
      throw std::invalid_argument(path + ": nested deeper than " + std::to_string(kMaxDepth) +
                                  " levels (the answers schema has 3)");
    return true;
  };
  try {
    return nlohmann::json::parse(text, limit);
  } catch (const nlohmann::json::exception& e) {  // parse_error, or out_of_range for 1e400
    // e.what() is "[json.exception.parse_error.101] parse error at line L, column C: …".
    std::string what = e.what();
    if (const size_t k = what.find("] "); k != std::string::npos) what = what.substr(k + 2);
    throw std::invalid_argument(path + ": " + what);
  }
}

void import_study_json(const std::string& path, const Dataset& d, Study& s) {
  using nlohmann::json;
  const json doc = parse_answers(path);
  const json* list = &doc;
  if (doc.is_object()) {
    if (!doc.contains("answers")) throw std::invalid_argument(path + ": no \"answers\" array");
    list = &doc["answers"];
  }
  if (!list->is_array()) throw std::invalid_argument(path + ": \"answers\" must be an array");
  SeenRecords seen(s);
  for (size_t k = 0; k < list->size(); ++k) {
    const std::string where = path + ": record " + std::to_string(k);
    const json& o = (*list)[k];
    if (!o.is_object()) throw std::invalid_argument(where + ": not an object");
    auto field = [&](const char* name, json::value_t t, bool required) -> const json* {
      const auto it = o.find(name);
      if (it == o.end()) {
        if (required) throw std::invalid_argument(where + ": missing \"" + name + "\"");
        return nullptr;
      }
      // Any JSON number is a number here (the library tells integers from floats).
      const bool ok = t == json::value_t::number_float ? it->is_number() : it->type() == t;
      if (!ok) throw std::invalid_argument(where + ": \"" + name + "\" has the wrong type");
      return &*it;
    };
    constexpr auto kStr = json::value_t::string, kNum = json::value_t::number_float,
                   kArr = json::value_t::array;
    Record r;
    r.participant = field("participant", kStr, true)->get<std::string>();
    r.kind = field("kind", kStr, true)->get<std::string>();
    for (const json& t : *field("trajectories", kArr, true)) {
      if (!t.is_number()) throw std::invalid_argument(where + ": trajectories must be numbers");
      r.trajectories.push_back(t.get<double>());
    }
    r.answer = field("answer", kNum, true)->get<double>();
    r.response_ms = field("response_ms", kNum, true)->get<double>();
    if (const json* t = field("timestamp", kNum, false)) r.timestamp = t->get<double>();
    if (const json* t = field("scenario", kStr, false)) r.scenario = t->get<std::string>();
    if (const json* t = field("scenario_features", kArr, false))
      for (const json& f : *t) {
        if (!f.is_string()) throw std::invalid_argument(where + ": scenario_features are strings");
        r.scenario_features.push_back(f.get<std::string>());
      }
    add(r, d, s, seen, where);
  }
}

}  // namespace sirl
