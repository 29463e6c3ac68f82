// The study's web server (cpp-httplib): one page running the paper's protocol, a small JSON API
// (app/study_http.h lists the routes), every answer committed to the study file before the reply.
#include "app/study_server.h"

#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "app/commands.h"
#include "app/study_http.h"
#include "app/study_service.h"
#include "datasets/environments.h"
#include "datasets/study.h"
#include "datasets/study_import.h"
#include "experiment/install_paths.h"
#include "results/file_lock.h"
#include "results/h5.h"
#include "results/study_store.h"

namespace sirl::app {

namespace {

namespace fs = std::filesystem;

struct ServeArgs {
  std::string env = "jaco2", participant, scenario, out, host = "127.0.0.1", profile;
  std::vector<std::string> scenario_features;
  int64_t similarity = 100, preference = 100, trajectories = 1000;
  int port = 8080, practice = 3;
  uint64_t seed = 0;
} g_serve;

struct ImportArgs {
  std::string file, out, env = "jaco2", format = "auto", profile;
  int64_t trajectories = 1000;
  uint64_t seed = 0;
} g_import;

CLI::App* g_serve_cmd = nullptr;
CLI::App* g_import_cmd = nullptr;

// The host to listen on: an IPv4 or IPv6 literal or "localhost" (checked before anything is
// written). Returns whether it is a loopback address; the URL host goes into `url_host`.
bool check_host(const std::string& host, std::string& url_host) {
  in_addr v4{};
  in6_addr v6{};
  if (host == "localhost") {
    url_host = host;
    return true;
  }
  if (inet_pton(AF_INET, host.c_str(), &v4) == 1) {
    const bool any = v4.s_addr == htonl(INADDR_ANY);
    url_host = any ? "127.0.0.1" : host;
    return (ntohl(v4.s_addr) >> 24) == 127;
  }
  if (inet_pton(AF_INET6, host.c_str(), &v6) == 1) {
    const bool any = IN6_IS_ADDR_UNSPECIFIED(&v6);
    url_host = any ? "[::1]" : "[" + host + "]";
    return IN6_IS_ADDR_LOOPBACK(&v6);
  }
  throw UsageError("--host '" + host +
                   "' is not an IP address (use 127.0.0.1, ::1, localhost, or an address of this "
                   "machine)");
}

// One server (or import) per study file: each rewrites the whole file from its memory, so two
// at once would lose each other's answers. Held for the process's life. The file's folder is
// created first, as every other writer does.
void lock_study(std::optional<FileLock>& lock, const std::string& out) {
  if (const fs::path dir = fs::path(out).parent_path(); !dir.empty()) fs::create_directories(dir);
  try {
    lock.emplace(out, "sirl study serve/import",
                 "one process per study file: stop the other first (participants take turns)");
  } catch (const FileBusy& e) {
    throw UsageError(e.what());
  }
}

// The self-pipe through which a stop signal reaches the server (see run_serve).
int g_stop_pipe[2] = {-1, -1};

int run_serve() {
  const ServeArgs& a = g_serve;
  validate_participant_id(a.participant);
  declare_profile_environments(a.profile);
  std::string url_host;
  if (!check_host(a.host, url_host))
    std::fprintf(stderr,
                 "sirl study serve: WARNING: --host %s is not a loopback address: anyone who can "
                 "reach this machine and has the link can answer as %s\n",
                 a.host.c_str(), a.participant.c_str());
  std::optional<FileLock> lock;
  lock_study(lock, a.out);
  Study s = new_study(a.env, a.trajectories, a.seed);  // --env checked before the file is read
  if (fs::exists(a.out)) {
    s = read_study(a.out);
    if (s.env != a.env || (env_spec(a.env).sampled && s.trajectories != a.trajectories))
      throw UsageError(a.out + " is a " + s.env + " study over " + std::to_string(s.trajectories) +
                       " trajectories; --env/--trajectories differ");
  }
  // The port before the file: a server that cannot listen writes nothing.
  httplib::Server srv;
  // cpp-httplib's default sets SO_REUSEPORT, which lets a second server bind a busy port and
  // take half of the requests. SO_REUSEADDR alone still allows a restart over TIME_WAIT.
  srv.set_socket_options([](socket_t sock) {  // httplib's global socket_t
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, reinterpret_cast<void*>(&yes), sizeof(yes));
  });
  // --port 0: any free port, chosen by the OS and printed (no check-then-bind race).
  const int port = a.port == 0 ? srv.bind_to_any_port(a.host) : a.port;
  if (port <= 0 || (a.port != 0 && !srv.bind_to_port(a.host, a.port)))
    throw UsageError("cannot listen on " + a.host + ":" + std::to_string(a.port) +
                     " (in use? try --port, or --port 0 for any free port)");
  if (!s.find(a.participant)) {
    const Dataset d = study_dataset(s);
    StudyParticipant p = plan_participant(d, a.participant, a.similarity, a.preference, a.seed);
    p.scenario = a.scenario;
    p.scenario_features = a.scenario_features;
    for (const auto& f : p.scenario_features)
      if (std::find(d.feature_names.begin(), d.feature_names.end(), f) == d.feature_names.end())
        throw UsageError("--scenario-features: unknown feature '" + f + "'");
    s.participants.push_back(std::move(p));
    write_study(a.out, s);
  }
  const std::string token = s.find(a.participant)->token;
  const std::string path = a.out;
  StudyService service(s, std::make_shared<const Dataset>(study_dataset(s)), a.participant,
                       a.practice, [path](const Study& st) { write_study(path, st); });
  configure_study_http(srv, service, data_dir() / "app" / "study_web");
  // Ctrl-C and SIGTERM stop the server between requests (each answer is already in the file),
  // then a line says what was saved. The handler (any thread may take the signal) only writes
  // the signal's number into a pipe; a thread of ours reads it and stops the server.
  if (::pipe2(g_stop_pipe, O_CLOEXEC) != 0)
    throw std::runtime_error(std::string("cannot create a pipe: ") + std::strerror(errno));
  struct sigaction sa {};
  sa.sa_handler = [](int sig) {
    const unsigned char b = static_cast<unsigned char>(sig);
    [[maybe_unused]] const ssize_t n = ::write(g_stop_pipe[1], &b, 1);
  };
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::atomic<int> stopped_by{0};
  std::atomic<bool> listening_over{false};
  std::thread stopper([&] {
    unsigned char b = 0;
    while (::read(g_stop_pipe[0], &b, 1) < 0 && errno == EINTR) {
    }
    if (b != 0) {
      stopped_by = b;
      // httplib's stop() does nothing until listen has begun: a signal that arrives between
      // the "open:" line and listen_after_bind() would otherwise be lost and the server would
      // run on. Repeat until the listen loop has returned.
      while (!listening_over.load()) {
        srv.stop();
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
    }
  });
  std::printf(
      "sirl study serve: participant %s on %s; answers go to %s\n"
      "open: http://%s:%d/?p=%s&t=%s\n",
      a.participant.c_str(), s.env.c_str(), a.out.c_str(), url_host.c_str(), port,
      a.participant.c_str(), token.c_str());
  std::fflush(stdout);
  srv.listen_after_bind();
  listening_over = true;
  const unsigned char done = 0;  // the server ended on its own: end the thread
  [[maybe_unused]] const ssize_t n = ::write(g_stop_pipe[1], &done, 1);
  stopper.join();
  const int by = stopped_by.load();
  const StudyParticipant p = service.participant();
  std::fprintf(stderr,
               "sirl study serve: stopped%s; %s answered %lld of %lld similarity and %lld of %lld "
               "preference queries, all saved in %s (serve again to continue)\n",
               by == SIGINT    ? " (Ctrl-C)"
               : by == SIGTERM ? " (SIGTERM)"
                               : "",
               a.participant.c_str(), static_cast<long long>(p.similarity_done()),
               static_cast<long long>(p.similarity_count()),
               static_cast<long long>(p.preference_done()),
               static_cast<long long>(p.preference_count()), a.out.c_str());
  return 0;
}

int run_import() {
  const ImportArgs& a = g_import;
  declare_profile_environments(a.profile);
  std::optional<FileLock> lock;
  lock_study(lock, a.out);
  Study s;
  if (std::filesystem::exists(a.out)) {
    s = read_study(a.out);  // add to an existing study (its env and trajectory space)
    if (s.env != a.env) throw UsageError(a.out + " is a " + s.env + " study; --env says " + a.env);
  } else {
    s = new_study(a.env, a.trajectories, a.seed);
  }
  const Dataset d = study_dataset(s);
  const size_t before = s.participants.size();
  int64_t n_sim = 0, n_pref = 0;
  for (const auto& p : s.participants) n_sim -= p.similarity_done(), n_pref -= p.preference_done();
  const std::string fmt = a.format != "auto"                        ? a.format
                          : fs::path(a.file).extension() == ".json" ? "json"
                                                                    : "csv";
  try {
    if (fmt == "json")
      import_study_json(a.file, d, s);
    else
      import_study_csv(a.file, d, s);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  for (const auto& p : s.participants) n_sim += p.similarity_done(), n_pref += p.preference_done();
  if (n_sim + n_pref == 0) throw UsageError(a.file + ": no answers");
  write_study(a.out, s);
  std::printf(
      "imported %lld similarity and %lld preference answers (%zu new participants) into %s\n",
      (long long)n_sim, (long long)n_pref, s.participants.size() - before, a.out.c_str());
  return 0;
}

}  // namespace

void register_study_serve(CLI::App& study) {
  auto* c = study.add_subcommand(
      "serve",
      "Serve the study page for one participant (local web server) and record every answer in\n"
      "the study file the moment it arrives. Restarting resumes at the next unanswered query.");
  ServeArgs& a = g_serve;
  c->add_option("--env", a.env, study_env_help())->capture_default_str();
  c->add_option("--profile", a.profile,
                "A profile whose [environments.<name>] (files) --env may name");
  c->add_option("--participant", a.participant, "Participant id (A-Z a-z 0-9 _ -)")->required();
  c->add_option("--similarity", a.similarity, "Recorded similarity queries")
      ->check(CLI::Range(int64_t(1), int64_t(10000)))
      ->capture_default_str();
  c->add_option("--preference", a.preference, "Recorded preference queries")
      ->check(CLI::Range(int64_t(1), int64_t(10000)))
      ->capture_default_str();
  c->add_option("--scenario", a.scenario, "The preference scenario shown before phase 2")
      ->required();
  c->add_option("--scenario-features", a.scenario_features,
                "Features the scenario's preference involves (e.g. table,laptop)")
      ->delimiter(',');
  c->add_option("--out", a.out, "Study file (created, or resumed)")
      ->required()
      ->check(output_file());
  c->add_option("--port", a.port, "TCP port (0: any free port; the URL printed names it)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  c->add_option("--host", a.host, "Address to listen on (127.0.0.1: this machine only)")
      ->capture_default_str();
  c->add_option("--trajectories", a.trajectories, "JacoRobot trajectory space size")
      ->check(CLI::Range(int64_t(10), int64_t(1000000)))
      ->capture_default_str();
  c->add_option("--practice", a.practice, "Unrecorded practice queries of each kind")
      ->check(CLI::Range(0, 20))
      ->capture_default_str();
  c->add_option("--seed", a.seed, "Seed of the data and the queries")->capture_default_str();
  c->callback([] {});
  g_serve_cmd = c;
}

void register_study_import(CLI::App& study) {
  auto* c = study.add_subcommand(
      "import",
      "Import answers collected elsewhere (CSV or JSON) into a study file; appends to an\n"
      "existing one. CSV header:\n"
      "participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,scenario_features\n"
      "JSON: {\"answers\": [{\"participant\", \"kind\", \"trajectories\": [...], \"answer\",\n"
      "\"response_ms\", \"timestamp\", \"scenario\", \"scenario_features\": [...]}, ...]}\n"
      "kind similarity: 3 rows of the trajectory space, answer = position (0-2) of the odd\n"
      "one out; kind preference: 2 rows, answer 1 = first, 0 = second, 0.5 = equal.\n"
      "scenario and scenario_features (CSV: ';'-separated) come from a participant's first "
      "record.\nRefused, with nothing written: an answer already in the study (same participant,\n"
      "trajectories, answer, response time and timestamp: the file imported before), and answers\n"
      "for a participant whose `serve` queries are still open.");
  ImportArgs& a = g_import;
  c->add_option("file", a.file, "CSV or JSON file")->required()->check(CLI::ExistingFile);
  c->add_option("--format", a.format, "csv, json, or auto (by extension)")
      ->check(CLI::IsMember({"auto", "csv", "json"}))
      ->capture_default_str();
  c->add_option("--out", a.out, "Study file to write")->required()->check(output_file());
  c->add_option("--env", a.env, study_env_help())->capture_default_str();
  c->add_option("--profile", a.profile,
                "A profile whose [environments.<name>] (files) --env may name");
  c->add_option("--trajectories", a.trajectories, "JacoRobot trajectory space size")
      ->check(CLI::Range(int64_t(10), int64_t(1000000)))
      ->capture_default_str();
  c->add_option("--seed", a.seed, "Data seed of the trajectory space")->capture_default_str();
  c->callback([] {});
  g_import_cmd = c;
}

int run_study_serve_or_import() {
  try {
    if (g_serve_cmd && g_serve_cmd->parsed()) return run_serve();
    if (g_import_cmd && g_import_cmd->parsed()) return run_import();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  return 2;
}

}  // namespace sirl::app
