// USBL: the acoustic timing (travel both ways, turnaround, a moving target fixed where the ping
// reached it), the sound-speed setting, range limits, noise, dropouts and determinism.
#include "unav_physics/usbl.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "unav_physics/scenario_builder.hpp"
#include "unav_physics/sensors.hpp"

using unav::physics::Usbl;
using unav::physics::UsblParams;
using unav::physics::UsblReading;

namespace {

UsblParams quiet() {
  UsblParams p;
  p.enabled = true;
  p.rate_hz = 2.0;
  p.transceiver_position = Eigen::Vector3d(0.0, 0.0, 1.0);
  p.sound_speed_mps = 1500.0;
  p.turnaround_s = 0.1;
  p.range_stddev_m = 0.0;
  p.angle_stddev_deg = 0.0;
  p.dropout_at_max_range = 0.0;
  p.outlier_probability = 0.0;
  return p;
}

// Steps a USBL at 1 kHz for `seconds` with the transponder at path(t); the readings in order.
std::vector<UsblReading> fly(const UsblParams& p, double seconds, const std::function<Eigen::Vector3d(double)>& path,
                             std::uint64_t seed = 1) {
  Usbl usbl(p, seed);
  std::vector<UsblReading> out;
  const auto steps = static_cast<long>(std::lround(seconds * 1000.0));
  for (long k = 0; k <= steps; ++k) {
    const double t = 1e-3 * static_cast<double>(k);
    if (usbl.step(t, path(t))) out.push_back(usbl.reading());
  }
  return out;
}

}  // namespace

// A still transponder 500 m away (3-4-5 in the horizontal plane): the reply arrives after
// 2 x 500 / 1500 s + 0.1 s = 0.7667 s; with no noise the fix is the transponder, range and
// angles exact (the gap c t - r is linear in t for a still target: the interpolation is exact).
// The next interrogation waits for the reply (0.5 s period < 0.77 s round trip).
TEST(Usbl, StillTransponderRoundTripAndFixAreExact) {
  const Eigen::Vector3d target(300.0, 400.0, 1.0);
  const auto r = fly(quiet(), 3.0, [&](double) { return Eigen::Vector3d(target); });
  ASSERT_GE(r.size(), 3u);
  const double round_trip = 2.0 * 500.0 / 1500.0 + 0.1;
  EXPECT_NEAR(r[0].stamp, round_trip, 1e-9);
  EXPECT_EQ(r[0].ping_stamp, 0.0);
  EXPECT_NEAR(r[1].ping_stamp, 0.767, 1e-9);  // the first physics step at or after the reply
  for (const auto& f : r) {
    ASSERT_TRUE(f.valid);
    EXPECT_NEAR(f.range_m, 500.0, 1e-9);
    EXPECT_NEAR(f.azimuth_rad, std::atan2(400.0, 300.0), 1e-12);
    EXPECT_NEAR(f.elevation_rad, 0.0, 1e-12);
    EXPECT_NEAR((f.p_W - target).norm(), 0.0, 1e-9);
  }
}

// A transponder moving at 2 m/s: the fix is where it was when the ping reached it, t1 solving
// c t1 = |p(t1) - x| (about 0.33 s after the ping: 0.67 m along), not where it is at the reply.
TEST(Usbl, MovingTransponderIsFixedWhereThePingReachedIt) {
  const Eigen::Vector3d p0(300.0, 400.0, 21.0), v(2.0, 0.0, 0.0), x(0.0, 0.0, 1.0);
  const auto path = [&](double t) -> Eigen::Vector3d { return p0 + v * t; };
  const auto r = fly(quiet(), 2.0, path);
  ASSERT_FALSE(r.empty());
  // t1 by fixed-point iteration (converges: |v| / c << 1).
  double t1 = 0.0;
  for (int i = 0; i < 50; ++i) t1 = (path(t1) - x).norm() / 1500.0;
  EXPECT_NEAR((r[0].truth_p_W - path(t1)).norm(), 0.0, 1e-6);
  EXPECT_NEAR(r[0].range_m, 1500.0 * t1, 1e-6);  // both legs: c t1 out, |p(t1) - x| back
  EXPECT_NEAR((r[0].p_W - path(t1)).norm(), 0.0, 1e-6);
  EXPECT_GT((r[0].p_W - path(r[0].stamp)).norm(), 0.8);  // the reply's time would be 0.87 m off
}

