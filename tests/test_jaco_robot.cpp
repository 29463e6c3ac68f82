// JacoRobot: MuJoCo kinematics against an independent DH computation, rigid links, stored
// features against a recomputation, deformations, determinism and config checks.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "datasets/jaco_robot.h"
#include "datasets/trajectory_deformation.h"
#include "kernels/rng.h"

namespace sirl {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Kinova's classic DH for the j2s7s300 (the published table, typed in independently of the
// MJCF): rows (alpha, a, d), frame i = frame(i−1)·Rz(q_i)·Tz(d_i)·Tx(a_i)·Rx(alpha_i), and
// frame 0 = Rx(π) (Kinova's base frame points down).
std::vector<Eigen::Matrix4d> dh_frames(const double* q) {
  const double D1 = 0.2755, D2 = 0.2050, D3 = 0.2050, D4 = 0.2073, D5 = 0.1038, D6 = 0.1038,
               D7 = 0.1600, e2 = 0.0098;
  const double alpha[7] = {kPi / 2, kPi / 2, kPi / 2, kPi / 2, kPi / 2, kPi / 2, kPi};
  const double d[7] = {-D1, 0, -(D2 + D3), -e2, -(D4 + D5), 0, -(D6 + D7)};
  auto rx = [](double a) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m(1, 1) = std::cos(a), m(1, 2) = -std::sin(a), m(2, 1) = std::sin(a), m(2, 2) = std::cos(a);
    return m;
  };
  auto rz = [](double a) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m(0, 0) = std::cos(a), m(0, 1) = -std::sin(a), m(1, 0) = std::sin(a), m(1, 1) = std::cos(a);
    return m;
  };
  Eigen::Matrix4d T = rx(kPi);
  std::vector<Eigen::Matrix4d> out;
  for (int i = 0; i < 7; ++i) {
    Eigen::Matrix4d tz = Eigen::Matrix4d::Identity();
    tz(2, 3) = d[i];
    T = T * rz(q[i]) * tz * rx(alpha[i]);
    out.push_back(T);
  }
  return out;
}

TEST(JacoKinematics, MatchesAnIndependentDhComputation) {
  JacoKinematics kin;
  Rng rng(5);
  for (int trial = 0; trial < 50; ++trial) {
    double q[7];
    for (int j = 0; j < 7; ++j) q[j] = trial == 0 ? 0.0 : rng.uniform(-2 * kPi, 2 * kPi);
    const JacoFrames f = kin.frames(q);
    const auto ref = dh_frames(q);
    for (int i = 0; i < 7; ++i) {
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(f.pos[3 * i + k], ref[i](k, 3), 1e-6) << i;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(f.rot[9 * i + 3 * r + c], ref[i](r, c), 1e-6);
    }
  }
  // Joint limits from the spec: 2, 4, 6 limited; 1, 3, 5, 7 continuous.
  EXPECT_TRUE(kin.limited[1] && kin.limited[3] && kin.limited[5]);
  EXPECT_FALSE(kin.limited[0] || kin.limited[2] || kin.limited[4] || kin.limited[6]);
  EXPECT_NEAR(kin.lower[1] * 180 / kPi, 47, 1e-4);
  EXPECT_NEAR(kin.upper[3] * 180 / kPi, 330, 1e-4);
  EXPECT_NEAR(kin.upper[5] * 180 / kPi, 295, 1e-4);
}

Dataset small(int64_t T = 300, int threads = 1, int deformations = 3) {
  JacoConfig c;
  c.trajectories = T;
  c.threads = threads;
  c.max_deformations = deformations;
  c.seed = 3;
  return make_jaco_dataset(c);
}

TEST(JacoDataset, StatesAreRigidBodyFramesWithOrthonormalRotations) {
  const Dataset d = small();
  ASSERT_EQ(d.input_dim, 21 * 97);
  double dist0[6];
  for (int64_t s = 0; s < d.count * 21; ++s) {
    const float* x = d.inputs.data() + s * 97;
    for (int i = 0; i < 7; ++i) {
      Eigen::Matrix3d R;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) R(r, c) = x[7 + 9 * i + 3 * r + c];
      ASSERT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-5);
      ASSERT_NEAR(R.determinant(), 1.0, 1e-5);
    }
    for (int i = 0; i < 6; ++i) {  // consecutive frame origins: constant distances
      double dd = 0;
      for (int k = 0; k < 3; ++k) dd += std::pow(x[70 + 3 * (i + 1) + k] - x[70 + 3 * i + k], 2);
      dd = std::sqrt(dd);
      if (s == 0) dist0[i] = dd;
      ASSERT_NEAR(dd, dist0[i], 2e-6) << "link " << i << " state " << s;
    }
    ASSERT_FLOAT_EQ(x[91], 0.f);  // laptop x
    ASSERT_FLOAT_EQ(x[92], -0.8f);
    ASSERT_FLOAT_EQ(x[95], -0.5f);  // human y
  }
  EXPECT_NEAR(dist0[1], 0.41, 1e-6);    // D2 + D3
  EXPECT_NEAR(dist0[5], 0.2638, 1e-6);  // D6 + D7
}

