// What the active-selection settings cost and how much disagreement they find, on GridRobot
// (the whole Ξ, the perfect teacher, a budget of 1000 triplets): for each setting, the seconds
// and GFLOP of choosing, and the mean score of the batches asked against the mean of their pools
// (vote entropy, nats; log 3 = 1.099 is three members voting three ways). A setting that finds no
// more disagreement than a random pick gains nothing from being active. No FPE or TPA is looked at
// here: the defaults are chosen by cost and signal, never by the outcome they lead to.
//   build/release/bench/sirl_active_settings [seeds]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "datasets/grid_robot.h"
#include "engine/active_queries.h"
#include "engine/hyperparams.h"

using namespace sirl;

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 3;
  const Dataset d = make_grid_dataset();
  struct Setting {
    int members;
    int64_t pool, batch;
    int epochs;
  };
  const std::vector<Setting> settings{{3, 2000, 100, 50}, {5, 2000, 100, 50}, {8, 2000, 100, 50},
                                      {5, 500, 100, 50},  {5, 8000, 100, 50}, {5, 2000, 50, 50},
                                      {5, 2000, 200, 50}, {5, 2000, 100, 10}, {5, 2000, 100, 150}};
  std::printf(
      "| K | pool | batch | epochs/round | rounds | s (median) | GFLOP | batch score | pool score "
      "| ratio |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Setting& s : settings) {
    std::vector<double> secs;
    double gflop = 0, batch = 0, pool = 0;
    int rounds = 0;
    for (int seed = 0; seed < seeds; ++seed) {
      ActiveConfig c;
      c.rule = Selection::vote;
      c.budget = 1000;
      c.members = s.members;
      c.pool = s.pool;
      c.batch = s.batch;
      c.round_epochs = s.epochs;
      c.hyper = paper_hyper("grid");
      const auto t0 = std::chrono::steady_clock::now();
      const ActiveQueries a = select_active_queries(d, Teacher{}, c, uint64_t(seed));
      secs.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      gflop += a.train_flops / 1e9 / seeds;
      rounds = a.rounds;
      for (int r = 1; r < a.rounds; ++r) {  // round 0 is uniform
        batch += a.batch_score[size_t(r)] / double(a.rounds - 1) / seeds;
        pool += a.pool_score[size_t(r)] / double(a.rounds - 1) / seeds;
      }
    }
    std::sort(secs.begin(), secs.end());
    std::printf("| %d | %lld | %lld | %d | %d | %.2f | %.0f | %.3f | %.3f | %.1f |\n", s.members,
                (long long)s.pool, (long long)s.batch, s.epochs, rounds, secs[secs.size() / 2],
                gflop, batch, pool, pool > 0 ? batch / pool : 0.0);
    std::fflush(stdout);
  }
}
