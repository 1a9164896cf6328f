#include "unav_localization/slam_optimizer.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <set>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

namespace unav::localization {
namespace {

constexpr double kChi2Mono = 5.991;  // 95% chi-square gate, 2 dof

void ToParams(const Eigen::Isometry3d& T, double* p) {
  const Eigen::AngleAxisd aa(T.linear());
  const Eigen::Vector3d v = aa.angle() * aa.axis();
  for (int i = 0; i < 3; ++i) {
    p[i] = v[i];
    p[3 + i] = T.translation()[i];
  }
}

Eigen::Isometry3d FromParams(const double* p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d v(p[0], p[1], p[2]);
  const double a = v.norm();
  if (a > 1e-15) T.linear() = Eigen::AngleAxisd(a, v / a).toRotationMatrix();
  T.translation() = Eigen::Vector3d(p[3], p[4], p[5]);
  return T;
}

template <typename T>
void Project(const PinholeCamera& c, const T* p, T* uv) {
  uv[0] = T(c.fx) * p[0] / p[2] + T(c.cx);
  uv[1] = T(c.fy) * p[1] / p[2] + T(c.cy);
}

// Reprojection of a point X_w (3) through a pose (angle-axis + translation of T_cw).
struct ReprojectionError {
  ReprojectionError(const PinholeCamera& c, const Eigen::Vector2d& uv, double inv_sigma)
      : cam(c), obs(uv), w(inv_sigma) {}
  template <typename T>
  bool operator()(const T* pose, const T* X, T* r) const {
    T p[3];
    ceres::AngleAxisRotatePoint(pose, X, p);
    p[0] += pose[3];
    p[1] += pose[4];
    p[2] += pose[5];
    if (p[2] < T(1e-6)) p[2] = T(1e-6);
    T uv[2];
    Project(cam, p, uv);
    r[0] = (uv[0] - T(obs.x())) * T(w);
    r[1] = (uv[1] - T(obs.y())) * T(w);
    return true;
  }
  PinholeCamera cam;
  Eigen::Vector2d obs;
  double w;
};

// Same with the point held constant (pose-only refinement).
struct PoseOnlyError {
  PoseOnlyError(const PinholeCamera& c, const Eigen::Vector3d& X, const Eigen::Vector2d& uv, double inv_sigma)
      : cam(c), X_w(X), obs(uv), w(inv_sigma) {}
  template <typename T>
  bool operator()(const T* pose, T* r) const {
    const T X[3] = {T(X_w.x()), T(X_w.y()), T(X_w.z())};
    return ReprojectionError(cam, obs, w)(pose, X, r);
  }
  PinholeCamera cam;
  Eigen::Vector3d X_w;
  Eigen::Vector2d obs;
  double w;
};

double Chi2(const PinholeCamera& cam, const Eigen::Isometry3d& T_cw, const Eigen::Vector3d& X_w,
            const Eigen::Vector2d& uv, double inv_sigma2, bool* behind = nullptr) {
  const Eigen::Vector3d p = T_cw * X_w;
  if (behind) *behind = p.z() <= 0;
  if (p.z() <= 0) return 1e9;
  return (cam.Project(p) - uv).squaredNorm() * inv_sigma2;
}

// Quiet, single-threaded, bounded solves: `solver` DENSE_QR for one pose, SPARSE_SCHUR for
// bundle adjustment (cameras and points).
ceres::Solver::Options SolverOptions(ceres::LinearSolverType solver, int iterations) {
  ceres::Solver::Options o;
  o.linear_solver_type = solver;
  o.max_num_iterations = iterations;
  o.num_threads = 1;
  o.logging_type = ceres::SILENT;
  o.minimizer_progress_to_stdout = false;
  return o;
}
ceres::Solver::Options SmallOptions(int iterations) { return SolverOptions(ceres::DENSE_QR, iterations); }
ceres::Solver::Options BaOptions(int iterations) { return SolverOptions(ceres::SPARSE_SCHUR, iterations); }

}  // namespace

int OptimizePose(const PinholeCamera& cam, std::vector<PoseObservation>* obs, Eigen::Isometry3d* T_cw) {
  double pose[6];
  ToParams(*T_cw, pose);
  int inliers = 0;
  for (int round = 0; round < 4; ++round) {
    ceres::Problem::Options po;
    po.enable_fast_removal = false;
    ceres::Problem problem(po);
    int n = 0;
    for (const auto& o : *obs) {
      if (o.outlier) continue;
      auto* cost = new ceres::AutoDiffCostFunction<PoseOnlyError, 2, 6>(
          new PoseOnlyError(cam, o.X_w, o.uv, std::sqrt(o.inv_sigma2)));
      problem.AddResidualBlock(cost, round < 3 ? new ceres::HuberLoss(std::sqrt(kChi2Mono)) : nullptr, pose);
      ++n;
    }
    if (n < 3) break;
    ceres::Solver::Summary summary;
    ceres::Solve(SmallOptions(10), &problem, &summary);
    const Eigen::Isometry3d T = FromParams(pose);
    inliers = 0;
    for (auto& o : *obs) {
      o.outlier = Chi2(cam, T, o.X_w, o.uv, o.inv_sigma2) > kChi2Mono;
      inliers += o.outlier ? 0 : 1;
    }
    if (inliers < 10) break;
  }
  *T_cw = FromParams(pose);
  return inliers;
}

namespace {

// A displacement or rotation factor beyond this many sigmas (chi-square 3 dof, 99 %: 11.34) weighs linearly:
// an interval the DVL and the map disagree on (the keyframes' attitude off in a fast turn) pulls,
// but cannot tear the local map away from its points.
constexpr double kDisplacementHuber = 3.368;

// p_j - p_i - d over sigma, p = T_cw^-1 o_c = R_cw^T (o_c - t_cw) (pose parameters: aa(R_cw), t_cw).
struct BodyDisplacementError {
  explicit BodyDisplacementError(const BodyDisplacementFactor& f) : factor(f) {}
  template <typename T>
  void BodyOrigin(const T* pose, T* p) const {
    const T d[3] = {T(factor.o_c.x()) - pose[3], T(factor.o_c.y()) - pose[4], T(factor.o_c.z()) - pose[5]};
    const T aa_inv[3] = {-pose[0], -pose[1], -pose[2]};
    ceres::AngleAxisRotatePoint(aa_inv, d, p);
  }
  template <typename T>
  bool operator()(const T* pose_i, const T* pose_j, T* r) const {
    T pi[3], pj[3];
    BodyOrigin(pose_i, pi);
    BodyOrigin(pose_j, pj);
    for (int k = 0; k < 3; ++k) r[k] = (pj[k] - pi[k] - T(factor.d_w[k])) / T(factor.sigma);
    return true;
  }
  BodyDisplacementFactor factor;
};

// Log(dR_b^T R_bi^T R_bj) over sigma; R_bi^T R_bj = R_bc R_cw_i R_cw_j^T R_cb (pose parameters:
// aa(R_cw), t_cw).
struct RelativeRotationError {
  explicit RelativeRotationError(const RelativeRotationFactor& f) : factor(f) {
    // The constant ends of the product: A = dR_b^T R_bc, B = R_cb.
    const Eigen::Matrix3d A = f.dR_b.transpose() * f.R_cb.transpose();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        a[r][c] = A(r, c);
        b[r][c] = f.R_cb(r, c);
      }
  }
  template <typename T>
  bool operator()(const T* pose_i, const T* pose_j, T* r) const {
    T Ri[9], Rj[9];  // column-major R_cw
    ceres::AngleAxisToRotationMatrix(pose_i, Ri);
    ceres::AngleAxisToRotationMatrix(pose_j, Rj);
    T M[3][3], N[3][3], E[9];
    for (int x = 0; x < 3; ++x)  // M = R_cw_i R_cw_j^T
      for (int y = 0; y < 3; ++y) {
        M[x][y] = T(0);
        for (int k = 0; k < 3; ++k) M[x][y] += Ri[k * 3 + x] * Rj[k * 3 + y];
      }
    for (int x = 0; x < 3; ++x)  // N = M B
      for (int y = 0; y < 3; ++y) {
        N[x][y] = T(0);
        for (int k = 0; k < 3; ++k) N[x][y] += M[x][k] * T(b[k][y]);
      }
    for (int x = 0; x < 3; ++x)  // E = A N (column-major for ceres)
      for (int y = 0; y < 3; ++y) {
        E[y * 3 + x] = T(0);
        for (int k = 0; k < 3; ++k) E[y * 3 + x] += T(a[x][k]) * N[k][y];
      }
    ceres::RotationMatrixToAngleAxis(E, r);
    for (int k = 0; k < 3; ++k) r[k] /= T(factor.sigma);
    return true;
  }
  RelativeRotationFactor factor;
  double a[3][3], b[3][3];
};

// The inertial edge's residual, whitened: L^T r with L L^T the information (the inverse of the
// preintegration's covariance). Differentiated numerically (central): the preintegration's
// residual is written for doubles, on the manifold.
struct InertialError {
  InertialError(const InertialFactor& f, const Eigen::Vector3d& g) : factor(f), g_w(g) {
    Matrix9d cov = f.pre.covariance();
    cov.diagonal().array() += 1e-12;  // a floor: samples of an ideal IMU have none
    sqrt_info = Eigen::LLT<Matrix9d>(cov.inverse()).matrixL().transpose();
  }
  NavState State(const double* pose, const double* v) const {
    const Eigen::Isometry3d T_wb = FromParams(pose).inverse() * factor.T_cb;
    return {T_wb.linear(), T_wb.translation(), Eigen::Vector3d(v[0], v[1], v[2])};
  }
  bool operator()(const double* pose_i, const double* pose_j, const double* v_i, const double* v_j, const double* bias,
                  double* r) const {
    ImuBias b;
    b.gyro = Eigen::Vector3d(bias[0], bias[1], bias[2]);
    b.accel = Eigen::Vector3d(bias[3], bias[4], bias[5]);
    Eigen::Map<Vector9d> out(r);
    out = sqrt_info * factor.pre.Residual(State(pose_i, v_i), State(pose_j, v_j), b, g_w);
    return true;
  }
  InertialFactor factor;
  Eigen::Vector3d g_w;
  Matrix9d sqrt_info;
};

// The window's bias against its prior.
struct BiasPriorError {
  template <typename T>
  bool operator()(const T* bias, T* r) const {
    for (int k = 0; k < 6; ++k) r[k] = (bias[k] - T(prior[k])) / T(sigma[k]);
    return true;
  }
  double prior[6], sigma[6];
};

BundleAdjustmentSummary RunBundleAdjustment(Map* map, const PinholeCamera& cam, const std::vector<double>& level_sigma2,
                                            const std::vector<int>& local_kfs, const std::vector<int>& fixed_kfs,
                                            const std::vector<int>& pts, int iterations, const BundleFactors& factors) {
  const auto t0 = std::chrono::steady_clock::now();
  BundleAdjustmentSummary s;
  std::map<int, std::array<double, 6>> poses;
  std::set<int> fixed(fixed_kfs.begin(), fixed_kfs.end());
  for (int k : local_kfs) ToParams(map->kf(k).T_cw, poses[k].data());
  for (int k : fixed_kfs) ToParams(map->kf(k).T_cw, poses[k].data());
  std::map<int, std::array<double, 3>> X;
  for (int p : pts) {
    const auto& v = map->mp(p).X_w;
    X[p] = {v.x(), v.y(), v.z()};
  }
  struct Obs {
    int kf, point, feature;
  };
  std::vector<Obs> all;
  for (int p : pts)
    for (const auto& [k, i] : map->mp(p).obs)
      if (poses.count(k)) all.push_back({k, p, i});
  std::vector<bool> outlier(all.size(), false);
  // The inertial states, as parameter blocks (written back below).
  std::map<int, std::array<double, 3>> velocities;
  std::array<double, 6> bias{};
  if (factors.states != nullptr) {
    // The velocities of the factors' keyframes only (the states keep every keyframe's).
    for (const auto& f : factors.inertial)
      for (const int k : {f.kf_i, f.kf_j})
        if (const auto v = factors.states->velocities.find(k); v != factors.states->velocities.end())
          velocities[k] = {v->second.x(), v->second.y(), v->second.z()};
    for (size_t k = 0; k < 3; ++k) {
      bias[k] = factors.states->bias.gyro[static_cast<Eigen::Index>(k)];
      bias[3 + k] = factors.states->bias.accel[static_cast<Eigen::Index>(k)];
    }
  }
  auto chi2_of = [&](const Obs& o) {
    const KeyFrame& kf = map->kf(o.kf);
    const auto& kp = kf.f.keypoints[static_cast<size_t>(o.feature)];
    const auto& x = X[o.point];
    return Chi2(cam, FromParams(poses[o.kf].data()), Eigen::Vector3d(x[0], x[1], x[2]),
                kf.f.un[static_cast<size_t>(o.feature)], 1.0 / level_sigma2[static_cast<size_t>(kp.octave)]);
  };
  for (int stage = 0; stage < 2; ++stage) {
    ceres::Problem problem;
    for (size_t n = 0; n < all.size(); ++n) {
      if (outlier[n]) continue;
      const Obs& o = all[n];
      const KeyFrame& kf = map->kf(o.kf);
      const int level = kf.f.keypoints[static_cast<size_t>(o.feature)].octave;
      auto* cost = new ceres::AutoDiffCostFunction<ReprojectionError, 2, 6, 3>(new ReprojectionError(
          cam, kf.f.un[static_cast<size_t>(o.feature)], 1.0 / std::sqrt(level_sigma2[static_cast<size_t>(level)])));
      problem.AddResidualBlock(cost, new ceres::HuberLoss(std::sqrt(kChi2Mono)), poses[o.kf].data(), X[o.point].data());
    }
    // Both keyframes in the problem (through their points), not both fixed.
    auto blocks = [&](int kf_i, int kf_j) -> std::pair<double*, double*> {
      const auto i = poses.find(kf_i), j = poses.find(kf_j);
      if (i == poses.end() || j == poses.end() || (fixed.count(kf_i) && fixed.count(kf_j))) return {nullptr, nullptr};
      if (!problem.HasParameterBlock(i->second.data()) || !problem.HasParameterBlock(j->second.data()))
        return {nullptr, nullptr};
      return {i->second.data(), j->second.data()};
    };
    for (const auto& f : factors.displacements)
      if (const auto [pi, pj] = blocks(f.kf_i, f.kf_j); pi != nullptr)
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<BodyDisplacementError, 3, 6, 6>(new BodyDisplacementError(f)),
            new ceres::HuberLoss(kDisplacementHuber), pi, pj);
    for (const auto& f : factors.rotations)
      if (const auto [pi, pj] = blocks(f.kf_i, f.kf_j); pi != nullptr)
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<RelativeRotationError, 3, 6, 6>(new RelativeRotationError(f)),
            new ceres::HuberLoss(kDisplacementHuber), pi, pj);
    if (factors.states != nullptr && !factors.inertial.empty()) {
      InertialStates& st = *factors.states;
      for (const auto& f : factors.inertial) {
        const auto [pi, pj] = blocks(f.kf_i, f.kf_j);
        if (pi == nullptr || !velocities.count(f.kf_i) || !velocities.count(f.kf_j)) continue;
        problem.AddResidualBlock(new ceres::NumericDiffCostFunction<InertialError, ceres::CENTRAL, 9, 6, 6, 3, 3, 6>(
                                     new InertialError(f, st.g_w)),
                                 nullptr, pi, pj, velocities[f.kf_i].data(), velocities[f.kf_j].data(), bias.data());
      }
      if (problem.HasParameterBlock(bias.data())) {
        auto* prior = new BiasPriorError;
        for (int k = 0; k < 3; ++k) {
          prior->prior[k] = st.bias_prior.gyro[k];
          prior->prior[3 + k] = st.bias_prior.accel[k];
          prior->sigma[k] = st.gyro_bias_prior_sigma;
          prior->sigma[3 + k] = st.accel_bias_prior_sigma;
        }
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<BiasPriorError, 6, 6>(prior), nullptr, bias.data());
      }
    }
    for (auto& [k, p] : poses)
      if (problem.HasParameterBlock(p.data()) && fixed.count(k)) problem.SetParameterBlockConstant(p.data());
    s.residuals = problem.NumResidualBlocks();
    if (s.residuals == 0) break;
    ceres::Solver::Summary summary;
    ceres::Solve(BaOptions(stage == 0 ? std::max(1, iterations / 2) : iterations), &problem, &summary);
    for (size_t n = 0; n < all.size(); ++n) outlier[n] = chi2_of(all[n]) > kChi2Mono;
  }
  // Write back; drop outlier observations.
  for (int k : local_kfs) map->kf(k).T_cw = FromParams(poses[k].data());
  if (factors.states != nullptr) {
    for (const auto& [k, v] : velocities) factors.states->velocities[k] = Eigen::Vector3d(v[0], v[1], v[2]);
    factors.states->bias.gyro = Eigen::Vector3d(bias[0], bias[1], bias[2]);
    factors.states->bias.accel = Eigen::Vector3d(bias[3], bias[4], bias[5]);
  }
  for (int p : pts) map->mp(p).X_w = Eigen::Vector3d(X[p][0], X[p][1], X[p][2]);
  for (size_t n = 0; n < all.size(); ++n)
    if (outlier[n] && !map->mp(all[n].point).bad) {
      map->EraseObservation(all[n].point, all[n].kf);
      ++s.outliers_removed;
    }
  s.keyframes = static_cast<int>(local_kfs.size());
  s.fixed_keyframes = static_cast<int>(fixed_kfs.size());
  s.points = static_cast<int>(pts.size());
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return s;
}

}  // namespace

