// Message <-> Eigen conversions, in one place (tf2_eigen's toMsg/fromMsg): a stamp, point,
// quaternion, pose, transform, twist or wrench crosses the message boundary through these
// functions, never field by field in a node.
//
//   const Eigen::Isometry3d X_WB = unav::from_msg(odom.pose().pose());
//   out.pose().pose() = unav::to_msg(X_WB);
//   const double t = unav::seconds(msg.header());
//
// Frames are not checked here: the caller names them (X_WB: body B in world W, NED/FRD).
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "builtin_interfaces/msg/time.hpp"
#include "geometry_msgs/msg/point.hpp"
#include "geometry_msgs/msg/pose.hpp"
#include "geometry_msgs/msg/quaternion.hpp"
#include "geometry_msgs/msg/transform.hpp"
#include "geometry_msgs/msg/transform_stamped.hpp"
#include "geometry_msgs/msg/twist.hpp"
#include "geometry_msgs/msg/vector3.hpp"
#include "geometry_msgs/msg/wrench.hpp"
#include "std_msgs/msg/header.hpp"
#include "unav_runtime/clock.hpp"

namespace unav {

using Vector6d = Eigen::Matrix<double, 6, 1>;

// --- time -------------------------------------------------------------------------------------

inline Time from_msg(const builtin_interfaces::msg::Time& m) { return Time::from_msg(m.sec(), m.nanosec()); }
inline builtin_interfaces::msg::Time to_msg(const Time& t) {
  builtin_interfaces::msg::Time m;
  m.sec(t.sec());
  m.nanosec(t.nanosec());
  return m;
}
/// Stamp of a header, s.
inline double seconds(const std_msgs::msg::Header& h) { return from_msg(h.stamp()).seconds(); }
/// Stamp of a header, ns.
inline int64_t nanoseconds(const std_msgs::msg::Header& h) { return from_msg(h.stamp()).ns; }
/// A header with the stamp t [s] and the frame.
inline std_msgs::msg::Header make_header(double t_s, const std::string& frame_id) {
  std_msgs::msg::Header h;
  h.stamp() = to_msg(Time::from_seconds(t_s));
  h.frame_id(frame_id);
  return h;
}

// --- vectors, points, rotations ------------------------------------------------------------------

inline Eigen::Vector3d from_msg(const geometry_msgs::msg::Vector3& m) { return {m.x(), m.y(), m.z()}; }
inline Eigen::Vector3d from_msg(const geometry_msgs::msg::Point& m) { return {m.x(), m.y(), m.z()}; }
/// Quaternion as sent (not normalised: a consumer that needs unit quaternions checks them).
inline Eigen::Quaterniond from_msg(const geometry_msgs::msg::Quaternion& m) {
  return Eigen::Quaterniond(m.w(), m.x(), m.y(), m.z());
}

inline geometry_msgs::msg::Vector3 to_vector3_msg(const Eigen::Vector3d& v) {
  geometry_msgs::msg::Vector3 m;
  m.x(v.x());
  m.y(v.y());
  m.z(v.z());
  return m;
}
inline geometry_msgs::msg::Point to_point_msg(const Eigen::Vector3d& p) {
  geometry_msgs::msg::Point m;
  m.x(p.x());
  m.y(p.y());
  m.z(p.z());
  return m;
}
inline geometry_msgs::msg::Quaternion to_msg(const Eigen::Quaterniond& q) {
  geometry_msgs::msg::Quaternion m;
  m.x(q.x());
  m.y(q.y());
  m.z(q.z());
  m.w(q.w());
  return m;
}

// --- poses and transforms ----------------------------------------------------------------------

/// Pose -> rigid transform. The quaternion is normalised (a pose must be a rotation).
inline Eigen::Isometry3d from_msg(const geometry_msgs::msg::Pose& m) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = from_msg(m.orientation()).normalized().toRotationMatrix();
  X.translation() = from_msg(m.position());
  return X;
}
inline Eigen::Isometry3d from_msg(const geometry_msgs::msg::Transform& m) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = from_msg(m.rotation()).normalized().toRotationMatrix();
  X.translation() = from_msg(m.translation());
  return X;
}
inline geometry_msgs::msg::Pose to_msg(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  geometry_msgs::msg::Pose m;
  m.position() = to_point_msg(p);
  m.orientation() = to_msg(q);
  return m;
}
inline geometry_msgs::msg::Pose to_msg(const Eigen::Isometry3d& X) {
  return to_msg(Eigen::Vector3d(X.translation()), Eigen::Quaterniond(X.linear()));
}
inline geometry_msgs::msg::Transform to_transform_msg(const Eigen::Isometry3d& X) {
  geometry_msgs::msg::Transform m;
  m.translation() = to_vector3_msg(X.translation());
  m.rotation() = to_msg(Eigen::Quaterniond(X.linear()));
  return m;
}
/// TransformStamped of child frame C in parent frame P (X_PC), stamped t [s].
inline geometry_msgs::msg::TransformStamped to_transform_stamped(const Eigen::Isometry3d& X_PC, double t_s,
                                                                 const std::string& parent, const std::string& child) {
  geometry_msgs::msg::TransformStamped m;
  m.header() = make_header(t_s, parent);
  m.child_frame_id(child);
  m.transform() = to_transform_msg(X_PC);
  return m;
}

// --- twists and wrenches ([linear; angular], [force; torque]) -----------------------------------

inline Vector6d from_msg(const geometry_msgs::msg::Twist& m) {
  Vector6d v;
  v << from_msg(m.linear()), from_msg(m.angular());
  return v;
}
inline Vector6d from_msg(const geometry_msgs::msg::Wrench& m) {
  Vector6d v;
  v << from_msg(m.force()), from_msg(m.torque());
  return v;
}
inline geometry_msgs::msg::Twist to_twist_msg(const Vector6d& v) {
  geometry_msgs::msg::Twist m;
  m.linear() = to_vector3_msg(v.head<3>());
  m.angular() = to_vector3_msg(v.tail<3>());
  return m;
}
inline geometry_msgs::msg::Wrench to_wrench_msg(const Vector6d& w) {
  geometry_msgs::msg::Wrench m;
  m.force() = to_vector3_msg(w.head<3>());
  m.torque() = to_vector3_msg(w.tail<3>());
  return m;
}

}  // namespace unav
