#include <gtest/gtest.h>

#include <cmath>

#include "unav_scene/world_generator.hpp"
#include "unav_sim/episode.hpp"

using namespace unav::sim;
using unav::control::PoseSetpoint;

namespace {

World pipe_world() {
  return unav::scene::load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
}

EpisodeSetup small_setup() {
  unav::scene::Scenario s;
  s.cameras.width = 160;  // half size: the tests check geometry and repeatability, not looks
  s.cameras.height = 90;
  return load_episode_setup(s);
}

RigidBodyState at(double n, double e, double d, double yaw = 0.0) {
  RigidBodyState x;
  x.p_WB_W = {n, e, d};
  x.q_WB = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
  return x;
}

}  // namespace

TEST(ScaleCamera, KeepsTheFieldOfViewAndTheOpticalCentre) {
  const auto c = unav::scene::CameraModel::from_hfov("c", 320, 180, M_PI / 2);
  const auto s = unav::scene::scale_camera(c, 80, 45);
  EXPECT_EQ(s.width, 80);
  EXPECT_NEAR(2.0 * std::atan(s.width / (2.0 * s.fx)), M_PI / 2, 1e-12);
  // The image centre (159.5, 89.5) maps to the centre (39.5, 22).
  EXPECT_NEAR(s.cx, 39.5, 1e-12);
  EXPECT_NEAR(s.cy, 22.0, 1e-12);
}

// The in-process loop flies a 1 m step: the MPC + allocator + physics of the DDS launch, called
// directly. After 6 s the vehicle holds the setpoint: the MPC test suite's own closed-loop
// tolerance (0.05 m) for a step of this size.
TEST(Episode, FliesToASetpointAndHoldsIt) {
  Episode ep(small_setup(), pipe_world());
  ep.reset(1, at(0, 0, 8.35));
  ep.set_setpoint(PoseSetpoint::FromPositionYaw({1.0, 0.0, 8.35}, 0.3));
  ep.advance(6.0);
  EXPECT_NEAR(ep.time(), 6.0, 1e-9);
  EXPECT_LT((ep.state().p_WB_W - Eigen::Vector3d(1.0, 0.0, 8.35)).norm(), 0.05);
  const Eigen::Vector3d f = ep.state().q_WB * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(std::atan2(f.y(), f.x()), 0.3, 0.02);
  EXPECT_EQ(ep.solver_failures(), 0);
  EXPECT_EQ(ep.timings().physics_steps, 6000u);
  EXPECT_EQ(ep.timings().control_steps, 120u);
}

// The in-process plant stands on the world's seabed, as the physics server's does (one builder:
// physics::build_simulator). The MPC asks for a depth 2 m below the pipe world's seabed (10 m,
// relief 0.15 m); the vehicle stops on it: its bottom point (z + 0.127 m) within the relief of
// 10 m, pressed in by at most the MPC's ~170 N of vertical thrust over the 2000 N/m stiffness
// (0.09 m). Without the seabed it reached 12 m.
TEST(Episode, StandsOnTheWorldsSeabed) {
  const World world = pipe_world();
  Episode ep(small_setup(), world);
  const double n = -6.0, e = -9.0;  // clear of the pipeline and the rocks' usual spots
  ep.reset(1, at(n, e, 8.0));
  ep.set_setpoint(PoseSetpoint::FromPositionYaw({n, e, 12.0}, 0.0));
  ep.advance(12.0);
  const auto& x = ep.state();
  const double seabed = world.seabed.depth_at(x.p_WB_W.x(), x.p_WB_W.y());
  EXPECT_NEAR(seabed, 10.0, 0.16);
  EXPECT_GT(x.p_WB_W.z() + 0.127, seabed - 1e-3);
  EXPECT_LT(x.p_WB_W.z() + 0.127, seabed + 0.09);
  EXPECT_LT((x.q_WB.conjugate() * Eigen::Vector3d::UnitZ()).dot(x.v_WB_B), 0.02) << "at rest on the seabed";
  ASSERT_NE(ep.simulator().seabed(), nullptr);
  EXPECT_NEAR(ep.simulator().seabed()->depth_at(n, e), world.seabed.depth_at(n, e), 1e-9);
}

