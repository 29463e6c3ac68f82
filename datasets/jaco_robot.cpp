#include "datasets/jaco_robot.h"

#include <mujoco/mujoco.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "datasets/trajectory_deformation.h"
#include "kernels/rng.h"

namespace sirl {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kThreshold = 0.3;  // m: laptop and proxemics radius
}  // namespace

void validate(const JacoConfig& c) {
  auto fail = [](const std::string& w) { throw std::invalid_argument("jaco: " + w); };
  if (c.trajectories < 1) fail("trajectories must be >= 1");
  if (c.waypoints < 3) fail("waypoints must be >= 3");
  if (c.max_deformations < 0) fail("max_deformations must be >= 0");
  if (!(c.max_deformation >= 0) || c.max_deformation > kPi)
    fail("max_deformation must be in [0, pi] rad");
  for (double v :
       {c.laptop[0], c.laptop[1], c.laptop[2], c.human[0], c.human[1], c.human[2], c.table_z})
    if (!std::isfinite(v) || std::abs(v) > 10) fail("object positions must be finite, within 10 m");
}

// ---------------------------------------------------------------- MuJoCo kinematics

struct JacoKinematics::Impl {
  mjModel* m = nullptr;
  std::vector<mjData*> data;
  int site[7];
};

JacoKinematics::JacoKinematics(const JacoConfig& cfg) : impl_(new Impl) {
  // Load the compiled-in MJCF from a virtual file system (MuJoCo 2.2 API).
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* xml = jaco_model_xml();
  const int len = int(std::strlen(xml));
  if (mj_makeEmptyFileVFS(vfs.get(), "jaco.xml", len) != 0)
    throw std::runtime_error("jaco: cannot create the MuJoCo virtual file");
  std::memcpy(vfs->filedata[vfs->nfile - 1], xml, len);
  char err[1000] = "";
  impl_->m = mj_loadXML("jaco.xml", vfs.get(), err, sizeof err);
  mj_deleteVFS(vfs.get());
  if (!impl_->m) throw std::runtime_error(std::string("jaco: MuJoCo rejected the model: ") + err);
  mjModel* m = impl_->m;
  if (m->nq != kJacoDofs) throw std::runtime_error("jaco: the model must have 7 hinge joints");
  for (int i = 0; i < 7; ++i) {
    const std::string name = "frame" + std::to_string(i + 1);
    impl_->site[i] = mj_name2id(m, mjOBJ_SITE, name.c_str());
    if (impl_->site[i] < 0) throw std::runtime_error("jaco: model lacks site " + name);
    limited[i] = m->jnt_limited[i];
    lower[i] = limited[i] ? m->jnt_range[2 * i] : -kPi;
    upper[i] = limited[i] ? m->jnt_range[2 * i + 1] : kPi;
  }
  // The scene follows the configuration (objects are static bodies: only their pose matters).
  const int laptop = mj_name2id(m, mjOBJ_BODY, "laptop"),
            human = mj_name2id(m, mjOBJ_BODY, "human");
  for (int k = 0; k < 3; ++k) {
    m->body_pos[3 * laptop + k] = cfg.laptop[k];
    m->body_pos[3 * human + k] = cfg.human[k];
  }
  ensure_workspaces(1);
}

JacoKinematics::~JacoKinematics() {
  for (mjData* d : impl_->data) mj_deleteData(d);
  mj_deleteModel(impl_->m);
  delete impl_;
}

int JacoKinematics::workspaces() const {
  return int(impl_->data.size());
}

void JacoKinematics::ensure_workspaces(int n) {
  while (int(impl_->data.size()) < n) impl_->data.push_back(mj_makeData(impl_->m));
}

JacoFrames JacoKinematics::frames(const double* q, int w) const {
  mjData* d = impl_->data.at(size_t(w));
  std::copy(q, q + kJacoDofs, d->qpos);
  mj_kinematics(impl_->m, d);
  JacoFrames f;
  for (int i = 0; i < 7; ++i) {
    std::copy(d->site_xpos + 3 * impl_->site[i], d->site_xpos + 3 * impl_->site[i] + 3,
              f.pos.begin() + 3 * i);
    std::copy(d->site_xmat + 9 * impl_->site[i], d->site_xmat + 9 * impl_->site[i] + 9,
              f.rot.begin() + 9 * i);
  }
  return f;
}

std::array<double, 4> jaco_state_features(const JacoConfig& c, const double* p, const double* R) {
  const double table = p[2] - c.table_z;
  const double upright = 1.0 - R[6];  // x-axis · ẑ = column 0, row 2 of the row-major matrix
  const double dlx = p[0] - c.laptop[0], dly = p[1] - c.laptop[1];
  const double laptop = std::max(0.0, kThreshold - std::sqrt(dlx * dlx + dly * dly));
  const double dhx = p[0] - c.human[0], dhy = (p[1] - c.human[1]) / 3.0;
  const double prox = std::max(0.0, kThreshold - std::sqrt(dhx * dhx + dhy * dhy));
  return {table, upright, laptop, prox};
}

