// Linear evaluation (kernels/linear_bradley_terry.h, engine/linear_tpa.h) and the references
// truth and raw (engine/representation.h): optimality of the fit, its invariance to units, both
// of its solution paths, cross-validation's choice, and what a cell scores.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "engine/fpe.h"
#include "engine/linear_tpa.h"
#include "kernels/bradley_terry_loss.h"
#include "kernels/linear_bradley_terry.h"
#include "kernels/linear_probe.h"
#include "kernels/rng.h"
#include "tests/grid_world.h"

namespace sirl {
namespace {

using namespace test;

// A random problem: X [n, in] normal features, M pairs over its rows, labels from a noisy linear
// reward (so the data are not separable and the minimiser is interior).
struct Problem {
  int n, in, M;
  std::vector<float> X, label;
  std::vector<int32_t> pairs;
};
Problem problem(int n, int in, int M, uint64_t seed) {
  Problem p{n, in, M, {}, {}, {}};
  Rng rng(seed);
  p.X.resize(size_t(n) * in);
  for (float& x : p.X) x = float(rng.normal());
  std::vector<double> w(static_cast<size_t>(in));
  for (double& v : w) v = rng.normal();
  for (int i = 0; i < M; ++i) {
    const int32_t a = int32_t(rng.uniform_int(n)), b = int32_t(rng.uniform_int(n));
    p.pairs.push_back(a);
    p.pairs.push_back(b);
    double z = 0;
    for (int j = 0; j < in; ++j)
      z += w[size_t(j)] * (p.X[size_t(a) * in + j] - p.X[size_t(b) * in + j]);
    p.label.push_back(z + rng.normal() > 0 ? 1.f : 0.f);
  }
  return p;
}

// The ridge loss of docs/linear-evaluation.md at weights θ [in + 1] (original units), computed
// here from its definition: the features standardised over the 2M training rows, w̃_j = θ_j σ_j,
// L = (1/M) Σ BCE(σ(r_A − r_B), ℓ) + α Σ w̃².
double ridge_loss(const Problem& p, const std::vector<double>& theta, double alpha) {
  std::vector<double> mu(size_t(p.in), 0.0), var(size_t(p.in), 0.0);
  for (int i = 0; i < 2 * p.M; ++i)
    for (int j = 0; j < p.in; ++j) mu[size_t(j)] += p.X[size_t(p.pairs[size_t(i)]) * p.in + j];
  for (double& m : mu) m /= 2 * p.M;
  for (int i = 0; i < 2 * p.M; ++i)
    for (int j = 0; j < p.in; ++j)
      var[size_t(j)] += std::pow(p.X[size_t(p.pairs[size_t(i)]) * p.in + j] - mu[size_t(j)], 2);
  double L = 0;
  for (int j = 0; j < p.in; ++j)
    L += alpha * std::pow(theta[size_t(j)], 2) * var[size_t(j)] / (2 * p.M);
  for (int i = 0; i < p.M; ++i) {
    double z = 0;
    for (int j = 0; j < p.in; ++j)
      z += theta[size_t(j)] * (double(p.X[size_t(p.pairs[size_t(2 * i)]) * p.in + j]) -
                               p.X[size_t(p.pairs[size_t(2 * i + 1)]) * p.in + j]);
    const double l = p.label[size_t(i)];
    L += (l * std::log1p(std::exp(-z)) + (1 - l) * std::log1p(std::exp(z))) / p.M;
  }
  return L;
}

TEST(LinearBradleyTerry, TheFitIsTheMinimumOfTheRidgeLoss) {
  // Convex loss: a zero gradient in w is the global minimum. Checked on the test's own loss by
  // central differences along every coordinate, and by the loss rising on both sides of each.
  const Problem p = problem(60, 5, 40, 3);
  const double alpha = 0.05;
  const LinearBtFit f =
      fit_linear_bradley_terry(p.X.data(), p.n, p.in, p.pairs.data(), p.label.data(), p.M, alpha);
  ASSERT_TRUE(f.converged);
  EXPECT_EQ(f.rank, p.in);
  EXPECT_LE(f.iterations, 20);
  const double L0 = ridge_loss(p, f.weights, alpha);
  for (int j = 0; j < p.in; ++j) {
    std::vector<double> up = f.weights, down = f.weights;
    up[size_t(j)] += 1e-5;
    down[size_t(j)] -= 1e-5;
    EXPECT_NEAR((ridge_loss(p, up, alpha) - ridge_loss(p, down, alpha)) / 2e-5, 0.0, 1e-7)
        << "coordinate " << j;
    for (double h : {1e-3, -1e-3}) {
      std::vector<double> t = f.weights;
      t[size_t(j)] += h;
      EXPECT_GT(ridge_loss(p, t, alpha), L0) << "coordinate " << j << " step " << h;
    }
  }
}

TEST(LinearBradleyTerry, AHandSolvedOnePairProblem) {
  // One feature, one pair: x_A = 1, x_B = 0, A preferred, α = 1. Over the two rows μ = 0.5 and
  // σ = 0.5, so the standardised difference is 2 and L(w̃) = softplus(−2w̃) + w̃²; ∂L/∂w̃ = 0 is
  // w̃ = 1/(1 + e^{2w̃}): w̃* = 0.3374158071711997 (bisection to 1e-16). In the input's units the
  // weight is w̃*/σ and the bias −w̃*μ/σ.
  const std::vector<float> X{1.f, 0.f}, label{1.f};
  const std::vector<int32_t> pairs{0, 1};
  const LinearBtFit f =
      fit_linear_bradley_terry(X.data(), 2, 1, pairs.data(), label.data(), 1, 1.0);
  ASSERT_TRUE(f.converged);
  EXPECT_NEAR(f.weights[0], 2 * 0.3374158071711997, 1e-9);
  EXPECT_NEAR(f.weights[1], -0.3374158071711997, 1e-9);
}

TEST(LinearBradleyTerry, TheRewardsDoNotDependOnFeatureUnitsOrOnFeaturesNoRowVaries) {
  // A column rescaled and shifted, a constant column and zero columns added: every row's reward
  // is the same (standardisation removes units; a feature constant over the training rows gets no
  // weight). Padding to 25 columns (> M = 8 pairs) switches the fit to its other solution path
  // (the pairs' Gram matrix); the answer must not change.
  const Problem p = problem(30, 3, 8, 5);
  Problem wide = p;
  const int extra = 22;  // column 0 × 1000 + 5 in its place, a constant 7, then 21 zero columns
  wide.in = p.in + extra;
  wide.X.assign(size_t(p.n) * wide.in, 0.f);
  for (int i = 0; i < p.n; ++i) {
    for (int j = 0; j < p.in; ++j) wide.X[size_t(i) * wide.in + j] = p.X[size_t(i) * p.in + j];
    wide.X[size_t(i) * wide.in] = 1000.f * p.X[size_t(i) * p.in] + 5.f;
    wide.X[size_t(i) * wide.in + p.in] = 7.f;
  }
  const LinearBtFit a =
      fit_linear_bradley_terry(p.X.data(), p.n, p.in, p.pairs.data(), p.label.data(), p.M, 0.1);
  const LinearBtFit b = fit_linear_bradley_terry(wide.X.data(), wide.n, wide.in, wide.pairs.data(),
                                                 wide.label.data(), wide.M, 0.1);
  ASSERT_TRUE(a.converged);
  ASSERT_TRUE(b.converged);
  EXPECT_EQ(a.rank, b.rank);
  std::vector<int32_t> all(size_t(p.n));
  for (int i = 0; i < p.n; ++i) all[size_t(i)] = i;
  const auto ra = linear_rewards(a, p.X.data(), p.in, all.data(), p.n);
  const auto rb = linear_rewards(b, wide.X.data(), wide.in, all.data(), p.n);
  for (int i = 0; i < p.n; ++i) EXPECT_NEAR(ra[size_t(i)], rb[size_t(i)], 1e-6) << "row " << i;
  EXPECT_NEAR(b.weights[0] * 1000, a.weights[0], 1e-5 * std::abs(a.weights[0]));
  for (int j = p.in; j < wide.in; ++j) EXPECT_EQ(b.weights[size_t(j)], 0.0) << "column " << j;
}

TEST(LinearBradleyTerry, CrossValidationChoosesThePenaltyOfLeastHeldOutLoss) {
  // The fold assignment (pair i in fold i mod 5) and the choice, redone here from single fits:
  // for each α the held-out BCE of every pair when its fold was left out; the chosen α is the
  // one of least loss, and the returned head is the fit on all pairs at it.
  const Problem p = problem(80, 30, 23, 11);  // wider than its pairs, as the raw reference
  const LinearBtOptions o;
  const LinearBtFit cv =
      fit_linear_bradley_terry_cv(p.X.data(), p.n, p.in, p.pairs.data(), p.label.data(), p.M, o);
  double best = INFINITY, best_alpha = 0;
  for (double alpha : o.alpha_grid) {
    double loss = 0;
    for (int fold = 0; fold < 5; ++fold) {
      std::vector<int32_t> fit_pairs;
      std::vector<float> fit_label;
      for (int i = 0; i < p.M; ++i)
        if (i % 5 != fold) {
          fit_pairs.insert(fit_pairs.end(), {p.pairs[size_t(2 * i)], p.pairs[size_t(2 * i + 1)]});
          fit_label.push_back(p.label[size_t(i)]);
        }
      const LinearBtFit f = fit_linear_bradley_terry(
          p.X.data(), p.n, p.in, fit_pairs.data(), fit_label.data(), int(fit_label.size()), alpha);
      for (int i = fold; i < p.M; i += 5) {
        const int32_t ab[2] = {p.pairs[size_t(2 * i)], p.pairs[size_t(2 * i + 1)]};
        const auto r = linear_rewards(f, p.X.data(), p.in, ab, 2);
        const double z = r[0] - r[1], l = p.label[size_t(i)];
        loss += (l * std::log1p(std::exp(-z)) + (1 - l) * std::log1p(std::exp(z))) / p.M;
      }
    }
    if (loss < best) best = loss, best_alpha = alpha;
  }
  EXPECT_EQ(cv.alpha, best_alpha);
  EXPECT_NEAR(cv.cv_loss, best, 1e-12);
  const LinearBtFit all = fit_linear_bradley_terry(p.X.data(), p.n, p.in, p.pairs.data(),
                                                   p.label.data(), p.M, best_alpha);
  EXPECT_EQ(cv.weights, all.weights);
  EXPECT_TRUE(cv.converged);
}

TEST(LinearBradleyTerry, BadInputIsRefused) {
  const std::vector<float> X{1.f, 0.f}, label{1.f};
  const std::vector<int32_t> bad{0, 2}, good{0, 1};
  EXPECT_THROW(fit_linear_bradley_terry(X.data(), 2, 1, bad.data(), label.data(), 1, 1.0),
               std::invalid_argument);
  EXPECT_THROW(fit_linear_bradley_terry(X.data(), 2, 1, good.data(), label.data(), 0, 1.0),
               std::invalid_argument);
  EXPECT_THROW(fit_linear_bradley_terry(X.data(), 2, 1, good.data(), label.data(), 1, 0.0),
               std::invalid_argument);
  EXPECT_THROW(fit_linear_bradley_terry_cv(X.data(), 2, 1, bad.data(), label.data(), 1),
               std::invalid_argument);
  // A penalty grid with a non-positive value, whichever fold would reach it first.
  const std::vector<int32_t> two{0, 1, 1, 0};
  const std::vector<float> labels{1.f, 0.f};
  LinearBtOptions zero;
  zero.alpha_grid = {1.0, 0.0};
  EXPECT_THROW(fit_linear_bradley_terry_cv(X.data(), 2, 1, two.data(), labels.data(), 2, zero),
               std::invalid_argument);
}

TEST(LinearTpa, TheTruthReferenceLearnsLinearRewardsAlmostPerfectly) {
  // The test rewards are linear in φ* and the teacher is perfect: a linear head on φ* must rank
  // held-out pairs almost perfectly from 80 pairs, and a learned-free raw reference (GridRobot's
  // input) must do worse; the untrained φ worse still than the truth.
  World w = world();
  const Representation truth = reference_representation(Method::truth, w.d);
  EXPECT_EQ(truth.dim(), w.d.feature_count());
  const LinearTpaResult t = evaluate_linear_tpa(truth, w.d, w.bundle.tpa, 80, {});
  RecordProperty("linear_tpa_truth_m80", std::to_string(t.mean));
  EXPECT_TRUE(t.converged);
  EXPECT_GE(t.mean, 0.9);
  ASSERT_EQ(t.accuracy.size(), 20u);
  const LinearTpaResult random = evaluate_linear_tpa(trained().random, w.d, w.bundle.tpa, 80, {});
  EXPECT_LT(random.mean, t.mean - 0.1);
}

TEST(LinearTpa, TheSameResultTwiceAndWhateverTheThreadCount) {
  World w = world();
  const LinearTpaResult a = evaluate_linear_tpa(trained().sirl, w.d, w.bundle.tpa, 50, {}, 1);
  const LinearTpaResult b = evaluate_linear_tpa(trained().sirl, w.d, w.bundle.tpa, 50, {}, 2);
  EXPECT_EQ(a.accuracy, b.accuracy);
  EXPECT_EQ(a.iterations, b.iterations);
}

TEST(LinearTpa, MOutsideTheTrainingSplitIsRefused) {
  World w = world();
  const Representation truth = reference_representation(Method::truth, w.d);
  EXPECT_THROW(evaluate_linear_tpa(truth, w.d, w.bundle.tpa, 0, {}), std::invalid_argument);
  EXPECT_THROW(evaluate_linear_tpa(truth, w.d, w.bundle.tpa, w.bundle.tpa[0].train + 1, {}),
               std::invalid_argument);
}

TEST(References, TruthAndRawAreTheFeaturesAndTheInputsOfTheirRows) {
  World w = world();
  const std::vector<int32_t> rows{5, 0, 17};
  const Representation truth = reference_representation(Method::truth, w.d);
  const Representation raw = reference_representation(Method::raw, w.d);
  EXPECT_TRUE(truth.is_table());
  EXPECT_EQ(raw.dim(), w.d.input_dim);
  const auto t = embed_rows(truth, w.d, rows), r = embed_rows(raw, w.d, rows);
  for (size_t i = 0; i < rows.size(); ++i) {
    for (int j = 0; j < truth.dim(); ++j)
      EXPECT_EQ(t[i * truth.dim() + j], w.d.feature(rows[i])[j]);
    for (int j = 0; j < raw.dim(); ++j) EXPECT_EQ(r[i * raw.dim() + j], w.d.input(rows[i])[j]);
  }
  EXPECT_THROW(reference_representation(Method::sirl, w.d), std::invalid_argument);
  // The truth's FPE is 0 up to rounding: the probe's targets are its own inputs.
  EXPECT_LT(evaluate_fpe(truth, w.d, w.bundle.fpe).fpe, 1e-20);
}

TEST(LinearProbe, FewerRowsThanUnknownsTakesTheLeastNormExactFit) {
  // 4 rows, 6 inputs (+ bias): many exact fits. The least-norm one is Aᵀ(AAᵀ)⁻¹y, computed here
  // by hand-written Gaussian elimination on the 4×4 AAᵀ (independent of the probe's solver).
  Rng rng(9);
  const int n = 4, in = 6;
  std::vector<float> X(static_cast<size_t>(n * in)), Y(static_cast<size_t>(n));
  for (float& x : X) x = float(rng.normal());
  for (float& y : Y) y = float(rng.normal());
  const LinearProbe p = fit_linear_probe(X.data(), Y.data(), n, in, 1);
  EXPECT_LT(linear_probe_mse(p, X.data(), Y.data(), n), 1e-20);
  auto a = [&](int i, int j) { return j < in ? double(X[size_t(i) * in + j]) : 1.0; };
  std::vector<double> G(n * n), y(Y.begin(), Y.end());
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k)
      for (int j = 0; j <= in; ++j) G[size_t(i * n + k)] += a(i, j) * a(k, j);
  for (int c = 0; c < n; ++c)  // G is symmetric positive definite: no pivoting needed
    for (int r2 = c + 1; r2 < n; ++r2) {
      const double f = G[size_t(r2 * n + c)] / G[size_t(c * n + c)];
      for (int k = c; k < n; ++k) G[size_t(r2 * n + k)] -= f * G[size_t(c * n + k)];
      y[size_t(r2)] -= f * y[size_t(c)];
    }
  std::vector<double> alpha(static_cast<size_t>(n));
  for (int r2 = n - 1; r2 >= 0; --r2) {
    double s = y[size_t(r2)];
    for (int k = r2 + 1; k < n; ++k) s -= G[size_t(r2 * n + k)] * alpha[size_t(k)];
    alpha[size_t(r2)] = s / G[size_t(r2 * n + r2)];
  }
  for (int j = 0; j <= in; ++j) {
    double beta = 0;
    for (int i = 0; i < n; ++i) beta += a(i, j) * alpha[size_t(i)];
    EXPECT_NEAR(p.weights[size_t(j)], beta, 1e-9) << "weight " << j;
  }
}

}  // namespace
}  // namespace sirl

