// Common types, frames and units of the physics core.
//
// Frames (declared once, here):
//   W  world, NED: x north, y east, z down (metres; z > 0 is below the water surface).
//   B  body, FRD: x forward, y right, z down; origin at the vehicle's reference point (the
//      centre of gravity for the bundled vehicles).
// Notation (Drake monogram): p_WB_W = position of B in W, expressed in W; v_WB_B = linear
// velocity of B in W, expressed in B; w_WB_B = angular velocity of B in W, expressed in B;
// q_WB = rotation taking B-frame vectors to W (R_WB). Generalised velocity nu = [v_WB_B; w_WB_B]
// (Fossen's [u v w p q r]). SI units everywhere: m, s, kg, N, N m, rad, Pa, T.
#pragma once

#include "unav_common/errors.hpp"
#include "unav_common/frames.hpp"
#include <cstddef>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace unav::physics {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Upper bound on thrusters per vehicle; thruster vectors are fixed-capacity (no heap).
constexpr int kMaxThrusters = 16;
using ThrusterVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxThrusters, 1>;
using ThrusterMatrix = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxThrusters>;

/// Thrown at configure time for a bad configuration value. The message names the source (file
/// path or "<in-memory>"), the key, the value and the rule it broke, e.g.
/// "config/vehicles/x.yaml: thrusters[3].direction has zero length (got [0, 0, 0])".
/// Bad configuration (file, key, value, rule): the one error type of the workspace.
using ConfigError = unav::ConfigError;

/// Skew-symmetric matrix S(a) with S(a) b = a x b.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d s;
  s << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return s;
}

/// Rigid-body state of a vehicle (explicit, copyable; what the integrators advance).
struct RigidBodyState {
  Eigen::Vector3d p_WB_W = Eigen::Vector3d::Zero();  ///< position in NED, m
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();  ///< attitude (unit), body -> NED
  Eigen::Vector3d v_WB_B = Eigen::Vector3d::Zero();  ///< linear velocity in body FRD, m/s
  Eigen::Vector3d w_WB_B = Eigen::Vector3d::Zero();  ///< angular velocity in body FRD, rad/s

  /// Fossen's nu = [u v w p q r].
  Vector6d nu() const {
    Vector6d n;
    n.head<3>() = v_WB_B;
    n.tail<3>() = w_WB_B;
    return n;
  }
  void set_nu(const Vector6d& nu) {
    v_WB_B = nu.head<3>();
    w_WB_B = nu.tail<3>();
  }
  /// Linear velocity in NED, m/s.
  Eigen::Vector3d v_WB_W() const { return q_WB * v_WB_B; }
};

// Roll, pitch, yaw (ZYX convention, rad) <-> attitude: one implementation, on the common floor.
using unav::common::quaternion_from_rpy;
using unav::common::roll_pitch_yaw;

/// World properties shared by the dynamics and the sensors.
struct EnvironmentParams {
  double gravity = 9.81;            ///< m/s^2, along +z of NED
  double water_density = 1025.0;    ///< kg/m^3 (sea water; fresh water ~ 999.7)
  double atmospheric_pressure = 101325.0;  ///< Pa at the surface
  /// Earth's magnetic field in NED, T (default: roughly central Europe, 48 uT, 64 deg dip).
  Eigen::Vector3d magnetic_field_W{2.1e-5, 0.0, 4.3e-5};
  /// Geodetic origin of the NED frame, for GPS fixes (flat-earth conversion); deg, deg, m.
  double origin_latitude_deg = 0.0;
  double origin_longitude_deg = 0.0;
  double origin_altitude_m = 0.0;

  /// False (with a message naming the field) when a value is non-finite or out of range.
  bool IsValid(std::string* msg) const;
};

}  // namespace unav::physics
