// physics_server over DDS: a server context and a test context in one process, on a domain of
// the test's own, spun alternately from this thread.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>

#include "physics_server_node.hpp"
#include "unav_runtime/lockstep_ack.hpp"
#include "unav_runtime/testing.hpp"

using namespace std::chrono_literals;
using unav::physics::PhysicsServer;
using unav::testing::make_link;

namespace {

std::unique_ptr<unav::Context> make_context(std::vector<std::string> args) {
  const unav::ContextOptions o = unav::testing::test_context_options();
  args.insert(args.begin(), {"physics_server", "--ros-args", "-p",
                             std::string("vehicle_config:=") + UNAV_CONFIG_DIR + "/vehicles/bluerov2_heavy.yaml"});
  std::vector<const char*> argv;
  argv.reserve(args.size());
  for (const auto& a : args) argv.push_back(a.c_str());
  return std::make_unique<unav::Context>(static_cast<int>(argv.size()), argv.data(), o);
}

double stamp_s(const std_msgs::msg::dds_::Header_& h) {
  return unav::Time::from_msg(h.stamp().sec(), h.stamp().nanosec()).seconds();
}

struct Harness {
  std::unique_ptr<unav::Context> server_ctx, test_ctx;
  std::unique_ptr<PhysicsServer> server;
  std::unique_ptr<unav::Node> probe;
  std::vector<nav_msgs::msg::Odometry> odoms;
  std::vector<double> clocks;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> odom_sub;
  std::shared_ptr<unav::Subscription<rosgraph_msgs::msg::Clock>> clock_sub;
  std::vector<tf2_msgs::msg::TFMessage> tfs;
  std::shared_ptr<unav::Subscription<tf2_msgs::msg::TFMessage>> tf_sub;
  std::shared_ptr<unav::Publisher<unav_msgs::msg::ThrusterCommand>> cmd_pub;
  std::shared_ptr<unav::Publisher<unav_msgs::msg::LockstepAck>> ack_pub;

  explicit Harness(const std::vector<std::string>& params) {
    server_ctx = make_context(params);
    server = std::make_unique<PhysicsServer>(unav::NodeOptions{server_ctx.get()});
    test_ctx = std::make_unique<unav::Context>(unav::testing::test_context_options());
    probe = std::make_unique<unav::Node>("probe", unav::NodeOptions{test_ctx.get()});
    odom_sub = probe->create_subscription<nav_msgs::msg::Odometry>(
        "/rov/ground_truth/odom", unav::QoS::reliable(100),
        [this](const nav_msgs::msg::Odometry& m) { odoms.push_back(m); });
    clock_sub = probe->create_subscription<rosgraph_msgs::msg::Clock>(
        "/clock", unav::QoS::reliable(100), [this](const rosgraph_msgs::msg::Clock& c) {
          clocks.push_back(unav::Time::from_msg(c.clock().sec(), c.clock().nanosec()).seconds());
        });
    tf_sub = probe->create_subscription<tf2_msgs::msg::TFMessage>(
        "/tf", unav::QoS::reliable(100), [this](const tf2_msgs::msg::TFMessage& m) { tfs.push_back(m); });
    cmd_pub = probe->create_publisher<unav_msgs::msg::ThrusterCommand>("/rov/thrusters/command", unav::QoS::reliable());
    ack_pub = probe->create_publisher<unav_msgs::msg::LockstepAck>("/lockstep/ack", unav::lockstep::ack_qos());
    // Both sides of every link matched before the test sends or counts anything (the server's
    // /lockstep/ack reader exists in lockstep mode only).
    std::vector<unav::testing::Link> links = {make_link(*cmd_pub, *server), make_link(*server, *odom_sub),
                                              make_link(*server, *clock_sub), make_link(*server, *tf_sub)};
    for (const auto* s : server->subscriptions())
      if (s->topic_name() == ack_pub->topic_name()) links.push_back(make_link(*ack_pub, *s));
    EXPECT_TRUE(unav::testing::wait_for_match({server_ctx.get(), test_ctx.get()}, links))
        << unav::testing::describe(links);
  }
  ~Harness() {
    odom_sub.reset();
    clock_sub.reset();
    tf_sub.reset();
    cmd_pub.reset();
    ack_pub.reset();
    probe.reset();
    server.reset();
    test_ctx.reset();
    server_ctx.reset();
  }
  bool spin_until(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
    return unav::testing::spin_until({server_ctx.get(), test_ctx.get()}, done, timeout);
  }
  void command(double t, const std::vector<double>& u) { command(*cmd_pub, t, u); }
  /// A thruster command stamped t on `pub` (the primary's or a fleet vehicle's topic).
  static void command(unav::Publisher<unav_msgs::msg::ThrusterCommand>& pub, double t, const std::vector<double>& u) {
    unav_msgs::msg::ThrusterCommand c;
    const unav::Time s{std::llround(t * 1e9)};
    c.header().stamp().sec(s.sec());
    c.header().stamp().nanosec(s.nanosec());
    c.u(u);
    pub.publish(c);
  }
};

// A physics server and a probe node, each on its own participant: the probe's links matched on
// both sides before a test counts anything.
struct ServerProbe {
  std::unique_ptr<unav::Context> server_ctx, test_ctx;
  std::unique_ptr<PhysicsServer> server;
  std::unique_ptr<unav::Node> probe;
  explicit ServerProbe(const std::vector<std::string>& params)
      : server_ctx(make_context(params)),
        test_ctx(make_context({})),
        server(std::make_unique<PhysicsServer>(unav::NodeOptions{server_ctx.get()})),
        probe(std::make_unique<unav::Node>("probe", unav::NodeOptions{test_ctx.get()})) {}
  ~ServerProbe() {
    probe.reset();
    server.reset();
  }
  ::testing::AssertionResult match(const std::vector<unav::testing::Link>& links) {
    if (unav::testing::wait_for_match({server_ctx.get(), test_ctx.get()}, links)) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << unav::testing::describe(links);
  }
  bool spin_until(const std::function<bool()>& done, std::chrono::milliseconds timeout = 20s) {
    return unav::testing::spin_until({server_ctx.get(), test_ctx.get()}, done, timeout);
  }
};

// Forward thrust from the four horizontal thrusters of the Heavy (REFERENCE.md directions).
const std::vector<double> kSurge = {0.5, 0.5, -0.5, -0.5, 0, 0, 0, 0};

}  // namespace

