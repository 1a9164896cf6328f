// ardusub_bridge over UDP and DDS: a scripted ArduPilot peer (our own, sending servo packets as
// ArduPilot documents them) drives the node through a loopback socket; the replies follow the
// physics, and the vehicle's state reaches DDS subscribers as from the physics server.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ardusub_bridge_node.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_runtime/testing.hpp"

using namespace std::chrono_literals;
using unav::testing::make_link;

namespace {

std::unique_ptr<unav::Context> make_context() {
  const std::string root = UNAV_REPO_ROOT;
  const std::vector<std::string> args = {"ardusub_bridge",
                                         "--ros-args",
                                         "-p",
                                         "scenario:=" + root + "/config/scenarios/ardusub_pipe.yaml",
                                         "-p",
                                         "motor_map:=" + root + "/config/autopilot/ardusub_bluerov2_heavy.yaml",
                                         "-p",
                                         "port:=0",
                                         "-p",
                                         "publish_period:=0.01"};
  std::vector<const char*> argv;
  argv.reserve(args.size());
  for (const auto& a : args) argv.push_back(a.c_str());
  return std::make_unique<unav::Context>(static_cast<int>(argv.size()), argv.data(),
                                         unav::testing::test_context_options());
}

struct Peer {  // ArduPilot's side of the link
  int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  explicit Peer(int port) {
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<std::uint16_t>(port));
    ::inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
  }
  ~Peer() { ::close(fd); }
  void send(const std::vector<std::uint8_t>& p) const {
    ::sendto(fd, p.data(), p.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
  }
  std::string receive() const {
    pollfd pfd{fd, POLLIN, 0};
    if (::poll(&pfd, 1, 0) <= 0) return "";
    char buf[1024];
    const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : "";
  }
};

}  // namespace

TEST(ArduSubBridge, AnswersServoPacketsAndPublishesTheVehicle) {
  auto node_ctx = make_context();
  unav::autopilot::ArduSubBridge bridge(unav::NodeOptions{node_ctx.get()});
  ASSERT_GT(bridge.bound_port(), 0);
  unav::Context test_ctx(unav::testing::test_context_options());
  unav::Node probe("probe", unav::NodeOptions{&test_ctx});
  std::vector<nav_msgs::msg::Odometry> odoms;
  auto odom_sub =
      probe.create_subscription<nav_msgs::msg::Odometry>("/rov/ground_truth/odom", unav::QoS::reliable(100),
                                                         [&](const nav_msgs::msg::Odometry& m) { odoms.push_back(m); });
  std::vector<sensor_msgs::msg::Imu> imus;
  auto imu_sub = probe.create_subscription<sensor_msgs::msg::Imu>(
      "/rov/imu", unav::QoS::sensor_data(), [&](const sensor_msgs::msg::Imu& m) { imus.push_back(m); });
  ASSERT_TRUE(unav::testing::wait_for_match({node_ctx.get(), &test_ctx},
                                            {make_link(bridge, *odom_sub), make_link(bridge, *imu_sub)}));

  Peer peer(bridge.bound_port());
  std::vector<std::uint16_t> pwm(16, 1500);
  for (int k = 4; k < 8; ++k) pwm[static_cast<std::size_t>(k)] = 1800;  // dive (vertical motors)
  std::string reply;
  constexpr int kFrames = 500;
  for (std::uint32_t f = 0; f < kFrames; ++f) {
    peer.send(unav::autopilot::encode_servo_packet(1000, f, pwm));
    // Lockstep as ArduPilot runs it: the next packet only after the reply to this one.
    ASSERT_TRUE(unav::testing::spin_until(
        {node_ctx.get(), &test_ctx}, [&] { return !(reply = peer.receive()).empty(); }, 10s))
        << "no reply to frame " << f;
  }
  const nlohmann::json j = nlohmann::json::parse(reply.substr(1, reply.size() - 2));
  EXPECT_NEAR(j["timestamp"].get<double>(), 0.5, 1e-9);  // 500 packets at 1 kHz = 0.5 s
  EXPECT_EQ(bridge.backend().stats().steps, static_cast<std::uint64_t>(kFrames));
  EXPECT_GT(j["position"][2].get<double>(), 2.0) << "diving from 2 m";
  // A malformed packet is counted and not answered.
  peer.send(std::vector<std::uint8_t>{1, 2, 3});
  unav::testing::spin_until(
      {node_ctx.get(), &test_ctx}, [&] { return bridge.backend().stats().dropped_total() > 0; }, 5s);
  EXPECT_EQ(bridge.backend().stats().dropped_total(), 1u);
  EXPECT_EQ(peer.receive(), "");
  // The states on DDS: every 10 ms of simulated time, the last one at 0.5 s with the reply's depth.
  ASSERT_TRUE(unav::testing::spin_until(
      {node_ctx.get(), &test_ctx}, [&] { return !odoms.empty() && unav::seconds(odoms.back().header()) > 0.5 - 1e-6; },
      10s))
      << odoms.size() << " states";
  EXPECT_EQ(odoms.back().pose().pose().position().z(), bridge.backend().simulator().state().p_WB_W.z());
  EXPECT_NEAR(odoms.back().pose().pose().position().z(), j["position"][2].get<double>(), 1e-8);
  EXPECT_GE(odoms.size(), 40u);
  // The vehicle's sensors as the physics server publishes them (the IMU at its configured rate).
  EXPECT_FALSE(imus.empty());
  EXPECT_GT(bridge.handle_us_percentile(0.5), 0.0);
}