BundleAdjustmentSummary LocalBundleAdjustment(Map* map, const PinholeCamera& cam,
                                              const std::vector<double>& level_sigma2, int kf_id, int max_local,
                                              int iterations, const BundleFactors& factors) {
  std::vector<int> local{kf_id};
  for (int k : map->kf(kf_id).BestCovisible(static_cast<size_t>(std::max(0, max_local - 1))))
    if (!map->kf(k).bad) local.push_back(k);
  std::set<int> local_set(local.begin(), local.end());
  std::vector<int> pts;
  std::set<int> seen;
  for (int k : local)
    for (int p : map->kf(k).points)
      if (p >= 0 && !map->mp(p).bad && seen.insert(p).second) pts.push_back(p);
  std::set<int> fixed_set;
  for (int p : pts)
    for (const auto& [k, i] : map->mp(p).obs)
      if (!local_set.count(k) && !map->kf(k).bad) fixed_set.insert(k);
  std::vector<int> opt, fixed(fixed_set.begin(), fixed_set.end());
  for (int k : local) {
    if (k == 0)
      fixed.push_back(k);  // the gauge
    else
      opt.push_back(k);
  }
  return RunBundleAdjustment(map, cam, level_sigma2, opt, fixed, pts, iterations, factors);
}

BundleAdjustmentSummary GlobalBundleAdjustment(Map* map, const PinholeCamera& cam,
                                               const std::vector<double>& level_sigma2, int iterations,
                                               const BundleFactors& factors) {
  std::vector<int> opt, fixed, pts;
  for (const auto& k : map->keyframes) {
    if (k->bad) continue;
    if (k->id == 0)
      fixed.push_back(k->id);
    else
      opt.push_back(k->id);
  }
  for (const auto& p : map->points)
    if (!p->bad && p->obs.size() >= 2) pts.push_back(p->id);
  return RunBundleAdjustment(map, cam, level_sigma2, opt, fixed, pts, iterations, factors);
}

