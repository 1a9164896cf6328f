// In-process facade: one vehicle with its thrusters, the water current, the seabed and the
// sensors, stepped at a fixed dt. The physics node and the gym environment embed it.
//   sim.set_command(t, u);   // validated; returns a status, never integrates bad input
//   sim.step();              // advances by options.dt
//   sim.state(); sim.sensors();
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "unav_physics/current.hpp"
#include "unav_physics/dynamics.hpp"
#include "unav_physics/seabed.hpp"
#include "unav_physics/sensors.hpp"
#include "unav_physics/tether.hpp"
#include "unav_physics/thrusters.hpp"
#include "unav_physics/vehicle.hpp"

namespace unav::physics {

enum class CommandStatus {
  kAccepted,
  kClamped,              ///< accepted, at least one |u_i| > 1 clamped to +-1
  kRejectedWrongLength,  ///< not one value per thruster; previous command kept
  kRejectedNonFinite,    ///< NaN or Inf in it; previous command kept
};
const char* to_string(CommandStatus status);

struct CommandStats {
  std::uint64_t accepted = 0;  ///< including clamped ones
  std::uint64_t clamped = 0;
  std::uint64_t rejected_wrong_length = 0;
  std::uint64_t rejected_non_finite = 0;
  std::uint64_t timeouts = 0;  ///< transitions into the timed-out state
};

/// Failsafe: expired(t) once more than `timeout_s` has passed since the last command (or since
/// start, when none came). timeout_s <= 0 disables it.
class CommandTimeout {
 public:
  explicit CommandTimeout(double timeout_s) : timeout_s_(timeout_s) {}
  void on_command(double t) { last_ = t; }
  bool expired(double t) const { return timeout_s_ > 0.0 && t - last_ > timeout_s_; }
  double timeout() const { return timeout_s_; }

 private:
  double timeout_s_;
  double last_ = 0.0;
};

struct SimulatorOptions {
  double dt = 1e-3;  ///< s, fixed step (1 kHz)
  Integrator integrator = Integrator::kVelocityVerlet;
  double command_timeout = 0.5;  ///< s without a command -> zero thrust; <= 0 disables
  EnvironmentParams environment;
  /// False with a message naming the option when a value is out of range.
  bool IsValid(std::string* msg) const;
};

/// Environment from a YAML map (keys: gravity, water_density, atmospheric_pressure,
/// magnetic_field [T, NED], origin_latitude, origin_longitude [deg], origin_altitude [m]).
EnvironmentParams parse_environment(const YAML::Node& node, const std::string& source,
                                    const std::string& key = "environment");

class Simulator {
 public:
  /// Throws ConfigError for invalid options or vehicle. current: null = still water;
  /// seabed: null = bottomless. The vehicle starts at `initial` (default: origin, level, at rest).
  Simulator(const VehicleParams& vehicle, const SimulatorOptions& options,
            std::unique_ptr<CurrentModel> current = nullptr, std::unique_ptr<Seabed> seabed = nullptr,
            const RigidBodyState& initial = RigidBodyState{});

  /// Thruster commands u_i in [-1, 1], one per thruster, received at simulated time t (s).
  CommandStatus set_command(double t, const double* u, std::size_t n);
  CommandStatus set_command(double t, const std::vector<double>& u) { return set_command(t, u.data(), u.size()); }
  /// Extra body wrench [F; M] (N, N m, FRD) added to the thrust from now on (tests, tethers).
  void set_external_wrench_B(const Vector6d& tau_B);

  /// Advances by options().dt: failsafe, thruster lag, dynamics, current, sensors.
  void step();
  /// Steps until time() >= t_end (s).
  void advance_to(double t_end);

  /// Resets time to 0, the state to x, thrusters to rest and the command to zero.
  void reset(const RigidBodyState& x);
  /// A new episode while time runs on: the state becomes x (its velocities included), the
  /// thrusters stop and the command is zero until the next one; time, the sensors' noise streams
  /// and the failsafe clock continue. Throws ConfigError for a non-finite x or a zero quaternion.
  void teleport(const RigidBodyState& x);

  double time() const { return static_cast<double>(steps_) * options_.dt; }  ///< s
  std::uint64_t steps() const { return steps_; }
  const RigidBodyState& state() const { return x_; }
  /// The body pose in the world (NED).
  Eigen::Isometry3d pose() const {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = x_.q_WB.toRotationMatrix();
    X.translation() = x_.p_WB_W;
    return X;
  }
  /// Where the vehicle that carries this vehicle's USBL transceiver is (sensors.usbl.
  /// transceiver_vehicle), before each step (the physics server, which steps both).
  void set_usbl_carrier_pose(const Eigen::Isometry3d& X_WB) { sensors_.set_usbl_carrier_pose(X_WB); }
  /// nu_dot = [v_dot; w_dot] (body axes) at the current state and inputs (computed on demand).
  const Vector6d& acceleration() const;
  const SensorReadings& sensors() const { return sensors_.readings(); }
  const ThrusterBank& thrusters() const { return thrusters_; }
  /// Last accepted (clamped) command u_i in [-1, 1]; zeros before the first one.
  const ThrusterVector& command() const { return u_cmd_; }
  const VehicleDynamics& dynamics() const { return dynamics_; }
  const CommandStats& command_stats() const { return stats_; }
  bool command_timed_out() const { return timed_out_; }
  /// Water velocity at the vehicle now, NED, m/s.
  Eigen::Vector3d current_velocity_W() const { return current_->velocity_W(time()); }
  const Seabed* seabed() const { return seabed_.get(); }
  /// The tether (null without one) and its force on the vehicle now, world NED [N].
  const Tether* tether() const { return tether_.get(); }
  Eigen::Vector3d tether_force_W() const;
  /// Pays the tether out (or in) to `length_m` from now on. Throws ConfigError without a tether.
  void set_tether_length(double length_m);
  const SimulatorOptions& options() const { return options_; }

 private:
  SimulatorOptions options_;
  VehicleDynamics dynamics_;
  ThrusterBank thrusters_;
  SensorSuite sensors_;
  std::unique_ptr<CurrentModel> current_;
  std::unique_ptr<Seabed> seabed_;
  CommandTimeout timeout_;
  RigidBodyState x_;
  DynamicsInputs inputs_at(double t) const;

  mutable Vector6d nu_dot_ = Vector6d::Zero();
  mutable bool nu_dot_fresh_ = false;
  Vector6d external_tau_B_ = Vector6d::Zero();
  std::unique_ptr<Tether> tether_;
  Vector6d tether_tau_B_ = Vector6d::Zero();  ///< the tether's wrench at the start of the step
  void update_tether_wrench();                // at the vehicle's present attachment point
  void update_tether_wrench(const Eigen::Vector3d& attach_W, const Eigen::Vector3d& attach_v_W);
  ThrusterVector u_cmd_, u_zero_;
  CommandStats stats_;
  bool timed_out_ = false;
  std::uint64_t steps_ = 0;
};

}  // namespace unav::physics
