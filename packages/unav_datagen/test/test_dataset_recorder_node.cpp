// dataset_recorder over DDS, in lockstep: its acks follow the latest odometry but never pass the
// next rgb frame it has not written (min(odometry, last frame + image_period - 1 ms)), so a frame
// lost on the way (published before this reader matched, or by a renderer killed before
// delivering it) holds the barrier until the renderer sends it again; a frame sent again is acked
// and not written twice. Every written frame has its ground-truth pose.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "unav_msgs/msg/lockstep_ack.hpp"
#include "unav_runtime/testing.hpp"

#define UNAV_DATASET_RECORDER_NO_MAIN
#include "../src/dataset_recorder_node.cpp"  // NOLINT(bugprone-suspicious-include): the node under test

using namespace std::chrono_literals;
using unav::testing::make_link;

namespace {

std::vector<std::string> data_lines(const std::string& path) {
  std::vector<std::string> out;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') out.push_back(line);
  return out;
}

}  // namespace

TEST(DatasetRecorderNode, LockstepAcksWaitForEveryFrameAndAFrameSentAgainIsNotWrittenTwice) {
  const std::string dir = ::testing::TempDir() + "recorder_node_test";
  std::filesystem::remove_all(dir);
  const std::string cams_path = ::testing::TempDir() + "recorder_node_cams.yaml";
  std::ofstream(cams_path) << "cameras:\n  - name: down\n    mount: {xyz_m: [0.1, 0, 0.2], rpy_deg: [0, -90, 0]}\n"
                              "    width: 8\n    height: 6\n    hfov_deg: 90\n";
  std::vector<int64_t> acks;
  {
    unav::testing::NodeUnderTest<unav::datagen::DatasetRecorder> fx(
        "dataset_recorder", {"--ros-args", "-p", "output_dir:=" + dir, "-p", "cameras_config:=" + cams_path, "-p",
                             "camera:=down", "-p", "lockstep:=true", "-p", "image_period:=0.1"});
    auto& node = fx.node;
    unav::Node& probe = fx.probe;
    auto odom_pub = probe.create_publisher<nav_msgs::msg::Odometry>("/rov/ground_truth/odom", unav::QoS::reliable(100));
    auto rgb_pub =
        probe.create_publisher<sensor_msgs::msg::Image>("/rov/camera/down/image_raw", unav::QoS::reliable(5));
    auto ack_sub = probe.create_subscription<unav_msgs::msg::LockstepAck>(
        "/lockstep/ack", unav::lockstep::ack_qos(), [&](const unav_msgs::msg::LockstepAck& a) {
          EXPECT_EQ(a.participant(), "recorder");
          acks.push_back(unav::nanoseconds(a.header()));
        });
    auto spin_until = [&](const std::function<bool()>& done) { return fx.spin_until(done, 20s); };
    const std::vector<unav::testing::Link> links = {make_link(*odom_pub, *node), make_link(*rgb_pub, *node),
                                                    make_link(*node, *ack_sub)};
    ASSERT_TRUE(fx.match(links));
    auto odom = [&](int64_t ms) {
      nav_msgs::msg::Odometry o;
      o.header().stamp() = unav::to_msg(unav::Time{ms * 1000000});
      o.header().frame_id("world_ned");
      o.pose().pose().position().x(0.01 * static_cast<double>(ms));
      o.pose().pose().orientation().w(1.0);
      odom_pub->publish(o);
    };
    auto frame = [&](int64_t ms) {
      sensor_msgs::msg::Image m;
      m.header().stamp() = unav::to_msg(unav::Time{ms * 1000000});
      m.header().frame_id("down_optical");
      m.width(8);
      m.height(6);
      m.encoding("rgb8");
      m.step(24);
      m.data(std::vector<uint8_t>(size_t{8} * 6 * 3, static_cast<uint8_t>(ms / 10)));
      rgb_pub->publish(m);
    };
    constexpr int64_t kMs = 1000000;
    // The physics ran to 0.3 s before any frame arrived: nothing may be acked past 0.099 s, the
    // instant just under the frame at 0.1 s, once the frame at 0 is written (and nothing before).
    for (int64_t ms : {0, 50, 100, 150, 200, 250, 300}) odom(ms);
    frame(0);
    ASSERT_TRUE(spin_until([&] { return !acks.empty() && acks.back() == 99 * kMs; }))
        << (acks.empty() ? std::string("no ack") : "last ack " + std::to_string(acks.back()));
    for (int64_t a : acks) EXPECT_LE(a, 99 * kMs);
    frame(100);
    ASSERT_TRUE(spin_until([&] { return acks.back() == 199 * kMs; })) << acks.back();
    frame(200);
    ASSERT_TRUE(spin_until([&] { return acks.back() == 299 * kMs; })) << acks.back();
    frame(300);  // now the odometry (0.3 s) is the limit
    ASSERT_TRUE(spin_until([&] { return acks.back() == 300 * kMs; })) << acks.back();
    odom(350);
    ASSERT_TRUE(spin_until([&] { return acks.back() == 350 * kMs; })) << acks.back();
    odom(400);  // a frame instant with no frame yet: acked up to just under it
    ASSERT_TRUE(spin_until([&] { return acks.back() == 399 * kMs; })) << acks.back();
    const size_t n = acks.size();
    frame(300);  // the renderer sends the last frame again (the lockstep held): acked, not written
    ASSERT_TRUE(spin_until([&] { return acks.size() > n; }));
    EXPECT_EQ(acks.back(), 399 * kMs);
    frame(400);
    ASSERT_TRUE(spin_until([&] { return acks.back() == 400 * kMs; })) << acks.back();
    for (size_t i = 1; i < acks.size(); ++i) EXPECT_GE(acks[i], acks[i - 1]) << "acks went backwards at " << i;
  }  // the recorder closes its files
  const auto rgb = data_lines(dir + "/rgb.txt");
  const auto gt = data_lines(dir + "/groundtruth.txt");
  ASSERT_EQ(rgb.size(), 5u);  // 0, 0.1, 0.2, 0.3, 0.4: the repeated 0.3 not twice
  EXPECT_EQ(rgb[3].substr(0, rgb[3].find(' ')), "0.300000000");
  EXPECT_EQ(gt.size(), 5u);  // each frame with the pose of its stamp
}
