// ROS time as nanoseconds since the epoch, with the conversions to and from
// builtin_interfaces/Time (sec, nanosec) and seconds. DDS-free: the node clock
// (unav_runtime/clock.hpp) and the cores share it.
#pragma once

#include <cmath>
#include <cstdint>

namespace unav {

/// Nanoseconds since the epoch (ROS time). An aggregate: unav::Time{ns}.
struct Time {
  int64_t ns = 0;

  double seconds() const { return static_cast<double>(ns) * 1e-9; }
  /// builtin_interfaces/Time.sec: floor(ns / 1e9) (negative times round down).
  int32_t sec() const { return static_cast<int32_t>(ns >= 0 ? ns / 1000000000 : (ns - 999999999) / 1000000000); }
  /// builtin_interfaces/Time.nanosec, in [0, 1e9).
  uint32_t nanosec() const { return static_cast<uint32_t>(ns - static_cast<int64_t>(sec()) * 1000000000); }
  static Time from_msg(int32_t sec, uint32_t nanosec) { return Time{int64_t{sec} * 1000000000 + nanosec}; }
  /// Rounded to the nearest nanosecond (std::llround(t * 1e9)).
  static Time from_seconds(double t) { return Time{static_cast<int64_t>(std::llround(t * 1e9))}; }
};

}  // namespace unav