namespace {

template <typename T>
void Sim3Apply(const T* S, const T* x, T* y) {  // y = s R x + t; S = aa(3), t(3), log s
  T rx[3];
  ceres::AngleAxisRotatePoint(S, x, rx);
  const T s = exp(S[6]);
  for (int i = 0; i < 3; ++i) y[i] = s * rx[i] + S[3 + i];
}

template <typename T>
void Sim3ApplyInverse(const T* S, const T* y, T* x) {  // x = R^T (y - t) / s
  const T d[3] = {y[0] - S[3], y[1] - S[4], y[2] - S[5]};
  const T aa_inv[3] = {-S[0], -S[1], -S[2]};
  T r[3];
  ceres::AngleAxisRotatePoint(aa_inv, d, r);
  const T inv_s = exp(-S[6]);
  for (int i = 0; i < 3; ++i) x[i] = r[i] * inv_s;
}

struct Sim3ReprojectionError {
  Sim3ReprojectionError(const PinholeCamera& c, const Sim3Match& m) : cam(c), match(m) {}
  template <typename T>
  bool operator()(const T* S, T* r) const {
    const T X2[3] = {T(match.X2_c2.x()), T(match.X2_c2.y()), T(match.X2_c2.z())};
    const T X1[3] = {T(match.X1_c1.x()), T(match.X1_c1.y()), T(match.X1_c1.z())};
    T p1[3], p2[3], uv[2];
    Sim3Apply(S, X2, p1);
    Sim3ApplyInverse(S, X1, p2);
    if (p1[2] < T(1e-6)) p1[2] = T(1e-6);
    if (p2[2] < T(1e-6)) p2[2] = T(1e-6);
    Project(cam, p1, uv);
    const T w1 = T(std::sqrt(match.inv_sigma2_1)), w2 = T(std::sqrt(match.inv_sigma2_2));
    r[0] = (uv[0] - T(match.uv1.x())) * w1;
    r[1] = (uv[1] - T(match.uv1.y())) * w1;
    Project(cam, p2, uv);
    r[2] = (uv[0] - T(match.uv2.x())) * w2;
    r[3] = (uv[1] - T(match.uv2.y())) * w2;
    return true;
  }
  PinholeCamera cam;
  Sim3Match match;
};

void Sim3ToParams(const Sim3& S, double* p) {
  const Eigen::AngleAxisd aa(S.R);
  const Eigen::Vector3d v = aa.angle() * aa.axis();
  for (int i = 0; i < 3; ++i) {
    p[i] = v[i];
    p[3 + i] = S.t[i];
  }
  p[6] = std::log(S.s);
}

Sim3 Sim3FromParams(const double* p) {
  Sim3 S;
  const Eigen::Vector3d v(p[0], p[1], p[2]);
  const double a = v.norm();
  if (a > 1e-15) S.R = Eigen::AngleAxisd(a, v / a).toRotationMatrix();
  S.t = Eigen::Vector3d(p[3], p[4], p[5]);
  S.s = std::exp(p[6]);
  return S;
}

}  // namespace

