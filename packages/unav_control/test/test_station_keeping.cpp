// Station keeping from a leader's USBL fixes: the setpoint sits distance_m behind the leader along
// its course at its depth (exact for a leader on a straight line once the tracker has converged),
// turns with the leader, ignores a multipath outlier, restarts the track when the leader really
// moved, and smooths noisy fixes below their own noise.
#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "unav_control/station_keeping.hpp"
#include "unav_physics/types.hpp"

using unav::control::StationKeeper;
using unav::control::StationKeepingOptions;

namespace {
double yaw_of(const Eigen::Quaterniond& q) {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}
}  // namespace

TEST(StationKeeping, HoldsDistanceBehindALeaderOnAStraightLineAndTurnsWithIt) {
  StationKeeper k;  // 5 m behind
  EXPECT_FALSE(k.Setpoint().has_value());
  // North at 0.5 m/s, a fix a second, depth 8 m.
  for (int i = 0; i <= 40; ++i) ASSERT_TRUE(k.AddFix(i, Eigen::Vector3d(0.5 * i, 2.0, 8.0)));
  // Started from the first two fixes, the alpha-beta tracker has no error on a constant velocity
  // (its residuals stay zero): the setpoint is 5 m behind the last fix.
  auto s = k.Setpoint();
  ASSERT_TRUE(s.has_value());
  EXPECT_NEAR(s->p_W.x(), 20.0 - 5.0, 1e-9);
  EXPECT_NEAR(s->p_W.y(), 2.0, 1e-9);
  EXPECT_NEAR(s->p_W.z(), 8.0, 1e-9);
  EXPECT_NEAR(yaw_of(s->q_WB), 0.0, 1e-9);
  EXPECT_NEAR(k.leader_velocity().x(), 0.5, 1e-9);
  // Between fixes, the leader predicted along its velocity (at most max_prediction_s = 2 s).
  EXPECT_NEAR(k.Setpoint(40.5)->p_W.x(), 20.25 - 5.0, 1e-9);
  EXPECT_NEAR(k.Setpoint(45.0)->p_W.x(), 21.0 - 5.0, 1e-9);
  EXPECT_NEAR(k.Setpoint(39.0)->p_W.x(), 20.0 - 5.0, 1e-9);  // never behind the last fix
  // The leader turns east: the tracker settles (damping alpha / (2 sqrt(beta)) = 0.88 at the default gains, ~30
  // fixes); 60 s later the setpoint is 5 m west of it, heading east, within a centimetre.
  for (int i = 1; i <= 60; ++i) ASSERT_TRUE(k.AddFix(40 + i, Eigen::Vector3d(20.0, 2.0 + 0.5 * i, 8.0)));
  s = k.Setpoint();
  EXPECT_NEAR(s->p_W.x(), 20.0, 0.01);
  EXPECT_NEAR(s->p_W.y(), 32.0 - 5.0, 0.01);
  EXPECT_NEAR(yaw_of(s->q_WB), M_PI / 2, 0.002);
  EXPECT_EQ(k.fixes_used(), 101u);
  EXPECT_EQ(k.fixes_rejected(), 0u);
}

TEST(StationKeeping, IgnoresAnOutlierAndReacquiresALeaderThatMoved) {
  StationKeepingOptions o;
  o.gate_m = 3.0;
  o.reacquire_after = 3;
  StationKeeper k(o);
  for (int i = 0; i <= 20; ++i) k.AddFix(i, Eigen::Vector3d(0.5 * i, 0.0, 8.0));
  const Eigen::Vector3d before = k.Setpoint()->p_W;
  // A multipath fix 5 m off (the USBL's outlier model): not used, nothing moves.
  EXPECT_FALSE(k.AddFix(21, Eigen::Vector3d(10.5, 5.0, 8.0)));
  EXPECT_EQ(k.fixes_rejected(), 1u);
  EXPECT_TRUE(k.AddFix(22, Eigen::Vector3d(11.0, 0.0, 8.0)));
  EXPECT_NEAR(k.Setpoint()->p_W.x(), before.x() + 1.0, 1e-9);  // two more seconds at 0.5 m/s
  EXPECT_NEAR(k.Setpoint()->p_W.y(), 0.0, 1e-9);
  // The leader was moved 30 m away (a reset): three fixes there in a row restart the track.
  EXPECT_FALSE(k.AddFix(23, Eigen::Vector3d(40.0, 30.0, 6.0)));
  EXPECT_FALSE(k.AddFix(24, Eigen::Vector3d(40.0, 30.0, 6.0)));
  EXPECT_TRUE(k.AddFix(25, Eigen::Vector3d(40.0, 30.0, 6.0)));
  EXPECT_NEAR(k.leader_position().x(), 40.0, 1e-9);
  EXPECT_NEAR(k.Setpoint()->p_W.z(), 6.0, 1e-9);
  EXPECT_NEAR(yaw_of(k.Setpoint()->q_WB), 0.0, 1e-9);  // the last course until it moves again
  // A stamp going back or a NaN fix is refused.
  EXPECT_FALSE(k.AddFix(24.5, Eigen::Vector3d(40.0, 30.0, 6.0)));
  EXPECT_FALSE(k.AddFix(26, Eigen::Vector3d(NAN, 30.0, 6.0)));
}

TEST(StationKeeping, SmoothsNoisyFixes) {
  // 0.3 m of noise per axis (the USBL's ~1 deg at ~20 m): the setpoint's error is well below it.
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 0.3);
  StationKeeper k;
  double sum_sq = 0.0;
  int count = 0;
  for (int i = 0; i <= 200; ++i) {
    const Eigen::Vector3d truth(0.4 * i, 0.0, 8.0);
    k.AddFix(i, truth + Eigen::Vector3d(n(rng), n(rng), n(rng)));
    if (i < 20) continue;  // converging
    const Eigen::Vector3d ideal = truth - Eigen::Vector3d(5.0, 0.0, 0.0);
    sum_sq += (k.Setpoint()->p_W - ideal).head<2>().squaredNorm();
    ++count;
  }
  const double rms = std::sqrt(sum_sq / count);
  EXPECT_LT(rms, 0.3 * std::sqrt(2.0) * 0.75) << "horizontal RMS " << rms << " m";
  EXPECT_EQ(k.fixes_rejected(), 0u);  // 3-sigma noise stays inside the 3 m gate
}

TEST(StationKeeping, RefusesImpossibleOptions) {
  StationKeepingOptions o;
  o.distance_m = 0.0;
  try {
    StationKeeper k(o);
    ADD_FAILURE() << "a zero distance accepted";
  } catch (const unav::physics::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("distance_m must be > 0"), std::string::npos) << e.what();
  }
  o = StationKeepingOptions{};
  o.alpha = 1.5;
  EXPECT_THROW(StationKeeper{o}, unav::physics::ConfigError);
}
