#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "unav_common/so3.hpp"
#include "unav_localization/imu_preintegration.hpp"

namespace {

using namespace unav::common;        // ExpSO3, LogSO3
using namespace unav::localization;  // ImuPreintegration and its types

const Eigen::Vector3d kGravity(0.0, 0.0, 9.81);  // NED

// A vehicle turning at a constant body rate while its position follows smooth curves: the state
// and the ideal IMU samples (angular rate, specific force) in closed form.
struct Trajectory {
  Eigen::Matrix3d R0 = ExpSO3(Eigen::Vector3d(0.2, -0.1, 0.7));
  Eigen::Vector3d w_B{0.1, -0.2, 0.3};
  NavState At(double t) const {
    NavState s;
    s.R_WB = R0 * ExpSO3(w_B * t);
    s.p_W = Eigen::Vector3d(std::sin(t), std::cos(2.0 * t), 0.5 * t * t);
    s.v_W = Eigen::Vector3d(std::cos(t), -2.0 * std::sin(2.0 * t), t);
    return s;
  }
  Eigen::Vector3d Accel(double t) const { return {-std::sin(t), -4.0 * std::cos(2.0 * t), 1.0}; }
  Eigen::Vector3d SpecificForce(double t) const { return At(t).R_WB.transpose() * (Accel(t) - kGravity); }
};

// Preintegrates [t0, t0 + T] with samples at the start of each step of dt.
ImuPreintegration Preintegrate(const Trajectory& tr, double t0, double T, double dt, const ImuBias& bias = {},
                               const ImuBias& sensor_bias = {}) {
  ImuPreintegration pre(bias);
  const int n = static_cast<int>(std::lround(T / dt));
  for (int k = 0; k < n; ++k) {
    const double t = t0 + k * dt;
    pre.Integrate(tr.w_B + sensor_bias.gyro, tr.SpecificForce(t) + sensor_bias.accel, dt);
  }
  return pre;
}

TEST(ImuPreintegration, ConstantRateGivesTheExactRotationAndFreeFallNoVelocityChange) {
  // Turning at w with zero specific force (free fall): dR = Exp(w T) exactly (each step is an
  // exact exponential), dv = dp = 0; the prediction then falls with gravity: v = g T, p = g T^2 / 2.
  ImuPreintegration pre;
  const Eigen::Vector3d w(0.4, -0.3, 1.1);
  for (int k = 0; k < 500; ++k) pre.Integrate(w, Eigen::Vector3d::Zero(), 0.002);
  EXPECT_NEAR(pre.dt(), 1.0, 1e-12);
  EXPECT_LT((pre.delta_R() - ExpSO3(w * 1.0)).norm(), 1e-12);
  EXPECT_LT(pre.delta_v().norm(), 1e-15);
  EXPECT_LT(pre.delta_p().norm(), 1e-15);
  const NavState j = pre.Predict(NavState{}, ImuBias{}, kGravity);
  EXPECT_LT((j.v_W - kGravity).norm(), 1e-12);
  EXPECT_LT((j.p_W - 0.5 * kGravity).norm(), 1e-12);
}

TEST(ImuPreintegration, ConstantSpecificForceWithoutRotationIsIntegratedExactly) {
  // dv = a T and dp = a T^2 / 2 hold exactly for the Euler scheme with the half-step term.
  ImuPreintegration pre;
  const Eigen::Vector3d a(0.5, -1.0, 2.0);
  for (int k = 0; k < 300; ++k) pre.Integrate(Eigen::Vector3d::Zero(), a, 0.01);
  EXPECT_LT((pre.delta_v() - a * 3.0).norm(), 1e-12);
  EXPECT_LT((pre.delta_p() - a * 4.5).norm(), 1e-11);
  // A vehicle holding depth measures -g: the prediction stays where it was.
  ImuPreintegration hold;
  for (int k = 0; k < 100; ++k) hold.Integrate(Eigen::Vector3d::Zero(), -kGravity, 0.01);
  const NavState j = hold.Predict(NavState{}, ImuBias{}, kGravity);
  EXPECT_LT(j.p_W.norm() + j.v_W.norm(), 1e-12);
}

TEST(ImuPreintegration, PredictsAFlownTrajectoryWithFirstOrderConvergence) {
  // Euler integration of samples held over each step is first order: the error of the predicted
  // state after 2 s halves when the step halves. At 1 kHz (our IMU's rate is 200 Hz; this is the
  // scheme's accuracy, not a noise test) the position is within a few mm.
  const Trajectory tr;
  const double t0 = 0.3, T = 2.0;
  auto error = [&](double dt) {
    const NavState j = Preintegrate(tr, t0, T, dt).Predict(tr.At(t0), ImuBias{}, kGravity);
    const NavState truth = tr.At(t0 + T);
    return Eigen::Vector3d(LogSO3(truth.R_WB.transpose() * j.R_WB).norm(), (j.v_W - truth.v_W).norm(),
                           (j.p_W - truth.p_W).norm());
  };
  const Eigen::Vector3d e1 = error(1e-3), e2 = error(5e-4);
  EXPECT_LT(e1(0), 1e-12);  // a constant body rate: the rotation is exact at any step
  EXPECT_LT(e1(1), 2e-2);
  EXPECT_LT(e1(2), 1e-2);
  EXPECT_NEAR(e1(1) / e2(1), 2.0, 0.1);
  EXPECT_NEAR(e1(2) / e2(2), 2.0, 0.1);
  // The residual of the true states is that same discretisation error, and zero for the prediction.
  const ImuPreintegration pre = Preintegrate(tr, t0, T, 5e-4);
  const NavState i = tr.At(t0);
  EXPECT_LT(pre.Residual(i, pre.Predict(i, ImuBias{}, kGravity), ImuBias{}, kGravity).norm(), 1e-12);
  EXPECT_LT(pre.Residual(i, tr.At(t0 + T), ImuBias{}, kGravity).norm(), 2e-2);
}

TEST(ImuPreintegration, BiasJacobiansCorrectTheDeltasToFirstOrder) {
  // The sensor has a bias the preintegration was not linearised at; correcting with the Jacobians
  // must match integrating again with the right bias up to second-order terms (< 1 % of the
  // change here), for gyro and accelerometer biases together.
  const Trajectory tr;
  ImuBias truth;
  truth.gyro = Eigen::Vector3d(2e-3, -1e-3, 3e-3);
  truth.accel = Eigen::Vector3d(0.05, -0.03, 0.08);
  const ImuPreintegration lin = Preintegrate(tr, 0.0, 1.5, 2e-3, ImuBias{}, truth);
  const ImuPreintegration again = Preintegrate(tr, 0.0, 1.5, 2e-3, truth, truth);
  const double change_R = LogSO3(lin.delta_R().transpose() * again.delta_R()).norm();
  const double change_v = (lin.delta_v() - again.delta_v()).norm();
  const double change_p = (lin.delta_p() - again.delta_p()).norm();
  ASSERT_GT(change_R, 1e-3);
  ASSERT_GT(change_v, 1e-2);
  EXPECT_LT(LogSO3(lin.CorrectedDeltaR(truth).transpose() * again.delta_R()).norm(), 0.01 * change_R);
  EXPECT_LT((lin.CorrectedDeltaV(truth) - again.delta_v()).norm(), 0.01 * change_v);
  EXPECT_LT((lin.CorrectedDeltaP(truth) - again.delta_p()).norm(), 0.01 * change_p);
}

TEST(ImuPreintegration, CovarianceMatchesMonteCarloNoise) {
  // 1000 noisy preintegrations of 1 s at 200 Hz: the spread of the deltas' errors against the
  // noise-free ones matches the propagated covariance. With 1000 samples a variance estimate has
  // a relative standard deviation of sqrt(2 / 1000) = 4.5 %: 15 % is over 3 sigma, and a
  // correlation's standard deviation is at most 1 / sqrt(1000) = 0.032: 0.1 is 3 sigma (fixed
  // seed). The gyro noise is large enough that rotation errors dominate the velocity and position
  // errors (through the ~10 m/s^2 specific force), so their coupling terms are checked too.
  const Trajectory tr;
  ImuNoise noise;
  noise.gyro_noise_density = 1e-2;
  noise.accel_noise_density = 1e-2;
  const double dt = 0.005;
  const int steps = 200, runs = 1000;
  ImuPreintegration clean({}, noise);
  for (int k = 0; k < steps; ++k) clean.Integrate(tr.w_B, tr.SpecificForce(k * dt), dt);
  std::mt19937 rng(7);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double sg = noise.gyro_noise_density / std::sqrt(dt), sa = noise.accel_noise_density / std::sqrt(dt);
  Matrix9d empirical = Matrix9d::Zero();
  for (int r = 0; r < runs; ++r) {
    ImuPreintegration noisy({}, noise);
    for (int k = 0; k < steps; ++k) {
      const Eigen::Vector3d ng(n01(rng), n01(rng), n01(rng)), na(n01(rng), n01(rng), n01(rng));
      noisy.Integrate(tr.w_B + sg * ng, tr.SpecificForce(k * dt) + sa * na, dt);
    }
    Vector9d e;
    e.segment<3>(0) = LogSO3(noisy.delta_R().transpose() * clean.delta_R());
    e.segment<3>(3) = clean.delta_v() - noisy.delta_v();
    e.segment<3>(6) = clean.delta_p() - noisy.delta_p();
    empirical += e * e.transpose() / runs;
  }
  const Matrix9d& C = clean.covariance();
  for (int d = 0; d < 9; ++d) EXPECT_NEAR(empirical(d, d) / C(d, d), 1.0, 0.15) << "component " << d;
  for (int a = 0; a < 9; ++a)
    for (int b = 0; b < a; ++b)
      EXPECT_NEAR(empirical(a, b) / std::sqrt(empirical(a, a) * empirical(b, b)),
                  C(a, b) / std::sqrt(C(a, a) * C(b, b)), 0.1)
          << "correlation of components " << a << " and " << b;
}

TEST(ImuPreintegration, RefusesNonFiniteSamplesAndSteps) {
  ImuPreintegration pre;
  const Eigen::Vector3d ok(0.1, 0.2, 0.3);
  EXPECT_THROW(pre.Integrate(Eigen::Vector3d(NAN, 0, 0), ok, 0.01), std::invalid_argument);
  EXPECT_THROW(pre.Integrate(ok, Eigen::Vector3d(0, INFINITY, 0), 0.01), std::invalid_argument);
  EXPECT_THROW(pre.Integrate(ok, ok, 0.0), std::invalid_argument);
  EXPECT_THROW(pre.Integrate(ok, ok, -0.01), std::invalid_argument);
  EXPECT_THROW(pre.Integrate(ok, ok, NAN), std::invalid_argument);
  EXPECT_EQ(pre.dt(), 0.0);  // nothing was integrated
  ImuNoise bad;
  bad.accel_noise_density = -1.0;
  EXPECT_THROW(ImuPreintegration({}, bad), std::invalid_argument);
}

}  // namespace
