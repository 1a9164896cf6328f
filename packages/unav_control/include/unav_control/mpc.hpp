// Nonlinear model-predictive controller on Ceres: body wrench for a pose setpoint.
//
// Model: the physics core's VehicleDynamics (Fossen 6-DOF, velocity Verlet, step `dt`), built
// from the MPC's own vehicle parameters (which may differ from the plant's), driven by
//   tau_k = lag(tau_cmd) + d_hat,
// where lag() is an optional first-order actuator model (time constant `actuator_time_constant`,
// the thrusters' spin-up) and d_hat a body-frame disturbance wrench estimated from the one-step
// prediction error (d_hat += gain * M * (nu_measured - nu_predicted) / dt_since_last_solve): a
// constant current or a model error leaves no steady-state offset.
// Decision variables: `control_blocks` wrenches held over equal parts of the horizon (move
// blocking), bounded by `input_bounds`. Cost (sum of squares):
//   sum_k |Wx (x_k - x_ref)|^2 (last step x terminal_weight_scale) + sum_b n_b |Wu (tau_b - tau_ss)|^2
//   + sum_b |Wd (tau_b - tau_{b-1})|^2,
// x - x_ref = [p_W - p_ref_W; Log(q_ref^-1 q); nu] (12 states: NED position, attitude error as a
// rotation vector in body axes, body velocities), tau_ss = g(eta_ref) - d_hat the wrench that holds
// the setpoint, tau_{-1} the previous command. Gauss-Newton Jacobians come from forward
// sensitivities of the rollout (finite differences of one model step per stage), so the cost
// needs no templated model. The Ceres Problem is built once and reused; each solve is warm-started
// from the previous plan shifted by the elapsed time.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "unav_control/allocator.hpp"
#include "unav_physics/types.hpp"
#include "unav_physics/vehicle.hpp"

namespace unav::control {

using Vector12d = Eigen::Matrix<double, 12, 1>;

/// Target pose: NED position (m) and attitude (unit quaternion, body FRD -> NED).
struct PoseSetpoint {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
  /// Level attitude (roll = pitch = 0) with the given yaw (rad).
  static PoseSetpoint FromPositionYaw(const Eigen::Vector3d& p_W, double yaw);
};

struct MpcOptions {
  int horizon_steps = 20;  ///< N, >= 1
  double dt = 0.05;        ///< model step, s, > 0
  int control_blocks = 5;  ///< move blocking: free wrenches over the horizon, 1..min(N, 20)
  /// Diagonal of Wx^2: [x y z (1/m^2), roll pitch yaw error (1/rad^2), u v w (s^2/m^2), p q r (s^2/rad^2)], >= 0.
  Vector12d state_weights = (Vector12d() << 200, 200, 200, 60, 60, 60, 30, 30, 30, 4, 4, 4).finished();
  double terminal_weight_scale = 5.0;  ///< multiplies state_weights at the last step, >= 0
  /// Diagonal of Wu^2 on tau - tau_ss (1/N^2, 1/(N m)^2), >= 0.
  Vector6d input_weights = (Vector6d() << 2e-3, 2e-3, 2e-3, 2e-2, 2e-2, 2e-2).finished();
  /// Diagonal of Wd^2 on the change between consecutive blocks (and from the previous command), >= 0.
  Vector6d input_rate_weights = (Vector6d() << 1e-3, 1e-3, 1e-3, 1e-2, 1e-2, 1e-2).finished();
  /// Wrench limits (body FRD, N / N m): usually Allocator::achievable_wrench_box() x margin.
  WrenchBox input_bounds{Vector6d::Constant(-50.0), Vector6d::Constant(50.0)};
  /// First-order lag between command and wrench in the model, s; 0 = none.
  double actuator_time_constant = 0.1;
  /// Disturbance estimator gain per solve, in [0, 1]; 0 disables the estimate.
  double disturbance_gain = 0.15;
  /// |d_hat| limits as a fraction of input_bounds (anti-windup), >= 0.
  double disturbance_limit_fraction = 0.8;
  int max_iterations = 10;  ///< Ceres iterations per solve, >= 1
  /// Ceres wall-time budget, ms, >= 0 (a late solve returns its best iterate). 0 = none: the solve
  /// is bounded by max_iterations only and repeats exactly (lockstep, learning, data generation).
  double max_solve_time_ms = 0.0;
  double function_tolerance = 1e-6;  ///< Ceres relative cost-change tolerance, > 0

  /// False, with a message naming the field and the offending values, when an option is invalid
  /// (horizon 0, non-finite or negative weights, lower > upper bounds, ...).
  bool IsValid(std::string* msg) const;
};

enum class MpcStatus {
  kConverged,        ///< Ceres converged
  kMaxIterations,    ///< iteration limit reached: best iterate used (normal under a tight budget)
  kTimeLimit,        ///< wall-time budget reached: best iterate used
  kSolverFailure,    ///< Ceres failed or the result was not finite: safe wrench
  kInvalidState,     ///< NaN/Inf or non-unit quaternion in the state: safe wrench
  kInvalidSetpoint,  ///< NaN/Inf or non-unit quaternion in the setpoint: safe wrench
  kInvalidTime,      ///< non-finite t: safe wrench
};
const char* to_string(MpcStatus status);

struct MpcSummary {
  MpcStatus status = MpcStatus::kConverged;
  int iterations = 0;          ///< Ceres iterations
  double solve_time_ms = 0.0;  ///< wall time of Solve(), ms
  double initial_cost = 0.0;   ///< cost of the warm start
  double cost = 0.0;           ///< cost of the returned plan
  std::string message;         ///< empty unless something went wrong
  /// True when the wrench came from this solve (converged, iteration or time limit).
  bool ok() const {
    return status == MpcStatus::kConverged || status == MpcStatus::kMaxIterations || status == MpcStatus::kTimeLimit;
  }
};

class Mpc {
 public:
  /// Throws physics::ConfigError for invalid options (message names the field and values) or an
  /// invalid model vehicle.
  Mpc(const physics::VehicleParams& model, const MpcOptions& options,
      const physics::EnvironmentParams& env = physics::EnvironmentParams{});
  ~Mpc();
  Mpc(const Mpc&) = delete;
  Mpc& operator=(const Mpc&) = delete;

  /// One control step at time t (s): state x_in (NED pose + body twist), setpoint sp -> *wrench_B
  /// (body FRD, N / N m, within input_bounds, always finite). Never throws. On any failure
  /// *wrench_B is the safe wrench: the previous plan's input for now, clamped to the bounds, or zero.
  MpcSummary Solve(const physics::RigidBodyState& x_in, const PoseSetpoint& sp, double t, Vector6d* wrench_B);

  /// Tells the estimator which wrench was really applied since the last Solve (e.g. the
  /// allocator's achieved wrench when it had to scale); default: the wrench Solve returned.
  void SetAppliedWrench(const Vector6d& wrench_B);
  /// Forgets the plan, the disturbance estimate and the actuator state.
  void Reset();

  /// Estimated body-frame disturbance wrench, N / N m.
  const Vector6d& disturbance_estimate() const;
  /// Planned wrench per block (control_blocks entries).
  std::vector<Vector6d> planned_wrenches() const;
  /// Predicted states x_1..x_N of the last plan.
  std::vector<physics::RigidBodyState> predicted_states() const;
  const MpcOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace unav::control
