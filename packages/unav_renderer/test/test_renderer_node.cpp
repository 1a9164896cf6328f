// underwater_renderer over DDS: odometry in, stamped images out (and lockstep acks).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "node_test_util.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_runtime/testing.hpp"
#include "unav_scene/camera.hpp"
#include "unav_scene/world.hpp"
#include "underwater_renderer_node.hpp"

using namespace std::chrono_literals;
using unav::renderer::test::ScenarioNode;
using unav::testing::make_link;

namespace {

std::string small_cameras() {
  // One small downward camera keeps llvmpipe fast.
  std::string p = ::testing::TempDir() + "node_cams.yaml";
  std::ofstream(p) << "cameras:\n  - name: down\n    mount: {xyz_m: [0, 0, 0], rpy_deg: [0, -90, 0]}\n"
                      "    width: 80\n    height: 48\n    hfov_deg: 90\n";
  return p;
}

// The renderer node at 10 Hz (one small down camera, no noise; in lockstep unless told) and a
// probe that sends it odometry and records its lockstep acks [s]; the tests add their own image
// readers.
struct LockstepRenderer : unav::testing::NodeUnderTest<unav::renderer::UnderwaterRendererNode> {
  explicit LockstepRenderer(const char* mode = "lockstep:=true")
      : NodeUnderTest(
            "underwater_renderer",
            {"--ros-args", "-p", std::string("world:=") + UNAV_REPO_ROOT + "/worlds/pipe_inspection/world.yaml", "-p",
             "cameras_config:=" + small_cameras(), "-p", mode, "-p", "rate:=10.0", "-p", "render.noise:=false"}) {}
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Odometry>> odom_pub =
      probe.create_publisher<nav_msgs::msg::Odometry>("/rov/ground_truth/odom", unav::QoS::reliable());
  std::vector<double> acks;
  std::shared_ptr<unav::Subscription<unav_msgs::msg::LockstepAck>> ack_sub =
      probe.create_subscription<unav_msgs::msg::LockstepAck>(
          "/lockstep/ack", unav::QoS::reliable(100), [this](const unav_msgs::msg::LockstepAck& a) {
            acks.push_back(unav::Time::from_msg(a.header().stamp().sec(), a.header().stamp().nanosec()).seconds());
          });

  std::shared_ptr<unav::Subscription<sensor_msgs::msg::Image>> image_reader(const std::string& topic,
                                                                            std::vector<sensor_msgs::msg::Image>* out) {
    return probe.create_subscription<sensor_msgs::msg::Image>(
        topic, unav::QoS::reliable(), [out](const sensor_msgs::msg::Image& m) { out->push_back(m); });
  }
  // 2 m above the 10 m deep seabed, over the pipe's first point (north 0, east 0 of the world)
  // unless told another north.
  void send(double t, double north = 0.0) { odom_pub->publish(unav::testing::odometry_at(t, {north, 0.0, 8.0})); }
};

}  // namespace

TEST(UnderwaterRendererNode, PublishesImagesStampedWithThePoseTimeAndAcks) {
  LockstepRenderer r;
  std::vector<sensor_msgs::msg::Image> images, depths, segs;
  auto img_sub = r.image_reader("/rov/camera/down/image_raw", &images);
  auto depth_sub = r.image_reader("/rov/camera/down/depth/image_raw", &depths);
  auto seg_sub = r.image_reader("/rov/camera/down/segmentation/image_raw", &segs);
  // Every link matched on BOTH sides before the first odometry. This test used to wait for the
  // probe's side only (its readers counting the node's writers): the node's ack and image writers
  // could still be unaware of the probe's readers, and what a volatile writer writes before it
  // knows a reader is never sent to it. On a slow machine the acks of 1.5 and 1.55 (and their
  // images) were lost that way: "1 of 3" answers. With all links matched on both sides, reliable
  // delivery within the history depths (odometry 10, images 5, acks 100) loses nothing.
  const std::vector<unav::testing::Link> links = {make_link(*r.odom_pub, *r.node), make_link(*r.node, *img_sub),
                                                  make_link(*r.node, *depth_sub), make_link(*r.node, *seg_sub),
                                                  make_link(*r.node, *r.ack_sub)};
  ASSERT_TRUE(r.match(links));
  r.send(1.5);   // a frame is due (first odometry)
  r.send(1.55);  // not due at 10 Hz: ack only
  r.send(1.6);   // due
  ASSERT_TRUE(r.spin_until([&] {
    return r.acks.size() == 3 && images.size() == 2 && depths.size() == 2 && segs.size() == 2;
  })) << r.acks.size()
      << " acks, " << images.size() << " images";
  const auto& img = images[0];
  EXPECT_EQ(unav::Time::from_msg(img.header().stamp().sec(), img.header().stamp().nanosec()).seconds(), 1.5);
  EXPECT_EQ(img.header().frame_id(), "down_optical");
  EXPECT_EQ(img.encoding(), "rgb8");
  EXPECT_EQ(img.width(), 80u);
  EXPECT_EQ(img.data().size(), 80u * 48u * 3u);
  EXPECT_NEAR(unav::Time::from_msg(images[1].header().stamp().sec(), images[1].header().stamp().nanosec()).seconds(),
              1.6, 1e-9);
  EXPECT_EQ(r.acks, (std::vector<double>{1.5, 1.55, 1.6}));
  // Depth at the image centre, looking straight down from 8 m over a 10 m seabed: the optical
  // axis meets sand (or the pipe top, radius <= 0.5 m) between 1.4 and 2.05 m away.
  float centre = 0.0f;
  std::memcpy(&centre, depths[0].data().data() + std::ptrdiff_t{24 * 80 + 40} * 4, 4);
  EXPECT_GT(centre, 1.4f);
  EXPECT_LT(centre, 2.05f);
  EXPECT_EQ(depths[0].encoding(), "32FC1");
  // Every pixel sees the seabed or the pipe: classes 1 (seabed) and 2 (pipeline) only... plus
  // rocks (3) possibly; never water (0) looking down from 2 m.
  for (uint8_t c : segs[0].data()) EXPECT_NE(c, 0);
}

