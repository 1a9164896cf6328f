// Runtime over real Fast DDS: two participants in one process on a domain of the test's own.
#include <gtest/gtest.h>

#include <fstream>
#include <thread>

#include "rosgraph_msgs/msg/clock.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "std_msgs/msg/string.hpp"
#include "unav_msgs/msg/thruster_command.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/testing.hpp"
#include "unav_runtime/tf_static.hpp"

using namespace std::chrono_literals;
using namespace unav;
using unav::testing::make_link;
using unav::testing::spin_until;
using unav::testing::test_context_options;

TEST(PubSub, MessagesArriveWithTheirContent) {
  Context ctx_a(test_context_options()), ctx_b(test_context_options());
  Node talker("talker", {&ctx_a}, "rov");
  Node listener("listener", {&ctx_b}, "rov");
  auto pub = talker.create_publisher<unav_msgs::msg::ThrusterCommand>("thrusters/command", QoS::reliable());
  std::vector<double> got;
  int count = 0;
  auto sub = listener.create_subscription<unav_msgs::msg::ThrusterCommand>(
      "/rov/thrusters/command", QoS::reliable(), [&](const unav_msgs::msg::ThrusterCommand& m) {
        got = m.u();
        ++count;
      });
  EXPECT_EQ(pub->topic_name(), "rt/rov/thrusters/command");
  ASSERT_TRUE(unav::testing::wait_for_match({&ctx_a, &ctx_b}, {make_link(*pub, *sub)})) << "no discovery";
  unav_msgs::msg::ThrusterCommand cmd;
  for (int i = 0; i < 5; ++i) {
    cmd.u({0.1 * i, -0.5});
    pub->publish(cmd);
  }
  ASSERT_TRUE(ctx_b.spin_until([&] { return count == 5; }, 10s)) << "got " << count;
  EXPECT_EQ(got, (std::vector<double>{0.4, -0.5}));
}

// The listener takes one sample ahead while the executor wakes (prefetch): every sample of a
// burst still reaches the callback once, in order, also when the callback is slow at times.
TEST(PubSub, BurstArrivesInOrderWithPrefetch) {
  Context ctx_a(test_context_options()), ctx_b(test_context_options());
  Node talker("talker", {&ctx_a});
  Node listener("listener", {&ctx_b});
  constexpr int kCount = 1000;
  auto pub = talker.create_publisher<unav_msgs::msg::ThrusterCommand>("burst", QoS::reliable(kCount));
  std::vector<double> got;
  auto sub = listener.create_subscription<unav_msgs::msg::ThrusterCommand>(
      "/burst", QoS::reliable(kCount), [&](const unav_msgs::msg::ThrusterCommand& m) {
        got.push_back(m.u().at(0));
        if (got.size() % 50 == 0) std::this_thread::sleep_for(2ms);  // the listener runs ahead meanwhile
      });
  ASSERT_TRUE(unav::testing::wait_for_match({&ctx_a, &ctx_b}, {make_link(*pub, *sub)}));
  unav_msgs::msg::ThrusterCommand cmd;
  for (int i = 0; i < kCount; ++i) {
    cmd.u({static_cast<double>(i)});
    ASSERT_TRUE(pub->publish(cmd));
  }
  ASSERT_TRUE(ctx_b.spin_until([&] { return got.size() >= static_cast<size_t>(kCount); }, 30s)) << got.size();
  ctx_b.spin_some(100ms);
  ASSERT_EQ(got.size(), static_cast<size_t>(kCount)) << "a sample was delivered twice";
  for (int i = 0; i < kCount; ++i) ASSERT_EQ(got[static_cast<size_t>(i)], i) << "out of order at " << i;
}

