// Similarity transforms Sim(3), x' = s R x + t, and the closed-form Umeyama (1991) estimate.
// Monocular maps (scale unobservable, drifting), loop corrections and trajectory alignment
// (evo's APE/RPE with Sim(3)/SE(3) alignment) all use this one type and this one function.
//
// Names stay in unav::common (no alias in `unav`): callers spell unav::common::Sim3, which keeps
// it apart from the per-package types it replaces while they migrate.
#pragma once

#include <string>

#include <Eigen/Geometry>

namespace unav::common {

struct Sim3 {
  double s = 1.0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Sim3() = default;
  Sim3(double scale, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation)
      : s(scale), R(rotation), t(translation) {}
  /// The rigid transform with scale 1.
  explicit Sim3(const Eigen::Isometry3d& T) : s(1.0), R(T.linear()), t(T.translation()) {}

  /// s * (R * x) + t.
  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const { return s * (R * x) + t; }
  /// Composition: (this * o) * x = this * (o * x).
  Sim3 operator*(const Sim3& o) const { return {s * o.s, R * o.R, s * (R * o.t) + t}; }
  Sim3 inverse() const {
    const Eigen::Matrix3d Rt = R.transpose();
    return {1.0 / s, Rt, -(Rt * t) / s};
  }
  /// R * (s * x) + t: the same map as operator* with evo's order of operations (its `align`
  /// scales the positions first); results may differ from operator* in the last bit.
  Eigen::Vector3d TransformScaleFirst(const Eigen::Vector3d& x) const { return R * (s * x) + t; }
  /// The rigid transform with the same rotation and the translation divided by the scale: the
  /// camera pose a Sim(3) world-to-camera correction stands for.
  Eigen::Isometry3d ToIsometryUnscaled() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R;
    T.translation() = t / s;
    return T;
  }
};

enum class UmeyamaStatus {
  kOk,
  kSizeMismatch,  ///< from and to have different numbers of points (nothing computed)
  kTooFewPoints,  ///< fewer than UmeyamaOptions::min_points (nothing computed)
  kNoSpread,      ///< source variance not above min_source_variance (S computed anyway)
  kCollinear,     ///< second singular value too small: rotation not unique (S computed anyway)
  kBadScale       ///< scale not finite or not positive (S computed anyway)
};
const char* to_string(UmeyamaStatus status);

struct UmeyamaOptions {
  /// false: s = 1 (SE(3) fit).
  bool with_scale = true;
  /// kTooFewPoints below this many point pairs.
  int min_points = 3;
  /// kNoSpread unless the source variance (mean squared distance to the centroid) > this [m^2].
  double min_source_variance = 1e-12;
  /// kCollinear unless sv(1) > collinear_tolerance * max(1, sv(0)), sv = singular values of the
  /// cross-covariance (descending).
  double collinear_tolerance = 1e-9;
};

struct UmeyamaResult {
  UmeyamaStatus status = UmeyamaStatus::kOk;
  /// to ~ S * from. Filled for every status but kSizeMismatch and kTooFewPoints.
  Sim3 S;
  double source_variance = 0.0;                               ///< m^2
  Eigen::Vector3d singular_values = Eigen::Vector3d::Zero();  ///< of the cross-covariance, descending
  bool ok() const { return status == UmeyamaStatus::kOk; }
  std::string message() const;
};

/// Least-squares similarity (Umeyama 1991) mapping the columns of `from` onto those of `to`.
/// With n points, centroids m_f, m_t, centred A = from - m_f, B = to - m_t:
///   var = |A|^2 / n, C = B A^T / n = U diag(sv) V^T,
///   R = U diag(1, 1, sign(det U det V)) V^T (Eigen::umeyama's rigid fit),
///   s = with_scale ? (sv0 + sv1 + sign(det C) sv2) / var : 1, t = m_t - s R m_f.
/// The status checks, in order: sizes, min_points, spread, collinearity, scale. The SLAM
/// (>= 3 points, spread, not collinear) and the evaluator (evo's rules: >= 2 points, collinear
/// accepted) each keep their own rules on top of the status and the diagnostics.
UmeyamaResult Umeyama(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to, const UmeyamaOptions& options = {});

}  // namespace unav::common