TEST(UnderwaterRendererNode, PublishesCameraMountsOnTfStaticForLateJoiners) {
  // The mount is published once, latched: a subscriber that joins after the node started still
  // receives base_link_frd -> down_optical, equal to the camera YAML's mount (what the
  // evaluator and estimators look up instead of reading the YAML).
  const std::string world = std::string("world:=") + UNAV_REPO_ROOT + "/worlds/pipe_inspection/world.yaml";
  const std::string cams_path = small_cameras();
  const std::string cams = "cameras_config:=" + cams_path;
  const char* argv[] = {"underwater_renderer", "--ros-args", "-p", world.c_str(), "-p", cams.c_str()};
  unav::Context node_ctx(6, argv, unav::testing::test_context_options());
  unav::renderer::UnderwaterRendererNode node({&node_ctx});
  const auto got = unav::testing::late_latched<tf2_msgs::msg::TFMessage>(node_ctx, "/tf_static");
  ASSERT_TRUE(got.has_value()) << "no /tf_static for a late subscriber";
  ASSERT_EQ(got->transforms().size(), 1u);
  const auto& t = got->transforms()[0];
  EXPECT_EQ(t.header().frame_id(), "base_link_frd");
  EXPECT_EQ(t.child_frame_id(), "down_optical");
  const Eigen::Isometry3d X_BC = unav::scene::load_cameras(cams_path)[0].X_BC;
  EXPECT_LT((unav::from_msg(t.transform()).matrix() - X_BC.matrix()).norm(), 1e-12);
  // A downward camera: its optical axis (z) is body down (+z), image top (-y) is body forward.
  EXPECT_NEAR((X_BC.linear() * Eigen::Vector3d::UnitZ()).z(), 1.0, 1e-12);
  EXPECT_NEAR((X_BC.linear() * -Eigen::Vector3d::UnitY()).x(), 1.0, 1e-12);
}

// Lockstep start-up with many processes: the renderer publishes the first frame before a frame
// consumer's reader matched (volatile: that reader never gets it), the consumer never acks, the
// barrier holds and the physics server repeats the state every second. The repeated state gets
// the same frame published again (not re-rendered): the late reader gets it, identical to the
// one an early reader had. A repeat of a state with no frame at its instant publishes nothing.
TEST(UnderwaterRendererNode, PublishesTheLastFrameAgainWhenTheLockstepRepeatsItsState) {
  LockstepRenderer r;
  std::vector<sensor_msgs::msg::Image> early, late;
  auto early_sub = r.image_reader("/rov/camera/down/image_raw", &early);
  std::vector<unav::testing::Link> links = {make_link(*r.odom_pub, *r.node), make_link(*r.node, *early_sub),
                                            make_link(*r.node, *r.ack_sub)};
  ASSERT_TRUE(r.match(links));
  r.send(0.0);
  ASSERT_TRUE(r.spin_until([&] { return r.acks.size() == 1 && early.size() == 1; }));
  // The consumer's reader matches only now.
  auto late_sub = r.image_reader("/rov/camera/down/image_raw", &late);
  links.push_back(make_link(*r.node, *late_sub));
  ASSERT_TRUE(r.match(links));
  r.send(0.0);  // the held state, repeated
  ASSERT_TRUE(r.spin_until([&] { return r.acks.size() == 2 && late.size() == 1 && early.size() == 2; }))
      << r.acks.size() << " acks, " << late.size() << " late images, " << early.size() << " early images";
  EXPECT_EQ(unav::nanoseconds(late[0].header()), 0);
  EXPECT_EQ(late[0].data(), early[0].data());  // the same frame, not a new render (noise is off anyway)
  EXPECT_EQ(early[1].data(), early[0].data());
  EXPECT_EQ(r.node->frames_published(), 1u);
  EXPECT_EQ(r.node->frames_republished(), 1u);
  // 0.05 s: no frame due at 10 Hz; its repeat publishes nothing either. 0.1: a new frame.
  r.send(0.05);
  r.send(0.05);
  r.send(0.1);
  ASSERT_TRUE(r.spin_until([&] { return r.acks.size() == 5 && late.size() == 2; }));
  EXPECT_EQ(r.acks, (std::vector<double>{0.0, 0.0, 0.05, 0.05, 0.1}));
  EXPECT_EQ(unav::nanoseconds(late[1].header()), 100000000);
  EXPECT_EQ(r.node->frames_published(), 2u);
  EXPECT_EQ(r.node->frames_republished(), 1u);
}

