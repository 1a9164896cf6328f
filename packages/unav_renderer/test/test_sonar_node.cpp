// sonar node over DDS: odometry in, marine_acoustic_msgs pings + viewing images out, lockstep
// acks, mounts on /tf_static.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>

#include "node_test_util.hpp"
#include "sonar_node.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_runtime/testing.hpp"
#include "unav_scene/sonar.hpp"

using unav::testing::make_link;

namespace {

std::string small_sonars() {
  // Small sonars keep llvmpipe fast: a 32-beam FLS at 10 Hz and a side-scan at 20 Hz.
  std::string p = ::testing::TempDir() + "node_sonars.yaml";
  std::ofstream(p) << "sonars:\n"
                      "  - name: fls\n    preset: oculus_m750d_lf\n    beams: 32\n    bins: 64\n"
                      "    max_range_m: 10\n    ping_rate_hz: 10\n"
                      "    mount: {xyz_m: [0.2, 0, 0], rpy_deg: [0, -30, 0]}\n"
                      "  - name: ss\n    preset: sidescan_900k\n    bins: 128\n    max_range_m: 10\n"
                      "    ping_rate_hz: 20\n";
  return p;
}

double stamp_s(const std_msgs::msg::Header& h) {
  return unav::Time::from_msg(h.stamp().sec(), h.stamp().nanosec()).seconds();
}

}  // namespace