TEST(PhysicsServer, LockstepHoldsEachBarrierUntilTheCommandArrives) {
  Harness h({"-p", "mode:=lockstep", "-p", "lockstep_wait_for_command:=true", "-p", "lockstep_period:=0.05", "-p",
             "publish_rate:=20.0"});
  std::vector<nav_msgs::msg::Path> paths;
  auto path_sub = h.probe->create_subscription<nav_msgs::msg::Path>(
      "/rov/ground_truth/path", unav::QoS::reliable(10), [&](const nav_msgs::msg::Path& m) { paths.push_back(m); });
  const std::vector<unav::testing::Link> path_link = {make_link(*h.server, *path_sub)};
  ASSERT_TRUE(unav::testing::wait_for_match({h.server_ctx.get(), h.test_ctx.get()}, path_link))
      << unav::testing::describe(path_link);
  // Closed loop over DDS: answer each barrier's odometry with a command stamped at its time.
  double answered = -1.0;
  for (int k = 0; k <= 20; ++k) {
    ASSERT_TRUE(h.spin_until([&] { return !h.odoms.empty() && stamp_s(h.odoms.back().header()) > answered; }, 10s))
        << "no odometry after barrier " << answered;
    answered = stamp_s(h.odoms.back().header());
    EXPECT_NEAR(answered, 0.05 * k, 1e-9);  // exactly one state per barrier, stamped at it
    h.command(answered, kSurge);
  }
  // The server never ran ahead of the loop: it holds at barrier 1.05 until answered.
  h.spin_until([] { return false; }, 200ms);
  EXPECT_NEAR(h.server->simulator().time(), 1.05, 1e-9);
  EXPECT_NEAR(h.clocks.back(), 1.05, 1e-9);
  const auto& p = h.odoms.back().pose().pose().position();
  EXPECT_GT(p.x(), 0.05) << "surge thrust must move the vehicle forward (north)";
  EXPECT_EQ(h.odoms.back().header().frame_id(), "world_ned");
  EXPECT_EQ(h.odoms.back().child_frame_id(), "base_link_frd");
  // The same state on /tf (world_ned -> base_link_frd), one transform per published state.
  ASSERT_TRUE(h.spin_until([&] { return h.tfs.size() >= h.odoms.size(); }, 10s)) << h.tfs.size() << " tf messages";
  const auto& t = h.tfs.back().transforms().at(0);
  EXPECT_EQ(t.header().frame_id(), "world_ned");
  EXPECT_EQ(t.child_frame_id(), "base_link_frd");
  EXPECT_EQ(stamp_s(t.header()), stamp_s(h.odoms.back().header()));
  EXPECT_EQ(t.transform().translation().x(), p.x());
  EXPECT_EQ(t.transform().rotation().w(), h.odoms.back().pose().pose().orientation().w());
  // ground_truth/path: a pose every 0.5 s of simulated time (0, 0.5, 1.0), each the odometry
  // of its instant; the last one published holds all three.
  ASSERT_TRUE(h.spin_until([&] { return !paths.empty() && paths.back().poses().size() == 3; }, 10s))
      << paths.size() << " paths";
  const auto& poses = paths.back().poses();
  for (std::size_t i = 0; i < poses.size(); ++i) EXPECT_NEAR(stamp_s(poses[i].header()), 0.5 * i, 1e-9);
  EXPECT_EQ(paths.back().header().frame_id(), "world_ned");
  const auto at_1s = std::find_if(h.odoms.begin(), h.odoms.end(), [](const nav_msgs::msg::Odometry& o) {
    return std::abs(stamp_s(o.header()) - 1.0) < 1e-9;
  });
  ASSERT_NE(at_1s, h.odoms.end());
  EXPECT_EQ(poses[2].pose().position().x(), at_1s->pose().pose().position().x());
  EXPECT_GT(poses[2].pose().position().x(), poses[0].pose().position().x());
  path_sub.reset();
}

