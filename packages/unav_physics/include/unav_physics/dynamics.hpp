// Fossen 6-DOF equation of motion in the body frame (Fossen 2011, SNAME notation):
//   M_RB nu_dot + C_RB(nu) nu + M_A nu_r_dot + C_A(nu_r) nu_r + D(nu_r) nu_r + g(eta) = tau
// nu_r = nu - nu_c, nu_c = [R^T v_c_W; 0], nu_c_dot = [-w x v_c_B + R^T a_c_W; 0], so
//   (M_RB + M_A) nu_dot = tau - C_RB(nu) nu - C_A(nu_r) nu_r - D(nu_r) nu_r - g(eta) + M_A nu_c_dot.
// Kinematics: p_dot_W = R(q) v_B, q_dot = 0.5 q (x) [0, w_B]. Fixed-size Eigen only: a step
// allocates nothing.
#pragma once

#include <string>

#include "unav_physics/types.hpp"
#include "unav_physics/vehicle.hpp"

namespace unav::physics {

class Seabed;

enum class Integrator {
  kVelocityVerlet,  ///< the paper's; 2 evaluations per step, second order
  kRk4,             ///< classic Runge-Kutta; 4 evaluations per step, fourth order
};
/// "velocity_verlet" / "rk4"; returns false for anything else.
bool parse_integrator(const std::string& name, Integrator* out);
const char* to_string(Integrator integrator);

/// Inputs held over one step (zero-order hold, except the current: first-order hold).
struct DynamicsInputs {
  Vector6d tau_B = Vector6d::Zero();  ///< generalised force [F; M] in body FRD, N / N m
  /// When true, the force varies within the step: tau_B at its start, tau_B_half at dt/2 and
  /// tau_B_end at dt (e.g. lagged thrust). RK4 evaluates each stage at its own time (4th order);
  /// velocity Verlet uses the start and end values. False: tau_B is held over the step.
  bool tau_staged = false;
  Vector6d tau_B_half = Vector6d::Zero();
  Vector6d tau_B_end = Vector6d::Zero();
  Eigen::Vector3d v_c_W = Eigen::Vector3d::Zero();  ///< water velocity at the step start, NED, m/s
  Eigen::Vector3d a_c_W = Eigen::Vector3d::Zero();  ///< its time derivative, m/s^2
  const Seabed* seabed = nullptr;                   ///< contact when non-null
};

/// The rotation Exp(phi) of a rotation vector phi [rad] as a quaternion (the integrators' and the
/// controllers' one exponential map).
Eigen::Quaterniond exp_rotation(const Eigen::Vector3d& phi);

/// C(nu) of Fossen eq. 6.43 for a symmetric 6x6 inertia M (skew-symmetric parametrisation).
Matrix6d coriolis_matrix(const Matrix6d& M, const Vector6d& nu);
/// C(nu) nu without forming the matrix.
Vector6d coriolis_times(const Matrix6d& M, const Vector6d& nu);

class VehicleDynamics {
 public:
  /// Validates params (throws ConfigError) and precomputes M_RB, M_A, (M_RB + M_A)^-1, B.
  VehicleDynamics(const VehicleParams& params, const EnvironmentParams& env = EnvironmentParams{});

  /// nu_dot at state x, `dt_since_start` seconds into the step whose inputs are `in`.
  Vector6d acceleration(const RigidBodyState& x, const DynamicsInputs& in, double dt_since_start = 0.0) const;
  /// Same, with R_WB = rotation matrix of x.q_WB (normalised) already computed.
  Vector6d acceleration(const RigidBodyState& x, const Eigen::Matrix3d& R_WB, const DynamicsInputs& in,
                        double dt_since_start) const;
  /// Advances x by dt seconds; the quaternion is renormalised.
  void step(RigidBodyState& x, double dt, const DynamicsInputs& in, Integrator integrator) const;

  /// One velocity Verlet step under a wrench held over it, with no current and no seabed (the
  /// model a controller predicts with), and its Jacobians in tangent coordinates: a state moves
  /// as (p + dp, q Exp(dtheta), nu + dnu) with dp in NED and dtheta in body axes, and
  ///   [dp; dtheta; dnu]_{k+1} = A [dp; dtheta; dnu]_k + B dtau.
  /// Advances x exactly as step(x, dt, {tau_B}, kVelocityVerlet) does (same arithmetic, same
  /// result); A and B are the analytic derivatives of that step (chain rule through both
  /// acceleration evaluations, the pose update and the rotation's exponential), ~1e-7 from its
  /// central differences. Either pointer may be null.
  void verlet_step_jacobians(RigidBodyState& x, double dt, const Vector6d& tau_B, Eigen::Matrix<double, 12, 12>* A,
                             Eigen::Matrix<double, 12, 6>* B) const;
  /// Restoring generalised force g(eta) (weight at r_g, buoyancy at r_b), body frame.
  Vector6d restoring(const RigidBodyState& x) const;
  Vector6d restoring(const Eigen::Matrix3d& R_WB, double z) const;
  /// Hydrodynamic damping force D(nu_r) nu_r (positive = opposing motion), body frame.
  Vector6d damping(const Vector6d& nu_r) const;
  /// Seabed contact force on the body, body frame (zero when not touching).
  Vector6d contact(const RigidBodyState& x, const Seabed* seabed) const;
  /// 0.5 nu^T (M_RB + M_A) nu, J (for a current-free check of the Coriolis terms).
  double kinetic_energy(const RigidBodyState& x) const;

  const Matrix6d& M_RB() const { return M_RB_; }
  const Matrix6d& M_A() const { return M_A_; }
  const Matrix6d& M() const { return M_; }
  double weight() const { return W_; }    ///< N
  double buoyancy() const { return B_; }  ///< N, fully submerged
  const VehicleParams& params() const { return params_; }

 private:
  struct Blocks {  // 3x3 blocks of a 6x6 inertia, and whether it is diagonal (fast path)
    Eigen::Matrix3d M11, M12, M21, M22;
    Vector6d diag;
    bool diagonal = false;
  };
  static Blocks make_blocks(const Matrix6d& M);
  static Vector6d coriolis_fast(const Blocks& b, const Eigen::Vector3d& v1, const Eigen::Vector3d& v2);
  /// d coriolis_fast / d [v1; v2] (6 x 6).
  static Matrix6d coriolis_jacobian(const Blocks& b, const Eigen::Vector3d& v1, const Eigen::Vector3d& v2);
  /// Derivatives of acceleration() without current or contact: with respect to a body-axes
  /// rotation of the attitude (6 x 3), the depth z (near the surface only) and nu (6 x 6).
  void acceleration_jacobians(const Eigen::Matrix3d& R_WB, double z, const Vector6d& nu,
                              Eigen::Matrix<double, 6, 3>* d_theta, Vector6d* d_z, Matrix6d* d_nu) const;

  VehicleParams params_;
  Blocks rb_, a_;
  bool damping_diagonal_ = false;
  Matrix6d M_RB_, M_A_, M_, M_inv_, D_l_, D_q_;
  double W_ = 0.0, B_ = 0.0;
};

}  // namespace unav::physics
