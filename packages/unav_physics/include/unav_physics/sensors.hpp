// Sensor models sampled from the physics state: each sensor has a rate, white noise and a bias
// random walk (seeded, deterministic). Outputs are plain structs with a `valid` flag and a
// timestamp; `seq` increments on every new sample so a node can publish only fresh ones.
// All sensors sit at the body origin (no lever arms yet).
#pragma once

#include <array>
#include <cstdint>
#include <random>
#include <string>

#include "unav_common/config.hpp"
#include "unav_physics/acoustic_modem.hpp"
#include "unav_physics/types.hpp"
#include "unav_physics/usbl.hpp"

namespace unav::physics {

class Seabed;

/// Per-channel noise: reading = truth + bias + N(0, noise_stddev^2); the bias starts at
/// initial_bias and walks: bias += bias_random_walk * sqrt(dt) * N(0, 1) at each sample.
struct NoiseParams {
  double noise_stddev = 0.0;      ///< unit of the reading
  double bias_random_walk = 0.0;  ///< unit of the reading per sqrt(s)
  double initial_bias = 0.0;      ///< unit of the reading

  /// The three keys at the caller's level (a sensor with one channel writes them flat).
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("noise_stddev", &noise_stddev).Doc("white noise, unit of the reading"));
    a->Visit(Field("bias_random_walk", &bias_random_walk).Doc("bias random walk, unit per sqrt(s)"));
    a->Visit(Field("initial_bias", &initial_bias).Doc("bias at t = 0"));
  }
};

/// The `enabled` and `rate` keys of every sensor (a vehicle file enables a sensor whose section it
/// gives unless it says `enabled: false`).
template <class Archive>
void VisitSensorSwitch(Archive* a, bool* enabled, double* rate_hz) {
  a->Visit(unav::common::Field("enabled", enabled).Doc("sample it"));
  a->Visit(unav::common::Field("rate", rate_hz).Unit("Hz").Doc("samples per second"));
}