// A new episode on sim/reset: the vehicle jumps to the pose given, at rest, while simulated
// time runs on (no stamp goes back); a NaN or non-rotation pose is rejected and counted.
TEST(PhysicsServer, ResetStartsAnEpisodeWhileTimeRunsOn) {
  Harness h({"-p", "mode:=lockstep", "-p", "lockstep_wait_for_command:=true", "-p", "lockstep_period:=0.05", "-p",
             "publish_rate:=20.0"});
  auto reset_pub = h.probe->create_publisher<geometry_msgs::msg::Pose>("/rov/sim/reset", unav::QoS::reliable());
  std::vector<unav::testing::Link> links;
  for (const auto* s : h.server->subscriptions())
    if (s->topic_name() == reset_pub->topic_name()) links.push_back(make_link(*reset_pub, *s));
  ASSERT_EQ(links.size(), 1u);
  ASSERT_TRUE(unav::testing::wait_for_match({h.server_ctx.get(), h.test_ctx.get()}, links));
  double answered = -1.0;
  auto answer = [&] {
    EXPECT_TRUE(h.spin_until([&] { return !h.odoms.empty() && stamp_s(h.odoms.back().header()) > answered; }, 10s));
    answered = stamp_s(h.odoms.back().header());
    h.command(answered, kSurge);
  };
  for (int k = 0; k < 10; ++k) answer();  // flying forward: ~0.1 m/s after 0.45 s
  geometry_msgs::msg::Pose bad;
  bad.position().x(std::nan(""));
  reset_pub->publish(bad);
  bad.position().x(0.0);
  bad.orientation().w(0.0);  // all-zero quaternion
  reset_pub->publish(bad);
  ASSERT_TRUE(h.spin_until([&] { return h.server->rejections().count("rt/rov/sim/reset") == 2; }, 10s));
  geometry_msgs::msg::Pose start;
  start.position().x(5.0);
  start.position().y(-2.0);
  start.position().z(3.0);
  start.orientation().z(std::sqrt(0.5));  // yaw 90 degrees
  start.orientation().w(std::sqrt(0.5));
  reset_pub->publish(start);
  ASSERT_TRUE(h.spin_until([&] { return h.server->simulator().state().p_WB_W.x() > 4.0; }, 10s)) << "no reset";
  const double v_before = h.odoms.back().twist().twist().linear().x();
  EXPECT_EQ(h.server->simulator().state().v_WB_B.norm(), 0.0) << "at rest";
  EXPECT_EQ(h.server->simulator().thrusters().thrust().norm(), 0.0) << "thrusters stopped";
  const double t_reset = h.server->simulator().time();
  EXPECT_GE(t_reset, 0.45) << "time must not go back to 0";
  // The first state published after it: at the new pose (within the few mm that one 0.05 s
  // barrier of buoyancy and spinning-up thrust moves it), at rest, stamped after the last one.
  while (stamp_s(h.odoms.back().header()) <= t_reset + 1e-9) answer();
  const auto& o = h.odoms.back();
  EXPECT_NEAR(stamp_s(o.header()), t_reset + 0.05, 1e-9);
  EXPECT_NEAR(o.pose().pose().position().x(), 5.0, 0.01);
  EXPECT_NEAR(o.pose().pose().position().y(), -2.0, 0.01);
  EXPECT_NEAR(o.pose().pose().position().z(), 3.0, 0.01);
  EXPECT_NEAR(o.pose().pose().orientation().z(), std::sqrt(0.5), 1e-3);
  // From rest, one barrier of the surge command (thrust spinning up through its 0.1 s lag) gives
  // ~0.03 m/s; the last episode's speed was several times that.
  EXPECT_GT(v_before, 0.1);
  EXPECT_LT(std::abs(o.twist().twist().linear().x()), 0.05) << "the forward speed of the last episode remains";
  EXPECT_EQ(h.server->rejections().total(), 2u);
}

TEST(PhysicsServer, LockstepWaitsForEveryParticipantAck) {
  Harness h({"-p", "mode:=lockstep", "-p", "lockstep_participants:=[renderer]", "-p", "lockstep_period:=0.1"});
  h.spin_until([] { return false; }, 300ms);
  EXPECT_EQ(h.server->simulator().time(), 0.0) << "no ack yet: must hold at t = 0";
  unav_msgs::msg::LockstepAck ack;
  ack.participant("renderer");
  h.ack_pub->publish(ack);  // stamped 0
  ASSERT_TRUE(h.spin_until([&] { return h.server->simulator().time() >= 0.1 - 1e-9; }, 10s));
  h.spin_until([] { return false; }, 200ms);
  EXPECT_NEAR(h.server->simulator().time(), 0.1, 1e-9) << "must hold at the next barrier";
}

TEST(PhysicsServer, RealtimeFailsafeAndBadCommands) {
  Harness h({"-p", "command_timeout:=0.2", "-p", "real_time_factor:=1.0"});
  h.command(0.0, kSurge);
  h.command(0.0, {0.1, 0.2});                  // wrong length: rejected
  h.command(0.0, {NAN, 0, 0, 0, 0, 0, 0, 0});  // NaN: rejected
  h.command(1000.0, kSurge);                   // stamped 1000 s ahead of simulated time: rejected
  ASSERT_TRUE(h.spin_until([&] { return h.server->simulator().command_stats().rejected_non_finite == 1; }, 5s));
  ASSERT_TRUE(h.spin_until([&] { return h.server->rejections().count("rt/rov/thrusters/command") == 1; }, 5s));
  EXPECT_EQ(h.server->simulator().command_stats().rejected_wrong_length, 1u);
  EXPECT_EQ(h.server->simulator().command_stats().accepted, 1u);
  // Simulated time follows the wall clock from the server's start, so the command was applied at
  // whatever simulated time discovery and matching took (more than the 0.2 s timeout on a loaded
  // machine): time the failsafe from then, not from t = 0.
  const double t_command = h.server->simulator().time();  // the command was applied at or before it
  // After > 0.2 s without a command, thrust goes to zero.
  ASSERT_TRUE(h.spin_until([&] { return h.server->simulator().time() > t_command + 1.0; }, 10s));
  EXPECT_TRUE(h.server->simulator().command_timed_out());
  // Thrust decays with the 0.1 s lag after the timeout 0.2 s after the command: e^-8 of ~40 N
  // 1 s after the command.
  EXPECT_LT(h.server->simulator().thrusters().thrust().cwiseAbs().maxCoeff(), 0.1);
  EXPECT_FALSE(h.odoms.empty());
}

namespace {

std::string write_world(const std::string& name, const std::string& body) {
  const std::string dir = ::testing::TempDir() + "unav_physics_world_" + name + "_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/world.yaml") << body;
  return dir + "/world.yaml";
}

}  // namespace

