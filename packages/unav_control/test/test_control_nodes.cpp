// Control nodes over DDS: the allocator (a wrench in gives the thruster command that produces it;
// a thruster marked failed at run time gets zero and the wrench is still produced), the MPC's
// parameter layers, the station keeper.
#include <gtest/gtest.h>

#include <fstream>

#include "control_nodes.hpp"
#include "unav_control/config.hpp"
#include "unav_runtime/testing.hpp"

using namespace std::chrono_literals;
using unav::testing::make_link;

TEST(ControlAllocatorNode, WrenchInCommandOutAndRuntimeFailure) {
  const std::string cfg_file = std::string(UNAV_CONFIG_DIR) + "/controllers/allocator.yaml";
  unav::testing::NodeUnderTest<unav::control::ControlAllocatorNode> fx(
      "control_allocator", {"--ros-args", "-p", "config_file:=" + cfg_file});
  unav::control::ControlAllocatorNode& node = *fx.node;
  unav::Node& probe = fx.probe;
  auto wrench_pub =
      probe.create_publisher<geometry_msgs::msg::WrenchStamped>("/rov/control/wrench_command", unav::QoS::reliable());
  auto fail_pub = probe.create_publisher<std_msgs::msg::String>("/rov/thrusters/set_failed", unav::QoS::reliable());
  std::vector<unav_msgs::msg::ThrusterCommand> cmds;
  auto sub = probe.create_subscription<unav_msgs::msg::ThrusterCommand>(
      "/rov/thrusters/command", unav::QoS::reliable(),
      [&](const unav_msgs::msg::ThrusterCommand& c) { cmds.push_back(c); });
  auto spin_until = [&](const std::function<bool()>& done) { return fx.spin_until(done); };
  // Both sides of every link matched before the first message (a reader that counts the writer
  // is not enough: the writer drops what it writes before it knows the reader).
  const std::vector<unav::testing::Link> links = {make_link(*wrench_pub, node), make_link(*fail_pub, node),
                                                  make_link(node, *sub)};
  ASSERT_TRUE(fx.match(links));
  // Reference allocator from the same config: the wrench a command produces.
  const auto cfg = unav::control::load_allocator_config(cfg_file, UNAV_CONFIG_DIR);
  unav::control::Allocator ref = unav::control::make_allocator(cfg);
  geometry_msgs::msg::WrenchStamped w;
  w.header().stamp().sec(3);
  w.wrench().force().x(20.0);  // N, surge
  w.wrench().torque().z(2.0);  // N m, yaw
  auto check = [&](const unav_msgs::msg::ThrusterCommand& c) {
    ASSERT_EQ(c.u().size(), 8u);
    unav::physics::ThrusterVector u(8);
    for (int i = 0; i < 8; ++i) u[i] = c.u()[static_cast<size_t>(i)];
    const auto tau = ref.WrenchFromCommand(u);
    // Feasible wrench: reproduced exactly (1e-9 N relative to ~40 N thrusters).
    EXPECT_NEAR(tau[0], 20.0, 1e-9);
    EXPECT_NEAR(tau[5], 2.0, 1e-9);
    EXPECT_NEAR(tau[1], 0.0, 1e-9);
    EXPECT_NEAR(tau[2], 0.0, 1e-9);
    EXPECT_EQ(c.header().stamp().sec(), 3);  // stamped as the wrench (lockstep)
  };
  wrench_pub->publish(w);
  ASSERT_TRUE(spin_until([&] { return cmds.size() == 1; }));
  check(cmds[0]);
  EXPECT_NE(cmds[0].u()[2], 0.0);
  std_msgs::msg::String f;
  f.data("T3");
  fail_pub->publish(f);
  // Same-process ordering is not guaranteed across two writers: wait until the node applied it.
  ref.SetThrusterFailed(2, true);
  ASSERT_TRUE(spin_until([&] {
    wrench_pub->publish(w);
    fx.spin_for(50ms);
    return cmds.back().u()[2] == 0.0;
  }));
  check(cmds.back());  // the remaining seven thrusters still produce the wrench
}

