#include "engine/linear_tpa.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "kernels/bradley_terry_loss.h"

namespace sirl {

LinearTpaResult evaluate_linear_tpa(const Representation& rep, const Dataset& d,
                                    const std::vector<TpaSet>& sets, int64_t M,
                                    const LinearBtOptions& options, int threads) {
  if (sets.empty()) throw std::invalid_argument("TPA needs at least one test reward");
  const int R = int(sets.size()), dim = rep.dim();
  LinearTpaResult res;
  for (int k = 0; k < R; ++k) {
    const TpaSet& s = sets[size_t(k)];
    if (M < 1 || M > s.train)
      throw std::invalid_argument("TPA M=" + std::to_string(M) + " outside [1, " +
                                  std::to_string(s.train) + "] for test reward " +
                                  std::to_string(k));
    const int64_t held = s.pairs.count - s.train;
    if (held < 1)
      throw std::invalid_argument("TPA test reward " + std::to_string(k) +
                                  " has no held-out pairs");
    // φ of every row the reward's pairs touch, in pair order: training pairs' rows [0, 2M), then
    // the held-out pairs' [2M, 2M + 2·held).
    std::vector<int32_t> rows(s.pairs.pairs.begin(), s.pairs.pairs.begin() + 2 * M);
    rows.insert(rows.end(), s.pairs.pairs.begin() + 2 * s.train,
                s.pairs.pairs.begin() + 2 * s.pairs.count);
    const std::vector<float> X = embed_rows(rep, d, rows, threads);
    require_finite(X, "linear TPA: φ(ξ)");
    const int64_t n = int64_t(rows.size());
    std::vector<int32_t> train(size_t(2 * M)), test(size_t(2 * held));
    for (int64_t i = 0; i < 2 * M; ++i) train[size_t(i)] = int32_t(i);
    for (int64_t i = 0; i < 2 * held; ++i) test[size_t(i)] = int32_t(2 * M + i);
    const LinearBtFit fit = fit_linear_bradley_terry_cv(X.data(), n, dim, train.data(),
                                                        s.pairs.label.data(), int(M), options);
    // Rewards laid out as the loss reads them: every pair's A, then every pair's B.
    auto accuracy = [&](const std::vector<int32_t>& idx, const float* label, int64_t pairs) {
      std::vector<int32_t> by_role(size_t(2 * pairs));
      for (int64_t i = 0; i < pairs; ++i) {
        by_role[size_t(i)] = idx[size_t(2 * i)];
        by_role[size_t(pairs + i)] = idx[size_t(2 * i + 1)];
      }
      const std::vector<double> r = linear_rewards(fit, X.data(), dim, by_role.data(), 2 * pairs);
      const std::vector<double> lab(label, label + pairs);
      return preference_accuracy<double>(r.data(), lab.data(), int(pairs));
    };
    res.accuracy.push_back(accuracy(test, s.pairs.label.data() + s.train, held));
    res.train_accuracy.push_back(accuracy(train, s.pairs.label.data(), M));
    res.iterations.push_back(fit.iterations);
    res.rank.push_back(fit.rank);
    res.alpha.push_back(fit.alpha);
    res.converged = res.converged && fit.converged;
    res.flops += fit.flops + 2.0 * double(2 * (M + held)) * (dim + 1);
  }
  double sum = 0;
  for (double a : res.accuracy) sum += a;
  res.mean = sum / R;
  double ss = 0;
  for (double a : res.accuracy) ss += (a - res.mean) * (a - res.mean);
  res.stddev = R > 1 ? std::sqrt(ss / (R - 1)) : 0.0;
  if (!std::isfinite(res.mean)) throw std::runtime_error("linear TPA is not finite");
  return res;
}

}  // namespace sirl
