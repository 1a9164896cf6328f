// Frames (same arithmetic as the renderer's frames.cpp and the physics' roll_pitch_yaw /
// quaternion_from_rpy, compared bit for bit with verbatim copies) and time conversions.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "unav_common/frames.hpp"
#include "unav_common/time.hpp"

namespace uc = unav::common;

namespace old_code {  // packages/unav_renderer/src/frames.cpp and packages/unav_physics/src/dynamics.cpp

Eigen::Matrix3d rotation_from_rpy(double roll_rad, double pitch_rad, double yaw_rad) {
  return (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Isometry3d pose_from_xyz_rpy(const Eigen::Vector3d& xyz_m, const Eigen::Vector3d& rpy_rad) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = rotation_from_rpy(rpy_rad.x(), rpy_rad.y(), rpy_rad.z());
  X.translation() = xyz_m;
  return X;
}

Eigen::Vector3d roll_pitch_yaw(const Eigen::Quaterniond& q_WB) {
  const Eigen::Matrix3d R = q_WB.normalized().toRotationMatrix();
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  return {std::atan2(R(2, 1), R(2, 2)), pitch, std::atan2(R(1, 0), R(0, 0))};
}

Eigen::Quaterniond quaternion_from_rpy(double roll, double pitch, double yaw) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

}  // namespace old_code

namespace {

TEST(Frames, BitIdenticalToTheRendererAndPhysicsHelpers) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  for (int i = 0; i < 1000; ++i) {
    const double r = u(rng), p = u(rng), y = u(rng);
    const Eigen::Matrix3d R_new = uc::rotation_from_rpy(r, p, y), R_old = old_code::rotation_from_rpy(r, p, y);
    for (int k = 0; k < 9; ++k) EXPECT_EQ(R_new(k), R_old(k));
    const Eigen::Vector3d xyz(u(rng), u(rng), u(rng));
    const Eigen::Matrix4d X_new = uc::pose_from_xyz_rpy(xyz, {r, p, y}).matrix();
    const Eigen::Matrix4d X_old = old_code::pose_from_xyz_rpy(xyz, {r, p, y}).matrix();
    for (int k = 0; k < 16; ++k) EXPECT_EQ(X_new(k), X_old(k));
    const Eigen::Quaterniond q_new = uc::quaternion_from_rpy(r, p, y), q_old = old_code::quaternion_from_rpy(r, p, y);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(q_new.coeffs()(k), q_old.coeffs()(k));
    const Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));  // not normalised
    const Eigen::Vector3d a_new = uc::roll_pitch_yaw(q), a_old = old_code::roll_pitch_yaw(q);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a_new(k), a_old(k));
  }
}

TEST(Frames, ConventionsAsDeclared) {
  // Yaw +90 deg turns body forward (x) to world east (y) in NED.
  const Eigen::Vector3d east = uc::rotation_from_rpy(0, 0, M_PI / 2) * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(east.y(), 1.0, 1e-15);
  // Round trip rpy -> q -> rpy away from gimbal lock.
  const Eigen::Vector3d rpy = uc::roll_pitch_yaw(uc::quaternion_from_rpy(0.3, -0.4, 2.0));
  EXPECT_NEAR(rpy.x(), 0.3, 1e-14);
  EXPECT_NEAR(rpy.y(), -0.4, 1e-14);
  EXPECT_NEAR(rpy.z(), 2.0, 1e-14);
  // The optical z axis is the camera-body x axis; a proper rotation.
  const Eigen::Matrix3d R = uc::R_camera_body_to_optical();
  EXPECT_EQ(R * Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX());
  EXPECT_EQ(R * Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY());
  EXPECT_EQ(R * Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ());
  EXPECT_EQ(R.determinant(), 1.0);
  EXPECT_STREQ(uc::kWorldFrame, "world_ned");
  EXPECT_STREQ(uc::kBodyFrame, "base_link_frd");
}

