// drl_planner over DDS: one setpoint per odometry, stamped as it; a decision waits for the image
// of its time (sync_images); the waypoint is 1 m from the pose in the direction the policy picks;
// a missing model is a one-line error.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "drl_planner_node.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_runtime/testing.hpp"

using unav::testing::make_link;

namespace {

// A "seabed" with smooth blotches and sensor noise (no straight edges) and a darker band 60 px
// wide (the pipe: two long straight edges) centred at column cx.
sensor_msgs::msg::Image band_image(double t, int cx) {
  const int w = 320, h = 180;
  sensor_msgs::msg::Image m;
  m.header() = unav::make_header(t, "down_optical");
  m.width(w);
  m.height(h);
  m.encoding("rgb8");
  m.step(w * 3);
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * h * 3);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> noise(-25, 25);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool pipe = std::abs(x - cx) < 30;
      const double blotch = 20.0 * std::sin(0.05 * x) * std::cos(0.07 * y);
      const int v = (pipe ? 70 : 140 + static_cast<int>(blotch)) + noise(rng) / 3;
      for (int c = 0; c < 3; ++c)
        px[(static_cast<std::size_t>(y) * w + x) * 3 + c] = static_cast<std::uint8_t>(std::clamp(v, 0, 255));
    }
  m.data(px);
  return m;
}

nav_msgs::msg::Odometry odom(double t, double n, double e, double d) {
  nav_msgs::msg::Odometry o;
  o.header() = unav::make_header(t, "world_ned");
  o.pose().pose() = unav::to_msg(Eigen::Vector3d(n, e, d), Eigen::Quaterniond::Identity());
  return o;
}

}  // namespace

TEST(DrlPlannerNode, OneSetpointPerOdometryDecisionsWaitForTheirImage) {
  unav::testing::NodeUnderTest<unav::planning::DrlPlannerNode> fx(
      "drl_planner", {"--ros-args", "-p", "policy:=classical", "-p", "step_period:=1.5"});
  unav::planning::DrlPlannerNode& node = *fx.node;
  unav::Node& probe = fx.probe;
  auto odom_pub = probe.create_publisher<nav_msgs::msg::Odometry>("/rov/ground_truth/odom", unav::QoS::reliable());
  auto img_pub = probe.create_publisher<sensor_msgs::msg::Image>("/rov/camera/down/image_raw", unav::QoS::reliable(5));
  std::vector<geometry_msgs::msg::PoseStamped> sp;
  auto sub = probe.create_subscription<geometry_msgs::msg::PoseStamped>(
      "/rov/control/pose_setpoint", unav::QoS::reliable(),
      [&](const geometry_msgs::msg::PoseStamped& s) { sp.push_back(s); });
  const std::vector<unav::testing::Link> links = {make_link(*odom_pub, node), make_link(*img_pub, node),
                                                  make_link(node, *sub)};
  ASSERT_TRUE(fx.match(links));
  auto spin_until = [&](const std::function<bool()>& done) { return fx.spin_until(done); };
  auto spin_a_bit = [&] { fx.spin_for(std::chrono::milliseconds(200)); };

  // t = 0: the odometry alone is not answered (its image is not there yet) ...
  odom_pub->publish(odom(0.0, 0.0, 0.0, 5.0));
  spin_a_bit();
  EXPECT_TRUE(sp.empty());
  // ... its image (pipe straight ahead, centred) releases it: a waypoint 1 m ahead at depth 5.
  img_pub->publish(band_image(0.0, 160));
  ASSERT_TRUE(spin_until([&] { return sp.size() == 1; }));
  EXPECT_EQ(unav::seconds(sp[0].header()), 0.0);
  const Eigen::Vector3d w0 = unav::from_msg(sp[0].pose().position());
  EXPECT_NEAR(w0.x(), 1.0, 0.05);  // straight ahead: |a1| small (a centred, vertical band)
  EXPECT_NEAR(w0.y(), 0.0, 0.2);
  EXPECT_EQ(w0.z(), 5.0);
  // Between decisions every odometry gets the same waypoint at once, stamped as the odometry.
  odom_pub->publish(odom(0.05, 0.02, 0.0, 5.0));
  ASSERT_TRUE(spin_until([&] { return sp.size() == 2; }));
  EXPECT_DOUBLE_EQ(unav::seconds(sp[1].header()), 0.05);
  EXPECT_EQ(unav::from_msg(sp[1].pose().position()), w0);
  // t = 1.5: the next decision; the pipe now right of the image centre -> the step goes right.
  odom_pub->publish(odom(1.5, 1.0, 0.0, 5.2));
  spin_a_bit();
  EXPECT_EQ(sp.size(), 2u);
  img_pub->publish(band_image(1.5, 250));
  ASSERT_TRUE(spin_until([&] { return sp.size() == 3; }));
  const Eigen::Vector3d w1 = unav::from_msg(sp[2].pose().position());
  EXPECT_GT(w1.y(), 0.2);  // east of the vehicle: right, facing north
  EXPECT_NEAR((w1 - Eigen::Vector3d(1.0, 0.0, 5.0)).head<2>().norm(), 1.0, 1e-9);  // a 1 m step
  EXPECT_EQ(w1.z(), 5.0);                                                          // depth held at the first odometry's
  EXPECT_EQ(node.decisions(), 2u);
}

TEST(DrlPlannerNode, MissingModelIsAOneLineError) {
  const unav::ContextOptions o = unav::testing::test_context_options();
  const char* argv[] = {"drl_planner", "--ros-args", "-p", "model:=/nonexistent/policy.onnx"};
  unav::Context ctx(4, argv, o);
  try {
    unav::planning::DrlPlannerNode node({&ctx});
    FAIL() << "constructed without a model";
  } catch (const std::exception& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("/nonexistent/policy.onnx"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}
