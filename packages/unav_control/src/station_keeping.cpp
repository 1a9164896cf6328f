#include "unav_control/station_keeping.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "unav_physics/types.hpp"

namespace unav::control {

bool StationKeepingOptions::IsValid(std::string* msg) const {
  auto fail = [&](const std::string& m) {
    if (msg) *msg = m;
    return false;
  };
  if (!(distance_m > 0.0 && std::isfinite(distance_m))) return fail("distance_m must be > 0");
  if (!std::isfinite(depth_offset_m)) return fail("depth_offset_m must be finite");
  if (!(alpha > 0.0 && alpha <= 1.0)) return fail("alpha must be in (0, 1]");
  if (!(beta >= 0.0 && beta < 2.0)) return fail("beta must be in [0, 2)");
  if (!(gate_m > 0.0 && std::isfinite(gate_m))) return fail("gate_m must be > 0");
  if (reacquire_after < 1) return fail("reacquire_after must be >= 1");
  if (!(min_speed_mps >= 0.0 && std::isfinite(min_speed_mps))) return fail("min_speed_mps must be >= 0");
  if (!std::isfinite(initial_course_rad)) return fail("initial_course_rad must be finite");
  if (!(max_prediction_s >= 0.0 && std::isfinite(max_prediction_s))) return fail("max_prediction_s must be >= 0");
  return true;
}

StationKeeper::StationKeeper(const StationKeepingOptions& options) : o_(options), course_(options.initial_course_rad) {
  std::string msg;
  if (!o_.IsValid(&msg)) throw physics::ConfigError("station keeping: " + msg);
}

bool StationKeeper::AddFix(double t, const Eigen::Vector3d& p_W) {
  if (!p_W.allFinite() || !std::isfinite(t) || (tracking_ && t < t_)) {
    ++rejected_;
    return false;
  }
  if (!tracking_) {
    tracking_ = true;
    have_velocity_ = false;
    t_ = t;
    x_ = p_W;
    v_.setZero();
    outliers_in_a_row_ = 0;
    ++used_;
    return true;
  }
  const double dt = t - t_;
  const Eigen::Vector3d predicted = x_ + v_ * dt;  // v_ is zero until the second fix
  const Eigen::Vector3d r = p_W - predicted;
  if (r.norm() > o_.gate_m) {
    ++rejected_;
    // A leader that really moved (not one multipath echo): start the track again at it.
    if (++outliers_in_a_row_ >= o_.reacquire_after) {
      tracking_ = false;
      return AddFix(t, p_W);
    }
    return false;
  }
  outliers_in_a_row_ = 0;
  if (!have_velocity_ && dt > 0.0) {
    // Two-point start: the velocity between the first two fixes (no lag on a steady leader).
    have_velocity_ = true;
    v_ = r / dt;
    x_ = p_W;
  } else {
    x_ = predicted + o_.alpha * r;
    if (dt > 0.0) v_ += (o_.beta / dt) * r;
  }
  t_ = t;
  if (v_.head<2>().norm() > o_.min_speed_mps) course_ = std::atan2(v_.y(), v_.x());
  ++used_;
  return true;
}

std::optional<PoseSetpoint> StationKeeper::Setpoint(std::optional<double> at) const {
  if (!tracking_) return std::nullopt;
  const double ahead = at ? std::clamp(*at - t_, 0.0, o_.max_prediction_s) : 0.0;
  const Eigen::Vector3d leader = x_ + v_ * ahead;
  Eigen::Vector3d p = leader - o_.distance_m * Eigen::Vector3d(std::cos(course_), std::sin(course_), 0.0);
  p.z() = leader.z() + o_.depth_offset_m;
  return PoseSetpoint::FromPositionYaw(p, course_);
}

}  // namespace unav::control