// ---------------------------------------------------------------- trajectory space

namespace {

double wrap(double a) {  // to (−π, π]
  a = std::fmod(a + kPi, 2 * kPi);
  if (a < 0) a += 2 * kPi;
  return a - kPi;
}

struct Deformation {
  int waypoint;             // interior index (0-based over the m interior waypoints)
  std::array<double, 7> u;  // direction of the torque
  double mu;                // rad: largest joint displacement it makes
};

}  // namespace

namespace {

// Everything about the dataset but its rows: sizes, names, units, objects.
Dataset jaco_dataset_header(const JacoConfig& cfg) {
  const int W = cfg.waypoints, n = kJacoDofs;
  const int64_t T = cfg.trajectories;
  Dataset d;
  d.env = cfg.with_human ? "jaco" : "jaco2";
  d.input_dim = W * kJacoStateDim;
  d.count = T;
  d.seed = cfg.seed;
  d.inputs.assign(size_t(T) * d.input_dim, 0.f);
  d.paths.assign(size_t(T) * W * n, 0.f);
  d.path_len = W;
  d.path_dofs = n;
  d.model_text = jaco_model_xml();
  d.input_description =
      std::to_string(W) +
      " states x 97: 7 joint angles (rad), 7 rotation matrices of DH frames "
      "1..7 (row-major, world), 7 frame positions (m, world; frame 7 = end effector), laptop "
      "xyz, human xyz (zeros in jaco2)";
  if (cfg.with_human) {
    d.feature_names = {"table", "upright", "laptop", "proxemics"};
    d.feature_units = {"m", "1", "m", "m"};
    d.object_names = {"laptop", "human"};
    d.object_positions = {float(cfg.laptop[0]), float(cfg.laptop[1]), float(cfg.laptop[2]),
                          float(cfg.human[0]),  float(cfg.human[1]),  float(cfg.human[2])};
  } else {
    d.feature_names = {"table", "laptop"};
    d.feature_units = {"m", "m"};
    d.object_names = {"laptop"};
    d.object_positions = {float(cfg.laptop[0]), float(cfg.laptop[1]), float(cfg.laptop[2])};
  }
  d.object_dim = 3;
  d.object_units = "m";
  d.features_raw.assign(size_t(T) * d.feature_count(), 0.f);
  return d;
}

// 1. Trajectory k's straight joint-space path [W, n] and its random deformations, from its own
// stream "jaco/trajectory/<k>".
void sample_path(const JacoConfig& cfg, const JacoKinematics& kin, int m, int64_t k,
                 std::vector<double>& p, std::vector<Deformation>& defs) {
  const int W = cfg.waypoints, n = kJacoDofs;
  Rng rng(seed_from_key("jaco/trajectory/" + std::to_string(k), cfg.seed));
  std::array<double, 7> start, delta;
  for (int j = 0; j < n; ++j) {
    start[j] = rng.uniform(kin.lower[j], kin.upper[j]);
    const double goal = rng.uniform(kin.lower[j], kin.upper[j]);
    // the shortest path: continuous joints may go either way round
    delta[j] = kin.limited[j] ? goal - start[j] : wrap(goal - start[j]);
  }
  p.assign(size_t(W) * n, 0.0);
  for (int t = 0; t < W; ++t)
    for (int j = 0; j < n; ++j) p[size_t(t) * n + j] = start[j] + delta[j] * t / (W - 1);
  const int count =
      cfg.max_deformations > 0 ? 1 + int(rng.uniform_int(uint64_t(cfg.max_deformations))) : 0;
  for (int i = 0; i < count; ++i) {
    Deformation df;
    df.waypoint = int(rng.uniform_int(uint64_t(m)));
    for (double& x : df.u) x = rng.uniform(-1.0, 1.0);
    df.mu = rng.uniform(0.0, cfg.max_deformation);
    defs.push_back(df);
  }
}

// 2. One CHOLMOD solve for every deformation of a chunk: column c of the result [columns, N] is
// A⁻¹ ũ_c.
std::vector<double> solve_deformations(const DeformationNorm& norm,
                                       const std::vector<std::vector<Deformation>>& defs) {
  const int N = norm.size(), m = norm.interior();
  int columns = 0;
  for (const auto& ds : defs) columns += int(ds.size());
  std::vector<double> B(size_t(N) * columns, 0.0);
  int col = 0;
  for (const auto& ds : defs)
    for (const auto& df : ds) {
      for (int j = 0; j < kJacoDofs; ++j) B[size_t(col) * N + j * m + df.waypoint] = df.u[j];
      ++col;
    }
  norm.solve(B.data(), columns);
  return B;
}

// 3. Adds μ·(A⁻¹ũ / ‖A⁻¹ũ‖∞) for each deformation (solutions from column `col` of B on); halves
// the μ's until the limited joints stay in range (undeformed as a last resort).
void apply_deformations(const JacoConfig& cfg, const JacoKinematics& kin,
                        const DeformationNorm& norm, const std::vector<Deformation>& ds,
                        const double* B, int& col, std::vector<double>& p) {
  const int W = cfg.waypoints, n = kJacoDofs, N = norm.size(), m = norm.interior();
  std::vector<double> disp(size_t(W) * n, 0.0);
  for (size_t k = 0; k < ds.size(); ++k) {
    const double* x = B + size_t(col++) * N;
    double peak = 0;
    for (int i = 0; i < N; ++i) peak = std::max(peak, std::abs(x[i]));
    if (peak == 0) continue;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < m; ++i) disp[size_t(i + 1) * n + j] += ds[k].mu * x[j * m + i] / peak;
  }
  for (int attempt = 0; attempt < 12; ++attempt) {
    bool ok = true;
    for (int t = 0; t < W && ok; ++t)
      for (int j = 0; j < n && ok; ++j)
        if (kin.limited[j]) {
          const double q = p[size_t(t) * n + j] + disp[size_t(t) * n + j];
          ok = q >= kin.lower[j] && q <= kin.upper[j];
        }
    if (ok) break;
    for (double& v : disp) v *= attempt < 11 ? 0.5 : 0.0;  // last resort: undeformed
  }
  for (size_t i = 0; i < p.size(); ++i) p[i] += disp[i];
}

