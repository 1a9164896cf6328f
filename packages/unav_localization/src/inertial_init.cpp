#include "unav_localization/inertial_init.hpp"

#include <cmath>
#include <memory>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "unav_common/so3.hpp"

namespace unav::localization {

namespace {

// One preintegration between keyframes i and j with the map's rotations of the bodies fixed:
// parameters [tilt of gravity (2), log scale (1), v_i (3), v_j (3), gyro bias (3), accel bias (3)].
struct InertialError {
  InertialError(const ImuPreintegration& pre, const Eigen::Matrix3d& R_i, const Eigen::Matrix3d& R_j,
                const Eigen::Vector3d& p_i, const Eigen::Vector3d& p_j, const Eigen::Vector3d& o_i,
                const Eigen::Vector3d& o_j, double gravity)
      : pre_(pre), R_i_(R_i), R_j_(R_j), p_i_(p_i), p_j_(p_j), o_i_(o_i), o_j_(o_j), g_(gravity) {
    // sqrt information: L^T with L L^T = covariance^-1 (a tiny floor keeps it invertible).
    const Matrix9d info = (pre.covariance() + 1e-12 * Matrix9d::Identity()).inverse();
    sqrt_info_ = Eigen::LLT<Matrix9d>(info).matrixU();
  }

  template <typename T>
  bool operator()(const T* tilt, const T* log_s, const T* v_i, const T* v_j, const T* bg, const T* ba,
                  T* residual) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    using M3 = Eigen::Matrix<T, 3, 3>;
    const T dt = T(pre_.dt());
    // Gravity in the map's world: Exp([tilt, 0]) (0, 0, g).
    const T aa[3] = {tilt[0], tilt[1], T(0)};
    T R_wg_data[9];
    ceres::AngleAxisToRotationMatrix(aa, ceres::ColumnMajorAdapter3x3(R_wg_data));
    const Eigen::Map<const M3> R_wg(R_wg_data);
    const V3 g = R_wg * V3(T(0), T(0), T(g_));
    const T s = exp(log_s[0]);
    const Eigen::Map<const V3> vi(v_i), vj(v_j), dbg(bg), dba(ba);
    const V3 dbg0 = dbg - pre_.bias().gyro.cast<T>();
    const V3 dba0 = dba - pre_.bias().accel.cast<T>();
    // Body positions: the scaled camera centre plus the (metric) camera-to-body offset.
    const V3 pi = s * p_i_.cast<T>() + o_i_.cast<T>();
    const V3 pj = s * p_j_.cast<T>() + o_j_.cast<T>();
    const M3 Rit = R_i_.transpose().cast<T>();
    // Rotation: Log((dR Exp(J dbg))^T R_i^T R_j).
    const V3 corr = pre_.dR_dbg().cast<T>() * dbg0;
    T Rc_data[9];
    ceres::AngleAxisToRotationMatrix(corr.data(), ceres::ColumnMajorAdapter3x3(Rc_data));
    const Eigen::Map<const M3> Rc(Rc_data);
    const M3 E = (pre_.delta_R().cast<T>() * Rc).transpose() * Rit * R_j_.cast<T>();
    V3 r_R;
    ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(E.data()), r_R.data());
    const V3 dv = pre_.delta_v().cast<T>() + pre_.dv_dbg().cast<T>() * dbg0 + pre_.dv_dba().cast<T>() * dba0;
    const V3 dp = pre_.delta_p().cast<T>() + pre_.dp_dbg().cast<T>() * dbg0 + pre_.dp_dba().cast<T>() * dba0;
    const V3 r_v = Rit * (vj - vi - g * dt) - dv;
    const V3 r_p = Rit * (pj - pi - vi * dt - T(0.5) * g * dt * dt) - dp;
    Eigen::Matrix<T, 9, 1> r;
    r << r_R, r_v, r_p;
    Eigen::Map<Eigen::Matrix<T, 9, 1>> out(residual);
    out = sqrt_info_.cast<T>() * r;
    return true;
  }

  const ImuPreintegration& pre_;
  Eigen::Matrix3d R_i_, R_j_;
  Eigen::Vector3d p_i_, p_j_, o_i_, o_j_;
  double g_;
  Matrix9d sqrt_info_;
};