TEST(SonarNode, PublishesStandardSonarMessagesAtTheirRatesAndAcks) {
  const std::string world = std::string("world:=") + UNAV_REPO_ROOT + "/worlds/pipe_inspection/world.yaml";
  unav::testing::NodeUnderTest<unav::renderer::SonarNode> fx(
      "sonar", {"--ros-args", "-p", world, "-p", "sonars_config:=" + small_sonars(), "-p", "lockstep:=true", "-p",
                "fan_width:=128", "-p", "waterfall_lines:=20"});
  unav::renderer::SonarNode& node = *fx.node;
  unav::Node& probe = fx.probe;
  auto odom_pub = probe.create_publisher<nav_msgs::msg::Odometry>("/rov/ground_truth/odom", unav::QoS::reliable());
  std::vector<marine_acoustic_msgs::msg::ProjectedSonarImage> fls;
  std::vector<marine_acoustic_msgs::msg::RawSonarImage> raw;
  std::vector<sensor_msgs::msg::Image> fans, falls;
  std::vector<double> acks;
  auto fls_sub = probe.create_subscription<marine_acoustic_msgs::msg::ProjectedSonarImage>(
      "/rov/sonar/fls/image", unav::QoS::reliable(),
      [&](const marine_acoustic_msgs::msg::ProjectedSonarImage& m) { fls.push_back(m); });
  auto raw_sub = probe.create_subscription<marine_acoustic_msgs::msg::RawSonarImage>(
      "/rov/sonar/ss/raw", unav::QoS::reliable(),
      [&](const marine_acoustic_msgs::msg::RawSonarImage& m) { raw.push_back(m); });
  auto fan_sub = probe.create_subscription<sensor_msgs::msg::Image>(
      "/rov/sonar/fls/image_fan", unav::QoS::reliable(), [&](const sensor_msgs::msg::Image& m) { fans.push_back(m); });
  auto fall_sub = probe.create_subscription<sensor_msgs::msg::Image>(
      "/rov/sonar/ss/waterfall", unav::QoS::reliable(), [&](const sensor_msgs::msg::Image& m) { falls.push_back(m); });
  auto ack_sub = probe.create_subscription<unav_msgs::msg::LockstepAck>(
      "/lockstep/ack", unav::QoS::reliable(100),
      [&](const unav_msgs::msg::LockstepAck& a) { acks.push_back(stamp_s(a.header())); });
  // Every link matched on both sides before the first odometry (a volatile writer drops what it
  // writes before it knows a reader).
  const std::vector<unav::testing::Link> links = {make_link(*odom_pub, node), make_link(node, *fls_sub),
                                                  make_link(node, *raw_sub),  make_link(node, *fan_sub),
                                                  make_link(node, *fall_sub), make_link(node, *ack_sub)};
  ASSERT_TRUE(fx.match(links));
  // 3 m above the 10 m seabed, over the pipe's start.
  auto send = [&](double t) { odom_pub->publish(unav::testing::odometry_at(t, {0.0, 0.0, 7.0})); };
  // FLS at 10 Hz: pings at 1.0 and 1.1; side-scan at 20 Hz: 1.0, 1.05, 1.1.
  for (double t : {1.0, 1.05, 1.1}) send(t);
  ASSERT_TRUE(fx.spin_until([&] {
    return acks.size() == 3 && fls.size() == 2 && raw.size() == 3 && fans.size() == 2 && falls.size() == 3;
  })) << acks.size()
      << " acks, " << fls.size() << " FLS, " << raw.size() << " side-scan";
  EXPECT_EQ(acks, (std::vector<double>{1.0, 1.05, 1.1}));
  const unav::scene::SonarModel m = unav::scene::load_sonar(small_sonars(), "fls");
  // ProjectedSonarImage: geometry field for field from the config.
  const auto& f = fls[0];
  EXPECT_DOUBLE_EQ(stamp_s(f.header()), 1.0);
  EXPECT_NEAR(stamp_s(fls[1].header()), 1.1, 1e-9);
  EXPECT_EQ(f.header().frame_id(), "fls_link");
  EXPECT_FLOAT_EQ(f.ping_info().frequency(), 750e3f);
  EXPECT_GT(f.ping_info().sound_speed(), 1450.0f);
  EXPECT_LT(f.ping_info().sound_speed(), 1560.0f);
  ASSERT_EQ(f.beam_directions().size(), 32u);
  ASSERT_EQ(f.ranges().size(), 64u);
  EXPECT_NEAR(f.ranges()[0], m.bin_center_m(0), 1e-6);
  EXPECT_NEAR(f.ranges()[63], m.bin_center_m(63), 1e-5);
  for (int k = 0; k < 32; ++k) {
    const auto& d = f.beam_directions()[static_cast<std::size_t>(k)];
    EXPECT_NEAR(std::atan2(d.y(), d.z()), m.beam_azimuth_rad(k), 1e-6);
    EXPECT_NEAR(d.x(), 0.0, 1e-12);
    EXPECT_NEAR(std::hypot(d.y(), d.z()), 1.0, 1e-9);
  }
  EXPECT_EQ(f.image().beam_count(), 32u);
  EXPECT_EQ(f.image().dtype(), marine_acoustic_msgs::msg::SonarImageData_Constants::DTYPE_UINT8);
  EXPECT_EQ(f.image().data().size(), 32u * 64u);
  int lit = 0;
  for (auto v : f.image().data()) lit += v > 0 ? 1 : 0;
  EXPECT_GT(lit, 32 * 64 / 4) << "the seabed fills the fan looking 30 deg down from 3 m";
  // RawSonarImage for the side-scan: 2 beams (port, starboard), samples at c / (2 dr).
  const auto& r = raw[0];
  EXPECT_EQ(r.header().frame_id(), "ss_link");
  EXPECT_EQ(r.samples_per_beam(), 128u);
  EXPECT_EQ(r.image().beam_count(), 2u);
  EXPECT_EQ(r.image().data().size(), 256u);
  ASSERT_EQ(r.rx_angles().size(), 2u);
  EXPECT_NEAR(r.rx_angles()[0], -M_PI / 2, 1e-6);
  EXPECT_NEAR(r.sample_rate(), r.ping_info().sound_speed() / (2.0 * (10.0 - 0.5) / 128), 1.0);
  // Viewing images.
  EXPECT_EQ(fans[0].encoding(), "mono8");
  EXPECT_EQ(fans[0].width(), 128u);
  EXPECT_EQ(falls.back().width(), 256u);
  EXPECT_EQ(falls.back().height(), 20u);
  EXPECT_EQ(node.pings_published(), 5u);
}