// The transceiver's sound-speed setting scales every range (a 1450 m/s setting in 1500 m/s water
// reads 3.3 % short); its axes turn the angles: a transceiver yawed 90 deg sees north on its left.
// A transceiver carried by another vehicle (a follower tracking its leader): the carrier moves
// at 3 m/s north and yaws 90 deg right, its transceiver mounted 0.5 m below its origin; the
// transponder is still 300 m east. The ping leaves where the transceiver was at t0 (x0), reaches
// the transponder at t1 (c t1 = |p - x0|), the reply reaches the moving transceiver at t2
// (c (t2 - t1 - turnaround) = |p - x(t2)|, solved step by step), and the transceiver measures the
// two-way range (|p - x0| + |p - x2|) / 2 and the direction p - x2 in its axes at reception.
TEST(Usbl, CarriedTransceiverMeasuresFromWhereItIsWhenTheReplyArrives) {
  UsblParams p = quiet();
  p.transceiver_vehicle = "leader";
  p.transceiver_position = Eigen::Vector3d(0.0, 0.0, 0.5);  // on the carrier, FRD
  const Eigen::Vector3d target(0.0, 300.0, 10.0), v(3.0, 0.0, 0.0);
  const Eigen::Matrix3d R_WB = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  auto carrier = [&](double t) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = R_WB;
    X.translation() = Eigen::Vector3d(0.0, 0.0, 2.0) + v * t;
    return X;
  };
  Usbl usbl(p, 1);
  EXPECT_FALSE(usbl.step(0.0, target));  // no carrier pose yet: no interrogation
  std::vector<UsblReading> r;
  for (long k = 0; k <= 1500; ++k) {
    const double t = 1e-3 * static_cast<double>(k);
    usbl.set_carrier_pose(carrier(t));
    if (usbl.step(t, target)) r.push_back(usbl.reading());
  }
  ASSERT_GE(r.size(), 1u);
  const UsblReading& f = r[0];
  ASSERT_TRUE(f.valid);
  const Eigen::Vector3d x0 = carrier(0.0) * p.transceiver_position;
  const double t1 = (target - x0).norm() / 1500.0;
  // t2 by fixed-point iteration (the carrier's speed << c).
  double t2 = t1;
  for (int i = 0; i < 50; ++i) t2 = t1 + 0.1 + (target - carrier(t2) * p.transceiver_position).norm() / 1500.0;
  const Eigen::Vector3d x2 = carrier(t2) * p.transceiver_position;
  // The carrier moves linearly: the step interpolation is exact to rounding.
  EXPECT_NEAR(f.stamp, t2, 1e-9);
  EXPECT_NEAR(f.range_m, 0.5 * ((target - x0).norm() + (target - x2).norm()), 1e-6);
  const Eigen::Vector3d d_X = R_WB.transpose() * (target - x2);  // the mount has the carrier's axes
  EXPECT_NEAR(f.azimuth_rad, std::atan2(d_X.y(), d_X.x()), 1e-9);
  EXPECT_NEAR(f.azimuth_rad, 0.0, 0.02);  // yawed 90 deg right the carrier faces east: the target is ahead
  // The world fix lies along the true direction from the transceiver at reception, off by the
  // two-way range's motion term (|p - x0| - |p - x2|) / 2 (~0.9 mm here: the carrier moves
  // across the line of sight).
  EXPECT_NEAR((f.p_W - x2).normalized().dot((target - x2).normalized()), 1.0, 1e-12);
  EXPECT_NEAR((f.p_W - target).norm(), std::abs(f.range_m - (target - x2).norm()), 1e-6);
  EXPECT_LT((f.p_W - target).norm(), 0.01);
}

TEST(Usbl, OneVehicleRunPathsRefuseACarriedTransceiver) {
  unav::physics::VehicleParams v;
  v.sensors.usbl.enabled = true;
  EXPECT_NO_THROW(unav::physics::require_fixed_usbl(v, "s.yaml", "an in-process episode"));
  v.sensors.usbl.transceiver_vehicle = "leader";
  std::string what = "accepted";
  try {
    unav::physics::require_fixed_usbl(v, "s.yaml", "an in-process episode");
  } catch (const std::exception& e) {
    what = e.what();
  }
  for (const char* part : {"s.yaml", "usbl.transceiver_vehicle", "leader", "in-process"})
    EXPECT_NE(what.find(part), std::string::npos) << what;
}

TEST(Usbl, SoundSpeedSettingScalesRangesAndTheMountTurnsAngles) {
  UsblParams p = quiet();
  p.assumed_sound_speed_mps = 1450.0;
  p.transceiver_rpy_deg = Eigen::Vector3d(0.0, 0.0, 90.0);
  const Eigen::Vector3d target(100.0, 0.0, 1.0);
  const auto r = fly(p, 1.0, [&](double) { return Eigen::Vector3d(target); });
  ASSERT_FALSE(r.empty());
  EXPECT_NEAR(r[0].range_m, 100.0 * 1450.0 / 1500.0, 1e-9);
  EXPECT_NEAR(r[0].azimuth_rad, -M_PI / 2, 1e-12);
  EXPECT_NEAR((r[0].p_W - (Eigen::Vector3d(0, 0, 1) + Eigen::Vector3d(100.0 * 1450.0 / 1500.0, 0, 0))).norm(), 0.0,
              1e-9);
}

