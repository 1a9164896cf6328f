// Discovery range and static peers (ROS 2's ROS_AUTOMATIC_DISCOVERY_RANGE / ROS_STATIC_PEERS):
// the plan read from the variables, and participants over real Fast DDS with each range.
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "std_msgs/msg/string.hpp"
#include "unav_runtime/discovery.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/testing.hpp"

using namespace std::chrono_literals;
using unav::discovery_plan;
using unav::DiscoveryRange;
using unav::testing::make_link;

namespace {

std::string error_of(const char* range, const char* peers) {
  try {
    discovery_plan(range, peers, nullptr, false);
  } catch (const unav::ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(DiscoveryPlan, DefaultsToMulticastAndToThisHostUnderSecurity) {
  EXPECT_EQ(discovery_plan(nullptr, nullptr, nullptr, false).range, DiscoveryRange::kSubnet);
  EXPECT_EQ(discovery_plan("", "", nullptr, false).range, DiscoveryRange::kSubnet);
  const auto secured = discovery_plan(nullptr, nullptr, nullptr, true);
  EXPECT_EQ(secured.range, DiscoveryRange::kLocalhost);
  EXPECT_NE(secured.reason.find("secured"), std::string::npos);
  EXPECT_EQ(discovery_plan(nullptr, nullptr, "1", false).range, DiscoveryRange::kLocalhost);
  EXPECT_EQ(discovery_plan(nullptr, nullptr, "0", false).range, DiscoveryRange::kSubnet);
  // Explicit ranges win over the older switch and over the secured default.
  EXPECT_EQ(discovery_plan("LOCALHOST", nullptr, nullptr, false).range, DiscoveryRange::kLocalhost);
  EXPECT_EQ(discovery_plan("OFF", nullptr, "1", false).range, DiscoveryRange::kOff);
  EXPECT_EQ(discovery_plan("SYSTEM_DEFAULT", nullptr, nullptr, false).range, DiscoveryRange::kSubnet);
  const auto multicast_secured = discovery_plan("SUBNET", nullptr, nullptr, true);
  EXPECT_EQ(multicast_secured.range, DiscoveryRange::kSubnet);
  EXPECT_NE(multicast_secured.warning.find("PR #3362"), std::string::npos);  // says why it is risky
}

TEST(DiscoveryPlan, StaticPeersAreIpv4AddressesSeparatedBySemicolons) {
  const auto plan = discovery_plan("OFF", " 10.0.0.2;192.168.1.40 ;;", nullptr, false);
  EXPECT_EQ(plan.static_peers, (std::vector<std::string>{"10.0.0.2", "192.168.1.40"}));
  EXPECT_TRUE(discovery_plan(nullptr, "", nullptr, false).static_peers.empty());
}

TEST(DiscoveryPlan, BadValuesAreNamedWithTheRule) {
  const std::string range = error_of("subnet", nullptr);
  EXPECT_NE(range.find("ROS_AUTOMATIC_DISCOVERY_RANGE='subnet'"), std::string::npos) << range;
  EXPECT_NE(range.find("SUBNET, LOCALHOST, OFF or SYSTEM_DEFAULT"), std::string::npos) << range;
  const std::string peer = error_of(nullptr, "10.0.0.2;robot.local");
  EXPECT_NE(peer.find("ROS_STATIC_PEERS"), std::string::npos) << peer;
  EXPECT_NE(peer.find("'robot.local' is not an IPv4 address"), std::string::npos) << peer;
}

// Over Fast DDS: with unicast discovery on this host two participants find each other and a
// message goes through; with discovery OFF they do not, until the other is a static peer.
class DiscoveryOverDds : public ::testing::Test {
 protected:
  void TearDown() override {
    unsetenv("ROS_AUTOMATIC_DISCOVERY_RANGE");
    unsetenv("ROS_STATIC_PEERS");
  }
  // Whether a talker and a listener in two participants match within `timeout` and, if they do,
  // whether a message arrives.
  static bool talk(std::chrono::milliseconds timeout) {
    unav::Context a(unav::testing::test_context_options());
    unav::ContextOptions ob = unav::testing::test_context_options();
    ob.domain_id = a.domain_id();
    unav::Context b(ob);
    unav::Node talker("talker", {&a});
    unav::Node listener("listener", {&b});
    auto pub = talker.create_publisher<std_msgs::msg::String>("chatter", unav::QoS::reliable());
    std::string got;
    auto sub = listener.create_subscription<std_msgs::msg::String>(
        "/chatter", unav::QoS::reliable(), [&](const std_msgs::msg::String& m) { got = m.data(); });
    if (!unav::testing::wait_for_match({&a, &b}, {make_link(*pub, *sub)}, timeout)) return false;
    std_msgs::msg::String m;
    m.data("over unicast discovery");
    pub->publish(m);
    return b.spin_until([&] { return !got.empty(); }, 10s) && got == "over unicast discovery";
  }
};

TEST_F(DiscoveryOverDds, LocalhostFindsThisHostsParticipants) {
  setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST", 1);
  EXPECT_TRUE(talk(20s));
}

TEST_F(DiscoveryOverDds, OffFindsOnlyStaticPeers) {
  setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "OFF", 1);
  // 3 s: discovery on loopback takes ~10-100 ms; no match by then is no discovery at all.
  EXPECT_FALSE(talk(3s));
  setenv("ROS_STATIC_PEERS", "127.0.0.1", 1);
  EXPECT_TRUE(talk(20s));
}
