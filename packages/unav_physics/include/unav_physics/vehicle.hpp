// Vehicle description as data: rigid body, hydrostatics, hydrodynamics, thrusters, contact,
// sensors. Built in memory (tests) or loaded from YAML (config/vehicles/*.yaml).
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "unav_physics/sensors.hpp"
#include "unav_physics/tether.hpp"
#include "unav_physics/types.hpp"

namespace unav::physics {

/// One thruster. Thrust T = k u_f (N) with k = C_T rho w_max^2 D^4 (paper eq. 3), u_f the
/// first-order low-pass (time constant t_c) of the command u in [-1, 1]; for u_f < 0 the
/// reverse coefficient C_T_reverse is used (asymmetric T200 curve), C_T when it is <= 0.
struct ThrusterParams {
  std::string name;
  Eigen::Vector3d position_B = Eigen::Vector3d::Zero();    ///< r_i, m, body FRD
  Eigen::Vector3d direction_B = Eigen::Vector3d::UnitX();  ///< n_i, positive thrust direction (normalised on load)
  double C_T = 0.344;                                      ///< thrust coefficient, -
  double C_T_reverse = 0.0;    ///< thrust coefficient for negative commands, - (<= 0: same as C_T)
  double rho = 1025.0;         ///< water density used by eq. 3, kg/m^3
  double w_max = 58.33;        ///< maximum propeller speed, rev/s
  double diameter = 0.076;     ///< propeller diameter D, m
  double time_constant = 0.1;  ///< t_c of the command low-pass, s (> 0)

  /// The propeller's keys (also the file's thruster_defaults).
  template <class Archive>
  void SerializeCoefficients(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("C_T", &C_T).Doc("thrust coefficient"));
    a->Visit(Field("C_T_reverse", &C_T_reverse).Doc("for negative commands; 0 = C_T"));
    a->Visit(Field("rho", &rho).Unit("kg/m^3").Doc("water density of eq. 3"));
    a->Visit(Field("w_max", &w_max).Unit("rev/s").Doc("maximum propeller speed"));
    a->Visit(Field("diameter", &diameter).Unit("m").Doc("propeller diameter"));
    a->Visit(Field("time_constant", &time_constant).Unit("s").Doc("command low-pass"));
  }
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("name", &name));
    a->Visit(Field("position", &position_B).Unit("m").Doc("body FRD"));
    a->Visit(Field("direction", &direction_B).Doc("positive thrust direction, body FRD (normalised)"));
    SerializeCoefficients(a);
  }

  double max_forward_thrust() const;  ///< N, at u = +1
  double max_reverse_thrust() const;  ///< N (positive), at u = -1
};

/// Penalty spring-damper between the vehicle's bottom (z + height/2) and the seabed.
struct ContactParams {
  double stiffness = 2000.0;  ///< N/m
  double damping = 500.0;     ///< N s/m (about critical for ~30 kg with added mass)
  double friction = 50.0;     ///< viscous horizontal friction while in contact, N s/m
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("stiffness", &stiffness).Unit("N/m"));
    a->Visit(Field("damping", &damping).Unit("N s/m"));
    a->Visit(Field("friction", &friction).Unit("N s/m").Doc("horizontal, while in contact"));
  }
};

struct VehicleParams {
  std::string name = "vehicle";
  std::string description;
  double mass = 1.0;                                      ///< m, kg
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Identity();  ///< about the CG, body axes, kg m^2
  Eigen::Vector3d r_g_B = Eigen::Vector3d::Zero();        ///< centre of gravity, m
  Eigen::Vector3d r_b_B = Eigen::Vector3d::Zero();        ///< centre of buoyancy, m
  /// Buoyancy force when fully submerged, N. Negative means "from volume" (rho g V) when
  /// volume > 0, else neutral (B = m g). Resolved by buoyancy_force().
  double buoyancy = -1.0;
  double volume = 0.0;  ///< displaced volume, m^3 (used when buoyancy < 0 and volume > 0)
  /// Vertical extent, m: the bottom touches the seabed at z + height/2, and the buoyancy scales
  /// with the submerged fraction clamp((z + height/2) / height, 0, 1) near the surface.
  double height = 0.25;
  Matrix6d added_mass = Matrix6d::Zero();         ///< M_A (positive convention), symmetric
  Matrix6d linear_damping = Matrix6d::Zero();     ///< D_l: force = -D_l nu_r
  Matrix6d quadratic_damping = Matrix6d::Zero();  ///< D_q: force = -D_q (|nu_r| .* nu_r)
  std::vector<ThrusterParams> thrusters;
  ContactParams contact;
  SensorSuiteParams sensors;
  TetherParams tether;

  /// The file's keys (config/vehicles/*.yaml) but thruster_defaults, which parse_vehicle() applies
  /// to each thruster entry that does not set a key itself, and buoyancy: neutral (the default).
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("name", &name));
    a->Visit(Field("description", &description));
    a->Visit(Field("mass", &mass).Unit("kg"));
    a->Visit(Field("inertia", &inertia).Unit("kg m^2").Doc("about the CG, body axes"));
    a->Visit(Field("center_of_gravity", &r_g_B).Unit("m"));
    a->Visit(Field("center_of_buoyancy", &r_b_B).Unit("m"));
    a->Visit(Field("buoyancy", &buoyancy).Unit("N").Doc("'neutral' (B = m g) or N; exclusive with volume"));
    a->Visit(Field("volume", &volume).Unit("m^3").Doc("displaced volume (B = rho g V)"));
    a->Visit(Field("height", &height).Unit("m").Doc("vertical extent (contact, surface)"));
    a->Visit(Field("added_mass", &added_mass).Doc("M_A, 6 numbers (diagonal) or 6x6"));
    a->Visit(Field("linear_damping", &linear_damping).Doc("D_l"));
    a->Visit(Field("quadratic_damping", &quadratic_damping).Doc("D_q"));
    a->Visit(Field("thrusters", &thrusters));
    a->Visit(Field("contact", &contact));
    a->Visit(Field("sensors", &sensors));
    a->Visit(Field("tether", &tether));
  }

  /// Fully submerged buoyancy, N, for this environment.
  double buoyancy_force(const EnvironmentParams& env) const;
  /// M_RB (Fossen eq. 3.44), with the inertia moved from the CG to the body origin.
  Matrix6d rigid_body_mass() const;
};

/// Checks every physical rule (mass > 0; inertia symmetric positive definite and satisfying the
/// triangle inequality; M_A symmetric with M_RB + M_A positive definite; damping diagonals >= 0;
/// thruster directions non-zero; time constants, coefficients, w_max, D > 0; finite values;
/// 1 <= thrusters <= kMaxThrusters; sensors). Throws ConfigError naming source + key + value + rule.
void validate_vehicle(const VehicleParams& p, const std::string& src = "<in-memory>");

/// Parses a vehicle map (layout: config/vehicles/bluerov2_heavy.yaml), rejecting unknown keys,
/// wrong types and NaN/Inf, normalising thruster directions, then validate_vehicle().
VehicleParams parse_vehicle(const YAML::Node& node, const std::string& source);
/// Loads and validates a vehicle file. Throws ConfigError (file unreadable, malformed, invalid).
VehicleParams load_vehicle(const std::string& yaml_path);

/// The BlueROV2 Heavy of REFERENCE.md section 1 in memory (neutral, same values as
/// config/vehicles/bluerov2_heavy.yaml without sensors), for tests and benchmarks.
VehicleParams bluerov2_heavy_params();

}  // namespace unav::physics
