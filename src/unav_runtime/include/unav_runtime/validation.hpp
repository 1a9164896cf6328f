// Checks on messages that come from the network. Anyone on the DDS domain can publish on a
// node's topics, and a diverged estimator can publish NaN: a node rejects what it cannot use
// (NaN/Inf, a quaternion that is not a rotation) and counts it, instead of flying, rendering,
// acking or recording it.
//
//   if (const std::string why = unav::odometry_problem(m); !why.empty()) {
//     rejections_.reject("ground_truth/odom", why);
//     return;
//   }
#pragma once

#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <utility>

#include "geometry_msgs/msg/pose.hpp"
#include "geometry_msgs/msg/twist.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "unav_runtime/logging.hpp"

namespace unav {

namespace detail {
inline std::string number(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}
inline std::string non_finite(const std::string& field, std::initializer_list<std::pair<const char*, double>> values) {
  for (const auto& [name, v] : values)
    if (!std::isfinite(v)) return field + "." + name + " = " + number(v) + ": must be finite";
  return "";
}
}  // namespace detail

/// A quaternion within this of unit norm is a rotation (float32 publishers round at ~1e-7;
/// anything further off is not a rotation someone meant).
inline constexpr double kUnitQuaternionTolerance = 1e-2;

/// Empty if `p` is usable; else "<field>.<member> = <value>: <rule>".
inline std::string pose_problem(const geometry_msgs::msg::Pose& p, const std::string& field = "pose") {
  const auto& t = p.position();
  const auto& q = p.orientation();
  std::string why = detail::non_finite(field + ".position", {{"x", t.x()}, {"y", t.y()}, {"z", t.z()}});
  if (why.empty())
    why = detail::non_finite(field + ".orientation", {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}});
  if (!why.empty()) return why;
  const double norm = std::sqrt(q.x() * q.x() + q.y() * q.y() + q.z() * q.z() + q.w() * q.w());
  if (std::abs(norm - 1.0) > kUnitQuaternionTolerance)
    return field + ".orientation has norm " + detail::number(norm) + ": must be a unit quaternion";
  return "";
}

inline std::string twist_problem(const geometry_msgs::msg::Twist& v, const std::string& field = "twist") {
  const auto& l = v.linear();
  const auto& a = v.angular();
  std::string why = detail::non_finite(field + ".linear", {{"x", l.x()}, {"y", l.y()}, {"z", l.z()}});
  return why.empty() ? detail::non_finite(field + ".angular", {{"x", a.x()}, {"y", a.y()}, {"z", a.z()}}) : why;
}

/// Empty if the odometry's pose and twist are usable.
inline std::string odometry_problem(const nav_msgs::msg::Odometry& m) {
  std::string why = pose_problem(m.pose().pose(), "pose.pose");
  return why.empty() ? twist_problem(m.twist().twist(), "twist.twist") : why;
}

/// Rejected input messages of one node, by topic. The first rejection on a topic is logged with
/// its reason, then the 2nd, 4th, 8th, ... with the count (a flood does not flood the log);
/// destruction logs the totals.
class RejectionCounter {
 public:
  explicit RejectionCounter(Logger logger) : logger_(std::move(logger)) {}
  RejectionCounter(const RejectionCounter&) = delete;
  RejectionCounter& operator=(const RejectionCounter&) = delete;
  ~RejectionCounter() {
    for (const auto& [topic, e] : entries_)
      logger_->warn("{} message(s) on '{}' were rejected (last: {})", e.count, topic, e.last_reason);
  }
  void reject(const std::string& topic, const std::string& reason) {
    Entry& e = entries_[topic];
    ++e.count;
    e.last_reason = reason;
    if ((e.count & (e.count - 1)) == 0)  // 1, 2, 4, 8, ...
      logger_->warn("message on '{}' rejected: {} ({} rejected on it so far)", topic, reason, e.count);
  }
  uint64_t count(const std::string& topic) const {
    auto it = entries_.find(topic);
    return it == entries_.end() ? 0 : it->second.count;
  }
  uint64_t total() const {
    uint64_t n = 0;
    for (const auto& [topic, e] : entries_) n += e.count;
    return n;
  }

 private:
  struct Entry {
    uint64_t count = 0;
    std::string last_reason;
  };
  Logger logger_;
  std::map<std::string, Entry> entries_;
};

}  // namespace unav