TEST(SonarNode, PublishesMountsOnTfStaticAndRejectsBadConfig) {
  const std::string world = std::string("world:=") + UNAV_REPO_ROOT + "/worlds/pipe_inspection/world.yaml";
  const std::string path = small_sonars();
  const std::string cfg = "sonars_config:=" + path;
  const char* argv[] = {"sonar", "--ros-args", "-p", world.c_str(), "-p", cfg.c_str()};
  unav::Context node_ctx(6, argv, unav::testing::test_context_options());
  unav::renderer::SonarNode node({&node_ctx});
  const auto got = unav::testing::late_latched<tf2_msgs::msg::TFMessage>(node_ctx, "/tf_static");
  ASSERT_TRUE(got.has_value()) << "no /tf_static for a late subscriber";
  ASSERT_EQ(got->transforms().size(), 2u);
  const auto& t = got->transforms()[0];
  EXPECT_EQ(t.header().frame_id(), "base_link_frd");
  EXPECT_EQ(t.child_frame_id(), "fls_link");
  const Eigen::Isometry3d X = unav::from_msg(t.transform());
  // z along the boresight: forward and 30 deg down; x up-ish.
  const Eigen::Vector3d z = X.linear().col(2);
  EXPECT_NEAR(z.x(), std::cos(M_PI / 6), 1e-9);
  EXPECT_NEAR(z.z(), std::sin(M_PI / 6), 1e-9);
  EXPECT_NEAR(X.translation().x(), 0.2, 1e-12);

  // A bad file is a clear configuration error naming the file and the key.
  const std::string bad = ::testing::TempDir() + "bad_sonars.yaml";
  std::ofstream(bad) << "sonars:\n  - name: fls\n    beams: 0\n";
  const std::string bad_cfg = "sonars_config:=" + bad;
  const char* argv2[] = {"sonar", "--ros-args", "-p", world.c_str(), "-p", bad_cfg.c_str()};
  unav::Context ctx2(6, argv2, unav::testing::test_context_options());
  try {
    unav::renderer::SonarNode n2({&ctx2});
    FAIL() << "beams: 0 accepted";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bad_sonars.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find("beams"), std::string::npos) << what;
  }
}

// A profiling sonar over DDS: looking straight down from 3 m above the demo world's seabed (5 m
// east of the pipe: sand with 0.15 m of relief), (nearly) every beam of its 90 deg fan returns: a
// PointCloud2 of x, y, z, intensity in prof_link whose nearest point is the nadir, ~3 m away.
TEST(SonarNode, ProfilerPublishesAPointCloudAcrossTrack) {
  const std::string path = ::testing::TempDir() + "node_profiler.yaml";
  std::ofstream(path)
      << "sonars:\n  - name: prof\n    type: profiling\n    beams: 48\n    bins: 256\n"
         "    horizontal_aperture_deg: 90\n    vertical_aperture_deg: 3\n    min_range_m: 0.3\n"
         "    max_range_m: 12\n    ping_rate_hz: 10\n    mount: {xyz_m: [0, 0, 0.1], rpy_deg: [0, -90, 0]}\n";
  const std::string world = std::string("world:=") + UNAV_REPO_ROOT + "/worlds/pipe_inspection/world.yaml";
  unav::testing::NodeUnderTest<unav::renderer::SonarNode> fx(
      "sonar", {"--ros-args", "-p", world, "-p", "sonars_config:=" + path});
  unav::renderer::SonarNode& node = *fx.node;
  unav::Node& probe = fx.probe;
  auto odom_pub = probe.create_publisher<nav_msgs::msg::Odometry>("/rov/ground_truth/odom", unav::QoS::reliable());
  std::vector<sensor_msgs::msg::PointCloud2> clouds;
  auto sub = probe.create_subscription<sensor_msgs::msg::PointCloud2>(
      "/rov/sonar/prof/points", unav::QoS::reliable(),
      [&](const sensor_msgs::msg::PointCloud2& m) { clouds.push_back(m); });
  const std::vector<unav::testing::Link> links = {make_link(*odom_pub, node), make_link(node, *sub)};
  ASSERT_TRUE(fx.match(links));
  odom_pub->publish(unav::testing::odometry_at(1.0, {3.0, 5.0, 7.0}));
  ASSERT_TRUE(fx.spin_until([&] { return !clouds.empty(); }));
  const auto& c = clouds[0];
  EXPECT_EQ(c.header().frame_id(), "prof_link");
  ASSERT_EQ(c.fields().size(), 4u);
  EXPECT_EQ(c.point_step(), 16u);
  // 3 m / cos 45 deg = 4.2 m: every beam reaches the seabed; a grazing beam at the fan's edge may
  // miss it when its speckle (K texture) leaves its echo less than 10 dB above its median, as real
  // profilers drop beams there: at most 3 of 48.
  EXPECT_GE(c.width(), 45u);
  EXPECT_LE(c.width(), 48u);
  ASSERT_EQ(c.data().size(), 16u * c.width());
  double nearest = 1e9;
  for (std::uint32_t i = 0; i < c.width(); ++i) {
    float v[4];
    std::memcpy(v, c.data().data() + (std::size_t{16} * i), sizeof(v));
    EXPECT_NEAR(v[0], 0.0f, 1e-6f);  // in the fan's plane (x up is out of it)
    nearest = std::min(nearest, std::hypot(static_cast<double>(v[1]), static_cast<double>(v[2])));
  }
  EXPECT_NEAR(nearest, 2.9, 0.25);  // 3 m less the 0.1 m mount, +- the relief
}

