#include "unav_common/sim3.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/SVD>

namespace unav::common {

const char* to_string(UmeyamaStatus status) {
  switch (status) {
    case UmeyamaStatus::kOk:
      return "ok";
    case UmeyamaStatus::kSizeMismatch:
      return "size mismatch";
    case UmeyamaStatus::kTooFewPoints:
      return "too few points";
    case UmeyamaStatus::kNoSpread:
      return "source points have no spread";
    case UmeyamaStatus::kCollinear:
      return "points are collinear";
    case UmeyamaStatus::kBadScale:
      return "scale is not finite and positive";
  }
  return "unknown";
}

std::string UmeyamaResult::message() const {
  std::string m = to_string(status);
  if (status == UmeyamaStatus::kNoSpread) m += " (variance " + std::to_string(source_variance) + " m^2)";
  if (status == UmeyamaStatus::kCollinear)
    m += " (singular values " + std::to_string(singular_values(0)) + ", " + std::to_string(singular_values(1)) + ")";
  if (status == UmeyamaStatus::kBadScale) m += " (s = " + std::to_string(S.s) + ")";
  return m;
}

UmeyamaResult Umeyama(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to, const UmeyamaOptions& options) {
  UmeyamaResult out;
  if (from.cols() != to.cols()) {
    out.status = UmeyamaStatus::kSizeMismatch;
    return out;
  }
  if (from.cols() < options.min_points || from.cols() == 0) {
    out.status = UmeyamaStatus::kTooFewPoints;
    return out;
  }
  // The estimate is Eigen's (Eigen::umeyama: the same closed form, one SVD of the 3x3
  // cross-covariance with the reflection fix): the rotation of its rigid fit, then the scale and
  // translation of Umeyama's eq. (41)-(42) from that rotation. The diagnostics below (source
  // variance, singular values) are ours: Eigen has no rejection rules.
  const double n = static_cast<double>(from.cols());
  const Eigen::Vector3d mean_from = from.rowwise().mean();
  const Eigen::Vector3d mean_to = to.rowwise().mean();
  const Eigen::Matrix3Xd from_c = from.colwise() - mean_from;
  const double var_from = from_c.squaredNorm() / n;
  const Eigen::Matrix3d cov = (to.colwise() - mean_to) * from_c.transpose() / n;
  const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::Matrix3d>(cov).singularValues();
  Sim3& S = out.S;
  S.R = Eigen::umeyama(from, to, /*with_scaling=*/false).topLeftCorner<3, 3>();
  // trace(diag(sv) D), D = diag(1, 1, sign(det U det V)) = diag(1, 1, sign(det cov)).
  const double trace_sv_d = sv(0) + sv(1) + (cov.determinant() < 0.0 ? -sv(2) : sv(2));
  S.s = options.with_scale ? trace_sv_d / var_from : 1.0;
  S.t = mean_to - S.s * S.R * mean_from;
  out.source_variance = var_from;
  out.singular_values = sv;
  if (!(var_from > options.min_source_variance)) {
    out.status = UmeyamaStatus::kNoSpread;
  } else if (!(sv(1) > options.collinear_tolerance * std::max(1.0, sv(0)))) {
    out.status = UmeyamaStatus::kCollinear;
  } else if (!(std::isfinite(S.s) && S.s > 0)) {
    out.status = UmeyamaStatus::kBadScale;
  }
  return out;
}

}  // namespace unav::common