TEST(PubSub, LargeImageTravelsIntact) {
  Context ctx_a(test_context_options()), ctx_b(test_context_options());
  Node cam("camera", {&ctx_a});
  Node viewer("viewer", {&ctx_b});
  auto pub = cam.create_publisher<sensor_msgs::msg::Image>("image_raw", QoS::reliable(2));
  sensor_msgs::msg::Image last;
  int count = 0;
  auto sub = viewer.create_subscription<sensor_msgs::msg::Image>("/image_raw", QoS::reliable(2),
                                                                 [&](const sensor_msgs::msg::Image& m) {
                                                                   last = m;
                                                                   ++count;
                                                                 });
  ASSERT_TRUE(unav::testing::wait_for_match({&ctx_a, &ctx_b}, {make_link(*pub, *sub)}));
  sensor_msgs::msg::Image img;
  img.height(480);
  img.width(640);
  img.encoding("rgb8");
  img.step(1920);
  img.data().resize(921600);
  for (size_t i = 0; i < img.data().size(); ++i) img.data()[i] = static_cast<uint8_t>((i * 7u) >> 3);
  pub->publish(img);
  ASSERT_TRUE(ctx_b.spin_until([&] { return count == 1; }, 10s));
  EXPECT_EQ(last.data(), img.data());
  EXPECT_EQ(last.encoding(), "rgb8");
}

TEST(PubSub, StaticQosReachesLateJoiners) {
  Context ctx_a(test_context_options()), ctx_b(test_context_options());
  Node pub_node("info_pub", {&ctx_a});
  auto pub = pub_node.create_publisher<std_msgs::msg::String>("camera_info_like", QoS::static_latched());
  std_msgs::msg::String s;
  s.data("latched");
  pub->publish(s);
  Node late("late", {&ctx_b});
  std::string got;
  auto sub = late.create_subscription<std_msgs::msg::String>("/camera_info_like", QoS::static_latched(),
                                                             [&](const std_msgs::msg::String& m) { got = m.data(); });
  ASSERT_TRUE(ctx_b.spin_until([&] { return !got.empty(); }, 10s));
  EXPECT_EQ(got, "latched");
}

TEST(PubSub, SimTimeFollowsClockAndDrivesTimers) {
  const char* argv[] = {"test", "--ros-args", "-p", "use_sim_time:=true"};
  ContextOptions o = test_context_options();
  Context ctx_sim(4, argv, o);
  Context ctx_phys(o);
  Node sim_node("controller", {&ctx_sim});
  EXPECT_TRUE(ctx_sim.clock().sim_time_active());
  EXPECT_EQ(sim_node.now().ns, 0);  // no /clock yet
  int ticks = 0;
  auto timer = sim_node.create_timer(100ms, [&] { ++ticks; });
  Node phys("physics", {&ctx_phys});
  auto clock_pub = phys.create_publisher<rosgraph_msgs::msg::Clock>("/clock", QoS::reliable(1));
  ASSERT_TRUE(spin_until({&ctx_sim, &ctx_phys}, [&] { return clock_pub->subscription_count() == 1; }));
  rosgraph_msgs::msg::Clock c;
  // Simulated time advances 1 s in 10 steps: the 100 ms timer must fire about 10 times,
  // whatever the wall clock does (tolerance 1: the first period starts at the first /clock).
  // The /clock reader belongs to the context (no node shows it) and is best effort, as in ROS 2:
  // each time is published again until the clock shows it (setting the same time twice is
  // harmless), so a sample sent before that reader matched the writer, or dropped, costs only
  // a retry.
  for (int i = 1; i <= 10; ++i) {
    c.clock().sec(0);
    c.clock().nanosec(static_cast<uint32_t>(i * 100000000));
    ASSERT_TRUE(spin_until({&ctx_phys},
                           [&] {
                             clock_pub->publish(c);
                             return spin_until(
                                 {&ctx_sim}, [&] { return sim_node.now().ns >= i * 100000000LL; }, 100ms);
                           }))
        << "clock " << i;
  }
  EXPECT_EQ(sim_node.now().ns, 1000000000LL);
  EXPECT_GE(ticks, 9);
  EXPECT_LE(ticks, 10);
}