// The world file drives the physics: its relief seabed becomes the contact/DVL/altimeter surface
// (exact at the render grid's nodes, bilinear between them) and its current moves the water.
TEST(PhysicsServer, WorldFileDrivesTheSeabedAndTheCurrent) {
  const std::string current = std::string(UNAV_CONFIG_DIR) + "/water/currents/constant.yaml";
  const std::string world_path =
      write_world("relief",
                  "seabed:\n  depth_m: 12.0\n  center_ne: [2.0, -3.0]\n  size_m: [20.0, 16.0]\n  resolution_m: 0.5\n"
                  "  relief: {amplitude_m: 0.4, wavelength_m: 4.0, seed: 5}\ncurrent: {file: " +
                      current + "}\n");
  const unav::scene::World world = unav::scene::load_world(world_path);
  ASSERT_FALSE(world.seabed.is_flat());
  std::unique_ptr<unav::Context> ctx = make_context({"-p", "world:=" + world_path});
  PhysicsServer server(unav::NodeOptions{ctx.get()});
  const unav::physics::Seabed* sb = server.simulator().seabed();
  ASSERT_NE(sb, nullptr);
  // Grid nodes: origin (2 - 10, -3 - 8), every 0.5 m: the same depth as the renderer's mesh vertices.
  double max_node_err = 0.0, max_relief = 0.0;
  for (int i = 0; i <= 40; i += 3)
    for (int j = 0; j <= 32; j += 3) {
      const double n = -8.0 + 0.5 * i, e = -11.0 + 0.5 * j;
      max_node_err = std::max(max_node_err, std::abs(sb->depth_at(n, e) - world.seabed.depth_at(n, e)));
      max_relief = std::max(max_relief, std::abs(world.seabed.depth_at(n, e) - 12.0));
    }
  EXPECT_LT(max_node_err, 1e-12);
  EXPECT_GT(max_relief, 0.05) << "the relief must actually vary the depth";
  // Between nodes a bilinear patch stays within its cell's corner depths.
  for (const auto& [n, e] : std::vector<std::pair<double, double>>{{0.26, 0.13}, {-5.1, 4.37}, {7.9, -10.6}}) {
    const double n0 = -8.0 + 0.5 * std::floor((n + 8.0) / 0.5), e0 = -11.0 + 0.5 * std::floor((e + 11.0) / 0.5);
    const double c[4] = {world.seabed.depth_at(n0, e0), world.seabed.depth_at(n0 + 0.5, e0),
                         world.seabed.depth_at(n0, e0 + 0.5), world.seabed.depth_at(n0 + 0.5, e0 + 0.5)};
    EXPECT_GE(sb->depth_at(n, e), *std::min_element(c, c + 4) - 1e-12);
    EXPECT_LE(sb->depth_at(n, e), *std::max_element(c, c + 4) + 1e-12);
  }
  // The world's current (config/water/currents/constant.yaml: 0.2 N, 0.1 E m/s).
  EXPECT_TRUE(server.simulator().current_velocity_W().isApprox(Eigen::Vector3d(0.2, 0.1, 0.0), 1e-12));
}

TEST(PhysicsServer, NodeParametersOverrideTheWorld) {
  const std::string world_path = write_world("flat", "seabed: {depth_m: 7.5}\n");
  {
    std::unique_ptr<unav::Context> ctx = make_context({"-p", "world:=" + world_path});
    PhysicsServer server(unav::NodeOptions{ctx.get()});
    ASSERT_NE(server.simulator().seabed(), nullptr);
    EXPECT_DOUBLE_EQ(server.simulator().seabed()->depth_at(3.0, -40.0), 7.5);  // flat world: flat seabed
    EXPECT_TRUE(server.simulator().current_velocity_W().isZero()) << "no current in the world: still water";
  }
  {
    const std::string current = std::string(UNAV_CONFIG_DIR) + "/water/currents/constant.yaml";
    const std::string seabed = std::string(UNAV_TEST_DATA_DIR) + "/seabed_grid.yaml";
    std::unique_ptr<unav::Context> ctx = make_context(
        {"-p", "world:=" + world_path, "-p", "seabed_config:=" + seabed, "-p", "current_config:=" + current});
    PhysicsServer server(unav::NodeOptions{ctx.get()});
    const auto expected = unav::physics::load_seabed(seabed);
    EXPECT_DOUBLE_EQ(server.simulator().seabed()->depth_at(0.3, 0.6), expected->depth_at(0.3, 0.6));
    EXPECT_FALSE(server.simulator().current_velocity_W().isZero());
  }
  {
    std::unique_ptr<unav::Context> ctx = make_context({});  // no world: flat at seabed_depth (10 m)
    PhysicsServer server(unav::NodeOptions{ctx.get()});
    EXPECT_DOUBLE_EQ(server.simulator().seabed()->depth_at(0.0, 0.0), 10.0);
  }
}

// An ack written before the physics server's reader exists (or has matched) still reaches it:
// /lockstep/ack is transient local. With a volatile writer, a participant that acked its first
// input during a slow start (16 processes on 2 cores) was never heard and the lockstep held at
// t = 0 for ever (seen once in three vslam_benchmark runs).
// The four-beam DVL on the wire: over the default flat seabed (10 m) with the vehicle starting at
// 5 m, every beam locks at a slant range of altitude / cos(22.5 deg) (the vehicle stays near level;
// 2 % covers its small tilt and drift while the failsafe holds the thrusters at zero).
TEST(PhysicsServer, DvlPublishesItsFourBeams) {
  ServerProbe h({});
  PhysicsServer& server = *h.server;
  unav::Node& probe = *h.probe;
  std::optional<unav_msgs::msg::Dvl> last;
  auto sub = probe.create_subscription<unav_msgs::msg::Dvl>("/rov/dvl", unav::QoS::sensor_data(),
                                                            [&](const unav_msgs::msg::Dvl& m) { last = m; });
  const std::vector<unav::testing::Link> links = {make_link(server, *sub)};
  ASSERT_TRUE(h.match(links));
  ASSERT_TRUE(h.spin_until([&] { return last && last->valid(); }, 20s)) << "no valid DVL reading";
  EXPECT_EQ(last->locked_beams(), 4);
  const double cos_a = std::cos(22.5 * M_PI / 180.0);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_TRUE(last->beam_valid()[i]) << i;
    EXPECT_NEAR(last->beam_range()[i] * cos_a / last->altitude(), 1.0, 0.02) << i;
  }
  EXPECT_NEAR(last->altitude(), 5.0, 0.5);
}

