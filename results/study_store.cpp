#include "results/study_store.h"

#include <filesystem>

#include "results/durable.h"
#include "results/h5.h"

namespace sirl {

namespace {
using u64 = uint64_t;
}  // namespace

void write_study(const std::string& path, const Study& s) {
  const std::string tmp = path + ".tmp";
  try {
    H5File f = H5File::create(tmp);
    // The file holds each participant's token (their credential for the study page): readable
    // by its owner only, from before the first token is written.
    std::filesystem::permissions(
        tmp, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write,
        std::filesystem::perm_options::replace);
    f.group("/study");
    f.set_attr("/study", "format", std::string("sirl-study-1"));
    f.set_attr("/study", "env", s.env);
    f.set_attr("/study", "trajectories", int64_t(s.trajectories));
    f.set_attr("/study", "data_seed", int64_t(s.data_seed));
    if (!s.env_data.empty()) f.set_attr("/study", "env_data", s.env_data);
    std::vector<std::string> ids;
    for (const auto& p : s.participants) {
      ids.push_back(p.id);
      const std::string g = "/study/participants/" + p.id;
      f.group(g);
      f.set_attr(g, "token", p.token);
      f.set_attr(g, "scenario", p.scenario);
      f.set_attr(g, "scenario_features", p.scenario_features);
      f.write(g + "/similarity", p.similarity.data(), {u64(p.similarity_count()), 3});
      f.write(g + "/preference", p.preference.data(), {u64(p.preference_count()), 2});
      f.write(g + "/reward", p.reward.data(), {u64(p.reward.size())});
      f.write(g + "/similarity_answer", p.similarity_answer.data(), {u64(p.similarity_done())});
      f.write(g + "/similarity_ms", p.similarity_ms.data(), {u64(p.similarity_done())});
      f.write(g + "/similarity_time", p.similarity_time.data(), {u64(p.similarity_done())});
      f.write(g + "/preference_answer", p.preference_answer.data(), {u64(p.preference_done())});
      f.write(g + "/preference_ms", p.preference_ms.data(), {u64(p.preference_done())});
      f.write(g + "/preference_time", p.preference_time.data(), {u64(p.preference_done())});
    }
    f.write_strings("/study/participant_ids", ids);
    f.close();  // a full disk shows here, not silently in a destructor
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);  // nothing half-written stays behind
    throw H5Error(path + ": the study file could not be written: " + e.what());
  }
  fsync_path(tmp);
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw H5Error(path + ": cannot move the study file into place: " + ec.message());
  fsync_path(std::filesystem::absolute(path).parent_path().string());
}

Study read_study(const std::string& path) {
  H5File f = H5File::open_read(path);
  if (!f.exists("/study") || f.attr_string("/study", "format") != "sirl-study-1")
    throw H5Error(path + ": not a sirl-bench study file (no /study@format = sirl-study-1)");
  Study s;
  s.env = f.attr_string("/study", "env");
  s.trajectories = f.attr_int("/study", "trajectories");
  s.data_seed = uint64_t(f.attr_int("/study", "data_seed"));
  if (f.has_attr("/study", "env_data")) s.env_data = f.attr_string("/study", "env_data");
  for (const auto& id : f.read_strings("/study/participant_ids")) {
    StudyParticipant p;
    p.id = id;
    const std::string g = "/study/participants/" + id;
    p.token = f.attr_string(g, "token");
    p.scenario = f.attr_string(g, "scenario");
    p.scenario_features = f.attr_strings(g, "scenario_features");
    p.similarity = f.read_i32(g + "/similarity", {-1, 3});
    p.preference = f.read_i32(g + "/preference", {-1, 2});
    p.reward = f.read_f32(g + "/reward", {-1});
    p.similarity_answer = f.read_i32(g + "/similarity_answer", {-1});
    p.similarity_ms = f.read_f32(g + "/similarity_ms", {int64_t(p.similarity_answer.size())});
    p.similarity_time = f.read_f64(g + "/similarity_time", {int64_t(p.similarity_answer.size())});
    std::vector<uint64_t> dims;
    p.preference_answer = f.read_f32(g + "/preference_answer", {-1});
    p.preference_ms = f.read_f32(g + "/preference_ms", {int64_t(p.preference_answer.size())});
    p.preference_time = f.read_f64(g + "/preference_time", {int64_t(p.preference_answer.size())});
    if (p.similarity_done() > p.similarity_count() || p.preference_done() > p.preference_count())
      throw H5Error(path + ": participant " + id + " has more answers than queries");
    s.participants.push_back(std::move(p));
  }
  return s;
}

}  // namespace sirl