int OptimizeSim3(const PinholeCamera& cam, std::vector<Sim3Match>* matches, Sim3* S_12, double chi2_gate) {
  double S[7];
  Sim3ToParams(*S_12, S);
  auto chi2 = [&](const Sim3Match& m) {
    const Sim3 s = Sim3FromParams(S);
    const Eigen::Vector3d p1 = s * m.X2_c2, p2 = s.inverse() * m.X1_c1;
    if (p1.z() <= 0 || p2.z() <= 0) return 1e9;
    return std::max((cam.Project(p1) - m.uv1).squaredNorm() * m.inv_sigma2_1,
                    (cam.Project(p2) - m.uv2).squaredNorm() * m.inv_sigma2_2);
  };
  int inliers = 0;
  for (int round = 0; round < 2; ++round) {
    ceres::Problem problem;
    for (const auto& m : *matches) {
      if (m.outlier) continue;
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<Sim3ReprojectionError, 4, 7>(new Sim3ReprojectionError(cam, m)),
          new ceres::HuberLoss(std::sqrt(chi2_gate)), S);
    }
    if (problem.NumResidualBlocks() < 3) return 0;
    ceres::Solver::Summary summary;
    ceres::Solve(SmallOptions(round == 0 ? 5 : 10), &problem, &summary);
    inliers = 0;
    for (auto& m : *matches) {
      m.outlier = chi2(m) > chi2_gate;
      inliers += m.outlier ? 0 : 1;
    }
  }
  *S_12 = Sim3FromParams(S);
  return inliers;
}