// The USBL on the wire (the shipped vehicle's transponder, a transceiver 1 m under the origin):
// fixes come about once a second, each after the acoustic round trip (2 x range / 1500 m/s + the
// 0.1 s turnaround), within a few standard deviations (0.1 m range, 1 deg angles at ~4 m) of
// the transponder on the vehicle held near its start (0, 0, 5) by the thruster failsafe.
TEST(PhysicsServer, UsblFixesTheVehicleAfterTheAcousticRoundTrip) {
  ServerProbe h({});
  PhysicsServer& server = *h.server;
  unav::Node& probe = *h.probe;
  std::vector<unav_msgs::msg::UsblFix> fixes;
  auto sub = probe.create_subscription<unav_msgs::msg::UsblFix>(
      "/rov/usbl/fix", unav::QoS::reliable(), [&](const unav_msgs::msg::UsblFix& m) { fixes.push_back(m); });
  const std::vector<unav::testing::Link> links = {make_link(server, *sub)};
  ASSERT_TRUE(h.match(links));
  ASSERT_TRUE(h.spin_until(
      [&] { return std::count_if(fixes.begin(), fixes.end(), [](const auto& f) { return f.valid(); }) >= 2; }, 20s))
      << "fewer than two valid USBL fixes";
  const auto& f = *std::find_if(fixes.begin(), fixes.end(), [](const auto& m) { return m.valid(); });
  EXPECT_EQ(f.header().frame_id(), "usbl_transceiver");
  const Eigen::Vector3d truth = server.simulator().state().p_WB_W + Eigen::Vector3d(-0.1, 0.0, -0.15);
  const Eigen::Vector3d tx(0.0, 0.0, 1.0);
  EXPECT_NEAR(f.range(), (truth - tx).norm(), 0.6);  // the vehicle drifts little while held
  EXPECT_NEAR(f.travel_time(), 2.0 * f.range() / 1500.0 + 0.1, 0.002);
  const Eigen::Vector3d world(f.position_world().x(), f.position_world().y(), f.position_world().z());
  EXPECT_NEAR((world - truth).norm(), 0.0, 0.7);
  EXPECT_NEAR((world - tx - Eigen::Vector3d(f.position().x(), f.position().y(), f.position().z())).norm(), 0.0, 1e-9);
  for (int i = 0; i < 3; ++i) EXPECT_GT(f.position_covariance()[static_cast<std::size_t>(4 * i)], 0.0);
}

// A USBL transceiver and a modem carried by another vehicle of the fleet: rov2 (20 m behind,
// facing east) carries the transceiver that tracks the primary's transponder and the other end of
// the primary's modem (the primary's vehicle.set names rov2 as their carrier). The fix on
// /rov/usbl/fix is the primary in rov2's transceiver axes: ahead of a vehicle facing east, 20 m
// north of it, is to its left (azimuth -90 deg), at the range between them; bytes rov2 sends on
// /rov2/modem/rov/tx arrive on /rov/modem/rx after ~20 m of travel. A carrier that is not a
// vehicle of the scenario is refused, naming the key.
TEST(PhysicsServer, UsblAndModemCarriedByAnotherVehicle) {
  const std::string world_path = write_world("usbl_pair", "seabed: {depth_m: 30.0}\n");
  const std::string dir = std::filesystem::path(world_path).parent_path().string();
  const std::string model = std::string(UNAV_CONFIG_DIR) + "/vehicles/bluerov2_heavy.yaml";
  const std::string quiet =
      "sensors.usbl.enabled=true, sensors.usbl.range_stddev_m=0, sensors.usbl.angle_stddev_deg=0, "
      "sensors.usbl.outlier_probability=0, sensors.usbl.dropout_at_max_range=0, sensors.modem.enabled=true, "
      "sensors.modem.loss_at_max_range=0, sensors.modem.station_vehicle=rov2";
  auto write = [&](const std::string& file, const std::string& carrier) {
    std::ofstream(dir + "/" + file) << "name: usbl_pair\nworld: world.yaml\n"
                                    << "vehicle: {model: " << model << ", initial_position: [0, 0, 5], set: [" << quiet
                                    << ", sensors.usbl.transceiver_vehicle=" << carrier << "]}\n"
                                    << "fleet:\n  - {name: rov2, model: " << model
                                    << ", initial_position: [-20, 0, 5], initial_rpy_deg: [0, 0, 90]}\n";
    return dir + "/" + file;
  };
  ServerProbe h({"-p", "scenario:=" + write("usbl_pair.yaml", "rov2")});
  PhysicsServer& server = *h.server;
  std::vector<unav_msgs::msg::UsblFix> fixes;
  auto sub = h.probe->create_subscription<unav_msgs::msg::UsblFix>(
      "/rov/usbl/fix", unav::QoS::reliable(), [&](const unav_msgs::msg::UsblFix& m) { fixes.push_back(m); });
  std::vector<unav_msgs::msg::AcousticPacket> got;
  const unav::QoS qos = unav::QoS::reliable(100);
  auto rx = h.probe->create_subscription<unav_msgs::msg::AcousticPacket>(
      "/rov/modem/rx", qos, [&](const unav_msgs::msg::AcousticPacket& m) { got.push_back(m); });
  auto tx = h.probe->create_publisher<unav_msgs::msg::AcousticPacket>("/rov2/modem/rov/tx", qos);
  ASSERT_TRUE(h.match({make_link(server, *sub), make_link(server, *rx), make_link(*tx, server)}));
  unav_msgs::msg::AcousticPacket packet;
  packet.data({1, 2, 3});
  tx->publish(packet);
  ASSERT_TRUE(h.spin_until([&] { return !fixes.empty() && fixes.back().valid(); }, 20s)) << "no valid USBL fix";
  const auto& f = fixes.back();
  // The vehicles drift apart little without thrust (both held near their starts).
  EXPECT_NEAR(f.range(), 20.0, 0.5);
  EXPECT_NEAR(f.azimuth(), -M_PI / 2, 0.05);
  EXPECT_NEAR(f.position().y(), -20.0, 0.5);  // transceiver axes: y right, the primary to the left
  const Eigen::Vector3d world(f.position_world().x(), f.position_world().y(), f.position_world().z());
  const Eigen::Vector3d truth = server.simulator().state().p_WB_W + Eigen::Vector3d(-0.1, 0.0, -0.15);
  EXPECT_NEAR((world - truth).norm(), 0.0, 0.5);
  ASSERT_TRUE(h.spin_until([&] { return !got.empty(); }, 20s)) << "no packet from rov2's modem";
  EXPECT_EQ(got[0].data(), (std::vector<std::uint8_t>{1, 2, 3}));
  // Modems at (-0.1, 0, -0.15) on each, 20 m apart along north (rov2 yawed: its modem 0.1 m west).
  EXPECT_NEAR(got[0].range(), 20.0, 0.5);
  EXPECT_NEAR(got[0].travel_time(), got[0].range() / 1500.0 + 24.0 / 100.0, 0.0011);  // 3 bytes at 100 bit/s

  std::string what = "accepted";
  try {
    ServerProbe b({"-p", "scenario:=" + write("usbl_bad.yaml", "rov9")});
  } catch (const std::exception& e) {
    what = e.what();
  }
  for (const char* part : {"usbl_bad.yaml", "vehicle.sensors.usbl.transceiver_vehicle = rov9", "no such vehicle"})
    EXPECT_NE(what.find(part), std::string::npos) << what;
}

