// What more cores buy one task on the paper's critical path (a cluster run is bound by it, not by
// its work): the JacoRobot VAE, a SIRL φ training and a frozen TPA cell's heads, each run by the
// engine's own training code on 1 and k threads. A class's time per unit of its schedule is the
// difference between its runs at 3 and 1 units (best wall time of `repeats` runs each), so what a
// call costs once (building networks, embedding Ξ at the end) is not read as the epochs' scaling:
// the paper's tasks run thousands of epochs. Prints each class's speed-up S_k and the serial
// fraction Amdahl's law gives from it,
//   S_k = k / (1 + s (k − 1))   ⇒   s = (k / S_k − 1) / (k − 1),
// which `sirl plan --serial-fraction` takes (its default is the largest such value measured:
// docs/performance-history.md, "Serial fraction"). Run it on an idle machine: a busy core reads as
// a serial fraction.
//   build/release/bench/sirl_serial_fraction [k=2] [repeats=3] [--json] [--class jaco/vae]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "datasets/environments.h"
#include "datasets/query_bundle.h"
#include "engine/hyperparams.h"
#include "engine/methods.h"
#include "engine/tpa.h"
#include "jobs/scheduler.h"

using namespace sirl;

namespace {

// The machine's CPU time so far from /proc/stat's first line: {all ticks, ticks stolen by the
// hypervisor}. On a VM a second core that is not ours reads as a serial fraction: the share
// stolen while a class was timed is printed beside it.
std::pair<double, double> cpu_ticks() {
  std::FILE* f = std::fopen("/proc/stat", "r");
  if (!f) return {0, 0};
  double v[10] = {};
  const int n = std::fscanf(f, "cpu %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2],
                            &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9]);
  std::fclose(f);
  double all = 0;
  for (int i = 0; i < std::max(n, 0); ++i) all += v[i];
  return {all, n >= 8 ? v[7] : 0};
}

// Best wall time of `repeats` calls of f, in seconds.
double best_seconds(int repeats, const std::function<void()>& f) {
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    best = std::min(best,
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  int k = 2, repeats = 3;
  bool json = false;
  std::string only;  // --class NAME: that class alone (e.g. under a profiler)
  std::vector<int> numbers;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0)
      json = true;
    else if (std::strcmp(argv[i], "--class") == 0 && i + 1 < argc)
      only = argv[++i];
    else
      numbers.push_back(std::atoi(argv[i]));
  }
  if (!numbers.empty()) k = numbers[0];
  if (numbers.size() > 1) repeats = numbers[1];
  const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
  if (k < 2 || k > cores || repeats < 1) {
    std::fprintf(stderr,
                 "usage: sirl_serial_fraction [k in 2..%d] [repeats >= 1] [--json] [--class C]\n",
                 cores);
    return 2;
  }
  // JacoRobot's networks (1024 wide, its paper hyper-parameters) on a sampled Ξ of 1000: the
  // products have the shapes of the paper's tasks (batch × width), only fewer steps.
  const EnvSpec& jaco = env_spec("jaco");
  EnvConfig cfg;
  jaco.set_sample(cfg, 1000, 0);
  const Dataset d = jaco.make(cfg);
  QueryBundleConfig qc;
  qc.similarity = qc.preference = 1000;
  const QueryBundle bundle = make_query_bundle(d, qc, 1);
  const Hyper paper = paper_hyper("jaco");
  // One unit of each schedule: a few epochs (the heads' epochs are short: 100 pairs each).
  auto lengths = [&](int scale) {
    Hyper h = paper;
    h.sirl.epochs = 4 * scale;
    h.vae.epochs = 3 * scale;
    h.tpa.epochs = 20 * scale;
    return h;
  };
  const Representation phi =
      train_representation(d, bundle, MethodConfig{Method::sirl, 1000, false, lengths(1)}, 1);

  struct Class {
    const char* name;
    std::function<void(int threads, int scale)> run;
  };
  const std::vector<Class> classes{
      {"jaco/vae", [&](int t, int x) { train_vae(d, lengths(x), 1, Execution{t}); }},
      {"jaco/rep_sirl",
       [&](int t, int x) {
         train_representation(d, bundle, MethodConfig{Method::sirl, 1000, false, lengths(x)}, 1,
                              nullptr, Execution{t});
       }},
      {"jaco/tpa_frozen",
       [&](int t, int x) {
         evaluate_tpa(phi, d, bundle.tpa, TpaConfig{100, true, lengths(x)}, 1, Execution{t});
       }},
  };
  // Seconds per unit of the class's schedule on `threads` threads.
  auto per_unit = [&](const Class& c, int threads) {
    const double one = best_seconds(repeats, [&] { c.run(threads, 1); });
    const double three = best_seconds(repeats, [&] { c.run(threads, 3); });
    return std::max(three - one, 1e-9) / 2.0;
  };
  std::string out = "[";
  double largest = 0;
  if (!json)
    std::printf("%-16s %12s %12s %8s %8s %8s   (seconds per unit of schedule)\n", "class",
                "1 thread", "k threads", "S_k", "s", "stolen");
  for (const Class& c : classes) {
    if (!only.empty() && only != c.name) continue;
    const auto before = cpu_ticks();
    const double t1 = per_unit(c, 1);
    const double tk = per_unit(c, k);
    const auto after = cpu_ticks();
    const double stolen = after.first > before.first
                              ? (after.second - before.second) / (after.first - before.first)
                              : 0.0;
    const double speedup = t1 / tk;
    const double s = serial_fraction_from_speedup(k, speedup);
    largest = std::max(largest, s);
    if (!json)
      std::printf("%-16s %11.4fs %11.4fs %8.2f %8.3f %7.1f%%\n", c.name, t1, tk, speedup, s,
                  100 * stolen);
    char row[256];
    std::snprintf(row, sizeof row,
                  "%s{\"class\": \"%s\", \"k\": %d, \"seconds_1\": %.6f, \"seconds_k\": %.6f, "
                  "\"speedup\": %.4f, \"serial_fraction\": %.4f, \"stolen\": %.4f}",
                  out.size() > 1 ? ", " : "", c.name, k, t1, tk, speedup, s, stolen);
    out += row;
  }
  out += "]";
  if (json)
    std::printf("%s\n", out.c_str());
  else
    std::printf("largest serial fraction: %.3f (k = %d, best of %d)\n", largest, k, repeats);
  return 0;
}
