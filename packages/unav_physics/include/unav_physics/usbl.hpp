// USBL positioning as a real system does it: a transceiver at a fixed point of the world (a
// surface vessel's pole or a seabed station) interrogates a transponder on the vehicle; the ping
// travels to the transponder at the speed of sound, which replies after a fixed turnaround; the
// transceiver times the round trip and measures the reply's direction of arrival (azimuth and
// elevation in its own axes). So a fix:
//   - is of the transponder where it was when the ping reached it (t1: solved each physics step
//     and interpolated within the step, so the acoustic path is exact to the physics' motion),
//   - arrives t2 = t1 + turnaround + |p1 - p_tx| / c after the ping (a 500 m slant range: 0.67 s),
//   - limits the rate: the next ping waits for the reply (or its timeout),
//   - measures range = c_assumed (t2 - t0 - turnaround) / 2 + noise (a wrong sound-speed setting
//     scales every range), angles + Gaussian noise, with multipath outliers (range off by up to
//     outlier_range_m) and dropouts whose probability grows as (range / max_range)^2; beyond
//     max_range_m no reply comes: the interrogation times out (a fix with valid = false).
// The transceiver may instead be carried by another vehicle (transceiver_vehicle: a vehicle of
// the scenario, e.g. a follower tracking its leader's transponder): transceiver_position and
// transceiver_rpy_deg are then its mount in that vehicle's body (FRD), set_carrier_pose() gives
// the carrier's pose every physics step, the ping leaves from where the transceiver was at t0,
// the reply is received where it is when the reply reaches it (solved each step, interpolated),
// and the direction of arrival is measured in its axes then.
// Deterministic under the seed. DDS-free; the physics server publishes the fixes (usbl/fix).
#pragma once

#include <cstdint>
#include <random>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "unav_common/config.hpp"

namespace unav::physics {

struct UsblParams {
  bool enabled = false;
  double rate_hz = 1.0;  ///< interrogations per second at most (the next one waits for the reply)
  /// "" = fixed in the world; else the vehicle carrying the transceiver (the physics server's
  /// namespace name for its primary vehicle, a fleet entry's name)
  std::string transceiver_vehicle;
  Eigen::Vector3d transceiver_position{0.0, 0.0, 1.0};  ///< world NED [m] (1 m under a vessel); or on the carrier, FRD
  Eigen::Vector3d transceiver_rpy_deg{0.0, 0.0, 0.0};   ///< its axes in the world (x fwd, y right, z down) or carrier
  Eigen::Vector3d transponder_xyz_m{0.0, 0.0, -0.2};    ///< on the vehicle, body FRD [m]
  double sound_speed_mps = 0.0;                         ///< the water's; 0 = the world's water (1500 without one)
  double assumed_sound_speed_mps = 0.0;                 ///< the transceiver's setting; 0 = the water's
  double turnaround_s = 0.1;                            ///< transponder reply delay (known to the transceiver)
  double range_stddev_m = 0.1;                          ///< white noise on the slant range
  double angle_stddev_deg = 1.0;                        ///< white noise on azimuth and elevation each
  double max_range_m = 1000.0;                          ///< no reply beyond
  double dropout_at_max_range = 0.3;                    ///< probability of no reply at max_range_m, ~ range^2
  double outlier_probability = 0.01;                    ///< a multipath reply
  double outlier_range_m = 5.0;                         ///< its range error, uniform in [-, +]

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("enabled", &enabled).Doc("interrogate the vehicle's transponder"));
    a->Visit(Field("transceiver_vehicle", &transceiver_vehicle).Doc("carrier of the transceiver; empty = fixed"));
    a->Visit(Field("rate", &rate_hz).Above(0.0).Max(50.0).Unit("Hz").Doc("interrogations per second at most"));
    a->Visit(Field("transceiver_position", &transceiver_position).Range(-1e5, 1e5).Unit("m").Doc("world NED"));
    a->Visit(Field("transceiver_rpy_deg", &transceiver_rpy_deg).Range(-360.0, 360.0).Unit("deg").Doc("its axes"));
    a->Visit(Field("transponder_xyz_m", &transponder_xyz_m).Range(-10.0, 10.0).Unit("m").Doc("on the vehicle, FRD"));
    a->Visit(Field("sound_speed_mps", &sound_speed_mps)
                 .Range(0.0, 1700.0)
                 .Unit("m/s")
                 .Doc("the water's; 0 = the world's water (Mackenzie at the transceiver), 1500 without one"));
    a->Visit(Field("assumed_sound_speed_mps", &assumed_sound_speed_mps)
                 .Range(0.0, 1700.0)
                 .Unit("m/s")
                 .Doc("the transceiver's setting; 0 = the water's"));
    a->Visit(Field("turnaround_s", &turnaround_s).Range(0.0, 10.0).Unit("s").Doc("transponder reply delay"));
    a->Visit(Field("range_stddev_m", &range_stddev_m).Range(0.0, 100.0).Unit("m"));
    a->Visit(Field("angle_stddev_deg", &angle_stddev_deg).Range(0.0, 45.0).Unit("deg").Doc("azimuth, elevation"));
    a->Visit(Field("max_range_m", &max_range_m).Above(0.0).Max(1e5).Unit("m").Doc("no reply beyond"));
    a->Visit(Field("dropout_at_max_range", &dropout_at_max_range).Range(0.0, 1.0).Doc("~ (range / max)^2"));
    a->Visit(Field("outlier_probability", &outlier_probability).Range(0.0, 1.0).Doc("multipath replies"));
    a->Visit(Field("outlier_range_m", &outlier_range_m).Range(0.0, 1000.0).Unit("m").Doc("their range error"));
  }
};