// Beyond max_range no reply comes: each interrogation ends in a timeout (valid false) at
// t0 + 2 max_range / c + turnaround, and the next waits for it.
TEST(Usbl, OutOfRangeTimesOut) {
  UsblParams p = quiet();
  p.max_range_m = 1000.0;
  const auto r = fly(p, 3.0, [](double) { return Eigen::Vector3d(1200.0, 0.0, 1.0); });
  ASSERT_GE(r.size(), 2u);
  EXPECT_FALSE(r[0].valid);
  EXPECT_NEAR(r[0].stamp, 2.0 * 1000.0 / 1500.0 + 0.1, 1e-9);
  EXPECT_NEAR(r[1].ping_stamp, 1.434, 1e-9);
}

// Noise and dropouts over 2000 interrogations of a still target at 0.7071 of max range:
// range and angle errors have the configured standard deviations (the estimate's relative
// standard error is 1 / sqrt(2 N) = 1.6 %: 10 % is over 6 of them), dropouts happen with
// probability 0.5 x 0.7071^2 = 0.25 (binomial sigma 0.0097 over 2000: +-0.05 is 5 sigma), and the
// reported covariance matches the scatter of the fixes (first order at 1 deg; each variance's
// relative standard error over ~1500 fixes is 3.7 %: 20 % is over 5 of them).
TEST(Usbl, NoiseAndDropoutsHaveTheirConfiguredStatistics) {
  UsblParams p = quiet();
  p.rate_hz = 50.0;
  p.range_stddev_m = 0.5;
  p.angle_stddev_deg = 1.0;
  p.max_range_m = 100.0 / 0.70710678;
  p.dropout_at_max_range = 0.5;
  const Eigen::Vector3d target(60.0, 80.0, 1.0);  // 100 m
  std::vector<UsblReading> r;
  {
    Usbl usbl(p, 7);
    for (long k = 0; r.size() < 2000; ++k) {
      const double t = 1e-3 * static_cast<double>(k);
      if (usbl.step(t, target)) r.push_back(usbl.reading());
    }
  }
  int dropped = 0;
  double s_range = 0, s_az = 0, s_el = 0;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero(), cov = Eigen::Matrix3d::Zero();
  int n = 0;
  for (const auto& f : r) {
    if (!f.valid) {
      ++dropped;
      continue;
    }
    ++n;
    s_range += std::pow(f.range_m - 100.0, 2);
    s_az += std::pow(f.azimuth_rad - std::atan2(80.0, 60.0), 2);
    s_el += std::pow(f.elevation_rad, 2);
    const Eigen::Vector3d e = f.p_X - Eigen::Vector3d(60.0, 80.0, 0.0);
    scatter += e * e.transpose();
    cov += unav::physics::usbl_fix_covariance(p, f);
  }
  EXPECT_NEAR(static_cast<double>(dropped) / 2000.0, 0.25, 0.05);
  EXPECT_NEAR(std::sqrt(s_range / n), 0.5, 0.05);
  EXPECT_NEAR(std::sqrt(s_az / n) * 180.0 / M_PI, 1.0, 0.1);
  EXPECT_NEAR(std::sqrt(s_el / n) * 180.0 / M_PI, 1.0, 0.1);
  scatter /= n;
  cov /= n;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(scatter(i, i) / cov(i, i), 1.0, 0.2) << i;
}

TEST(Usbl, SameSeedSameFixesOtherSeedOthers) {
  UsblParams p = quiet();
  p.range_stddev_m = 0.3;
  p.angle_stddev_deg = 2.0;
  p.outlier_probability = 0.2;
  p.dropout_at_max_range = 0.5;
  const auto path = [](double t) { return Eigen::Vector3d(50.0 + t, 20.0, 10.0); };
  const auto a = fly(p, 20.0, path, 3), b = fly(p, 20.0, path, 3), c = fly(p, 20.0, path, 4);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].valid, b[i].valid);
    EXPECT_EQ(a[i].p_W, b[i].p_W);
  }
  const auto first_valid = [](const std::vector<UsblReading>& r) {
    for (const auto& f : r)
      if (f.valid) return f.p_W;
    return Eigen::Vector3d(Eigen::Vector3d::Zero());
  };
  EXPECT_NE(first_valid(a), first_valid(c));
}

// In the sensor suite the transponder rides on the vehicle at its lever arm: a vehicle yawed
// 90 deg carries a transponder 1 m forward of its origin 1 m east.
TEST(Usbl, TheSensorSuiteFixesTheTransponderAtItsLeverArm) {
  unav::physics::SensorSuiteParams sp;
  sp.usbl = quiet();
  sp.usbl.transponder_xyz_m = Eigen::Vector3d(1.0, 0.0, 0.0);
  unav::physics::SensorSuite suite(sp, unav::physics::EnvironmentParams{});
  unav::physics::RigidBodyState x;
  x.p_WB_W = Eigen::Vector3d(30.0, 40.0, 11.0);
  x.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  for (long k = 0; k <= 500; ++k)
    suite.update(1e-3 * static_cast<double>(k), x, unav::physics::Vector6d::Zero(), nullptr);
  const auto& f = suite.readings().usbl;
  ASSERT_TRUE(f.valid);
  EXPECT_NEAR((f.p_W - Eigen::Vector3d(30.0, 41.0, 11.0)).norm(), 0.0, 1e-9);
}
