// Waypoint follower (see waypoint_follower.hpp).
#include "unav_control/waypoint_follower.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace unav::control {

bool WaypointFollowerOptions::IsValid(std::string* msg) const {
  std::ostringstream os;
  if (!(std::isfinite(acceptance_radius) && acceptance_radius > 0.0)) {
    os << "acceptance_radius must be finite and > 0 m (got " << acceptance_radius << ")";
  } else if (!(std::isfinite(min_heading_segment) && min_heading_segment >= 0.0)) {
    os << "min_heading_segment must be finite and >= 0 m (got " << min_heading_segment << ")";
  }
  if (os.tellp() == 0) return true;
  if (msg != nullptr) *msg = os.str();
  return false;
}

WaypointFollower::WaypointFollower(const WaypointFollowerOptions& options) : options_(options) {
  std::string msg;
  if (!options.IsValid(&msg)) throw physics::ConfigError("waypoint follower options: " + msg);
}

bool WaypointFollower::SetPath(const std::vector<PoseSetpoint>& path, std::string* msg) {
  auto reject = [&](const std::string& m) {
    if (msg != nullptr) *msg = m;
    return false;
  };
  if (path.empty()) return reject("path is empty");
  for (std::size_t i = 0; i < path.size(); ++i) {
    const auto& w = path[i];
    if (!w.p_W.allFinite() || !w.q_WB.coeffs().allFinite() || std::abs(w.q_WB.norm() - 1.0) > 1e-3) {
      std::ostringstream os;
      os << "path[" << i << "] is not a finite pose with a unit quaternion (p = " << w.p_W.transpose()
         << ", q xyzw = " << w.q_WB.coeffs().transpose() << ")";
      return reject(os.str());
    }
  }
  path_ = path;
  for (auto& w : path_) w.q_WB.normalize();
  const int n = static_cast<int>(path_.size());
  cumulative_.assign(path_.size(), 0.0);
  yaw_.assign(path_.size(), 0.0);
  for (int i = 1; i < n; ++i) cumulative_[i] = cumulative_[i - 1] + (path_[i].p_W - path_[i - 1].p_W).norm();
  // Path-direction yaw: heading of the segment into each waypoint; the first takes the first
  // segment's; near-vertical segments keep the previous heading.
  double yaw = physics::roll_pitch_yaw(path_[0].q_WB).z();
  bool have = false;
  for (int i = 1; i < n; ++i) {
    const Eigen::Vector2d d = (path_[i].p_W - path_[i - 1].p_W).head<2>();
    if (d.norm() >= std::max(options_.min_heading_segment, 1e-9)) {
      yaw = std::atan2(d.y(), d.x());
      if (!have) yaw_[0] = yaw;
      have = true;
    }
    yaw_[i] = yaw;
  }
  if (!have) yaw_.assign(path_.size(), yaw);
  target_ = 0;
  finished_ = false;
  return true;
}

PoseSetpoint WaypointFollower::SetpointFor(int index) const {
  const PoseSetpoint& w = path_[static_cast<std::size_t>(index)];
  if (options_.yaw_mode == YawMode::kWaypoint) return w;
  return PoseSetpoint::FromPositionYaw(w.p_W, yaw_[static_cast<std::size_t>(index)]);
}

WaypointUpdate WaypointFollower::Update(const Eigen::Vector3d& p_W) {
  WaypointUpdate u;
  if (path_.empty()) {
    u.setpoint.p_W = p_W.allFinite() ? p_W : Eigen::Vector3d::Zero();
    u.finished = true;
    u.progress = 1.0;
    return u;
  }
  const int n = static_cast<int>(path_.size());
  if (p_W.allFinite()) {
    while (!finished_ && (path_[static_cast<std::size_t>(target_)].p_W - p_W).norm() <= options_.acceptance_radius) {
      if (target_ == n - 1) {
        finished_ = true;
      } else {
        ++target_;
      }
    }
  }
  u.target_index = target_;
  u.finished = finished_;
  u.setpoint = SetpointFor(target_);
  u.distance = p_W.allFinite() ? (path_[static_cast<std::size_t>(target_)].p_W - p_W).norm() : 0.0;
  const double total = cumulative_.back();
  if (finished_ || total <= 0.0) {
    u.progress = finished_ ? 1.0 : 0.0;
  } else if (target_ == 0) {
    u.progress = 0.0;
  } else {
    // Covered length: up to the previous waypoint plus the projection onto the current segment.
    const Eigen::Vector3d a = path_[static_cast<std::size_t>(target_ - 1)].p_W;
    const Eigen::Vector3d seg = path_[static_cast<std::size_t>(target_)].p_W - a;
    const double len = seg.norm();
    const double along = (len > 0.0 && p_W.allFinite()) ? std::clamp((p_W - a).dot(seg) / len, 0.0, len) : 0.0;
    u.progress = std::clamp((cumulative_[static_cast<std::size_t>(target_ - 1)] + along) / total, 0.0, 1.0);
  }
  return u;
}

std::vector<PoseSetpoint> path_above(const std::vector<Eigen::Vector3d>& points_W, double height) {
  std::vector<PoseSetpoint> out;
  double yaw = 0.0;
  for (std::size_t i = 0; i < points_W.size(); ++i) {
    const std::size_t j = i + 1 < points_W.size() ? i + 1 : i;
    const std::size_t k = i + 1 < points_W.size() ? i : (i > 0 ? i - 1 : i);
    const Eigen::Vector2d d = (points_W[j] - points_W[k]).head<2>();
    if (d.norm() > 1e-9) yaw = std::atan2(d.y(), d.x());
    out.push_back(PoseSetpoint::FromPositionYaw(points_W[i] - height * Eigen::Vector3d::UnitZ(), yaw));
  }
  return out;
}

}  // namespace unav::control
