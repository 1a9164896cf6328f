// Equation of motion, integrators and thrusters.
#include "unav_physics/dynamics.hpp"

#include <algorithm>
#include <cmath>

#include "unav_physics/seabed.hpp"
#include "unav_physics/thrusters.hpp"

namespace unav::physics {

bool parse_integrator(const std::string& name, Integrator* out) {
  if (name == "velocity_verlet") {
    *out = Integrator::kVelocityVerlet;
  } else if (name == "rk4") {
    *out = Integrator::kRk4;
  } else {
    return false;
  }
  return true;
}

const char* to_string(Integrator integrator) { return integrator == Integrator::kRk4 ? "rk4" : "velocity_verlet"; }

Eigen::Quaterniond exp_rotation(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, phi / angle));
}

Matrix6d coriolis_matrix(const Matrix6d& M, const Vector6d& nu) {
  const Eigen::Vector3d a1 = M.topLeftCorner<3, 3>() * nu.head<3>() + M.topRightCorner<3, 3>() * nu.tail<3>();
  const Eigen::Vector3d a2 = M.bottomLeftCorner<3, 3>() * nu.head<3>() + M.bottomRightCorner<3, 3>() * nu.tail<3>();
  Matrix6d C = Matrix6d::Zero();
  C.topRightCorner<3, 3>() = -skew(a1);
  C.bottomLeftCorner<3, 3>() = -skew(a1);
  C.bottomRightCorner<3, 3>() = -skew(a2);
  return C;
}

Vector6d coriolis_times(const Matrix6d& M, const Vector6d& nu) {
  // C nu = [-a1 x v2; -a1 x v1 - a2 x v2] with a1, a2 the momenta of eq. 6.43.
  const Eigen::Vector3d v1 = nu.head<3>(), v2 = nu.tail<3>();
  const Eigen::Vector3d a1 = M.topLeftCorner<3, 3>() * v1 + M.topRightCorner<3, 3>() * v2;
  const Eigen::Vector3d a2 = M.bottomLeftCorner<3, 3>() * v1 + M.bottomRightCorner<3, 3>() * v2;
  Vector6d out;
  out.head<3>() = v2.cross(a1);
  out.tail<3>() = v1.cross(a1) + v2.cross(a2);
  return out;
}

VehicleDynamics::Blocks VehicleDynamics::make_blocks(const Matrix6d& M) {
  Blocks b;
  b.M11 = M.topLeftCorner<3, 3>();
  b.M12 = M.topRightCorner<3, 3>();
  b.M21 = M.bottomLeftCorner<3, 3>();
  b.M22 = M.bottomRightCorner<3, 3>();
  b.diag = M.diagonal();
  b.diagonal = M.isDiagonal(0.0);
  return b;
}

Vector6d VehicleDynamics::coriolis_fast(const Blocks& b, const Eigen::Vector3d& v1, const Eigen::Vector3d& v2) {
  Eigen::Vector3d a1, a2;
  if (b.diagonal) {
    a1 = b.diag.head<3>().cwiseProduct(v1);
    a2 = b.diag.tail<3>().cwiseProduct(v2);
  } else {
    a1 = b.M11 * v1 + b.M12 * v2;
    a2 = b.M21 * v1 + b.M22 * v2;
  }
  Vector6d out;
  out.head<3>() = v2.cross(a1);
  out.tail<3>() = v1.cross(a1) + v2.cross(a2);
  return out;
}

VehicleDynamics::VehicleDynamics(const VehicleParams& params, const EnvironmentParams& env) : params_(params) {
  validate_vehicle(params);
  std::string msg;
  if (!env.IsValid(&msg)) throw ConfigError("environment: " + msg);
  M_RB_ = params.rigid_body_mass();
  M_A_ = 0.5 * (params.added_mass + params.added_mass.transpose());
  M_ = M_RB_ + M_A_;
  M_inv_ = M_.inverse();
  D_l_ = params.linear_damping;
  D_q_ = params.quadratic_damping;
  rb_ = make_blocks(M_RB_);
  a_ = make_blocks(M_A_);
  damping_diagonal_ = D_l_.isDiagonal(0.0) && D_q_.isDiagonal(0.0);
  W_ = params.mass * env.gravity;
  B_ = params.buoyancy_force(env);
}

