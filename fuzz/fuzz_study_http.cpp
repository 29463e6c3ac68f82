// libFuzzer target: raw bytes through the study server's own socket path. A cpp-httplib server
// configured exactly as `sirl study serve` configures it (app/study_http.h) listens on loopback in
// a thread; each input is sent as is on a fresh TCP connection (request lines, headers, chunked
// encodings, duplicate headers, bodies: whatever the bytes say), the write side is shut, and the
// reply is read to the end. Contract, checked after each input:
//   - the server answers or closes, within the read timeout (no hang: libFuzzer's -timeout);
//   - its resident memory stays within 128 MiB of what it was after 512 inputs (a body the
//     server buffered whole, chunked or not, would break it; ctest runs it with ASan's quarantine
//     of freed memory cut to 16 MiB, which otherwise grows to 256 MiB by design).
#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <thread>

#include "app/study_http.h"
#include "app/study_service.h"
#include "datasets/study.h"

namespace {

struct Served {
  httplib::Server srv;
  std::unique_ptr<sirl::app::StudyService> service;
  int port = 0;
};

// A GridRobot study with one participant "ann" (token "tok"); answers are kept in memory.
Served& served() {
  static Served* s = [] {
    auto* s = new Served;
    sirl::Study study;
    study.env = "grid";
    auto data = std::make_shared<const sirl::Dataset>(sirl::study_dataset(study));
    sirl::StudyParticipant p = sirl::plan_participant(*data, "ann", 3, 2, 7);
    p.token = "tok";
    study.participants.push_back(std::move(p));
    s->service =
        std::make_unique<sirl::app::StudyService>(study, data, "ann", 1, [](const sirl::Study&) {});
    sirl::app::configure_study_http(s->srv, *s->service, SIRL_SOURCE_DIR "/app/study_web");
    // One connection at a time comes from here: 4 workers instead of the 256 that serve slow
    // clients, so every worker's stack is resident before the memory baseline is taken.
    s->srv.new_task_queue = [] { return new httplib::ThreadPool(4); };
    s->port = s->srv.bind_to_any_port("127.0.0.1");
    if (s->port <= 0) {
      std::fprintf(stderr, "fuzz_study_http: cannot listen on loopback\n");
      std::abort();
    }
    std::thread([s] { s->srv.listen_after_bind(); }).detach();
    while (!s->srv.is_running()) std::this_thread::yield();
    return s;
  }();
  return *s;
}

long resident_kib() {
  std::ifstream in("/proc/self/status");
  std::string key;
  long v = 0;
  while (in >> key)
    if (key == "VmRSS:" && in >> v) return v;
  return 0;
}

void exchange(int port, const uint8_t* data, size_t size) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return;
  timeval tv{5, 0};  // the server's read timeout is 1 s: a reply or a close comes well before
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(uint16_t(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) {
    size_t sent = 0;
    while (sent < size) {
      const ssize_t n = ::send(fd, data + sent, size - sent, MSG_NOSIGNAL);
      if (n <= 0) break;  // the server refused and closed: the rest is never read
      sent += size_t(n);
    }
    ::shutdown(fd, SHUT_WR);
    char buf[4096];
    while (::recv(fd, buf, sizeof buf, 0) > 0) {
    }
  }
  ::close(fd);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static long baseline = 0;
  static uint64_t runs = 0;
  Served& s = served();
  exchange(s.port, data, size);
  ++runs;
  if (runs == 512) baseline = resident_kib();
  if (baseline > 0 && runs % 64 == 0 && resident_kib() > baseline + 128 * 1024) {
    std::fprintf(stderr, "contract broken: resident memory %ld KiB, %ld after the first inputs\n",
                 resident_kib(), baseline);
    std::abort();
  }
  return 0;
}
