// Analytic Jacobians of the velocity Verlet step (VehicleDynamics::verlet_step_jacobians): what
// an optimising controller linearises its predictions with. Tangent coordinates: position in
// NED, attitude perturbed on the right (body axes), nu as it is.
#include <algorithm>
#include <cmath>

#include "unav_physics/dynamics.hpp"

namespace unav::physics {
namespace {

using Matrix3x18 = Eigen::Matrix<double, 3, 18>;
using Matrix6x18 = Eigen::Matrix<double, 6, 18>;

// Right Jacobian of SO(3): Exp(phi + d) ~ Exp(phi) Exp(Jr(phi) d).
Eigen::Matrix3d right_jacobian(const Eigen::Vector3d& phi) {
  const double th = phi.norm();
  const Eigen::Matrix3d S = skew(phi);
  if (th < 1e-6) return Eigen::Matrix3d::Identity() - 0.5 * S + (1.0 / 6.0) * S * S;
  const double th2 = th * th;
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(th)) / th2 * S + (th - std::sin(th)) / (th2 * th) * S * S;
}

}  // namespace

Matrix6d VehicleDynamics::coriolis_jacobian(const Blocks& b, const Eigen::Vector3d& v1, const Eigen::Vector3d& v2) {
  // out = [v2 x a1; v1 x a1 + v2 x a2], a1 = M11 v1 + M12 v2, a2 = M21 v1 + M22 v2; d(a x b) = a x db - b x da.
  const Eigen::Vector3d a1 = b.M11 * v1 + b.M12 * v2;
  const Eigen::Vector3d a2 = b.M21 * v1 + b.M22 * v2;
  const Eigen::Matrix3d S1 = skew(v1), S2 = skew(v2);
  Matrix6d J;
  J.topLeftCorner<3, 3>() = S2 * b.M11;
  J.topRightCorner<3, 3>() = -skew(a1) + S2 * b.M12;
  J.bottomLeftCorner<3, 3>() = -skew(a1) + S1 * b.M11 + S2 * b.M21;
  J.bottomRightCorner<3, 3>() = S1 * b.M12 - skew(a2) + S2 * b.M22;
  return J;
}

void VehicleDynamics::acceleration_jacobians(const Eigen::Matrix3d& R_WB, double z, const Vector6d& nu,
                                             Eigen::Matrix<double, 6, 3>* d_theta, Vector6d* d_z,
                                             Matrix6d* d_nu) const {
  // rhs = tau - C_RB(nu) nu - C_A(nu) nu - D(nu) nu - g(R, z); acceleration = M^-1 rhs.
  const Eigen::Vector3d v = nu.head<3>(), w = nu.tail<3>();
  Matrix6d dD;
  if (damping_diagonal_) {
    dD = (D_l_.diagonal().array() + 2.0 * D_q_.diagonal().array() * nu.array().abs()).matrix().asDiagonal();
  } else {
    dD = D_l_ + D_q_ * (2.0 * nu.cwiseAbs()).asDiagonal();
  }
  *d_nu = -M_inv_ * (coriolis_jacobian(rb_, v, w) + coriolis_jacobian(a_, v, w) + dD);
  // g = [-(W - B f) down; -(W r_g - B f r_b) x down], down = R^T e_z: d down / d theta = down x.
  const double h = params_.height;
  const double s = (z + 0.5 * h) / h;
  const double f = std::clamp(s, 0.0, 1.0);
  const Eigen::Vector3d down = R_WB.row(2).transpose();
  const Eigen::Matrix3d Sd = skew(down);
  Eigen::Matrix<double, 6, 3> dg;
  dg.topRows<3>() = -(W_ - B_ * f) * Sd;
  dg.bottomRows<3>() = -(W_ * skew(params_.r_g_B) - B_ * f * skew(params_.r_b_B)) * Sd;
  *d_theta = -M_inv_ * dg;
  // Buoyancy grows with the submerged fraction f(z) between the surface and one height below.
  const double df = (s > 0.0 && s < 1.0) ? 1.0 / h : 0.0;
  Vector6d dgz;
  dgz.head<3>() = B_ * df * down;
  dgz.tail<3>() = B_ * df * params_.r_b_B.cross(down);
  *d_z = -M_inv_ * dgz;
}

