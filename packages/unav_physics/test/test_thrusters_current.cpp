// Thrusters, allocation, currents and command handling.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "unav_physics/simulator.hpp"

namespace up = unav::physics;

namespace {

const std::string kConfig = UNAV_CONFIG_DIR;

up::SimulatorOptions no_timeout() {
  up::SimulatorOptions o;
  o.command_timeout = 0.0;
  return o;
}

TEST(Thrusters, DefaultT200GivesAbout40N) {
  // REFERENCE.md 1: C_T rho w_max^2 D^4 = 0.344 * 1025 * 58.33^2 * 0.076^4 = 40.0 N.
  const up::ThrusterParams t;
  EXPECT_NEAR(t.max_forward_thrust(), 40.0, 0.1);
  EXPECT_DOUBLE_EQ(t.max_reverse_thrust(), t.max_forward_thrust());
}

TEST(Thrusters, LagReaches63PercentAfterTimeConstant) {
  // First-order lag: u_f(t_c) = 1 - e^-1 = 0.632 for a unit step; the exact discretisation makes
  // it exact up to round-off at every multiple of dt.
  up::ThrusterBank bank(up::bluerov2_heavy_params().thrusters);
  up::ThrusterVector u = up::ThrusterVector::Zero(bank.size());
  u(0) = 1.0;
  const double dt = 1e-3, tc = 0.1;
  for (int k = 0; k < static_cast<int>(std::lround(tc / dt)); ++k) bank.step(dt, u);
  EXPECT_NEAR(bank.filtered_command()(0), 1.0 - std::exp(-1.0), 1e-9);
  EXPECT_NEAR(bank.thrust()(0), (1.0 - std::exp(-1.0)) * 40.0, 0.1);
  EXPECT_EQ(bank.filtered_command()(1), 0.0);
}

TEST(Thrusters, MeanThrustIsTheExactIntegralOfTheLagOverTheStep) {
  // u_f(t) = u + (u_f0 - u) e^(-t/t_c); its mean over [0, dt] is u + (u_f0 - u)(t_c/dt)(1 - e^(-dt/t_c)).
  // Checked against a 100k-point midpoint quadrature of T(u_f(t)), including a step that crosses
  // zero thrust with different forward and reverse gains (quadrature error ~1e-10 relative).
  up::VehicleParams v = up::bluerov2_heavy_params();
  v.thrusters[0].C_T_reverse = 0.6 * v.thrusters[0].C_T;
  up::ThrusterBank bank(v.thrusters);
  const double tc = v.thrusters[0].time_constant, gf = v.thrusters[0].max_forward_thrust(),
               gr = v.thrusters[0].max_reverse_thrust();
  const double dt = 0.05;
  auto quadrature = [&](double u0, double u) {
    const int n = 100000;
    double sum = 0.0;
    for (int k = 0; k < n; ++k) {
      const double t = (k + 0.5) * dt / n, uf = u + (u0 - u) * std::exp(-t / tc);
      sum += (uf >= 0.0 ? gf : gr) * uf;
    }
    return sum / n;
  };
  up::ThrusterVector u = up::ThrusterVector::Zero(bank.size());
  u(0) = 1.0;
  bank.step(dt, u);  // 0 -> rising towards 1
  EXPECT_NEAR(bank.mean_thrust()(0), quadrature(0.0, 1.0), 1e-7);
  const double uf1 = bank.filtered_command()(0);
  EXPECT_NEAR(uf1, 1.0 - std::exp(-dt / tc), 1e-12);
  EXPECT_LT(bank.mean_thrust()(0), bank.thrust()(0));  // the end value leads the mean
  u(0) = -1.0;
  bank.step(dt, u);  // crosses zero within the step (uf1 ~ 0.39, t* = t_c ln(1 + uf1) ~ 0.033 s)
  EXPECT_NEAR(bank.mean_thrust()(0), quadrature(uf1, -1.0), 1e-7);
  EXPECT_LT(bank.filtered_command()(0), 0.0);
}

TEST(Thrusters, WrenchIsSumOfForcesAndMoments) {
  up::ThrusterBank bank(up::bluerov2_heavy_params().thrusters);
  up::ThrusterVector u = up::ThrusterVector::Zero(bank.size());
  u(4) = 1.0;  // T5 at (0.12, 0.218, 0) pushing up (-z)
  for (int k = 0; k < 5000; ++k) bank.step(1e-3, u);
  const double T = bank.thrust()(4);
  const Eigen::Vector3d r(0.12, 0.218, 0.0), n(0, 0, -1);
  up::Vector6d expected;
  expected << n * T, r.cross(n * T);
  EXPECT_LT((bank.wrench_B() - expected).norm(), 1e-9);
}

TEST(Thrusters, HorizontalThrustersAloneMakeAPitchMoment) {
  // REFERENCE.md 2: thrusters 8.5 cm below the CG pitch the vehicle: half forward command on the
  // four horizontals (T3, T4 point backwards, so they run reversed) gives a surge force of
  // 4 * 20 * 0.7071 = 56.6 N and a pitch moment 56.6 * 0.085 = 4.8 N m.
  up::ThrusterBank bank(up::bluerov2_heavy_params().thrusters);
  up::ThrusterVector u = up::ThrusterVector::Zero(bank.size());
  u.head<4>() << 0.5, 0.5, -0.5, -0.5;
  for (int k = 0; k < 5000; ++k) bank.step(1e-3, u);
  EXPECT_NEAR(bank.wrench_B()(0), 56.6, 0.2);
  EXPECT_NEAR(bank.wrench_B()(4), 56.6 * 0.085, 0.05);
}

TEST(Thrusters, PseudoInverseSurgeAllocationDrivesHeavyStraight) {
  // u = pinv(B diag(T_max)) [F 0 0 0 0 0]: a pure surge force, the vertical thrusters cancelling
  // the horizontals' pitch moment. By symmetry nothing may yaw, sway, heave or pitch (bounds are
  // round-off), and the speed reaches the root of X_u u + X_uu u^2 = F (0.5%).
  up::RigidBodyState x0;
  x0.p_WB_W.z() = 10.0;
  up::Simulator sim(up::bluerov2_heavy_params(), no_timeout(), nullptr, nullptr, x0);
  const auto& B = sim.thrusters().thruster_matrix();
  const Eigen::MatrixXd A = Eigen::MatrixXd(B) * Eigen::VectorXd(sim.thrusters().max_forward_thrust()).asDiagonal();
  const Eigen::MatrixXd pinv = A.completeOrthogonalDecomposition().pseudoInverse();
  const double F = 20.0;
  up::Vector6d tau = up::Vector6d::Zero();
  tau(0) = F;
  const Eigen::VectorXd u = pinv * tau;
  ASSERT_LE(u.cwiseAbs().maxCoeff(), 1.0);
  ASSERT_LT((A * u - tau).norm(), 1e-9);
  EXPECT_EQ(sim.set_command(0.0, std::vector<double>(u.data(), u.data() + u.size())), up::CommandStatus::kAccepted);
  sim.advance_to(20.0);
  const Eigen::Vector3d rpy = up::roll_pitch_yaw(sim.state().q_WB);
  EXPECT_LT(rpy.cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT(std::abs(sim.state().p_WB_W.y()), 1e-9);
  EXPECT_LT(std::abs(sim.state().p_WB_W.z() - 10.0), 1e-9);
  const double expected = (-13.7 + std::sqrt(13.7 * 13.7 + 4 * 141.0 * F)) / (2 * 141.0);
  EXPECT_NEAR(sim.state().v_WB_B.x(), expected, 0.005 * expected);
}

TEST(Thrusters, AsymmetricReverseThrustFromConfig) {
  // config/vehicles/bluerov2.yaml: T200 at 16 V, 51.5 N forward, 40.2 N reverse.
  const up::VehicleParams v = up::load_vehicle(kConfig + "/vehicles/bluerov2.yaml");
  EXPECT_NEAR(v.thrusters[0].max_forward_thrust(), 51.5, 0.1);
  EXPECT_NEAR(v.thrusters[0].max_reverse_thrust(), 40.2, 0.1);
  up::ThrusterBank bank(v.thrusters);
  up::ThrusterVector u = up::ThrusterVector::Constant(bank.size(), -1.0);
  for (int k = 0; k < 5000; ++k) bank.step(1e-3, u);
  EXPECT_NEAR(bank.thrust()(0), -40.2, 0.1);
}

TEST(Commands, BadCommandsAreRejectedCountedAndNeverIntegrated) {
  up::RigidBodyState x0;
  x0.p_WB_W.z() = 10.0;  // fully submerged, neutral: only a command could move it
  up::Simulator sim(up::bluerov2_heavy_params(), no_timeout(), nullptr, nullptr, x0);
  std::vector<double> u(8, 0.0);
  u[2] = std::nan("");
  EXPECT_EQ(sim.set_command(0.0, u), up::CommandStatus::kRejectedNonFinite);
  u[2] = INFINITY;
  EXPECT_EQ(sim.set_command(0.0, u), up::CommandStatus::kRejectedNonFinite);
  EXPECT_EQ(sim.set_command(0.0, std::vector<double>(6, 0.5)), up::CommandStatus::kRejectedWrongLength);
  sim.advance_to(1.0);
  EXPECT_EQ(sim.thrusters().thrust().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(sim.state().nu().norm(), 0.0);
  EXPECT_EQ(sim.command_stats().rejected_non_finite, 2u);
  EXPECT_EQ(sim.command_stats().rejected_wrong_length, 1u);
  EXPECT_EQ(sim.command_stats().accepted, 0u);

  std::vector<double> big(8, 0.0);
  big[0] = 3.0;
  big[1] = -2.0;
  EXPECT_EQ(sim.set_command(1.0, big), up::CommandStatus::kClamped);
  sim.advance_to(3.0);
  EXPECT_NEAR(sim.thrusters().filtered_command()(0), 1.0, 1e-6);
  EXPECT_NEAR(sim.thrusters().filtered_command()(1), -1.0, 1e-6);
  EXPECT_EQ(sim.command_stats().clamped, 1u);
  EXPECT_EQ(sim.command_stats().accepted, 1u);
}

TEST(Commands, TimeoutFailsafeZeroesThrust) {
  up::SimulatorOptions o;
  o.command_timeout = 0.5;
  up::Simulator sim(up::bluerov2_heavy_params(), o);
  EXPECT_EQ(sim.set_command(0.0, std::vector<double>(8, 0.5)), up::CommandStatus::kAccepted);
  sim.advance_to(0.4);
  EXPECT_FALSE(sim.command_timed_out());
  EXPECT_GT(sim.thrusters().filtered_command()(0), 0.4);
  sim.advance_to(2.0);  // 1.5 s = 15 t_c after the timeout: u_f = 0.5 e^-15
  EXPECT_TRUE(sim.command_timed_out());
  EXPECT_LT(sim.thrusters().filtered_command().cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(sim.command_stats().timeouts, 1u);
  sim.set_command(sim.time(), std::vector<double>(8, 0.1));
  sim.step();
  EXPECT_FALSE(sim.command_timed_out());

  up::CommandTimeout t(2.0);
  t.on_command(1.0);
  EXPECT_FALSE(t.expired(2.9));
  EXPECT_TRUE(t.expired(3.1));
  EXPECT_FALSE(up::CommandTimeout(0.0).expired(1e9));
}

TEST(Currents, AnalyticModelsAndDerivatives) {
  const up::SinusoidalCurrent sine(Eigen::Vector3d(0.1, 0, 0), Eigen::Vector3d(0.2, 0.1, 0), 0.05, 0.3);
  const double t = 3.7, w = 2 * M_PI * 0.05;
  EXPECT_NEAR(sine.velocity_W(t).x(), 0.1 + 0.2 * std::sin(w * t + 0.3), 1e-15);
  const double h = 1e-5;  // central difference, error ~ h^2 * max|v'''| ~ 1e-12
  EXPECT_LT((sine.acceleration_W(t) - (sine.velocity_W(t + h) - sine.velocity_W(t - h)) / (2 * h)).norm(), 1e-8);
  const up::SumOfSinesCurrent sum(Eigen::Vector3d(0.05, 0, 0),
                                  {{Eigen::Vector3d(0.1, 0, 0), 0.01, 0.0}, {Eigen::Vector3d(0.03, 0.03, 0.01), 0.125, 1.0}});
  EXPECT_NEAR(sum.velocity_W(t).y(), 0.03 * std::sin(2 * M_PI * 0.125 * t + 1.0), 1e-15);
  EXPECT_LT((sum.acceleration_W(t) - (sum.velocity_W(t + h) - sum.velocity_W(t - h)) / (2 * h)).norm(), 1e-8);
}

TEST(Currents, GaussMarkovIsSeededAndHasItsStationaryStatistics) {
  const Eigen::Vector3d mean(0.2, 0.0, 0.0), sd(0.05, 0.1, 0.0);
  up::GaussMarkovCurrent a(mean, sd, 1.0, 42, mean), b(mean, sd, 1.0, 42, mean), c(mean, sd, 1.0, 43, mean);
  double sum = 0, sum2 = 0;
  const int n = 200000;  // dt = 0.05 s, T = 1 s: ~10 000 s, ~5000 correlation times
  for (int k = 0; k < n; ++k) {
    a.step(k * 0.05, 0.05);
    b.step(k * 0.05, 0.05);
    c.step(k * 0.05, 0.05);
    ASSERT_EQ(a.velocity_W(0).x(), b.velocity_W(0).x());
    const double e = a.velocity_W(0).y();
    sum += e;
    sum2 += e * e;
  }
  EXPECT_NE(a.velocity_W(0).x(), c.velocity_W(0).x());
  EXPECT_EQ(a.velocity_W(0).z(), 0.0);
  // ~5000 independent samples: the sample std has ~1% relative error; 5% bound.
  EXPECT_NEAR(std::sqrt(sum2 / n - (sum / n) * (sum / n)), 0.1, 0.005);
  EXPECT_NEAR(sum / n, 0.0, 0.01);
}

TEST(Currents, BundledConfigsLoad) {
  const auto constant = up::load_current(kConfig + "/water/currents/constant.yaml");
  EXPECT_LT((constant->velocity_W(12.0) - Eigen::Vector3d(0.2, 0.1, 0.0)).norm(), 1e-15);
  const auto sine = up::load_current(kConfig + "/water/currents/sinusoidal.yaml");
  EXPECT_NEAR(sine->velocity_W(5.0).x(), 0.1 + 0.1 * std::sin(2 * M_PI * 0.05 * 5.0), 1e-12);
  const auto sum = up::load_current(kConfig + "/water/currents/sum_of_sines.yaml");
  EXPECT_NEAR(sum->velocity_W(0.0).x(), 0.05 + 0.03 * std::sin(1.0) + 0.01 * std::sin(2.0), 1e-12);
  auto gm1 = up::load_current(kConfig + "/water/currents/gauss_markov.yaml");
  auto gm2 = up::load_current(kConfig + "/water/currents/gauss_markov.yaml");
  EXPECT_LT((gm1->velocity_W(0) - Eigen::Vector3d(0.15, 0.05, 0)).norm(), 1e-15);
  for (int k = 0; k < 100; ++k) {
    gm1->step(k * 0.1, 0.1);
    gm2->step(k * 0.1, 0.1);
  }
  EXPECT_EQ(gm1->velocity_W(10.0), gm2->velocity_W(10.0));
}

TEST(Currents, GaussMarkovRunsAreReproducible) {
  // Same config twice: bit-identical trajectories (no wall clock, seeded randomness).
  auto run = [] {
    up::SimulatorOptions o;
    o.command_timeout = 0.0;
    up::RigidBodyState x;
    x.p_WB_W.z() = 5.0;
    up::Simulator sim(up::bluerov2_heavy_params(), o, up::load_current(kConfig + "/water/currents/gauss_markov.yaml"),
                      nullptr, x);
    sim.advance_to(5.0);
    return sim.state().p_WB_W;
  };
  EXPECT_EQ(run(), run());
}

}  // namespace