TEST(MpcControllerNode, OneParameterSystemFileThenParamsFileThenCommandLine) {
  // The MPC's schema is read from its config file; a params file and -p override single keys,
  // with the schema's rules (the file says horizon_steps 20, dt 0.05).
  const std::string cfg_file = std::string(UNAV_CONFIG_DIR) + "/controllers/mpc.yaml";
  const std::string params = ::testing::TempDir() + "mpc_params.yaml";
  std::ofstream(params) << "mpc_controller:\n  ros__parameters:\n    dt: 0.04\n    position_weights: [1.0, 2.0, 3.0]\n";
  const std::string c = "config_file:=" + cfg_file;
  const char* argv[] = {"mpc_controller", "--ros-args",   "-p", c.c_str(),
                        "--params-file",  params.c_str(), "-p", "horizon_steps:=30"};
  unav::Context ctx(8, argv, unav::testing::test_context_options());
  unav::control::MpcControllerNode node({&ctx});
  EXPECT_EQ(node.parameters().at("horizon_steps").as<int>(), 30);
  EXPECT_DOUBLE_EQ(node.parameters().at("dt").as<double>(), 0.04);
  EXPECT_DOUBLE_EQ(node.parameters().at("position_weights")[2].as<double>(), 3.0);
  EXPECT_EQ(node.parameters().at("control_blocks").as<int>(), 5);  // from the file
  bool listed = false;
  for (const auto& row : node.parameter_table())
    listed = listed || (row.name == "horizon_steps" && row.rule == "[1, 500]");
  EXPECT_TRUE(listed);

  // Out of range and unknown keys are errors naming the source, key, value and rule.
  const char* bad[] = {"mpc_controller", "--ros-args", "-p", c.c_str(), "-p", "horizon_steps:=0"};
  unav::Context bad_ctx(6, bad, unav::testing::test_context_options());
  try {
    unav::control::MpcControllerNode n({&bad_ctx});
    ADD_FAILURE() << "horizon_steps 0 accepted";
  } catch (const unav::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'-p horizon_steps:=0'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("horizon_steps = 0: must be in [1, 500]"), std::string::npos) << e.what();
  }
}

// station_keeper over DDS (in /rov2, following /rov's USBL fixes): before a fix it holds the
// first pose it received; a fix is applied 0.1 s (fix_delay_s) after its stamp (so lockstep runs
// repeat); then the setpoint is 5 m behind the leader along its course, the leader predicted to
// the odometry's time, stamped with each odometry. Invalid fixes are not used.
TEST(StationKeeperNode, SetpointFiveMetresBehindTheLeadersFixes) {
  unav::testing::NodeUnderTest<unav::control::StationKeeperNode> t(
      "station_keeper", {"--ros-args", "-r", "__ns:=/rov2", "-p", "leader_fix_topic:=/rov/usbl/fix"});
  auto fix_pub = t.probe.create_publisher<unav_msgs::msg::UsblFix>("/rov/usbl/fix", unav::QoS::reliable(100));
  auto odom_pub = t.probe.create_publisher<nav_msgs::msg::Odometry>("/rov2/ground_truth/odom", unav::QoS::reliable());
  std::vector<geometry_msgs::msg::PoseStamped> sps;
  auto sub = t.probe.create_subscription<geometry_msgs::msg::PoseStamped>(
      "/rov2/control/pose_setpoint", unav::QoS::reliable(),
      [&](const geometry_msgs::msg::PoseStamped& m) { sps.push_back(m); });
  ASSERT_TRUE(t.match({make_link(*fix_pub, *t.node), make_link(*odom_pub, *t.node), make_link(*t.node, *sub)}));
  auto stamp = [](auto& header, double s) {
    header.stamp().sec(static_cast<int32_t>(std::floor(s)));
    header.stamp().nanosec(static_cast<uint32_t>(std::llround((s - std::floor(s)) * 1e9)));
  };
  auto odom = [&](double s) {  // the follower itself, somewhere behind
    nav_msgs::msg::Odometry m;
    stamp(m.header(), s);
    m.pose().pose().position().x(-3.0);
    m.pose().pose().position().z(8.0);
    m.pose().pose().orientation().w(1.0);
    const size_t before = sps.size();
    odom_pub->publish(m);
    EXPECT_TRUE(t.spin_until([&] { return sps.size() == before + 1; }));
  };
  auto fix = [&](double s, double x, bool valid = true) {
    unav_msgs::msg::UsblFix f;
    stamp(f.header(), s);
    f.valid(valid);
    f.position_world().x(x);
    f.position_world().y(1.0);
    f.position_world().z(7.5);
    fix_pub->publish(f);
  };
  odom(0.0);
  EXPECT_DOUBLE_EQ(sps.back().pose().position().x(), -3.0);  // holding its first pose
  // The leader heads north at 0.5 m/s; fixes at 0.5 and 1.5 s (and an invalid one).
  fix(0.5, 0.25);
  fix(1.0, 99.0, false);
  fix(1.5, 0.75);
  t.spin_for(300ms);  // the fixes reach the node (reliable)
  odom(0.55);         // the fix at 0.5 s is used 0.1 s after its stamp (fix_delay_s): not yet
  EXPECT_DOUBLE_EQ(sps.back().pose().position().x(), -3.0);
  odom(0.6);  // now: the first fix only (one position, no velocity yet: the course is north)
  EXPECT_NEAR(sps.back().pose().position().x(), 0.25 - 5.0, 1e-9);
  odom(1.6);  // the second; velocity 0.5 m/s north: 5 m behind the leader predicted to 1.6 s
  EXPECT_NEAR(sps.back().pose().position().x(), 0.75 + 0.05 - 5.0, 1e-9);
  EXPECT_NEAR(sps.back().pose().position().y(), 1.0, 1e-9);
  EXPECT_NEAR(sps.back().pose().position().z(), 7.5, 1e-9);
  EXPECT_EQ(sps.back().header().stamp().sec(), 1);
  EXPECT_EQ(sps.back().header().frame_id(), "world_ned");
  EXPECT_EQ(t.node->keeper().fixes_used(), 2u);
}
