#include "app/study_http.h"

#include <httplib.h>

#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "app/study_service.h"

namespace sirl::app {

namespace fs = std::filesystem;

namespace {

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void json_reply(httplib::Response& res, const Reply& reply) {
  res.status = reply.status;
  res.set_content(reply.body, "application/json");
}

// Framing headers a proxy and this server could read differently, refused before any body is
// read: two Content-Length headers, one that is not decimal digits ("0x10" was read as 0), or one
// beside Transfer-Encoding. Returns why, or "".
std::string bad_framing(const httplib::Request& r) {
  const size_t lengths = r.get_header_value_count("Content-Length");
  if (lengths > 1) return "more than one Content-Length header";
  if (lengths == 0) return "";
  const std::string v = r.get_header_value("Content-Length");
  if (v.empty() || v.size() > 18 || v.find_first_not_of("0123456789") != std::string::npos)
    return "Content-Length must be decimal digits";
  if (r.has_header("Transfer-Encoding")) return "Content-Length beside Transfer-Encoding";
  return "";
}

// Only `POST /api/answer` takes a body, read by its own bounded reader. cpp-httplib reads any
// other request's body whole before routing it (chunked: unbounded; a POST, PUT, PATCH or DELETE
// without Content-Length: until the client closes), so a request elsewhere that announces one,
// or a body-carrying method that gives no length, is refused before a byte of it is read.
// Returns {status, why}, or {0, ""}.
std::pair<int, std::string> unwanted_body(const httplib::Request& r) {
  const bool chunked = r.has_header("Transfer-Encoding");
  // bad_framing has made sure a Content-Length is decimal digits: a non-zero digit means a body.
  const bool sized =
      r.get_header_value("Content-Length").find_first_not_of('0') != std::string::npos;
  const bool takes_body = r.method == "POST" || r.method == "PUT" || r.method == "PATCH" ||
                          r.method == "DELETE" || r.method == "PRI";
  const bool answer = r.method == "POST" && r.path == "/api/answer";
  if (!answer && (chunked || sized)) return {413, "only POST /api/answer takes a request body"};
  if (takes_body && !chunked && !r.has_header("Content-Length"))
    return {411, "a request body needs Content-Length or chunked transfer encoding"};
  return {0, ""};
}

}  // namespace

void configure_study_http(httplib::Server& srv, StudyService& service, const fs::path& web) {
  srv.set_payload_max_length(kMaxAnswerBody);  // a declared longer body: 413, never read
  srv.set_pre_routing_handler([](const httplib::Request& r, httplib::Response& res) {
    std::pair<int, std::string> refusal{400, bad_framing(r)};
    if (refusal.second.empty()) refusal = unwanted_body(r);
    if (refusal.second.empty()) return httplib::Server::HandlerResponse::Unhandled;
    res.set_header("Connection", "close");  // the unread body must not be parsed as a request
    json_reply(res, error_reply(refusal.first, refusal.second));
    return httplib::Server::HandlerResponse::Handled;
  });
  // Slow or idle clients must not starve a participant: each connection holds a worker thread
  // while it is read, so reads time out after 1 s of silence, and the pool is large enough that
  // 64 trickling clients plus a crowd of idle ones leave threads free (study_server.py opens 64
  // slow and 200 idle connections and times a real request).
  // One request per connection: cpp-httplib 0.11 keeps reading a connection after a handler
  // answers "Connection: close", so the unread body of a refused request would be parsed as the
  // next request. A local study page loses nothing measurable by reconnecting.
  srv.set_read_timeout(1, 0);
  srv.set_write_timeout(5, 0);
  srv.set_keep_alive_timeout(1);
  srv.set_keep_alive_max_count(1);
  srv.new_task_queue = [] { return new httplib::ThreadPool(256); };

  const auto api = [&service](Reply (StudyService::*handler)(const RequestParams&)) {
    return [&service, handler](const httplib::Request& r, httplib::Response& res) {
      json_reply(res, (service.*handler)(r.params));
    };
  };
  const fs::path three = web / "node_modules" / "three";
  srv.Get("/", [web](const httplib::Request&, httplib::Response& res) {
    res.set_content(read_file(web / "index.html"), "text/html; charset=utf-8");
  });
  srv.Get(R"(/static/([A-Za-z0-9_.-]+))", [web](const httplib::Request& r, httplib::Response& res) {
    const fs::path f = web / r.matches[1].str();
    if (!fs::is_regular_file(f)) return json_reply(res, error_reply(404, "no such file"));
    res.set_content(read_file(f), f.extension() == ".js" ? "text/javascript" : "text/css");
  });
  srv.Get(R"(/vendor/three/((build|examples/jsm/controls)/[A-Za-z0-9_.]+\.js))",
          [three](const httplib::Request& r, httplib::Response& res) {
            const fs::path f = three / r.matches[1].str();
            if (!fs::is_regular_file(f))
              return json_reply(res,
                                error_reply(404, "three.js is not installed (scripts/setup.sh)"));
            res.set_content(read_file(f), "text/javascript");
          });
  srv.Get("/api/state", api(&StudyService::state));
  srv.Get("/api/trajectory", api(&StudyService::trajectory));
  // The answer's form body is read here, chunk by chunk, and refused past the limit: cpp-httplib
  // bounds a body whose length is declared, but reads a chunked one whole before any plain handler.
  srv.Post("/api/answer", [&service](const httplib::Request& r, httplib::Response& res,
                                     const httplib::ContentReader& read_body) {
    std::string body;
    bool too_large = false;
    const bool whole = read_body([&](const char* data, size_t n) {
      if (body.size() + n > kMaxAnswerBody) {
        too_large = true;
        return false;  // stop reading: the rest of the body is never buffered
      }
      body.append(data, n);
      return true;
    });
    // A declared length past the limit: cpp-httplib skips the body without calling the receiver
    // (bad_framing has made sure it is decimal digits).
    if (!whole && r.has_header("Content-Length") &&
        std::stoull(r.get_header_value("Content-Length")) > kMaxAnswerBody)
      too_large = true;
    if (too_large || !whole) {
      res.set_header("Connection", "close");  // the unread rest must not be parsed as a request
      return json_reply(
          res, error_reply(too_large ? 413 : 400, too_large ? "the request body is over 64 KiB"
                                                            : "the request body was cut short"));
    }
    RequestParams params = r.params;  // the URL's query; the form body's fields are added
    httplib::detail::parse_query_text(body, params);
    json_reply(res, service.answer(params));
  });
}

}  // namespace sirl::app