Vector6d VehicleDynamics::restoring(const RigidBodyState& x) const {
  return restoring(x.q_WB.normalized().toRotationMatrix(), x.p_WB_W.z());
}

Vector6d VehicleDynamics::restoring(const Eigen::Matrix3d& R_WB, double z) const {
  // Buoyancy scales with the submerged fraction near the surface (vertical extent `height`).
  const double h = params_.height;
  const double fraction = std::clamp((z + 0.5 * h) / h, 0.0, 1.0);
  const Eigen::Vector3d down_B = R_WB.row(2).transpose();  // NED +z in body axes
  const Eigen::Vector3d f_g_B = W_ * down_B;
  const Eigen::Vector3d f_b_B = (-B_ * fraction) * down_B;
  Vector6d g;
  g.head<3>() = -(f_g_B + f_b_B);
  g.tail<3>() = -(params_.r_g_B.cross(f_g_B) + params_.r_b_B.cross(f_b_B));
  return g;
}

Vector6d VehicleDynamics::damping(const Vector6d& nu_r) const {
  if (damping_diagonal_) {
    return (D_l_.diagonal().array() + D_q_.diagonal().array() * nu_r.array().abs()).matrix().cwiseProduct(nu_r);
  }
  return D_l_ * nu_r + D_q_ * nu_r.cwiseAbs().cwiseProduct(nu_r);
}

Vector6d VehicleDynamics::contact(const RigidBodyState& x, const Seabed* seabed) const {
  Vector6d f = Vector6d::Zero();
  if (seabed == nullptr) return f;
  // Penalty spring-damper on the bottom point (origin + height/2 straight down in NED), normal
  // taken as vertical (locally flat seabed); it only pushes (never pulls) and adds viscous
  // horizontal friction while touching. Applied at the body origin (no contact torque).
  const double penetration = x.p_WB_W.z() + 0.5 * params_.height - seabed->depth_at(x.p_WB_W.x(), x.p_WB_W.y());
  if (penetration <= 0.0) return f;
  const Eigen::Vector3d v_W = x.q_WB * x.v_WB_B;
  const auto& c = params_.contact;
  const double f_down = std::min(0.0, -(c.stiffness * penetration + c.damping * v_W.z()));
  const Eigen::Vector3d f_W(-c.friction * v_W.x(), -c.friction * v_W.y(), f_down);
  f.head<3>() = x.q_WB.conjugate() * f_W;
  return f;
}

double VehicleDynamics::kinetic_energy(const RigidBodyState& x) const {
  const Vector6d nu = x.nu();
  return 0.5 * nu.dot(M_ * nu);
}

Vector6d VehicleDynamics::acceleration(const RigidBodyState& x, const DynamicsInputs& in, double dt_since_start) const {
  return acceleration(x, x.q_WB.normalized().toRotationMatrix(), in, dt_since_start);
}

Vector6d VehicleDynamics::acceleration(const RigidBodyState& x, const Eigen::Matrix3d& R_WB, const DynamicsInputs& in,
                                       double dt_since_start) const {
  const Eigen::Matrix3d R_BW = R_WB.transpose();
  const Eigen::Vector3d v_c_B = R_BW * (in.v_c_W + dt_since_start * in.a_c_W);
  Vector6d nu_r, nu_c_dot;
  nu_r.head<3>() = x.v_WB_B - v_c_B;
  nu_r.tail<3>() = x.w_WB_B;
  nu_c_dot.head<3>() = R_BW * in.a_c_W - x.w_WB_B.cross(v_c_B);
  nu_c_dot.tail<3>().setZero();

  Vector6d rhs = in.tau_B - coriolis_fast(rb_, x.v_WB_B, x.w_WB_B) - coriolis_fast(a_, nu_r.head<3>(), x.w_WB_B) -
                 damping(nu_r) - restoring(R_WB, x.p_WB_W.z());
  if (a_.diagonal) {
    rhs.head<3>() += a_.diag.head<3>().cwiseProduct(nu_c_dot.head<3>());
  } else {
    rhs += M_A_ * nu_c_dot;
  }
  if (in.seabed != nullptr) rhs += contact(x, in.seabed);
  return M_inv_ * rhs;
}

