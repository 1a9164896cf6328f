// The node clock: system time, or simulated time from /clock when use_sim_time is true.
#pragma once

#include <atomic>
#include <cstdint>

namespace unav {

/// Nanoseconds since the epoch (ROS time) for conversions to builtin_interfaces/Time.
struct Time {
  int64_t ns = 0;
  double seconds() const { return static_cast<double>(ns) * 1e-9; }
  int32_t sec() const { return static_cast<int32_t>(ns >= 0 ? ns / 1000000000 : (ns - 999999999) / 1000000000); }
  uint32_t nanosec() const { return static_cast<uint32_t>(ns - static_cast<int64_t>(sec()) * 1000000000); }
  static Time from_msg(int32_t sec, uint32_t nanosec) { return Time{int64_t{sec} * 1000000000 + nanosec}; }
};

class Clock {
 public:
  /// ROS time: simulated time once use_sim_time is active (0 until the first /clock message),
  /// system time otherwise.
  Time now() const;
  bool sim_time_active() const { return sim_active_; }
  void set_sim_time_active(bool active) { sim_active_ = active; }
  /// Called with every /clock message.
  void set_sim_time(Time t) { sim_ns_ = t.ns; }

 private:
  std::atomic<bool> sim_active_{false};
  std::atomic<int64_t> sim_ns_{0};
};

}  // namespace unav