struct TestNodeParams {
  double rate = 1.0;
  std::string name = "x";
  int64_t missing = 7;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(unav::common::Field("rate", &rate).Range(0.0, 100.0).Unit("Hz"));
    a->Visit(unav::common::Field("name", &name));
    a->Visit(unav::common::Field("missing", &missing));
  }
};

TEST(PubSub, NodeParametersFromFileAndCommandLine) {
  const std::string path = ::testing::TempDir() + "node_params.yaml";
  std::ofstream(path) << "talker:\n  ros__parameters:\n    rate: 5.0\n    name: abc\n    typo_key: 1\n";
  const char* argv[] = {"t", "--ros-args", "--params-file", path.c_str(), "-p", "name:=cli", "-r", "__ns:=/rov"};
  Context ctx(8, argv, test_context_options());
  Node n("talker", {&ctx});
  EXPECT_EQ(n.fully_qualified_name(), "/rov/talker");
  TestNodeParams p;
  n.declare_params(&p);
  EXPECT_EQ(p.rate, 5.0);
  EXPECT_EQ(p.name, "cli");
  EXPECT_EQ(p.missing, 7);
  EXPECT_EQ(n.parameters().at("rate").as<double>(), 5.0);
  try {
    n.check_undeclared_parameters();
    FAIL() << "typo_key should be reported";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("typo_key"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("node_params.yaml"), std::string::npos);
  }
  TestNodeParams again;
  EXPECT_THROW(n.declare_params(&again), ParameterError);  // declared twice
}

TEST(PubSub, WrongParameterTypeNamesFileKeyAndValue) {
  const std::string path = ::testing::TempDir() + "bad_type.yaml";
  std::ofstream(path) << "talker:\n  ros__parameters:\n    rate: fast\n";
  const char* argv[] = {"t", "--ros-args", "--params-file", path.c_str()};
  Context ctx(4, argv, test_context_options());
  Node n("talker", {&ctx});
  try {
    TestNodeParams p;
    n.declare_params(&p);
    FAIL();
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("bad_type.yaml"), std::string::npos) << msg;
    EXPECT_NE(msg.find("rate"), std::string::npos) << msg;
    EXPECT_NE(msg.find("fast"), std::string::npos) << msg;
  }
}

// The values a params file or `-p` gives are typed and checked by the node's schema: integers
// are valid doubles, `-p name:=` is the empty string (as in ROS 2), and a wrong type, a value
// out of range or NaN is an error naming the source, key and value.
struct OverrideParams {
  double rate = 1.0;
  std::string name = "x";
  std::vector<double> gains{1.0, 2.0};
  bool on = false;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(unav::common::Field("rate", &rate).Range(0.1, 100.0).Unit("Hz"));
    a->Visit(unav::common::Field("name", &name));
    a->Visit(unav::common::Field("gains", &gains));
    a->Visit(unav::common::Field("on", &on));
  }
};