namespace {

struct Derivative {
  Eigen::Vector3d p_dot;
  Eigen::Vector4d q_dot;  // quaternion coefficients (x, y, z, w)
  Vector6d nu_dot;
};

}  // namespace

void VehicleDynamics::step(RigidBodyState& x, double dt, const DynamicsInputs& in, Integrator integrator) const {
  if (integrator == Integrator::kVelocityVerlet) {
    // Velocity Verlet for velocity-dependent forces: pose from a second-order Taylor step with
    // a_n, velocity from the trapezoid of a_n and a_{n+1} evaluated at the new pose and the
    // predicted velocity nu_n + dt a_n.
    const Eigen::Matrix3d R0 = x.q_WB.toRotationMatrix();
    const Vector6d a0 = acceleration(x, R0, in, 0.0);
    const Vector6d nu0 = x.nu();
    const Eigen::Vector3d dp_B = dt * x.v_WB_B + 0.5 * dt * dt * (a0.head<3>() + x.w_WB_B.cross(x.v_WB_B));
    x.p_WB_W += R0 * dp_B;
    x.q_WB = (x.q_WB * exp_rotation(dt * x.w_WB_B + 0.5 * dt * dt * a0.tail<3>())).normalized();
    x.set_nu(nu0 + dt * a0);
    DynamicsInputs in_end = in;
    if (in.tau_staged) in_end.tau_B = in.tau_B_end;
    const Vector6d a1 = acceleration(x, in_end, dt);
    x.set_nu(nu0 + 0.5 * dt * (a0 + a1));
    return;
  }
  // Classic RK4 on (p, q coefficients, nu); the quaternion is renormalised after the step.
  // Stage inputs: a staged force is evaluated at each stage's time (t0, t0 + dt/2, t0 + dt).
  DynamicsInputs in_half = in, in_end = in;
  if (in.tau_staged) {
    in_half.tau_B = in.tau_B_half;
    in_end.tau_B = in.tau_B_end;
  }
  auto derivative = [&](const RigidBodyState& s, double h) {
    const DynamicsInputs& in_h = h == 0.0 ? in : (h < dt ? in_half : in_end);
    Derivative d;
    const Eigen::Matrix3d R = s.q_WB.normalized().toRotationMatrix();
    d.p_dot = R * s.v_WB_B;
    const Eigen::Quaterniond omega(0.0, s.w_WB_B.x(), s.w_WB_B.y(), s.w_WB_B.z());
    d.q_dot = 0.5 * (s.q_WB * omega).coeffs();
    d.nu_dot = acceleration(s, R, in_h, h);
    return d;
  };
  auto advance = [&](const RigidBodyState& s, const Derivative& d, double h) {
    RigidBodyState out;
    out.p_WB_W = s.p_WB_W + h * d.p_dot;
    out.q_WB.coeffs() = s.q_WB.coeffs() + h * d.q_dot;
    out.v_WB_B = s.v_WB_B + h * d.nu_dot.head<3>();
    out.w_WB_B = s.w_WB_B + h * d.nu_dot.tail<3>();
    return out;
  };
  const Derivative k1 = derivative(x, 0.0);
  const Derivative k2 = derivative(advance(x, k1, 0.5 * dt), 0.5 * dt);
  const Derivative k3 = derivative(advance(x, k2, 0.5 * dt), 0.5 * dt);
  const Derivative k4 = derivative(advance(x, k3, dt), dt);
  const double w = dt / 6.0;
  x.p_WB_W += w * (k1.p_dot + 2.0 * k2.p_dot + 2.0 * k3.p_dot + k4.p_dot);
  x.q_WB.coeffs() += w * (k1.q_dot + 2.0 * k2.q_dot + 2.0 * k3.q_dot + k4.q_dot);
  x.q_WB.normalize();
  x.set_nu(x.nu() + w * (k1.nu_dot + 2.0 * k2.nu_dot + 2.0 * k3.nu_dot + k4.nu_dot));
}

// ---------------------------------------------------------------------------------------------
// Thrusters