// The acoustic modem link on the wire: 4 bytes handed to the surface station's modem arrive on
// the vehicle's after the travel (~4 m at 1500 m/s) plus 0.32 s on the air at 100 bit/s.
TEST(PhysicsServer, ModemCarriesBytesFromTheSurfaceToTheVehicle) {
  ServerProbe h({});
  PhysicsServer& server = *h.server;
  unav::Node& probe = *h.probe;
  std::vector<unav_msgs::msg::AcousticPacket> got;
  const unav::QoS qos = unav::QoS::reliable(100);
  auto sub = probe.create_subscription<unav_msgs::msg::AcousticPacket>(
      "/rov/modem/rx", qos, [&](const unav_msgs::msg::AcousticPacket& m) { got.push_back(m); });
  auto pub = probe.create_publisher<unav_msgs::msg::AcousticPacket>("/surface/modem/tx", qos);
  const std::vector<unav::testing::Link> links = {make_link(server, *sub), make_link(*pub, server)};
  ASSERT_TRUE(h.match(links));
  unav_msgs::msg::AcousticPacket m;
  m.data({0xDE, 0xAD, 0xBE, 0xEF});
  pub->publish(m);
  ASSERT_TRUE(h.spin_until([&] { return !got.empty(); }, 20s)) << "no packet arrived";
  EXPECT_EQ(got[0].data(), (std::vector<std::uint8_t>{0xDE, 0xAD, 0xBE, 0xEF}));
  EXPECT_EQ(got[0].header().frame_id(), "modem");
  EXPECT_NEAR(got[0].range(), 3.9, 0.6);  // the vehicle held near (0, 0, 5), the station at (0, 0, 1)
  EXPECT_NEAR(got[0].travel_time(), got[0].range() / 1500.0 + 0.32, 0.0011);  // + up to a step of hand-over
}

TEST(LockstepAck, AnAckWrittenBeforeTheServerMatchedStillArrives) {
  unav::Context participant_ctx(unav::testing::test_context_options());
  unav::Node participant("late_ack_participant", {&participant_ctx});
  unav::lockstep::Acker acker(participant, "renderer");
  std_msgs::msg::Header input;
  input.stamp().sec(2);
  input.stamp().nanosec(500000000);
  acker.ack(input);  // nobody is listening yet
  unav::Context server_ctx(unav::testing::test_context_options());
  unav::Node server("late_ack_server", {&server_ctx});
  std::vector<unav_msgs::msg::LockstepAck> got;
  auto sub = server.create_subscription<unav_msgs::msg::LockstepAck>(
      "/lockstep/ack", unav::lockstep::ack_qos(), [&](const unav_msgs::msg::LockstepAck& a) { got.push_back(a); });
  ASSERT_TRUE(unav::testing::spin_until(
      {&participant_ctx, &server_ctx}, [&] { return !got.empty(); }, std::chrono::seconds(20)));
  EXPECT_EQ(got[0].participant(), "renderer");
  EXPECT_EQ(got[0].header().stamp().sec(), 2);
  EXPECT_EQ(got[0].header().stamp().nanosec(), 500000000u);
}

