// The node clock: system time, or simulated time from /clock when use_sim_time is true.
#pragma once

#include <atomic>
#include <cstdint>

#include "unav_common/time.hpp"  // unav::Time

namespace unav {

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