ThrusterBank::ThrusterBank(const std::vector<ThrusterParams>& thrusters) {
  const int n = static_cast<int>(thrusters.size());
  if (n > kMaxThrusters) {
    throw ConfigError("thrusters: at most " + std::to_string(kMaxThrusters) + " supported (got " + std::to_string(n) +
                      ")");
  }
  B_.resize(6, n);
  gain_fwd_.resize(n);
  gain_rev_.resize(n);
  tc_.resize(n);
  alpha_.resize(n);
  decay_half_.resize(n);
  u_f_.setZero(n);
  thrust_.setZero(n);
  mean_thrust_.setZero(n);
  u_f0_.setZero(n);
  u_.setZero(n);
  for (int i = 0; i < n; ++i) {
    const ThrusterParams& t = thrusters[static_cast<std::size_t>(i)];
    const double len = t.direction_B.norm();
    if (!(len > 1e-9)) throw ConfigError("thrusters[" + std::to_string(i) + "].direction has zero length");
    const Eigen::Vector3d n_B = t.direction_B / len;
    B_.col(i) << n_B, t.position_B.cross(n_B);
    gain_fwd_(i) = t.max_forward_thrust();
    gain_rev_(i) = t.max_reverse_thrust();
    tc_(i) = t.time_constant;
  }
}

void ThrusterBank::reset() {
  u_f_.setZero();
  thrust_.setZero();
  wrench_.setZero();
  mean_thrust_.setZero();
  u_f0_.setZero();
  u_.setZero();
}

Vector6d ThrusterBank::wrench_at_B(double h) const {
  ThrusterVector T(size());
  const bool half = h == 0.5 * alpha_dt_;  // the integrator's midpoint: e^(-h/t_c) kept from step()
  for (int i = 0; i < size(); ++i) {
    const double uf = u_(i) + (u_f0_(i) - u_(i)) * (half ? decay_half_(i) : std::exp(-h / tc_(i)));
    T(i) = uf >= 0.0 ? gain_fwd_(i) * uf : gain_rev_(i) * uf;
  }
  return B_ * T;
}

void ThrusterBank::step(double dt, const ThrusterVector& u) {
  if (dt != alpha_dt_) {  // the step size rarely changes: its decays are computed once
    for (int i = 0; i < size(); ++i) {
      alpha_(i) = 1.0 - std::exp(-dt / tc_(i));
      decay_half_(i) = std::exp(-(0.5 * dt) / tc_(i));
    }
    alpha_dt_ = dt;
  }
  for (int i = 0; i < size(); ++i) {
    const double u0 = u_f_(i), ui = u(i), tc = tc_(i);
    const auto gain = [&](double v) { return v >= 0.0 ? gain_fwd_(i) : gain_rev_(i); };
    // Integral of u_f over [a, b] within the step: u (b - a) + (u0 - u) t_c (e^(-a/t_c) - e^(-b/t_c)).
    const auto integral = [&](double a, double b, double e_a, double e_b) {
      return ui * (b - a) + (u0 - ui) * tc * (e_a - e_b);
    };
    const double e_dt = 1.0 - alpha_(i);  // e^(-dt/t_c)
    u_f0_(i) = u0;
    u_(i) = ui;
    u_f_(i) = u0 + alpha_(i) * (ui - u0);
    thrust_(i) = gain(u_f_(i)) * u_f_(i);
    if ((u0 > 0.0 && u_f_(i) < 0.0) || (u0 < 0.0 && u_f_(i) > 0.0)) {
      // u_f is monotonic and crosses zero once, at e^(-t*/t_c) = -u / (u0 - u).
      const double e_star = -ui / (u0 - ui);
      const double t_star = -tc * std::log(e_star);
      mean_thrust_(i) =
          (gain(u0) * integral(0.0, t_star, 1.0, e_star) + gain(ui) * integral(t_star, dt, e_star, e_dt)) / dt;
    } else {
      const double mean_u = integral(0.0, dt, 1.0, e_dt) / dt;
      mean_thrust_(i) = gain(u0 != 0.0 ? u0 : ui) * mean_u;
    }
  }
  wrench_ = B_ * thrust_;
}

}  // namespace unav::physics