// Same seed, same calls: bit-identical states and images (the MPC runs on iterations only).
// After reset(seed) the episode repeats itself, including the camera noise.
TEST(Episode, RepeatsExactlyForTheSameSeed) {
  Episode a(small_setup(), pipe_world());
  auto run = [](Episode& ep, std::uint64_t seed) {
    ep.reset(seed, at(0, 0, 8.35));
    ep.set_setpoint(PoseSetpoint::FromPositionYaw({1.0, 0.5, 8.3}, 0.2));
    ep.advance(1.0);
    return std::make_pair(ep.state(), ep.render("down").rgb);
  };
  const auto [x1, img1] = run(a, 7);
  const auto [x2, img2] = run(a, 7);
  EXPECT_EQ(x1.p_WB_W, x2.p_WB_W);
  EXPECT_EQ(x1.q_WB.coeffs(), x2.q_WB.coeffs());
  EXPECT_EQ(img1, img2);
  const auto [x3, img3] = run(a, 8);  // another seed: other camera noise, same dynamics
  EXPECT_EQ(x1.p_WB_W, x3.p_WB_W);
  EXPECT_NE(img1, img3);
}

// reset() with a new world swaps the scene in the same context: right above the pipe the
// segmentation sees pipeline pixels; above a generated pipe elsewhere too; the GL context is
// the same object.
TEST(Episode, ResetWithANewWorldKeepsTheContext) {
  Episode ep(small_setup(), pipe_world());
  const auto* ctx = &ep.renderer().context();
  auto pipe_pixels = [](const Frame& f) {
    int n = 0;
    for (auto s : f.seg) n += s == static_cast<std::uint8_t>(unav::scene::SegClass::kPipeline);
    return n;
  };
  ep.reset(1, at(3.0, 0.0, 8.35));
  const int on_fixed = pipe_pixels(ep.render("down"));
  EXPECT_GT(on_fixed, 500);  // a 0.5 m pipe 1.5 m below a 90 deg camera: ~1/6 of 160 x 90
  unav::scene::WorldGenerator spec;
  spec.pipeline.heading_deg = 30.0;
  spec.pipeline.legs = {{-40.0, 6.0}};
  const World gen = unav::scene::generate_world(spec, pipe_world(), 3);
  const auto& P = gen.pipelines[0].points_W;
  const Eigen::Vector3d mid = 0.5 * (P[0] + P[1]);
  ep.reset(1, at(mid.x(), mid.y(), mid.z() - 1.5), &gen);
  EXPECT_EQ(&ep.renderer().context(), ctx);
  EXPECT_EQ(ep.world().name, gen.name);
  EXPECT_GT(pipe_pixels(ep.render("down")), 300);
  ep.reset(1, at(mid.x() + 30.0, mid.y() + 30.0, mid.z() - 1.5));  // far from the pipe
  EXPECT_EQ(pipe_pixels(ep.render("down")), 0);
}

TEST(Episode, TeleportKeepsTheClock) {
  Episode ep(small_setup(), pipe_world());
  ep.reset(1, at(0, 0, 8.35));
  ep.advance(0.5);
  ep.teleport(at(2.0, 0.0, 8.35, 0.5), 1.5);
  EXPECT_NEAR(ep.time(), 2.0, 1e-9);
  EXPECT_EQ(ep.state().p_WB_W, Eigen::Vector3d(2.0, 0.0, 8.35));
  const Frame f = ep.render("down");
  EXPECT_NEAR(f.stamp_s, 2.0, 1e-9);
  EXPECT_EQ(f.width, 160);
  EXPECT_EQ(f.rgb.size(), 160u * 90u * 3u);
}
