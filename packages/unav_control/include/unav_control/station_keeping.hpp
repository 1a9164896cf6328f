// Station keeping behind a leader from its USBL fixes: an alpha-beta tracker of the leader's
// position and velocity (world NED) from the fixes (started from its first two), with a gate that rejects outliers
// (multipath: a fix far from the prediction), and the follower's setpoint `distance_m` behind the leader along its
// course (the direction of its tracked velocity; until it moves faster than min_speed_mps, the last course, or
// `initial_course_rad`), at the leader's depth + depth_offset_m, heading along the course. Fixes come at the USBL's
// rate (~1 Hz) and are noisy (~0.3 m at 20 m): the tracker smooths them; the MPC then flies the setpoint.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "unav_control/mpc.hpp"

namespace unav::control {

struct StationKeepingOptions {
  double distance_m = 5.0;          ///< behind the leader along its course, > 0
  double depth_offset_m = 0.0;      ///< setpoint depth = the leader's + this
  double alpha = 0.25;              ///< position gain of the tracker, (0, 1]
  double beta = 0.02;               ///< velocity gain, [0, 2): beta < alpha^2 / (2 - alpha) keeps it smooth
  double gate_m = 3.0;              ///< a fix farther than this from the prediction is an outlier, > 0
  int reacquire_after = 3;          ///< consecutive outliers that restart the track (the leader moved), >= 1
  double min_speed_mps = 0.05;      ///< the course follows the velocity above this speed
  double initial_course_rad = 0.0;  ///< the course until the leader first moves
  double max_prediction_s = 2.0;    ///< Setpoint(at) predicts the leader at most this far, >= 0
  bool IsValid(std::string* msg) const;
};

class StationKeeper {
 public:
  /// Throws physics::ConfigError naming the option and its rule.
  explicit StationKeeper(const StationKeepingOptions& options = StationKeepingOptions{});

  /// A leader fix at time t [s] (non-decreasing), position in world NED. Returns false when the
  /// fix is not used: an outlier beyond the gate, a stamp before the last fix, NaN/Inf.
  bool AddFix(double t, const Eigen::Vector3d& p_W);

  /// The follower's setpoint; nullopt before the first fix. With `at` [s] after the last fix, the
  /// leader is predicted to then along its tracked velocity (at most max_prediction_s ahead): the
  /// fixes come a second apart and arrive late.
  std::optional<PoseSetpoint> Setpoint(std::optional<double> at = std::nullopt) const;

  /// The tracked leader (position at the last fix, velocity), course [rad].
  const Eigen::Vector3d& leader_position() const { return x_; }
  const Eigen::Vector3d& leader_velocity() const { return v_; }
  double course() const { return course_; }
  std::uint64_t fixes_used() const { return used_; }
  std::uint64_t fixes_rejected() const { return rejected_; }

 private:
  StationKeepingOptions o_;
  bool tracking_ = false, have_velocity_ = false;
  double t_ = 0.0;
  Eigen::Vector3d x_ = Eigen::Vector3d::Zero(), v_ = Eigen::Vector3d::Zero();
  double course_ = 0.0;
  int outliers_in_a_row_ = 0;
  std::uint64_t used_ = 0, rejected_ = 0;
};

}  // namespace unav::control
