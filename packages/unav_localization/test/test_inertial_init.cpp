#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "unav_common/so3.hpp"
#include "unav_localization/inertial_init.hpp"

namespace {

using namespace unav::common;        // ExpSO3, RightJacobianSO3
using namespace unav::localization;  // ImuPreintegration, InertialOnlyInit

const Eigen::Vector3d kGravity(0.0, 0.0, 9.81);  // NED

// A vehicle weaving in all three axes while it turns (the excitation an initialisation needs):
// R_WB = Exp(theta(t)), so the body rate is Jr(theta) theta'(t).
struct Weave {
  static Eigen::Vector3d Theta(double t) { return {0.2 * std::sin(0.7 * t), 0.3 * std::sin(0.5 * t), 0.4 * t}; }
  static Eigen::Vector3d ThetaDot(double t) { return {0.14 * std::cos(0.7 * t), 0.15 * std::cos(0.5 * t), 0.4}; }
  static Eigen::Matrix3d R(double t) { return ExpSO3(Theta(t)); }
  static Eigen::Vector3d P(double t) {
    return {0.6 * std::sin(1.3 * t), 0.5 * std::cos(0.9 * t), 0.3 * std::sin(2.1 * t)};
  }
  static Eigen::Vector3d V(double t) {
    return {0.78 * std::cos(1.3 * t), -0.45 * std::sin(0.9 * t), 0.63 * std::cos(2.1 * t)};
  }
  static Eigen::Vector3d A(double t) {
    return {-1.014 * std::sin(1.3 * t), -0.405 * std::cos(0.9 * t), -1.323 * std::sin(2.1 * t)};
  }
  static Eigen::Vector3d Gyro(double t) { return RightJacobianSO3(Theta(t)) * ThetaDot(t); }
  static Eigen::Vector3d SpecificForce(double t) { return R(t).transpose() * (A(t) - kGravity); }
};

// One initialisation of a map `1 / s_true` the size of the truth; prints what it found.
void CheckInit(double s_true) {
  SCOPED_TRACE("map scale 1/" + std::to_string(s_true));
  const double dt = 0.005, kf_dt = 0.25;
  const int kfs = 17;
  const Eigen::Matrix3d R_mw = ExpSO3(Eigen::Vector3d(0.9, -0.4, 2.0));
  const Eigen::Vector3d t_mw(3.0, -1.0, 0.5);
  Eigen::Isometry3d T_bc = Eigen::Isometry3d::Identity();  // a down camera ahead of the IMU
  T_bc.linear() = ExpSO3(Eigen::Vector3d(0.0, 0.0, M_PI / 2));
  T_bc.translation() = Eigen::Vector3d(0.2, 0.0, 0.1);
  ImuBias bias;
  bias.gyro = Eigen::Vector3d(0.01, -0.02, 0.015);
  bias.accel = Eigen::Vector3d(0.003, -0.002, 0.004);
  const ImuNoise noise;  // defaults: EuRoC's ADIS16448
  std::mt19937 rng(3);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double sg = noise.gyro_noise_density / std::sqrt(dt), sa = noise.accel_noise_density / std::sqrt(dt);

  std::vector<Eigen::Isometry3d> map;
  std::vector<ImuPreintegration> pre;
  for (int k = 0; k < kfs; ++k) {
    const double t = k * kf_dt;
    Eigen::Isometry3d T_wb = Eigen::Isometry3d::Identity();
    T_wb.linear() = Weave::R(t);
    T_wb.translation() = Weave::P(t);
    const Eigen::Isometry3d T_wc = T_wb * T_bc;
    Eigen::Isometry3d T_mc = Eigen::Isometry3d::Identity();
    T_mc.linear() = R_mw * T_wc.linear();
    T_mc.translation() = (R_mw * T_wc.translation() + t_mw) / s_true;
    map.push_back(T_mc);
    if (k + 1 == kfs) break;
    ImuPreintegration p({}, noise);
    for (int i = 0; i < static_cast<int>(std::lround(kf_dt / dt)); ++i) {
      const double tm = t + (i + 0.5) * dt;
      const Eigen::Vector3d ng(n01(rng), n01(rng), n01(rng)), na(n01(rng), n01(rng), n01(rng));
      p.Integrate(Weave::Gyro(tm) + bias.gyro + sg * ng, Weave::SpecificForce(tm) + bias.accel + sa * na, dt);
    }
    pre.push_back(p);
  }
  const auto r = InertialOnlyInit(map, pre, T_bc);
  ASSERT_TRUE(r.ok) << r.message;
  const Eigen::Vector3d g_expected = R_mw * kGravity;
  const double g_err_deg = std::acos(std::min(1.0, r.gravity_w.normalized().dot(g_expected.normalized()))) * 180 / M_PI;
  std::printf("scale %.4f (true %.4f), gravity %.3f deg off, gyro bias error %.2e rad/s, %d iterations\n", r.scale,
              s_true, g_err_deg, (r.bias.gyro - bias.gyro).norm(), r.iterations);
  // Tolerances: the scheme's discretisation at 200 Hz and the noise leave ~0.1 % on the
  // velocity deltas; 1 % of scale and 0.5 deg of gravity are what ORB-SLAM3 reports after its
  // first initialisation on EuRoC (Campos et al. 2020, Table II).
  EXPECT_NEAR(r.scale, s_true, 0.01 * s_true);
  EXPECT_LT(g_err_deg, 0.5);
  EXPECT_LT((r.bias.gyro - bias.gyro).norm(), 0.2 * bias.gyro.norm()) << r.bias.gyro.transpose();
  ASSERT_EQ(r.velocities.size(), static_cast<std::size_t>(kfs));
  for (int k = 0; k < kfs; ++k)
    EXPECT_LT((r.velocities[static_cast<std::size_t>(k)] - R_mw * Weave::V(k * kf_dt)).norm(), 0.03) << k;
}

TEST(InertialOnlyInit, RecoversScaleGravityVelocitiesAndGyroBiasOfAMonocularMap) {
  // 4 s of weaving, keyframes every 0.25 s, a 200 Hz IMU with biases and EuRoC-like noise
  // (samples at each step's midpoint). The map is the true camera trajectory in a world turned
  // and shifted arbitrarily and shrunk or grown, as a monocular map is; the search starts at
  // scale 1 whatever the map's.
  for (const double s_true : {0.4, 2.5, 10.0}) CheckInit(s_true);
}

TEST(InertialOnlyInit, SaysWhatIsMissing) {
  std::vector<Eigen::Isometry3d> two(2, Eigen::Isometry3d::Identity());
  std::vector<ImuPreintegration> one(1);
  const auto r = InertialOnlyInit(two, one, Eigen::Isometry3d::Identity());
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("at least 3 keyframes"), std::string::npos) << r.message;
}

}  // namespace
