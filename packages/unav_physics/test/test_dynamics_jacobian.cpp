// The velocity Verlet step's analytic Jacobians (VehicleDynamics::verlet_step_jacobians) against
// central differences of the step itself, and the step against step().
#include <gtest/gtest.h>

#include <random>

#include "unav_physics/dynamics.hpp"

namespace up = unav::physics;

namespace {

using Matrix12d = Eigen::Matrix<double, 12, 12>;
using Matrix12x6 = Eigen::Matrix<double, 12, 6>;
using Vector12d = Eigen::Matrix<double, 12, 1>;

up::RigidBodyState perturbed(const up::RigidBodyState& x, const Vector12d& d) {
  up::RigidBodyState y = x;
  y.p_WB_W += d.head<3>();
  y.q_WB = x.q_WB * up::exp_rotation(d.segment<3>(3));
  y.set_nu(x.nu() + d.tail<6>());
  return y;
}

Vector12d difference(const up::RigidBodyState& y, const up::RigidBodyState& x) {  // y minus x, tangent at x
  Vector12d d;
  d.head<3>() = y.p_WB_W - x.p_WB_W;
  const Eigen::AngleAxisd aa(x.q_WB.conjugate() * y.q_WB);
  d.segment<3>(3) = aa.angle() * aa.axis();
  if (aa.angle() > M_PI) d.segment<3>(3) -= 2.0 * M_PI * aa.axis();
  d.tail<6>() = y.nu() - x.nu();
  return d;
}

up::RigidBodyState stepped(const up::VehicleDynamics& dyn, up::RigidBodyState x, double dt, const up::Vector6d& tau) {
  up::DynamicsInputs in;
  in.tau_B = tau;
  dyn.step(x, dt, in, up::Integrator::kVelocityVerlet);
  return x;
}

// A state with speeds and rates of a vehicle in manoeuvre (0.5 m/s, 30 deg/s), tilted.
up::RigidBodyState random_state(std::mt19937& rng, double depth) {
  std::normal_distribution<double> n(0.0, 1.0);
  up::RigidBodyState x;
  x.p_WB_W = Eigen::Vector3d(3.0 * n(rng), 3.0 * n(rng), depth);
  x.q_WB = up::exp_rotation(Eigen::Vector3d(0.3 * n(rng), 0.3 * n(rng), 2.0 * n(rng)));
  x.v_WB_B = 0.5 * Eigen::Vector3d(n(rng), n(rng), n(rng));
  x.w_WB_B = 0.5 * Eigen::Vector3d(n(rng), n(rng), n(rng));
  return x;
}

void check_against_central_differences(const up::VehicleDynamics& dyn, const up::RigidBodyState& x0,
                                       const up::Vector6d& tau, double dt) {
  up::RigidBodyState x = x0;
  Matrix12d A;
  Matrix12x6 B;
  dyn.verlet_step_jacobians(x, dt, tau, &A, &B);
  const up::RigidBodyState x1 = stepped(dyn, x0, dt, tau);
  // The same state as step(), bit for bit: the rollout and its linearisation agree exactly.
  EXPECT_EQ(x.p_WB_W, x1.p_WB_W);
  EXPECT_EQ(x.q_WB.coeffs(), x1.q_WB.coeffs());
  EXPECT_EQ(x.nu(), x1.nu());
  // Central differences: truncation O(h^2) ~ 1e-12 and round-off ~1e-16 / h ~ 1e-10 relative, so
  // 1e-7 (absolute, plus relative to the entry) bounds a wrong term by orders of magnitude.
  const double h_x = 1e-5, h_u = 1e-3;  // states O(1) in SI, wrenches O(10) N
  for (int j = 0; j < 12; ++j) {
    const Vector12d e = Vector12d::Unit(j);
    const Vector12d col = (difference(stepped(dyn, perturbed(x0, h_x * e), dt, tau), x1) -
                           difference(stepped(dyn, perturbed(x0, -h_x * e), dt, tau), x1)) /
                          (2.0 * h_x);
    for (int i = 0; i < 12; ++i)
      EXPECT_NEAR(A(i, j), col(i), 1e-7 * (1.0 + std::abs(col(i)))) << "A(" << i << ", " << j << ")";
  }
  for (int j = 0; j < 6; ++j) {
    const up::Vector6d e = up::Vector6d::Unit(j);
    const Vector12d col =
        (difference(stepped(dyn, x0, dt, tau + h_u * e), x1) - difference(stepped(dyn, x0, dt, tau - h_u * e), x1)) /
        (2.0 * h_u);
    for (int i = 0; i < 12; ++i)
      EXPECT_NEAR(B(i, j), col(i), 1e-7 * (1.0 + std::abs(col(i)))) << "B(" << i << ", " << j << ")";
  }
}

}  // namespace

TEST(VerletJacobians, MatchCentralDifferencesOfTheStep) {
  const up::VehicleDynamics dyn(up::bluerov2_heavy_params());
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int k = 0; k < 20; ++k) {
    up::Vector6d tau;
    for (int i = 0; i < 6; ++i) tau(i) = (i < 3 ? 40.0 : 8.0) * n(rng);
    // The MPC's model step (50 ms) and the physics step (1 ms).
    check_against_central_differences(dyn, random_state(rng, 10.0), tau, k % 2 == 0 ? 0.05 : 0.001);
  }
}

TEST(VerletJacobians, BuoyancyNearTheSurfaceEntersThroughTheDepth) {
  // Within one vehicle height of the surface the buoyancy depends on z: A's depth column is not
  // the unit column it is below.
  const up::VehicleDynamics dyn(up::bluerov2_heavy_params());
  std::mt19937 rng(8);
  const up::RigidBodyState x0 = random_state(rng, 0.05);
  check_against_central_differences(dyn, x0, up::Vector6d::Zero(), 0.05);
  up::RigidBodyState x = x0;
  Matrix12d A;
  dyn.verlet_step_jacobians(x, 0.05, up::Vector6d::Zero(), &A, nullptr);
  EXPECT_GT(std::abs(A(8, 2)), 1e-3);  // heave velocity responds to depth
}

TEST(VerletJacobians, NonDiagonalInertiaAndDamping) {
  // Off-diagonal added mass and damping take the general branches.
  up::VehicleParams p = up::bluerov2_heavy_params();
  p.added_mass(0, 4) = p.added_mass(4, 0) = 0.8;
  p.added_mass(1, 3) = p.added_mass(3, 1) = -0.5;
  p.linear_damping(0, 2) = 1.5;
  p.quadratic_damping(1, 5) = 2.0;
  const up::VehicleDynamics dyn(p);
  std::mt19937 rng(9);
  for (int k = 0; k < 5; ++k)
    check_against_central_differences(dyn, random_state(rng, 8.0), up::Vector6d::Constant(5.0), 0.05);
}