struct BiasPrior {
  explicit BiasPrior(double std) : w_(1.0 / std) {}
  template <typename T>
  bool operator()(const T* b, T* r) const {
    for (int k = 0; k < 3; ++k) r[k] = T(w_) * b[k];
    return true;
  }
  double w_;
};

}  // namespace

InertialInitResult InertialOnlyInit(const std::vector<Eigen::Isometry3d>& keyframes,
                                    const std::vector<ImuPreintegration>& preintegrations,
                                    const Eigen::Isometry3d& T_bc, const InertialInitOptions& options) {
  InertialInitResult out;
  const std::size_t n = keyframes.size();
  if (n < 3 || preintegrations.size() + 1 != n) {
    out.message = "needs at least 3 keyframes and one preintegration between each two (" + std::to_string(n) +
                  " keyframes, " + std::to_string(preintegrations.size()) + " preintegrations)";
    return out;
  }
  // Body rotation and camera-to-body offset of each keyframe in the map's world.
  const Eigen::Isometry3d T_cb = T_bc.inverse();
  std::vector<Eigen::Matrix3d> R(n);
  std::vector<Eigen::Vector3d> p(n), o(n);
  for (std::size_t k = 0; k < n; ++k) {
    R[k] = keyframes[k].linear() * T_cb.linear();
    p[k] = keyframes[k].translation();
    o[k] = keyframes[k].linear() * T_cb.translation();
  }
  // Initial gravity: the accelerometer's mean specific force points against it (ORB-SLAM3).
  Eigen::Vector3d dir = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k + 1 < n; ++k) dir -= R[k] * preintegrations[k].delta_v();
  if (dir.norm() < 1e-9) {
    out.message = "the accelerometer integrates to zero: no gravity to align to";
    return out;
  }
  dir.normalize();
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d axis = z.cross(dir);
  const double angle = std::atan2(axis.norm(), z.dot(dir));
  double tilt[2] = {0.0, 0.0};
  if (axis.norm() > 1e-12) {
    tilt[0] = axis.x() / axis.norm() * angle;
    tilt[1] = axis.y() / axis.norm() * angle;
  } else if (z.dot(dir) < 0.0) {
    tilt[0] = M_PI;  // gravity along -z of the map: half a turn about x
  }
  double log_s = 0.0;
  std::vector<Eigen::Vector3d> v(n, Eigen::Vector3d::Zero());
  for (std::size_t k = 0; k + 1 < n; ++k) v[k] = (p[k + 1] - p[k]) / preintegrations[k].dt();
  v[n - 1] = v[n - 2];
  Eigen::Vector3d bg = Eigen::Vector3d::Zero(), ba = Eigen::Vector3d::Zero();

  ceres::Problem problem;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    auto* cost = new ceres::AutoDiffCostFunction<InertialError, 9, 2, 1, 3, 3, 3, 3>(
        new InertialError(preintegrations[k], R[k], R[k + 1], p[k], p[k + 1], o[k], o[k + 1], options.gravity));
    problem.AddResidualBlock(cost, nullptr, tilt, &log_s, v[k].data(), v[k + 1].data(), bg.data(), ba.data());
  }
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<BiasPrior, 3, 3>(new BiasPrior(options.gyro_bias_prior_std)),
                           nullptr, bg.data());
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<BiasPrior, 3, 3>(new BiasPrior(options.accel_bias_prior_std)), nullptr,
      ba.data());
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.logging_type = ceres::SILENT;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);

  out.iterations = static_cast<int>(summary.iterations.size());
  out.final_cost = summary.final_cost;
  out.scale = std::exp(log_s);
  out.R_wg = common::ExpSO3(Eigen::Vector3d(tilt[0], tilt[1], 0.0));
  out.gravity_w = out.R_wg * Eigen::Vector3d(0.0, 0.0, options.gravity);
  out.bias.gyro = bg;
  out.bias.accel = ba;
  out.velocities = v;
  if (!summary.IsSolutionUsable() || !std::isfinite(out.scale)) {
    out.message = "the optimisation failed: " + summary.message;
  } else if (out.scale < options.min_scale) {
    out.message = "scale " + std::to_string(out.scale) + " below " + std::to_string(options.min_scale) +
                  ": the motion did not excite the accelerometer";
  } else {
    out.ok = true;
  }
  return out;
}

}  // namespace unav::localization