struct UsblReading {
  bool valid = false;       ///< a reply came back (false: no reply, the interrogation timed out)
  double stamp = 0.0;       ///< s, when the reply arrived (or the timeout)
  double ping_stamp = 0.0;  ///< s, when the interrogation was sent
  std::uint64_t seq = 0;
  double range_m = 0.0;                                 ///< measured slant range
  double azimuth_rad = 0.0;                             ///< atan2(y, x) of the reply's arrival, transceiver axes
  double elevation_rad = 0.0;                           ///< asin(z / r): > 0 below the transceiver's x-y plane
  Eigen::Vector3d p_X = Eigen::Vector3d::Zero();        ///< the fix in transceiver axes
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();        ///< the fix in the world (NED; the carrier's true pose)
  Eigen::Vector3d truth_p_W = Eigen::Vector3d::Zero();  ///< the transponder when the ping reached it
  double truth_range_m = 0.0;                           ///< |truth_p_W - transceiver|
  bool outlier = false;                                 ///< a multipath reply (ground truth)
};

/// Covariance of a fix in transceiver axes from the range and angle noise (first order).
Eigen::Matrix3d usbl_fix_covariance(const UsblParams& p, const UsblReading& r);

/// The transceiver's state machine; step() it at every physics step with the transponder's
/// world position.
class Usbl {
 public:
  Usbl() = default;
  Usbl(const UsblParams& params, std::uint64_t seed);
  /// Advances to time t with the transponder at p_W. Returns true when a new reading is out.
  bool step(double t, const Eigen::Vector3d& p_W);
  /// A carried transceiver (params.transceiver_vehicle): the carrier's body pose in the world now,
  /// before each step() (no interrogation before the first). Ignored for a fixed transceiver. Run
  /// paths with one vehicle refuse a carried transceiver (physics::require_fixed_usbl).
  void set_carrier_pose(const Eigen::Isometry3d& X_WB);
  bool carried() const { return !p_.transceiver_vehicle.empty(); }
  const UsblReading& reading() const { return reading_; }
  const UsblParams& params() const { return p_; }

 private:
  enum class Phase { kIdle, kOutbound, kInbound, kTimeout };
  void finish();
  UsblParams p_;
  Eigen::Matrix3d R_WX_ = Eigen::Matrix3d::Identity();                               ///< the transceiver's axes now
  Eigen::Vector3d x_W_ = Eigen::Vector3d::Zero();                                    ///< the transceiver now
  Eigen::Matrix3d R_BX_ = Eigen::Matrix3d::Identity();                               ///< carried: its mount
  Eigen::Vector3d x0_ = Eigen::Vector3d::Zero();                                     ///< where the ping left
  Eigen::Vector3d x2_ = Eigen::Vector3d::Zero(), prev_x_ = Eigen::Vector3d::Zero();  ///< carried: reception
  double t1_ = 0.0;
  bool carrier_set_ = false;
  std::mt19937_64 gen_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  Phase phase_ = Phase::kIdle;
  double next_ping_ = 0.0, t0_ = 0.0, t_reply_ = 0.0;
  double prev_t_ = 0.0, prev_gap_ = 0.0;
  Eigen::Vector3d prev_p_ = Eigen::Vector3d::Zero(), p1_ = Eigen::Vector3d::Zero();
  bool drop_ = false;
  UsblReading reading_;
};

}  // namespace unav::physics