// One scenario, two paths (DESIGN.md section 9): the physics server given `scenario:=FILE` over
// DDS in lockstep and the simulator that physics::build_simulator() makes in process from the
// same file, driven by the same commands at the same barriers, give the same trajectory bit for
// bit (same code, same inputs, same order of floating-point operations: nothing to tolerate). The
// thrust drives the vehicle down into the scenario world's seabed, where both stop on it.
TEST(PhysicsServer, ScenarioRunsTheSameOverDdsAndInProcess) {
  const std::string world_path = write_world("scenario", "seabed: {depth_m: 6.0}\n");
  const std::string scenario_path = std::filesystem::path(world_path).parent_path().string() + "/scenario.yaml";
  std::ofstream(scenario_path) << "name: dive\nworld: world.yaml\n"
                               << "vehicle: {model: " << UNAV_CONFIG_DIR
                               << "/vehicles/bluerov2_heavy.yaml, initial_position: [1.0, 2.0, 4.5],"
                                  " initial_rpy_deg: [0, 0, 30]}\n";
  // Down on the four vertical thrusters (their positive thrust is up: REFERENCE.md directions).
  const std::vector<double> dive = {0, 0, 0, 0, -0.8, -0.8, -0.8, -0.8};
  Harness h({"-p", "scenario:=" + scenario_path, "-p", "mode:=lockstep", "-p", "lockstep_wait_for_command:=true", "-p",
             "lockstep_period:=0.05", "-p", "publish_rate:=20.0"});
  const unav::scene::Scenario sc = unav::scene::load_scenario(scenario_path);
  const unav::scene::World world = unav::scene::load_world(sc.world);
  auto sim = unav::physics::build_simulator(sc, world, unav::physics::scenario_simulator_options(sc, 0.5));
  constexpr int kBarriers = 100;  // 5 s: long enough to reach the seabed 1.5 m below and settle
  double answered = -1.0;
  for (int k = 0; k <= kBarriers; ++k) {
    ASSERT_TRUE(h.spin_until([&] { return !h.odoms.empty() && stamp_s(h.odoms.back().header()) > answered; }, 10s))
        << "no odometry after barrier " << answered;
    answered = stamp_s(h.odoms.back().header());
    ASSERT_NEAR(answered, 0.05 * k, 1e-9);
    // The state the server published for this barrier = the in-process state after k periods.
    const auto& p = h.odoms.back().pose().pose().position();
    const auto& q = h.odoms.back().pose().pose().orientation();
    const auto& x = sim->state();
    ASSERT_EQ(p.x(), x.p_WB_W.x()) << "barrier " << k;
    ASSERT_EQ(p.y(), x.p_WB_W.y()) << "barrier " << k;
    ASSERT_EQ(p.z(), x.p_WB_W.z()) << "barrier " << k;
    ASSERT_EQ(q.w(), x.q_WB.w()) << "barrier " << k;
    ASSERT_EQ(q.z(), x.q_WB.z()) << "barrier " << k;
    h.command(answered, dive);
    sim->set_command(sim->time(), dive);
    for (int i = 0; i < 50; ++i) sim->step();
  }
  // On the seabed: the bottom point (z + height/2 = z + 0.127) pressed in by at most the net
  // downward force over the stiffness (4 x ~0.8 x 40 N thrust + ~2 N weight - buoyancy) / 2000 N/m
  // = 0.07 m, and at rest vertically.
  const double bottom = h.odoms.back().pose().pose().position().z() + 0.127;
  EXPECT_GT(bottom, 6.0 - 1e-3);
  EXPECT_LT(bottom, 6.0 + 0.07);
  EXPECT_LT(std::abs(sim->state().v_WB_B.z()), 0.01);
}

// The tether on the wire, enabled by a scenario's vehicle.set: its shape (anchor first, one pose
// per node) and its pull arrive; tether/length pays it out; a NaN length is rejected and counted.
TEST(PhysicsServer, ScenarioTetherIsPublishedAndPaidOut) {
  const std::string world_path = write_world("tether", "seabed: {depth_m: 20.0}\n");
  const std::string scenario_path = std::filesystem::path(world_path).parent_path().string() + "/tether.yaml";
  std::ofstream(scenario_path)
      << "name: tethered\nworld: world.yaml\n"
      << "vehicle: {model: " << UNAV_CONFIG_DIR
      << "/vehicles/bluerov2_heavy.yaml, initial_position: [3.0, 0.0, 5.0],"
         " set: ['tether.anchor_position=[0, 0, 0.5]', tether.length_m=12, tether.segments=12]}\n";
  ServerProbe h({"-p", "scenario:=" + scenario_path});
  PhysicsServer& server = *h.server;
  unav::Node& probe = *h.probe;
  ASSERT_NE(server.simulator().tether(), nullptr);
  std::optional<nav_msgs::msg::Path> path;
  std::optional<geometry_msgs::msg::WrenchStamped> wrench;
  auto path_sub = probe.create_subscription<nav_msgs::msg::Path>("/rov/tether/path", unav::QoS::reliable(1),
                                                                 [&](const nav_msgs::msg::Path& m) { path = m; });
  auto wrench_sub = probe.create_subscription<geometry_msgs::msg::WrenchStamped>(
      "/rov/tether/wrench", unav::QoS::sensor_data(), [&](const geometry_msgs::msg::WrenchStamped& m) { wrench = m; });
  auto length_pub = probe.create_publisher<std_msgs::msg::Float64>("/rov/tether/length", unav::QoS::reliable());
  const std::vector<unav::testing::Link> links = {make_link(server, *path_sub), make_link(server, *wrench_sub),
                                                  make_link(*length_pub, server)};
  ASSERT_TRUE(h.match(links));
  ASSERT_TRUE(h.spin_until([&] { return path && wrench; }, 20s));
  ASSERT_EQ(path->poses().size(), 13u);
  EXPECT_EQ(path->header().frame_id(), "world_ned");
  EXPECT_DOUBLE_EQ(path->poses()[0].pose().position().z(), 0.5);
  EXPECT_TRUE(std::isfinite(wrench->wrench().force().z()));
  std_msgs::msg::Float64 len;
  len.data(std::nan(""));
  length_pub->publish(len);
  len.data(20.0);
  length_pub->publish(len);
  ASSERT_TRUE(h.spin_until([&] { return std::abs(server.simulator().tether()->length() - 20.0) < 1e-9; }, 20s));
  EXPECT_EQ(server.rejections().count("rt/rov/tether/length"), 1u);
}