namespace {

struct PoseGraphError {
  explicit PoseGraphError(const Sim3& meas) : S_ij(meas) {}
  template <typename T>
  bool operator()(const T* Si, const T* Sj, T* r) const {
    using M3 = Eigen::Matrix<T, 3, 3>;
    using V3 = Eigen::Matrix<T, 3, 1>;
    M3 Ri, Rj;
    ceres::AngleAxisToRotationMatrix(Si, ceres::ColumnMajorAdapter3x3(Ri.data()));
    ceres::AngleAxisToRotationMatrix(Sj, ceres::ColumnMajorAdapter3x3(Rj.data()));
    const V3 ti(Si[3], Si[4], Si[5]), tj(Sj[3], Sj[4], Sj[5]);
    // S = S_iw * S_jw^-1 (camera j -> camera i), then E = S_ij_meas^-1 * S.
    const T s = exp(Si[6] - Sj[6]);
    const M3 R = Ri * Rj.transpose();
    const V3 t = ti - s * (R * tj);
    const M3 Rm = S_ij.R.cast<T>();
    const V3 tm = S_ij.t.cast<T>();
    const M3 Re = Rm.transpose() * R;
    const V3 te = Rm.transpose() * (t - tm) / T(S_ij.s);
    T aa[3];
    ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(Re.data()), aa);
    for (int k = 0; k < 3; ++k) {
      r[k] = aa[k];
      r[3 + k] = te[k];
    }
    r[6] = Si[6] - Sj[6] - T(std::log(S_ij.s));
    return true;
  }
  Sim3 S_ij;
};

}  // namespace