namespace sirl {
namespace {

// x [m, m] · sol = b by Gaussian elimination with partial pivoting (the test's own solver).
std::vector<double> solve_dense(std::vector<double> A, std::vector<double> b, int m) {
  for (int c = 0; c < m; ++c) {
    int piv = c;
    for (int r = c + 1; r < m; ++r)
      if (std::abs(A[size_t(r * m + c)]) > std::abs(A[size_t(piv * m + c)])) piv = r;
    for (int k = 0; k < m; ++k) std::swap(A[size_t(c * m + k)], A[size_t(piv * m + k)]);
    std::swap(b[size_t(c)], b[size_t(piv)]);
    for (int r = c + 1; r < m; ++r) {
      const double f = A[size_t(r * m + c)] / A[size_t(c * m + c)];
      for (int k = c; k < m; ++k) A[size_t(r * m + k)] -= f * A[size_t(c * m + k)];
      b[size_t(r)] -= f * b[size_t(c)];
    }
  }
  std::vector<double> x(static_cast<size_t>(m));
  for (int r = m - 1; r >= 0; --r) {
    double s = b[size_t(r)];
    for (int k = r + 1; k < m; ++k) s -= A[size_t(r * m + k)] * x[size_t(k)];
    x[size_t(r)] = s / A[size_t(r * m + r)];
  }
  return x;
}

// Ridge with an unpenalised bias on rows `rows` of X [n, in], y [n]: (w, b) by the normal
// equations of the centred rows.
std::pair<std::vector<double>, double> ridge_fit(const std::vector<float>& X,
                                                 const std::vector<float>& y, int in,
                                                 const std::vector<int>& rows, double a) {
  std::vector<double> xm(static_cast<size_t>(in), 0.0);
  double ym = 0;
  for (int i : rows) {
    for (int j = 0; j < in; ++j) xm[size_t(j)] += X[size_t(i * in + j)] / double(rows.size());
    ym += y[size_t(i)] / double(rows.size());
  }
  std::vector<double> A(size_t(in * in), 0.0), rhs(static_cast<size_t>(in), 0.0);
  for (int i : rows)
    for (int j = 0; j < in; ++j) {
      const double xj = X[size_t(i * in + j)] - xm[size_t(j)];
      rhs[size_t(j)] += xj * (y[size_t(i)] - ym);
      for (int k = 0; k < in; ++k)
        A[size_t(j * in + k)] += xj * (X[size_t(i * in + k)] - xm[size_t(k)]);
    }
  for (int j = 0; j < in; ++j) A[size_t(j * in + j)] += a;
  const std::vector<double> w = solve_dense(A, rhs, in);
  double b = ym;
  for (int j = 0; j < in; ++j) b -= w[size_t(j)] * xm[size_t(j)];
  return {w, b};
}

TEST(RidgeProbe, ItsLeaveOneOutErrorIsThatOfRefittingWithoutEachRow) {
  // 12 rows of 20 inputs (wider than the rows, as the raw reference's): for every candidate
  // weight, the closed-form leave-one-out error must equal refitting 12 times without each row
  // (by the test's own normal equations), and the probe must pick the smallest.
  Rng rng(4);
  const int n = 12, in = 20;
  std::vector<float> X(static_cast<size_t>(n * in)), y(static_cast<size_t>(n));
  for (float& x : X) x = float(rng.normal());
  for (int i = 0; i < n; ++i)
    y[size_t(i)] = X[size_t(i * in)] - 0.5f * X[size_t(i * in + 3)] + 0.1f * float(rng.normal());
  const RidgeProbe p = fit_ridge_probe_loocv(X.data(), y.data(), n, in, 1);
  double scale = 0;  // mean squared singular value of the centred X over its rank (n − 1)
  {
    std::vector<int> all(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) all[size_t(i)] = i;
    std::vector<double> xm(static_cast<size_t>(in), 0.0);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < in; ++j) xm[size_t(j)] += X[size_t(i * in + j)] / n;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < in; ++j) scale += std::pow(X[size_t(i * in + j)] - xm[size_t(j)], 2);
    scale /= (n - 1);
  }
  double best = INFINITY, best_a = 0;
  for (int e = -8; e <= 2; ++e) {
    const double a = scale * std::pow(10.0, e);
    double loo = 0;
    for (int out = 0; out < n; ++out) {
      std::vector<int> rows;
      for (int i = 0; i < n; ++i)
        if (i != out) rows.push_back(i);
      const auto [w, b] = ridge_fit(X, y, in, rows, a);
      double pred = b;
      for (int j = 0; j < in; ++j) pred += w[size_t(j)] * X[size_t(out * in + j)];
      loo += std::pow(pred - y[size_t(out)], 2) / n;
    }
    if (loo < best) best = loo, best_a = a;
  }
  EXPECT_NEAR(p.weight / best_a, 1.0, 1e-9);
  EXPECT_NEAR(p.loo_mse, best, 1e-9 * best);
  // The probe's weights are the ridge fit on every row at that weight.
  std::vector<int> all;
  for (int i = 0; i < n; ++i) all.push_back(i);
  const auto [w, b] = ridge_fit(X, y, in, all, best_a);
  for (int j = 0; j < in; ++j) EXPECT_NEAR(p.probe.weights[size_t(j)], w[size_t(j)], 1e-9);
  EXPECT_NEAR(p.probe.weights[size_t(in)], b, 1e-9);
  EXPECT_THROW(fit_ridge_probe_loocv(X.data(), y.data(), 1, in, 1), std::invalid_argument);
}

}  // namespace
}  // namespace sirl