TEST(SonarNode, RangesTheOtherVehiclesWhereTheyAre) {
  // A scenario with a fleet vehicle (rov2): the primary's sonar (/rov) draws it as a box at its
  // ground-truth pose. A profiler looking down from 7.1 m (mount 0.1 m under the body at 7.0 m)
  // ranges the seabed at ~2.9 m; with rov2 centred 1.5 m under the body, its top face (0.127 m
  // above its centre) is the nearest return: 8.5 - 0.127 - 7.1 = 1.273 m (bins of 4.6 cm).
  const std::string sonars = ::testing::TempDir() + "node_fleet_profiler.yaml";
  std::ofstream(sonars)
      << "sonars:\n  - name: prof\n    type: profiling\n    beams: 48\n    bins: 256\n"
         "    horizontal_aperture_deg: 90\n    vertical_aperture_deg: 3\n    min_range_m: 0.3\n"
         "    max_range_m: 12\n    ping_rate_hz: 10\n    mount: {xyz_m: [0, 0, 0.1], rpy_deg: [0, -90, 0]}\n";
  const std::string scenario = ::testing::TempDir() + "sonar_fleet_scenario.yaml";
  std::ofstream(scenario) << "world: " << UNAV_REPO_ROOT << "/worlds/pipe_inspection/world.yaml\n"
                          << "sonars: {config: " << sonars << ", names: [prof]}\n"
                          << "fleet: [{name: rov2, initial_position: [40.0, 40.0, 9.0]}]\n";
  unav::renderer::test::ScenarioNode<unav::renderer::SonarNode> fx("sonar", scenario, {"noise:=false"});
  unav::renderer::SonarNode& node = *fx.node;
  auto& odom_pub = fx.odom_pub;
  auto& other_pub = fx.other_pub;
  std::vector<sensor_msgs::msg::PointCloud2> clouds;
  auto sub = fx.probe.create_subscription<sensor_msgs::msg::PointCloud2>(
      "/rov/sonar/prof/points", unav::QoS::reliable(),
      [&](const sensor_msgs::msg::PointCloud2& m) { clouds.push_back(m); });
  ASSERT_TRUE(fx.match({make_link(*odom_pub, node), make_link(*other_pub, node), make_link(node, *sub)}));
  auto state = [](double t, double depth) { return unav::testing::odometry_at(t, {3.0, 5.0, depth}); };
  auto nearest = [](const sensor_msgs::msg::PointCloud2& c) {
    double n = 1e9;
    for (std::uint32_t i = 0; i < c.width(); ++i) {
      float v[4];
      std::memcpy(v, c.data().data() + (std::size_t{16} * i), sizeof(v));
      n = std::min(n, std::hypot(static_cast<double>(v[1]), static_cast<double>(v[2])));
    }
    return n;
  };
  odom_pub->publish(state(1.0, 7.0));  // rov2 not heard yet: where the scenario starts it, far away
  ASSERT_TRUE(fx.spin_until([&] { return clouds.size() == 1; }));
  other_pub->publish(state(1.0, 8.5));  // then under the profiler
  ASSERT_TRUE(fx.spin_until([&] { return node.fleet_states() == 1; }));
  odom_pub->publish(state(1.1, 7.0));  // ours first: the ping waits for rov2's 1.1 s state
  other_pub->publish(state(1.1, 8.5));
  ASSERT_TRUE(fx.spin_until([&] { return clouds.size() == 2; }));
  std::printf("profiler: nearest return %.3f m without rov2, %.3f m with it below\n", nearest(clouds[0]),
              nearest(clouds[1]));
  EXPECT_NEAR(nearest(clouds[0]), 2.9, 0.25);
  EXPECT_NEAR(nearest(clouds[1]), 1.273, 0.05);
}