TEST(JacoDataset, StoredFeaturesAgreeWithARecomputation) {
  const Dataset d = small();
  for (int64_t k = 0; k < d.count; ++k) {
    double f[4] = {0, 0, 0, 0};
    for (int t = 0; t < 21; ++t) {
      const float* x = d.input(k) + t * 97;
      const double ex = x[88], ey = x[89], ez = x[90];
      const double xz = x[7 + 54 + 6];  // EE rotation (2, 0): x-axis · world z
      f[0] += ez / 21;
      f[1] += (1 - xz) / 21;
      f[2] += std::max(0.0, 0.3 - std::hypot(ex - 0.0, ey + 0.8)) / 21;
      f[3] += std::max(0.0, 0.3 - std::hypot(ex + 0.2, (ey + 0.5) / 3)) / 21;
    }
    for (int i = 0; i < 4; ++i) ASSERT_NEAR(d.features_raw[k * 4 + i], f[i], 2e-5) << k << "," << i;
  }
  // Normalised to [0, 1] over the dataset, each feature actually varying.
  for (int i = 0; i < 4; ++i) EXPECT_GT(d.feature_max[i], d.feature_min[i]);
}

TEST(JacoDataset, JointAnglesInTheStatesAreThePathsAndStayInLimits) {
  const Dataset d = small();
  JacoKinematics kin;
  for (int64_t k = 0; k < d.count; ++k)
    for (int t = 0; t < 21; ++t)
      for (int j = 0; j < 7; ++j) {
        const float q = d.paths[(k * 21 + t) * 7 + j];
        ASSERT_EQ(q, d.input(k)[t * 97 + j]);
        if (kin.limited[j]) {
          ASSERT_GE(q, kin.lower[j] - 1e-5);
          ASSERT_LE(q, kin.upper[j] + 1e-5);
        }
      }
}

TEST(JacoDataset, DeformationsKeepStartAndGoalAndBendTheMiddle) {
  const Dataset straight = small(100, 1, 0), bent = small(100, 1, 3);
  int bent_count = 0;
  for (int64_t k = 0; k < 100; ++k) {
    for (int j = 0; j < 7; ++j) {
      EXPECT_EQ(straight.paths[(k * 21 + 0) * 7 + j], bent.paths[(k * 21 + 0) * 7 + j]);
      EXPECT_EQ(straight.paths[(k * 21 + 20) * 7 + j], bent.paths[(k * 21 + 20) * 7 + j]);
    }
    double diff = 0;
    for (int i = 0; i < 21 * 7; ++i)
      diff =
          std::max(diff, double(std::abs(straight.paths[k * 147 + i] - bent.paths[k * 147 + i])));
    bent_count += diff > 1e-3;
  }
  EXPECT_GT(bent_count, 80);  // nearly every trajectory is deformed (a few hit joint limits)
}

TEST(JacoDataset, SameSeedSameDataWhateverTheThreadCount) {
  const Dataset a = small(300, 1), b = small(300, 2);
  EXPECT_EQ(a.inputs, b.inputs);
  EXPECT_EQ(a.features, b.features);
  JacoConfig c;
  c.trajectories = 300;
  c.seed = 4;
  EXPECT_NE(make_jaco_dataset(c).inputs, a.inputs);
}

TEST(JacoDataset, UserStudyVariantHasTwoFeaturesAndNoHuman) {
  JacoConfig c;
  c.trajectories = 50;
  c.with_human = false;
  const Dataset d = make_jaco_dataset(c);
  EXPECT_EQ(d.env, "jaco2");
  EXPECT_EQ(d.feature_names, (std::vector<std::string>{"table", "laptop"}));
  for (int64_t s = 0; s < d.count * 21; ++s)
    for (int k = 94; k < 97; ++k) ASSERT_EQ(d.inputs[s * 97 + k], 0.f);
}

TEST(JacoDataset, RejectsBadConfigs) {
  JacoConfig c;
  c.trajectories = 0;
  EXPECT_THROW(make_jaco_dataset(c), std::invalid_argument);
  c = JacoConfig{};
  c.waypoints = 2;
  EXPECT_THROW(make_jaco_dataset(c), std::invalid_argument);
  c = JacoConfig{};
  c.laptop[0] = std::nan("");
  EXPECT_THROW(make_jaco_dataset(c), std::invalid_argument);
}

}  // namespace
}  // namespace sirl