// Free-running, one camera on two workers: a frame due while the previous one still renders
// starts at once on the other worker. The frames come out in order, each stamped with its pose's
// time, and each is the frame one Renderer draws for that pose in that order, bit for bit (noise
// off; marine snow, caustics, shadows and materials on).
TEST(UnderwaterRendererNode, FreeRunningRendersSuccessiveFramesAtOnceInOrder) {
  LockstepRenderer r("lockstep:=false");
  EXPECT_EQ(r.node->max_frames_in_flight(), 2u);
  std::vector<sensor_msgs::msg::Image> images;
  auto img_sub = r.image_reader("/rov/camera/down/image_raw", &images);
  const std::vector<unav::testing::Link> links = {make_link(*r.odom_pub, *r.node), make_link(*r.node, *img_sub)};
  ASSERT_TRUE(r.match(links));
  // Six instants due at 10 Hz, sent at once (within the odometry and image history depths of 10):
  // none may be dropped or reordered, however the renders overlap.
  const int n = 6;
  for (int k = 0; k < n; ++k) r.send(0.1 * k, 0.25 * k);
  ASSERT_TRUE(r.spin_until([&] { return images.size() == static_cast<size_t>(n); })) << images.size() << " images";
  EXPECT_EQ(r.node->frames_published(), static_cast<std::uint64_t>(n));
  EXPECT_LE(r.node->peak_frames_in_flight(), 2u);

  unav::scene::World world =
      unav::scene::load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
  unav::renderer::RenderOptions ro;  // the node's defaults, noise off as in the fixture
  ro.noise = false;
  unav::renderer::Renderer reference(world, unav::scene::load_cameras(small_cameras()), ro);
  for (int k = 0; k < n; ++k) {
    const auto& img = images[static_cast<size_t>(k)];
    EXPECT_EQ(unav::nanoseconds(img.header()), std::llround(0.1 * k * 1e9)) << "frame " << k;
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.translation() = Eigen::Vector3d(0.25 * k, 0.0, 8.0);
    const unav::renderer::Frame f = reference.render(X_WB, "down", 0.1 * k);
    EXPECT_TRUE(img.data() == f.rgb) << "frame " << k << " differs from one Renderer's";
  }
  EXPECT_NE(images[0].data(), images[n - 1].data());  // 1.25 m apart: the poses were applied
}

// `scenario:=FILE` gives the renderer its part of a scenario (world, water, cameras with their
// render size, realism switches, seed), as the in-process Episode takes it: here the small down
// camera of small_cameras() rendered at the scenario's 40 x 24.
TEST(UnderwaterRendererNode, TakesItsPartOfAScenario) {
  const std::string scenario = ::testing::TempDir() + "renderer_scenario.yaml";
  std::ofstream(scenario) << "world: " << UNAV_REPO_ROOT << "/worlds/pipe_inspection/world.yaml\nwater: 3C\n"
                          << "cameras: {config: " << small_cameras() << ", names: [down], width: 40, height: 24}\n"
                          << "render: {noise: false, marine_snow: false}\n";
  ScenarioNode<unav::renderer::UnderwaterRendererNode> fx("underwater_renderer", scenario);
  std::vector<sensor_msgs::msg::Image> images;
  auto img_sub = fx.probe.create_subscription<sensor_msgs::msg::Image>(
      "/rov/camera/down/image_raw", unav::QoS::reliable(),
      [&images](const sensor_msgs::msg::Image& m) { images.push_back(m); });
  ASSERT_TRUE(fx.match({make_link(*fx.odom_pub, *fx.node), make_link(*fx.node, *img_sub)}));
  fx.odom_pub->publish(unav::testing::odometry_at(0.0, {0.0, 0.0, 8.0}));
  ASSERT_TRUE(fx.spin_until([&] { return !images.empty(); }));
  EXPECT_EQ(images[0].width(), 40u);
  EXPECT_EQ(images[0].height(), 24u);
  EXPECT_EQ(images[0].data().size(), 40u * 24u * 3u);
}