void OptimizePoseGraph(std::vector<Sim3>* S_iw, const std::vector<bool>& active,
                       const std::vector<PoseGraphEdge>& edges, const std::vector<int>& fixed, int iterations) {
  std::vector<std::array<double, 7>> p(S_iw->size());
  for (size_t k = 0; k < S_iw->size(); ++k) Sim3ToParams((*S_iw)[k], p[k].data());
  ceres::Problem problem;
  for (const auto& e : edges) {
    if (!active[static_cast<size_t>(e.i)] || !active[static_cast<size_t>(e.j)]) continue;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PoseGraphError, 7, 7, 7>(new PoseGraphError(e.S_ij)),
                             nullptr, p[static_cast<size_t>(e.i)].data(), p[static_cast<size_t>(e.j)].data());
  }
  for (int f : fixed)
    if (problem.HasParameterBlock(p[static_cast<size_t>(f)].data()))
      problem.SetParameterBlockConstant(p[static_cast<size_t>(f)].data());
  ceres::Solver::Options o = BaOptions(iterations);
  o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  ceres::Solver::Summary summary;
  ceres::Solve(o, &problem, &summary);
  for (size_t k = 0; k < S_iw->size(); ++k)
    if (active[k]) (*S_iw)[k] = Sim3FromParams(p[k].data());
}

}  // namespace unav::localization