struct ImuParams {
  bool enabled = false;
  double rate_hz = 200.0;
  NoiseParams accel;  ///< specific force, m/s^2
  NoiseParams gyro;   ///< angular rate, rad/s
  template <class Archive>
  void Serialize(Archive* a) {
    VisitSensorSwitch(a, &enabled, &rate_hz);
    a->Visit(unav::common::Field("accel", &accel).Doc("specific force, m/s^2"));
    a->Visit(unav::common::Field("gyro", &gyro).Doc("angular rate, rad/s"));
  }
};
struct PressureParams {
  bool enabled = false;
  double rate_hz = 50.0;
  NoiseParams pressure;  ///< Pa
  template <class Archive>
  void Serialize(Archive* a) {
    VisitSensorSwitch(a, &enabled, &rate_hz);
    pressure.Serialize(a);
  }
};
/// A bottom-tracking DVL at the body origin. beams = 4: a Janus array (Water Linked A50 /
/// Nortek DVL1000 layout: four beams beam_angle_deg off the body's down axis, at azimuths 45, 135,
/// 225, 315 deg), each a ray cast against the seabed; a beam locks when the bottom it hits is
/// min_altitude..max_altitude below the sensor (vertically) and seen within max_incidence_deg of
/// its normal; each locked beam measures the sensor's bottom-relative velocity along itself (+
/// noise per beam), and the velocity is the least-squares solution of 3 or 4 locked beams (a
/// 3-beam solution when one is lost, as real units give); fewer: invalid. Altitude: the mean
/// vertical distance of the locked beams' bottom points. beams = 0: the ideal sensor (body
/// velocity + noise per axis, altitude straight down).
struct DvlParams {
  bool enabled = false;
  double rate_hz = 10.0;
  NoiseParams velocity;             ///< m/s: per beam (beams = 4) or per axis (beams = 0)
  double min_altitude = 0.3;        ///< m; below it (or above max) a beam (or the reading) is invalid
  double max_altitude = 50.0;       ///< m
  int beams = 4;                    ///< 4 (Janus) or 0 (ideal)
  double beam_angle_deg = 22.5;     ///< off the down axis (A50: 22.5, DVL1000: 25, Pathfinder: 30)
  double max_incidence_deg = 70.0;  ///< a beam hitting the bottom more obliquely loses lock
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    VisitSensorSwitch(a, &enabled, &rate_hz);
    velocity.Serialize(a);
    a->Visit(Field("min_altitude", &min_altitude).Unit("m").Doc("bottom lock from"));
    a->Visit(Field("max_altitude", &max_altitude).Unit("m").Doc("bottom lock up to"));
    a->Visit(Field("beams", &beams).Doc("4 (Janus array) or 0 (ideal sensor)"));
    a->Visit(Field("beam_angle_deg", &beam_angle_deg).Unit("deg").Doc("off the down axis"));
    a->Visit(Field("max_incidence_deg", &max_incidence_deg).Unit("deg").Doc("steeper bottom: no lock"));
  }
};
struct AltimeterParams {
  bool enabled = false;
  double rate_hz = 10.0;
  NoiseParams range;         ///< m
  double min_range = 0.3;    ///< m
  double max_range = 100.0;  ///< m
  template <class Archive>
  void Serialize(Archive* a) {
    VisitSensorSwitch(a, &enabled, &rate_hz);
    range.Serialize(a);
    a->Visit(unav::common::Field("min_range", &min_range).Unit("m"));
    a->Visit(unav::common::Field("max_range", &max_range).Unit("m"));
  }
};
struct MagnetometerParams {
  bool enabled = false;
  double rate_hz = 50.0;
  NoiseParams field;  ///< T
  template <class Archive>
  void Serialize(Archive* a) {
    VisitSensorSwitch(a, &enabled, &rate_hz);
    field.Serialize(a);
  }
};
struct GpsParams {
  bool enabled = false;
  double rate_hz = 5.0;
  NoiseParams horizontal;  ///< m, north and east
  NoiseParams vertical;    ///< m, down
  double max_depth = 0.1;  ///< m; a fix only while the antenna is within this of the surface
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    VisitSensorSwitch(a, &enabled, &rate_hz);
    a->Visit(Field("horizontal", &horizontal).Doc("m, north and east"));
    a->Visit(Field("vertical", &vertical).Doc("m, down"));
    a->Visit(Field("max_depth", &max_depth).Unit("m").Doc("a fix only this close to the surface"));
  }
};
struct SensorSuiteParams {
  int64_t seed = 0;  ///< >= 0; each sensor draws from its own generator seeded from this
  ImuParams imu;
  PressureParams pressure;
  DvlParams dvl;
  AltimeterParams altimeter;
  MagnetometerParams magnetometer;
  GpsParams gps;
  UsblParams usbl;            ///< the transponder on the vehicle, the transceiver in the world
  AcousticModemParams modem;  ///< the vehicle's acoustic modem and the station's (carried by the node's ports)
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("seed", &seed).Min(0.0).Doc("noise seed of every sensor"));
    a->Visit(Field("imu", &imu));
    a->Visit(Field("pressure", &pressure));
    a->Visit(Field("dvl", &dvl));
    a->Visit(Field("altimeter", &altimeter));
    a->Visit(Field("magnetometer", &magnetometer));
    a->Visit(Field("gps", &gps));
    a->Visit(Field("usbl", &usbl));
    a->Visit(Field("modem", &modem));
  }
};

struct ImuReading {
  bool valid = false;
  double stamp = 0.0;  ///< s, simulated time
  std::uint64_t seq = 0;
  Eigen::Vector3d specific_force_B = Eigen::Vector3d::Zero();  ///< m/s^2, FRD ((0,0,-g) at rest, level)
  Eigen::Vector3d angular_rate_B = Eigen::Vector3d::Zero();    ///< rad/s, FRD
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();    ///< true attitude (for an AHRS output)
};
struct PressureReading {
  bool valid = false;
  double stamp = 0.0;
  std::uint64_t seq = 0;
  double pressure_pa = 0.0;  ///< absolute, Pa: p_atm + rho g z under water
  double depth_m = 0.0;      ///< (pressure - p_atm) / (rho g), m
};
struct DvlReading {
  bool valid = false;  ///< >= 3 beams locked (beams = 4) / altitude in range (beams = 0)
  double stamp = 0.0;
  std::uint64_t seq = 0;
  Eigen::Vector3d velocity_B = Eigen::Vector3d::Zero();  ///< seabed-relative velocity, FRD, m/s
  double altitude_m = 0.0;                               ///< vertical distance to the seabed, m
  int locked_beams = 0;                                  ///< beams = 4: how many have bottom lock
  std::array<bool, 4> beam_valid{};
  std::array<double, 4> beam_range_m{};   ///< slant range along each beam, m (valid beams)
  std::array<double, 4> beam_velocity{};  ///< measured velocity along each beam, m/s (valid beams)
};