// Several vehicles in one world (a scenario's fleet): the physics server steps each with the
// primary one, each on its own ports (/<name>/...) and /tf frame (<name>/base_link_frd). A fleet
// vehicle flies what is commanded on its own topic only, exactly as the in-process simulator
// of the same scenario entry flies it (bit for bit: same builder, same commands, same steps);
// the other vehicles do not move with it. Bad fleets are refused naming the file, key and rule.
TEST(PhysicsServer, FleetVehiclesFlyOnTheirOwnTopics) {
  const std::string world_path = write_world("fleet", "seabed: {depth_m: 30.0}\n");
  const std::string dir = std::filesystem::path(world_path).parent_path().string();
  const std::string model = std::string(UNAV_CONFIG_DIR) + "/vehicles/bluerov2_heavy.yaml";
  std::ofstream(dir + "/fleet.yaml") << "name: pair\nworld: world.yaml\n"
                                     << "vehicle: {model: " << model << ", initial_position: [0, 0, 5]}\n"
                                     << "fleet:\n"
                                     << "  - {name: rov2, model: " << model
                                     << ", initial_position: [-5, 0, 5], initial_rpy_deg: [0, 0, 90]}\n"
                                     << "  - {name: rov3, model: " << model << ", initial_position: [0, 8, 6]}\n";
  Harness h({"-p", "scenario:=" + dir + "/fleet.yaml", "-p", "mode:=lockstep", "-p", "lockstep_wait_for_command:=true",
             "-p", "lockstep_period:=0.05", "-p", "publish_rate:=20.0"});
  PhysicsServer& server = *h.server;
  ASSERT_EQ(server.fleet_size(), 2u);
  std::vector<nav_msgs::msg::Odometry> rov2, rov3;
  auto rov2_sub = h.probe->create_subscription<nav_msgs::msg::Odometry>(
      "/rov2/ground_truth/odom", unav::QoS::reliable(100),
      [&](const nav_msgs::msg::Odometry& m) { rov2.push_back(m); });
  auto rov3_sub = h.probe->create_subscription<nav_msgs::msg::Odometry>(
      "/rov3/ground_truth/odom", unav::QoS::reliable(100),
      [&](const nav_msgs::msg::Odometry& m) { rov3.push_back(m); });
  auto rov2_cmd =
      h.probe->create_publisher<unav_msgs::msg::ThrusterCommand>("/rov2/thrusters/command", unav::QoS::reliable());
  auto rov3_cmd =
      h.probe->create_publisher<unav_msgs::msg::ThrusterCommand>("/rov3/thrusters/command", unav::QoS::reliable());
  const std::vector<unav::testing::Link> links = {make_link(server, *rov2_sub), make_link(server, *rov3_sub),
                                                  make_link(*rov2_cmd, server), make_link(*rov3_cmd, server)};
  ASSERT_TRUE(unav::testing::wait_for_match({h.server_ctx.get(), h.test_ctx.get()}, links))
      << unav::testing::describe(links);

  const unav::scene::Scenario sc = unav::scene::load_scenario(dir + "/fleet.yaml");
  const unav::scene::World world = unav::scene::load_world(sc.world);
  auto sim = unav::physics::build_simulator(sc, world, unav::physics::scenario_simulator_options(sc, 0.0),
                                            unav::physics::scenario_vehicle(sc.fleet[0].vehicle, "fleet[0]"),
                                            sc.fleet[0].vehicle);
  const std::vector<double> hover(8, 0.0);
  double answered = -1.0;
  for (int k = 0; k <= 20; ++k) {  // 1 s, the primary commanded to do nothing
    ASSERT_TRUE(h.spin_until(
        [&] {
          return !h.odoms.empty() && stamp_s(h.odoms.back().header()) > answered && !rov2.empty() &&
                 stamp_s(rov2.back().header()) == stamp_s(h.odoms.back().header());
        },
        10s))
        << "no odometry after barrier " << answered;
    answered = stamp_s(h.odoms.back().header());
    const auto& p = rov2.back().pose().pose().position();
    ASSERT_EQ(p.x(), sim->state().p_WB_W.x()) << "barrier " << k;
    ASSERT_EQ(p.y(), sim->state().p_WB_W.y()) << "barrier " << k;
    ASSERT_EQ(p.z(), sim->state().p_WB_W.z()) << "barrier " << k;
    // Every vehicle answers the barrier (each holds it: lockstep_wait_for_command); rov2 surges,
    // heading east (yaw 90 deg), the others hover.
    Harness::command(*rov3_cmd, answered, hover);
    h.command(answered, hover);
    if (k == 3) {  // the barrier holds for rov2, which has not answered yet
      h.spin_until([] { return false; }, 100ms);
      EXPECT_NEAR(server.simulator().time(), answered, 1e-9);
    }
    Harness::command(*rov2_cmd, answered, kSurge);
    sim->set_command(sim->time(), kSurge);
    for (int i = 0; i < 50; ++i) sim->step();
  }
  const auto& p2 = rov2.back().pose().pose().position();
  EXPECT_GT(p2.y(), 0.05) << "rov2 surges east";
  EXPECT_NEAR(p2.x(), -5.0, 0.02);
  EXPECT_EQ(rov2.back().header().frame_id(), "world_ned");
  EXPECT_EQ(rov2.back().child_frame_id(), "rov2/base_link_frd");
  const auto& p1 = h.odoms.back().pose().pose().position();
  EXPECT_NEAR(p1.x(), 0.0, 1e-3) << "the primary does not move with rov2";
  EXPECT_NEAR(p1.y(), 0.0, 1e-3);
  ASSERT_FALSE(rov3.empty());
  EXPECT_NEAR(rov3.back().pose().pose().position().x(), 0.0, 1e-3);
  EXPECT_NEAR(rov3.back().pose().pose().position().y(), 8.0, 1e-3);
  // /tf: every vehicle's body frame, each in a message of its own.
  std::set<std::string> children;
  for (const auto& m : h.tfs) children.insert(m.transforms().at(0).child_frame_id());
  EXPECT_EQ(children, (std::set<std::string>{"base_link_frd", "rov2/base_link_frd", "rov3/base_link_frd"}));
  rov2_sub.reset();
  rov3_sub.reset();
  rov2_cmd.reset();
  rov3_cmd.reset();

  // Bad fleets: the file, the key and the rule.
  const auto refused = [&](const std::string& fleet, const std::string& expect) {
    std::ofstream(dir + "/bad.yaml") << "name: bad\nworld: world.yaml\nvehicle: {model: " << model << "}\nfleet:\n"
                                     << fleet;
    try {
      unav::scene::load_scenario(dir + "/bad.yaml");
      ADD_FAILURE() << "accepted: " << fleet;
    } catch (const unav::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(dir + "/bad.yaml"), std::string::npos) << e.what();
    }
  };
  refused("  - {name: rov2, model: " + model + "}\n  - {name: rov2, model: " + model + "}\n",
          "fleet[1].name");  // twice the same namespace
  refused("  - {name: 2rov, model: " + model + "}\n", "a letter, then letters, digits or _");
  refused("  - {name: rov2, model: nowhere.yaml}\n", "fleet[0].model");
}