// 4. Forward kinematics of every waypoint of trajectory k → its input row (the state layout of
// jaco_robot.h), its true features (means over the waypoints) and its stored path.
void write_trajectory(const JacoConfig& cfg, JacoKinematics& kin, int worker, int64_t k,
                      const std::vector<double>& p, Dataset& d) {
  const int W = cfg.waypoints, n = kJacoDofs;
  float* in = d.inputs.data() + size_t(k) * d.input_dim;
  std::array<double, 4> feat{0, 0, 0, 0};
  for (int t = 0; t < W; ++t) {
    const double* q = p.data() + size_t(t) * n;
    const JacoFrames fr = kin.frames(q, worker);
    float* s = in + size_t(t) * kJacoStateDim;
    for (int j = 0; j < n; ++j) s[kJacoAngles + j] = float(q[j]);
    for (int i = 0; i < 9 * n; ++i) s[kJacoRotations + i] = float(fr.rot[i]);
    for (int i = 0; i < 3 * n; ++i) s[kJacoPositions + i] = float(fr.pos[i]);
    for (int i = 0; i < 3; ++i) {
      s[kJacoLaptop + i] = float(cfg.laptop[i]);
      s[kJacoHuman + i] = cfg.with_human ? float(cfg.human[i]) : 0.f;
    }
    const auto f = jaco_state_features(cfg, fr.pos.data() + 18, fr.rot.data() + 54);
    for (int i = 0; i < 4; ++i) feat[i] += f[i] / W;  // mean over the waypoints
  }
  float* fr = d.features_raw.data() + size_t(k) * d.feature_count();
  if (cfg.with_human)
    for (int i = 0; i < 4; ++i) fr[i] = float(feat[i]);
  else
    fr[0] = float(feat[0]), fr[1] = float(feat[2]);
  std::transform(p.begin(), p.end(), d.paths.begin() + size_t(k) * W * n,
                 [](double v) { return float(v); });
}

}  // namespace

Dataset make_jaco_dataset(const JacoConfig& cfg) {
  validate(cfg);
  const int64_t T = cfg.trajectories;
  const DeformationNorm norm(cfg.waypoints, kJacoDofs);
  JacoKinematics kin(cfg);
  const int threads = cfg.threads > 0 ? cfg.threads : omp_get_max_threads();
  kin.ensure_workspaces(threads);
  Dataset d = jaco_dataset_header(cfg);

  // Chunks of trajectories share one sparse solve; every trajectory draws from its own stream,
  // so the data never depends on the thread count.
  constexpr int64_t kChunk = 128;
  const int64_t chunks = (T + kChunk - 1) / kChunk;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (int64_t c = 0; c < chunks; ++c) {
    const int w = omp_get_thread_num();
    const int64_t k0 = c * kChunk, k1 = std::min(T, k0 + kChunk);
    std::vector<std::vector<double>> path(k1 - k0);
    std::vector<std::vector<Deformation>> defs(k1 - k0);
    for (int64_t k = k0; k < k1; ++k)
      sample_path(cfg, kin, norm.interior(), k, path[k - k0], defs[k - k0]);
    const std::vector<double> B = solve_deformations(norm, defs);
    int col = 0;
    for (int64_t k = k0; k < k1; ++k) {
      apply_deformations(cfg, kin, norm, defs[k - k0], B.data(), col, path[k - k0]);
      write_trajectory(cfg, kin, w, k, path[k - k0], d);
    }
  }
  normalise_features(d);
  return d;
}

std::string mujoco_version() {
  return mj_versionString();
}
}  // namespace sirl
