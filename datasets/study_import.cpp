#include "datasets/study_import.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
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

void add(const Record& r, const Dataset& d, Study& s, const std::string& where) {
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
    np.token = "imported";
    np.scenario = r.scenario;
    for (const auto& f : r.scenario_features) {
      if (std::find(d.feature_names.begin(), d.feature_names.end(), f) == d.feature_names.end())
        throw bad("unknown feature '" + f + "'");
      np.scenario_features.push_back(f);
    }
    s.participants.push_back(std::move(np));
    p = &s.participants.back();
  }
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

// A small JSON reader (objects, arrays, strings, numbers, true/false/null): enough for the
// documented import schema, with the byte offset in every error.
struct Json {
  enum Type { Null, Bool, Num, Str, Arr, Obj } type = Null;
  double num = 0;
  bool b = false;
  std::string str;
  std::vector<Json> arr;
  std::map<std::string, Json> obj;
};

class JsonReader {
 public:
  explicit JsonReader(const std::string& s, std::string where) : s_(s), where_(std::move(where)) {}
  Json parse() {
    Json v = value();
    ws();
    if (i_ != s_.size()) fail("unexpected text after the document");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& what) {
    throw std::invalid_argument(where_ + ": byte " + std::to_string(i_) + ": " + what);
  }
  void ws() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool eat(char c) {
    ws();
    if (i_ < s_.size() && s_[i_] == c) return ++i_, true;
    return false;
  }
  Json value() {
    ws();
    if (i_ >= s_.size()) fail("unexpected end of file");
    Json v;
    const char c = s_[i_];
    if (c == '{') {
      ++i_;
      v.type = Json::Obj;
      if (eat('}')) return v;
      do {
        ws();
        if (i_ >= s_.size() || s_[i_] != '"') fail("expected a key string");
        std::string k = string();
        if (!eat(':')) fail("expected ':'");
        v.obj[k] = value();
      } while (eat(','));
      if (!eat('}')) fail("expected ',' or '}'");
    } else if (c == '[') {
      ++i_;
      v.type = Json::Arr;
      if (eat(']')) return v;
      do v.arr.push_back(value());
      while (eat(','));
      if (!eat(']')) fail("expected ',' or ']'");
    } else if (c == '"') {
      v.type = Json::Str;
      v.str = string();
    } else if (s_.compare(i_, 4, "true") == 0 || s_.compare(i_, 5, "false") == 0) {
      v.type = Json::Bool;
      v.b = s_[i_] == 't';
      i_ += v.b ? 4 : 5;
    } else if (s_.compare(i_, 4, "null") == 0) {
      i_ += 4;
    } else {
      size_t used = 0;
      try {
        v.num = std::stod(s_.substr(i_, 64), &used);
      } catch (const std::exception&) {
        fail("expected a value");
      }
      v.type = Json::Num;
      i_ += used;
    }
    return v;
  }
  std::string string() {
    std::string out;
    ++i_;  // opening quote
    while (i_ < s_.size() && s_[i_] != '"') {
      char c = s_[i_++];
      if (c == '\\') {
        if (i_ >= s_.size()) break;
        const char e = s_[i_++];
        switch (e) {
          case 'n':
            c = '\n';
            break;
          case 't':
            c = '\t';
            break;
          case 'u':  // keep it simple: \uXXXX below 0x80 only
            if (i_ + 4 > s_.size()) fail("bad \\u escape");
            c = char(std::stoi(s_.substr(i_, 4), nullptr, 16) & 0x7f);
            i_ += 4;
            break;
          default:
            c = e;
        }
      }
      out += c;
    }
    if (i_ >= s_.size()) fail("unterminated string");
    ++i_;
    return out;
  }
  const std::string& s_;
  std::string where_;
  size_t i_ = 0;
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot read");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

void import_study_csv(const std::string& path, const Dataset& d, Study& s) {
  std::istringstream in(slurp(path));
  std::string line;
  std::getline(in, line);
  const std::string header =
      "participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,scenario_features";
  if (line.rfind(header, 0) != 0)
    throw std::invalid_argument(path + ":1: the header must be: " + header);
  int64_t row = 1;
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
    add(r, d, s, where);
  }
}

void import_study_json(const std::string& path, const Dataset& d, Study& s) {
  const std::string text = slurp(path);
  const Json doc = JsonReader(text, path).parse();
  const Json* list = &doc;
  if (doc.type == Json::Obj) {
    auto it = doc.obj.find("answers");
    if (it == doc.obj.end()) throw std::invalid_argument(path + ": no \"answers\" array");
    list = &it->second;
  }
  if (list->type != Json::Arr) throw std::invalid_argument(path + ": \"answers\" must be an array");
  for (size_t k = 0; k < list->arr.size(); ++k) {
    const std::string where = path + ": record " + std::to_string(k);
    const Json& o = list->arr[k];
    if (o.type != Json::Obj) throw std::invalid_argument(where + ": not an object");
    auto field = [&](const char* name, Json::Type t, bool required) -> const Json* {
      auto it = o.obj.find(name);
      if (it == o.obj.end()) {
        if (required) throw std::invalid_argument(where + ": missing \"" + name + "\"");
        return nullptr;
      }
      if (it->second.type != t)
        throw std::invalid_argument(where + ": \"" + name + "\" has the wrong type");
      return &it->second;
    };
    Record r;
    r.participant = field("participant", Json::Str, true)->str;
    r.kind = field("kind", Json::Str, true)->str;
    for (const Json& t : field("trajectories", Json::Arr, true)->arr) {
      if (t.type != Json::Num)
        throw std::invalid_argument(where + ": trajectories must be numbers");
      r.trajectories.push_back(t.num);
    }
    r.answer = field("answer", Json::Num, true)->num;
    r.response_ms = field("response_ms", Json::Num, true)->num;
    if (const Json* t = field("timestamp", Json::Num, false)) r.timestamp = t->num;
    if (const Json* t = field("scenario", Json::Str, false)) r.scenario = t->str;
    if (const Json* t = field("scenario_features", Json::Arr, false))
      for (const Json& f : t->arr) {
        if (f.type != Json::Str)
          throw std::invalid_argument(where + ": scenario_features are strings");
        r.scenario_features.push_back(f.str);
      }
    add(r, d, s, where);
  }
}

}  // namespace sirl