void VehicleDynamics::verlet_step_jacobians(RigidBodyState& x, double dt, const Vector6d& tau_B,
                                            Eigen::Matrix<double, 12, 12>* A, Eigen::Matrix<double, 12, 6>* B) const {
  // The step, as step() computes it (same statements, so the same state bit for bit).
  DynamicsInputs in;
  in.tau_B = tau_B;
  const RigidBodyState x0 = x;
  const Eigen::Matrix3d R0 = x.q_WB.toRotationMatrix();
  const Vector6d a0 = acceleration(x, R0, in, 0.0);
  const Vector6d nu0 = x.nu();
  const Eigen::Vector3d dp_B = dt * x.v_WB_B + 0.5 * dt * dt * (a0.head<3>() + x.w_WB_B.cross(x.v_WB_B));
  x.p_WB_W += R0 * dp_B;
  const Eigen::Vector3d phi = dt * x.w_WB_B + 0.5 * dt * dt * a0.tail<3>();
  const Eigen::Quaterniond dq = exp_rotation(phi);
  x.q_WB = (x.q_WB * dq).normalized();
  x.set_nu(nu0 + dt * a0);
  const Vector6d nu_p = x.nu();
  const Vector6d a1 = acceleration(x, in, dt);
  x.set_nu(nu0 + 0.5 * dt * (a0 + a1));
  if (A == nullptr && B == nullptr) return;

  // Chain rule over the 18 inputs [dp (W); dtheta (B); dnu; dtau].
  Matrix3x18 Dp = Matrix3x18::Zero(), Dth0 = Matrix3x18::Zero();
  Matrix6x18 Dnu0 = Matrix6x18::Zero(), Dtau = Matrix6x18::Zero();
  Dp.block<3, 3>(0, 0).setIdentity();
  Dth0.block<3, 3>(0, 3).setIdentity();
  Dnu0.block<6, 6>(0, 6).setIdentity();
  Dtau.block<6, 6>(0, 12).setIdentity();
  Eigen::Matrix<double, 6, 3> J_th;
  Vector6d J_z;
  Matrix6d J_nu;
  acceleration_jacobians(R0, x0.p_WB_W.z(), nu0, &J_th, &J_z, &J_nu);
  const Matrix6x18 Da0 = J_th * Dth0 + J_z * Dp.row(2) + J_nu * Dnu0 + M_inv_ * Dtau;
  const Eigen::Vector3d v0 = x0.v_WB_B, w0 = x0.w_WB_B;
  const Matrix3x18 Dv = Dnu0.topRows<3>(), Dw = Dnu0.bottomRows<3>();
  const Matrix3x18 DdpB = dt * Dv + 0.5 * dt * dt * (Da0.topRows<3>() - skew(v0) * Dw + skew(w0) * Dv);
  const Matrix3x18 Dp1 = Dp - R0 * skew(dp_B) * Dth0 + R0 * DdpB;
  const Matrix3x18 Dphi = dt * Dw + 0.5 * dt * dt * Da0.bottomRows<3>();
  // R1 Exp(dtheta1) = R0 Exp(dtheta0) Exp(phi + dphi) -> dtheta1 = Exp(phi)^T dtheta0 + Jr(phi) dphi.
  const Matrix3x18 Dth1 = dq.toRotationMatrix().transpose() * Dth0 + right_jacobian(phi) * Dphi;
  const Matrix6x18 Dnup = Dnu0 + dt * Da0;
  acceleration_jacobians(x.q_WB.toRotationMatrix(), x.p_WB_W.z(), nu_p, &J_th, &J_z, &J_nu);
  const Matrix6x18 Da1 = J_th * Dth1 + J_z * Dp1.row(2) + J_nu * Dnup + M_inv_ * Dtau;
  const Matrix6x18 Dnu1 = Dnu0 + 0.5 * dt * (Da0 + Da1);
  if (A != nullptr) {
    A->topRows<3>() = Dp1.leftCols<12>();
    A->middleRows<3>(3) = Dth1.leftCols<12>();
    A->bottomRows<6>() = Dnu1.leftCols<12>();
  }
  if (B != nullptr) {
    B->topRows<3>() = Dp1.rightCols<6>();
    B->middleRows<3>(3) = Dth1.rightCols<6>();
    B->bottomRows<6>() = Dnu1.rightCols<6>();
  }
}

}  // namespace unav::physics
