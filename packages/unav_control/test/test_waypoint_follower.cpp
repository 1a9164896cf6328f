// Waypoint follower: acceptance radius, yaw along the path, progress, pipeline offset path.
#include <gtest/gtest.h>

#include "unav_control/waypoint_follower.hpp"

namespace unav::control {
namespace {

double yaw_of(const PoseSetpoint& s) { return physics::roll_pitch_yaw(s.q_WB).z(); }

TEST(WaypointFollower, PathAbovePipelineOffsetAndYaw) {
  // A pipeline on a 10 m deep seabed: north 4 m, then east 3 m.
  const std::vector<Eigen::Vector3d> pipe = {{0, 0, 10}, {4, 0, 10}, {4, 3, 10}};
  const auto path = path_above(pipe, 1.5);
  ASSERT_EQ(path.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(path[i].p_W.z(), 8.5, 1e-12);  // 1.5 m above (NED z up is -)
  EXPECT_NEAR(yaw_of(path[0]), 0.0, 1e-12);
  EXPECT_NEAR(yaw_of(path[1]), M_PI / 2, 1e-12);
  EXPECT_NEAR(yaw_of(path[2]), M_PI / 2, 1e-12);
}

TEST(WaypointFollower, AdvancesWithinRadiusAndFinishes) {
  WaypointFollowerOptions o;
  o.acceptance_radius = 0.2;
  WaypointFollower f(o);
  const std::vector<Eigen::Vector3d> pts = {{0, 0, 5}, {2, 0, 5}, {2, 2, 5}};
  ASSERT_TRUE(f.SetPath(path_above(pts, 0.0)));
  WaypointUpdate u = f.Update({0.5, 0.5, 5});  // 0.71 m from the first waypoint
  EXPECT_EQ(u.target_index, 0);
  EXPECT_FALSE(u.finished);
  u = f.Update({0.1, 0.1, 5});  // within 0.2 m: on to waypoint 1
  EXPECT_EQ(u.target_index, 1);
  EXPECT_NEAR(yaw_of(u.setpoint), 0.0, 1e-12);  // heading of segment 0 -> 1 (north)
  EXPECT_NEAR(u.progress, 0.1 / 4.0, 1e-12);    // 0.1 m along a 4 m path
  u = f.Update({1.0, 0.0, 5});
  EXPECT_NEAR(u.progress, 0.25, 1e-12);
  u = f.Update({2.0, 0.15, 5});
  EXPECT_EQ(u.target_index, 2);
  EXPECT_NEAR(yaw_of(u.setpoint), M_PI / 2, 1e-12);  // east
  EXPECT_NEAR(u.setpoint.p_W.y(), 2.0, 1e-12);
  u = f.Update({2.0, 1.9, 5});
  EXPECT_TRUE(u.finished);
  EXPECT_DOUBLE_EQ(u.progress, 1.0);
  EXPECT_NEAR(u.setpoint.p_W.y(), 2.0, 1e-12);  // holds the last waypoint
}

TEST(WaypointFollower, BadPathAndOptions) {
  WaypointFollower f;
  std::string msg;
  EXPECT_FALSE(f.SetPath({}, &msg));
  EXPECT_NE(msg.find("empty"), std::string::npos);
  std::vector<PoseSetpoint> p = path_above({{0, 0, 5}, {1, 0, 5}}, 0.0);
  p[1].q_WB.coeffs() << 0, 0, 0, 3;
  EXPECT_FALSE(f.SetPath(p, &msg));
  EXPECT_NE(msg.find("path[1]"), std::string::npos) << msg;
  WaypointUpdate u = f.Update({1, 2, 3});  // no path: hold where we are
  EXPECT_TRUE(u.finished);
  EXPECT_EQ(u.setpoint.p_W, Eigen::Vector3d(1, 2, 3));
  WaypointFollowerOptions o;
  o.acceptance_radius = -1.0;
  EXPECT_THROW(WaypointFollower{o}, physics::ConfigError);
}

}  // namespace
}  // namespace unav::control