TEST(UnderwaterRendererNode, DrawsTheOtherVehiclesWhereTheyAre) {
  // A scenario with a fleet vehicle (rov2): the primary's renderer (/rov) draws it as a box of
  // class vehicle at its ground-truth pose. In lockstep a frame waits for rov2's state of the same
  // stamp: the frame at 0.1 s, whose odometry comes first, shows rov2 where its 0.1 s state puts it
  // (1 m under the down camera: the image's centre), not where its 0 s state had it (out of view).
  const std::string scenario = ::testing::TempDir() + "renderer_fleet_scenario.yaml";
  std::ofstream(scenario) << "world: " << UNAV_REPO_ROOT << "/worlds/pipe_inspection/world.yaml\n"
                          << "cameras: {config: " << small_cameras() << ", names: [down]}\n"
                          << "render: {noise: false, marine_snow: false}\n"
                          << "fleet: [{name: rov2, initial_position: [40.0, 40.0, 9.0]}]\n";
  ScenarioNode<unav::renderer::UnderwaterRendererNode> fx("underwater_renderer", scenario);
  unav::renderer::UnderwaterRendererNode& node = *fx.node;
  auto& odom_pub = fx.odom_pub;
  auto& other_pub = fx.other_pub;
  std::vector<sensor_msgs::msg::Image> seg;
  auto seg_sub = fx.probe.create_subscription<sensor_msgs::msg::Image>(
      "/rov/camera/down/segmentation/image_raw", unav::QoS::reliable(),
      [&seg](const sensor_msgs::msg::Image& m) { seg.push_back(m); });
  const auto own_link = make_link(*odom_pub, node);
  ASSERT_TRUE(fx.match({own_link, make_link(*other_pub, node), make_link(node, *seg_sub)}));
  using unav::testing::odometry_at;
  auto vehicle_pixels = [](const sensor_msgs::msg::Image& m) {
    int n = 0;
    for (auto v : m.data()) n += v == static_cast<std::uint8_t>(unav::scene::SegClass::kVehicle) ? 1 : 0;
    return n;
  };
  auto centre = [](const sensor_msgs::msg::Image& m) { return m.data()[(m.height() / 2) * m.step() + m.width() / 2]; };
  other_pub->publish(odometry_at(0.0, {40.0, 0.0, 9.0}));  // rov2 out of view
  ASSERT_TRUE(fx.spin_until([&] { return node.fleet_states() == 1; }));
  odom_pub->publish(odometry_at(0.0, {0.0, 0.0, 8.0}));
  ASSERT_TRUE(fx.spin_until([&] { return seg.size() == 1; }));
  EXPECT_EQ(vehicle_pixels(seg[0]), 0);
  odom_pub->publish(odometry_at(0.1, {0.0, 0.0, 8.0}));  // ours first: the frame waits for rov2's 0.1 s state
  ASSERT_TRUE(fx.spin_until([&] { return unav::testing::delivered(own_link); }));  // the node took it
  fx.spin_for(50ms);  // (and would have published by now: a frame of 80 x 48 takes a few ms)
  EXPECT_EQ(seg.size(), 1u) << "a frame went out before the other vehicle's state of its stamp";
  other_pub->publish(odometry_at(0.1, {0.0, 0.0, 9.0}));  // 1 m under the camera
  ASSERT_TRUE(fx.spin_until([&] { return seg.size() == 2; }));
  const int n = vehicle_pixels(seg[1]);
  std::printf("rov2 1 m under the down camera: %d vehicle pixels, centre class %d\n", n, centre(seg[1]));
  EXPECT_EQ(centre(seg[1]), static_cast<std::uint8_t>(unav::scene::SegClass::kVehicle));
  // Its top face (0.457 x 0.575 m at 0.873 m) covers ~(0.457 x 0.575) / (2 x 0.873)^2 of the 90 x 62
  // deg view's 80 x 48 px (a 2 x 1.2 m footprint there): ~10 % = ~400 px; its sides add a little.
  EXPECT_GT(n, 200);
  EXPECT_LT(n, 1200);
}
