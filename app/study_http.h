// The study server's HTTP surface on a cpp-httplib server: body limit, framing checks, timeouts
// and routes. `sirl study serve` (app/study_server.cpp) and the raw-bytes fuzz target
// (fuzz/fuzz_study_http.cpp) configure their servers with it, so the fuzzer tests what serves.
//
//   GET  /                       the page (app/study_web/index.html)
//   GET  /static/<file>          the page's scripts; /vendor/three/… three.js from npm
//   GET  /api/state?p=ID&t=TOK   stage, progress, the next query, practice queries, scenario
//   GET  /api/trajectory?p&t&id  what to draw for one trajectory (EE path / grid cells, objects)
//   POST /api/answer             form fields p, t, kind (similarity|preference), index, answer,
//                                response_ms → 200, or 400/403/413 with a message, nothing written
#pragma once
#include <cstddef>
#include <filesystem>

namespace httplib {
class Server;
}

namespace sirl::app {

class StudyService;

// An answer is a few form fields: a longer body, declared or chunked, is refused (413) as it
// arrives, never buffered whole.
inline constexpr size_t kMaxAnswerBody = 64 * 1024;

// `web`: the folder holding index.html, the page's scripts and node_modules/three. `service`
// must outlive the server.
void configure_study_http(httplib::Server& srv, StudyService& service,
                          const std::filesystem::path& web);

}  // namespace sirl::app