TEST(Time, MessageConversions) {
  const unav::Time t{1500000000};
  EXPECT_EQ(t.sec(), 1);
  EXPECT_EQ(t.nanosec(), 500000000u);
  EXPECT_EQ(t.seconds(), 1.5);
  const unav::Time neg{-1};  // 1 ns before the epoch: sec -1, nanosec 999999999
  EXPECT_EQ(neg.sec(), -1);
  EXPECT_EQ(neg.nanosec(), 999999999u);
  EXPECT_EQ(unav::Time::from_msg(neg.sec(), neg.nanosec()).ns, -1);
  EXPECT_EQ(unav::Time{-1000000000}.sec(), -1);
  EXPECT_EQ(unav::Time{-1000000000}.nanosec(), 0u);
  EXPECT_EQ(unav::Time::from_msg(2, 5).ns, 2000000005);
  EXPECT_EQ(unav::Time::from_msg(std::numeric_limits<int32_t>::max(), 999999999).sec(),
            std::numeric_limits<int32_t>::max());
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<int64_t> ns(-4000000000000000000LL, 4000000000000000000LL);
  for (int i = 0; i < 1000; ++i) {
    const unav::Time x{ns(rng) / 1000};
    EXPECT_EQ(unav::Time::from_msg(x.sec(), x.nanosec()).ns, x.ns);
    EXPECT_LT(x.nanosec(), 1000000000u);
  }
}

TEST(Time, FromSecondsRoundsToTheNearestNanosecond) {
  EXPECT_EQ(unav::Time::from_seconds(1.6).ns, 1600000000);  // 1.6 * 1e9 = 1599999999.9999998
  EXPECT_EQ(unav::Time::from_seconds(0.1).ns, 100000000);
  EXPECT_EQ(unav::Time::from_seconds(-0.5e-9).ns, -1);  // llround: halves away from zero
  EXPECT_EQ(unav::Time::from_seconds(2.4e-9).ns, 2);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-1e6, 1e6);
  for (int i = 0; i < 1000; ++i) {
    const double s = u(rng);
    EXPECT_EQ(unav::Time::from_seconds(s).ns, std::llround(s * 1e9));  // what the nodes did by hand
  }
}

}  // namespace

namespace {

unav::common::Pose pose(double x, double y, double z, double roll, double pitch, double yaw) {
  return unav::common::pose_from_xyz_rpy(Eigen::Vector3d(x, y, z), Eigen::Vector3d(roll, pitch, yaw));
}

}  // namespace

// A mount chain base -> camera_link -> camera_optical and a sibling base -> imu: lookups compose
// the edges up to the common ancestor and back down, in either direction, as tf2 does.
TEST(TransformGraph, ComposesChainsThroughTheCommonAncestor) {
  unav::common::TransformGraph g;
  const auto X_BL = pose(0.2, 0.0, 0.1, 0.0, -0.5, 0.0);
  const auto X_LO = pose(0.0, 0.01, 0.0, 0.3, 0.0, 1.2);
  const auto X_BI = pose(-0.1, 0.05, 0.0, 0.0, 0.0, 3.0);
  g.set("base", "camera_link", X_BL);
  g.set("camera_link", "camera_optical", X_LO);
  g.set("base", "imu", X_BI);
  ASSERT_EQ(g.size(), 3u);
  const auto X_BO = g.lookup("base", "camera_optical");
  ASSERT_TRUE(X_BO.has_value());
  EXPECT_TRUE(X_BO->isApprox(X_BL * X_LO, 1e-12));
  const auto X_OB = g.lookup("camera_optical", "base");
  ASSERT_TRUE(X_OB.has_value());
  EXPECT_TRUE(X_OB->isApprox((X_BL * X_LO).inverse(), 1e-12));
  const auto X_IO = g.lookup("imu", "camera_optical");
  ASSERT_TRUE(X_IO.has_value());
  EXPECT_TRUE(X_IO->isApprox(X_BI.inverse() * X_BL * X_LO, 1e-12));
  EXPECT_TRUE(g.lookup("imu", "imu")->isApprox(unav::common::Pose::Identity()));
}

TEST(TransformGraph, UnknownOrDisconnectedFramesHaveNoTransform) {
  unav::common::TransformGraph g;
  g.set("base", "camera_optical", pose(1, 2, 3, 0, 0, 0));
  g.set("world", "buoy", pose(0, 0, 0, 0, 0, 1));
  EXPECT_FALSE(g.lookup("base", "buoy").has_value());
  EXPECT_FALSE(g.lookup("base", "nowhere").has_value());
  // A second parent replaces the first (one parent per frame), and a cycle does not hang.
  g.set("world", "base", pose(0, 0, 5, 0, 0, 0));
  EXPECT_TRUE(g.lookup("buoy", "camera_optical")
                  ->translation()
                  .isApprox(pose(0, 0, 0, 0, 0, 1).inverse() * Eigen::Vector3d(1, 2, 8), 1e-12));
  g.set("camera_optical", "world", pose(0, 0, 0, 0, 0, 0));
  EXPECT_FALSE(g.lookup("base", "elsewhere").has_value());
  (void)g.lookup("world", "buoy");  // terminates
}