/// Unit vector of DVL beam i (0..3) in body FRD axes: beam_angle_deg off +z, azimuth 45 + 90 i deg.
Eigen::Vector3d dvl_beam_B(int i, double beam_angle_deg);
/// Slant range along the unit ray from `origin` (NED) to the seabed, or a negative number when
/// it does not reach it within max_range (ray marched in 5 cm steps, then bisected to 1e-12 m).
double seabed_ray_range(const Seabed& seabed, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                        double max_range);
struct RangeReading {
  bool valid = false;
  double stamp = 0.0;
  std::uint64_t seq = 0;
  double range_m = 0.0;  ///< along body +z (down) to the seabed, m
};
struct MagnetometerReading {
  bool valid = false;
  double stamp = 0.0;
  std::uint64_t seq = 0;
  Eigen::Vector3d field_B = Eigen::Vector3d::Zero();  ///< T, FRD
};
struct GpsReading {
  bool valid = false;  ///< only within max_depth of the surface
  double stamp = 0.0;
  std::uint64_t seq = 0;
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();  ///< NED position fix, m
  double latitude_deg = 0.0, longitude_deg = 0.0, altitude_m = 0.0;
};
struct SensorReadings {
  ImuReading imu;
  PressureReading pressure;
  DvlReading dvl;
  RangeReading altimeter;
  MagnetometerReading magnetometer;
  GpsReading gps;
  UsblReading usbl;
};

/// Updates every enabled sensor at its own rate from the physics state. Allocation-free.
class SensorSuite {
 public:
  SensorSuite(const SensorSuiteParams& params, const EnvironmentParams& env);
  /// Samples the sensors due at time t (s). nu_dot = [v_dot; w_dot] in body axes (for the IMU);
  /// seabed may be null (no seabed: DVL and altimeter invalid).
  void update(double t, const RigidBodyState& x, const Vector6d& nu_dot, const Seabed* seabed);
  const SensorReadings& readings() const { return readings_; }
  /// The carrier's pose of a carried USBL transceiver (UsblParams::transceiver_vehicle).
  void set_usbl_carrier_pose(const Eigen::Isometry3d& X_WB) { usbl_.set_carrier_pose(X_WB); }
  /// True when update(t, ...) will sample the IMU (the only sensor that needs nu_dot).
  bool imu_due(double t) const { return s_imu_.due(t); }
  const SensorSuiteParams& params() const { return params_; }

 private:
  struct Channel {  // noise state of one scalar channel
    NoiseParams p;
    double bias = 0.0;
  };
  struct Schedule {
    double period = 0.0;
    double next = 0.0;
    bool due(double t) const { return period > 0.0 && t >= next - 1e-9; }
    void advance(double t) {
      while (next <= t + 1e-9) next += period;
    }
  };
  struct Gaussian {  // one seeded N(0, 1) stream per sensor
    std::mt19937_64 gen;
    std::normal_distribution<double> dist{0.0, 1.0};
    double operator()() { return dist(gen); }
  };
  static double noisy(Channel& c, Gaussian& g, double truth, double dt);
  void update_dvl_beams(const RigidBodyState& x, const Eigen::Matrix3d& R, const Seabed* seabed, bool underwater);

  SensorSuiteParams params_;
  EnvironmentParams env_;
  SensorReadings readings_;
  Gaussian g_imu_, g_pressure_, g_dvl_, g_alt_, g_mag_, g_gps_;
  Usbl usbl_;
  Schedule s_imu_, s_pressure_, s_dvl_, s_alt_, s_mag_, s_gps_;
  Channel accel_[3], gyro_[3], pressure_, dvl_[4], range_, mag_[3], gps_[3];
};

/// Throws ConfigError ("<src>: sensors.imu.rate = -1: must be > 0 Hz") on a bad value.
void validate_sensors(const SensorSuiteParams& p, const std::string& src);

}  // namespace unav::physics
