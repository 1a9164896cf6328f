// Message <-> Eigen conversions: round trips are exact, stamps split into sec/nanosec as ROS 2 does.
#include <gtest/gtest.h>

#include "unav_runtime/conversions.hpp"

TEST(Conversions, StampsRoundTripThroughNanoseconds) {
  const unav::Time t = unav::Time::from_seconds(12.345678901);
  EXPECT_EQ(t.ns, 12345678901);
  const auto m = unav::to_msg(t);
  EXPECT_EQ(m.sec(), 12);
  EXPECT_EQ(m.nanosec(), 345678901u);
  EXPECT_EQ(unav::from_msg(m).ns, t.ns);
  // Negative times: sec rounds down, nanosec stays in [0, 1e9) (builtin_interfaces/Time).
  const auto neg = unav::to_msg(unav::Time{-1});
  EXPECT_EQ(neg.sec(), -1);
  EXPECT_EQ(neg.nanosec(), 999999999u);
  const auto h = unav::make_header(2.5, "world_ned");
  EXPECT_DOUBLE_EQ(unav::seconds(h), 2.5);
  EXPECT_EQ(unav::nanoseconds(h), 2500000000);
  EXPECT_EQ(h.frame_id(), "world_ned");
}

TEST(Conversions, PoseAndTransformRoundTrip) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  X.translation() = Eigen::Vector3d(1.5, -2.0, 10.25);
  const Eigen::Isometry3d Y = unav::from_msg(unav::to_msg(X));
  EXPECT_LT((Y.matrix() - X.matrix()).norm(), 1e-15);
  const Eigen::Isometry3d Z = unav::from_msg(unav::to_transform_msg(X));
  EXPECT_LT((Z.matrix() - X.matrix()).norm(), 1e-15);
  const auto ts = unav::to_transform_stamped(X, 1.0, "base_link_frd", "down_optical");
  EXPECT_EQ(ts.header().frame_id(), "base_link_frd");
  EXPECT_EQ(ts.child_frame_id(), "down_optical");
  // A pose's quaternion is normalised on the way in; a bare quaternion is passed as sent.
  geometry_msgs::msg::Pose p = unav::to_msg(X);
  p.orientation().w(p.orientation().w() * 2.0);
  p.orientation().x(p.orientation().x() * 2.0);
  p.orientation().y(p.orientation().y() * 2.0);
  p.orientation().z(p.orientation().z() * 2.0);
  EXPECT_LT((unav::from_msg(p).linear() - X.linear()).norm(), 1e-15);
  EXPECT_NEAR(unav::from_msg(p.orientation()).norm(), 2.0, 1e-15);
}

TEST(Conversions, TwistAndWrenchKeepLinearThenAngular) {
  unav::Vector6d v;
  v << 1, 2, 3, 4, 5, 6;
  const auto w = unav::to_wrench_msg(v);
  EXPECT_EQ(w.force().x(), 1.0);
  EXPECT_EQ(w.torque().z(), 6.0);
  EXPECT_EQ(unav::from_msg(w), v);
  const auto t = unav::to_twist_msg(v);
  EXPECT_EQ(t.linear().y(), 2.0);
  EXPECT_EQ(t.angular().x(), 4.0);
  EXPECT_EQ(unav::from_msg(t), v);
}