TEST(PubSub, ParameterOverridesAreTypedAndCheckedByTheSchema) {
  const auto declare = [](const std::vector<std::string>& overrides) {
    std::vector<std::string> args{"t", "--ros-args"};
    for (const auto& o : overrides) {
      args.push_back("-p");
      args.push_back(o);
    }
    std::vector<const char*> argv;
    argv.reserve(args.size());
    for (const auto& a : args) argv.push_back(a.c_str());
    Context ctx(static_cast<int>(argv.size()), argv.data(), test_context_options());
    Node n("talker", {&ctx});
    OverrideParams p;
    n.declare_params(&p);
    return p;
  };
  const auto error_of = [&](const std::vector<std::string>& overrides) {
    try {
      declare(overrides);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const OverrideParams p = declare({"rate:=5", "name:=", "gains:=[1, 2.5]", "on:=true"});
  EXPECT_EQ(p.rate, 5.0);
  EXPECT_EQ(p.name, "");
  EXPECT_EQ(p.gains, (std::vector<double>{1.0, 2.5}));
  EXPECT_TRUE(p.on);
  const std::string wrong_type = error_of({"rate:=fast"});
  EXPECT_NE(wrong_type.find("rate:=fast"), std::string::npos) << wrong_type;  // the source
  EXPECT_NE(wrong_type.find("number"), std::string::npos) << wrong_type;
  const std::string range = error_of({"rate:=1000"});
  EXPECT_NE(range.find("[0.1, 100]"), std::string::npos) << range;
  EXPECT_NE(error_of({"rate:=.nan"}), "");
  EXPECT_NE(error_of({"on:=3"}), "");
  EXPECT_NE(error_of({"name:=[1]"}), "");
  EXPECT_NE(error_of({"gains:=[1, x]"}).find("gains[1]"), std::string::npos) << error_of({"gains:=[1, x]"});
}

// A mount published once, latched, before the listener exists, reaches it (transient local, as
// tf2's static broadcaster relies on), and the listener composes a chain of two static edges.
TEST(PubSub, StaticTransformListenerGetsLatchedMountsAsALateJoiner) {
  Context ctx_a(test_context_options()), ctx_b(test_context_options());
  Node owner("renderer", {&ctx_a}, "rov");
  auto pub = owner.create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", QoS::static_latched());
  Eigen::Isometry3d X_BL = Eigen::Isometry3d::Identity(), X_LO = Eigen::Isometry3d::Identity();
  X_BL.translation() << 0.2, 0.0, 0.1;
  X_BL.linear() = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  X_LO.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  tf2_msgs::msg::TFMessage m;
  m.transforms().push_back(to_transform_stamped(X_BL, 0.0, "base_link_frd", "down_link"));
  m.transforms().push_back(to_transform_stamped(X_LO, 0.0, "down_link", "down_optical"));
  pub->publish(m);  // before anyone listens

  Node late("estimator", {&ctx_b}, "rov");
  StaticTransformListener tf(late);
  int updates = 0;
  tf.on_update([&] { ++updates; });
  ASSERT_TRUE(unav::testing::wait_for_match({&ctx_a, &ctx_b}, {make_link(*pub, *tf.subscription())}));
  ASSERT_TRUE(spin_until(
      {&ctx_a, &ctx_b}, [&] { return tf.lookup("base_link_frd", "down_optical").has_value(); }, 10s));
  EXPECT_EQ(updates, 1);
  // Through the message (double -> quaternion -> double): equal to ~1e-15.
  EXPECT_TRUE(tf.lookup("base_link_frd", "down_optical")->isApprox(X_BL * X_LO, 1e-12));
  EXPECT_TRUE(tf.lookup("down_optical", "base_link_frd")->isApprox((X_BL * X_LO).inverse(), 1e-12));
  EXPECT_FALSE(tf.lookup("base_link_frd", "front_optical").has_value());
}

// UNAV_TRANSPORT picks the transports: UDPv4 by default, shared memory only when asked for (Fast
// DDS 2.9 cannot reach a participant that reuses the shared-memory port of a SIGKILLed one), and
// a typo is an error naming the variable, the value and the choices, not a silent default.
TEST(PubSub, TransportComesFromTheEnvironmentAndATypoIsAnError) {
  const char* saved = std::getenv("UNAV_TRANSPORT");
  const std::string restore = saved ? saved : "";
  ::unsetenv("UNAV_TRANSPORT");
  EXPECT_FALSE(shm_transport_from_environment());
  ::setenv("UNAV_TRANSPORT", "udp", 1);
  EXPECT_FALSE(shm_transport_from_environment());
  ::setenv("UNAV_TRANSPORT", "shm", 1);
  EXPECT_TRUE(shm_transport_from_environment());
  ::setenv("UNAV_TRANSPORT", "tcp", 1);
  try {
    Context ctx(test_context_options());
    ADD_FAILURE() << "a Context was made with UNAV_TRANSPORT=tcp";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("UNAV_TRANSPORT='tcp': expected udp (the default) or shm"), std::string::npos)
        << e.what();
  }
  if (saved) {
    ::setenv("UNAV_TRANSPORT", restore.c_str(), 1);
  } else {
    ::unsetenv("UNAV_TRANSPORT");
  }
}
