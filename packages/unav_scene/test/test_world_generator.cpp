// The one pipe-world generator: its geometry follows the spec exactly, it is deterministic in the
// seed, and drawn through the one sampler (distributions, a repeat of legs) every part stays in
// its range.
#include "unav_scene/world_generator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "unav_common/errors.hpp"
#include "unav_common/sampling.hpp"
#include "unav_scene/scenario.hpp"

using namespace unav::scene;

namespace {

const World& base() {
  static const World w = load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
  return w;
}

// The learning config's scene distribution (config/learning/pipe_following.yaml, pipe_scenes).
constexpr const char* kScenes = R"(
pipeline:
  heading_deg: {uniform: [0, 360]}
  first_length_m: {uniform: [5, 9]}
  legs: {repeat: {count: {int: [0, 3]}, each: {turn_deg: {uniform: [-75, 75]}, length_m: {uniform: [4, 9]}}}}
  radius_m: {uniform: [0.15, 0.35]}
  bend_radius_m: {uniform: [0.8, 2.5]}
  burial_fraction: {uniform: [0.0, 0.5]}
seabed: {depth_m: {uniform: [8, 14]}, relief_m: {uniform: [0, 0.35]}}
rocks: {per_100m2: {uniform: [0, 6]}}
water: {preset: {choice: [IB, 3C]}}
)";

}  // namespace

// A fixed spec: a 7 m run north, a 90 deg turn to the east and a 5 m run: the vertices, the pipe
// on the seabed at its burial, the seabed square around it, the water scaled by the turbidity.
TEST(WorldGenerator, TheGeometryIsTheSpecs) {
  WorldGenerator g;
  g.pipeline.first_length_m = 7.0;
  g.pipeline.legs = {{90.0, 5.0}};
  g.pipeline.radius_m = 0.3;
  g.pipeline.burial_fraction = 0.5;  // centre on the seabed
  g.seabed.depth_m = 12.0;
  g.seabed.relief_m = 0.0;
  g.water.preset = "3C";
  g.water.turbidity = 2.0;
  const World w = generate_world(g, base(), 7);
  ASSERT_EQ(w.pipelines.size(), 1u);
  const auto& P = w.pipelines[0].points_W;
  ASSERT_EQ(P.size(), 3u);
  EXPECT_NEAR((P[0] - Eigen::Vector3d(0, 0, 12)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((P[1] - Eigen::Vector3d(7, 0, 12)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((P[2] - Eigen::Vector3d(7, 5, 12)).norm(), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(w.pipelines[0].bend_radius_m, 1.5);  // max(1.5, 4 r = 1.2)
  // Bounding box 7 x 5 m, 12 m margin each side: 31 m, a whole number of 1 m cells.
  EXPECT_EQ(w.seabed.size_m, Eigen::Vector2d(31.0, 31.0));
  EXPECT_EQ(w.seabed.center_ne, Eigen::Vector2d(3.5, 2.5));
  const WaterModel c3 = jerlov_preset("3C");
  EXPECT_EQ(w.water.beta_D, 2.0 * c3.beta_D);
  EXPECT_EQ(w.water.K_d, 2.0 * c3.K_d);
  EXPECT_EQ(w.lamps.size(), base().lamps.size());  // lamp_count < 0: the base's
  EXPECT_TRUE(w.objects.empty());
  for (const auto& rock : w.rocks) EXPECT_GT(nearest_pipe_point(w, rock.p_W, true).horizontal_distance_m, 0.7);
}

TEST(WorldGenerator, SameSpecAndSeedSameWorld) {
  const unav::common::Stochastic<WorldGenerator> scenes(YAML::Load(kScenes), "scenes.yaml");
  const World a = generate_world(scenes.Sample(42), base(), 42), b = generate_world(scenes.Sample(42), base(), 42);
  ASSERT_EQ(a.pipelines[0].points_W.size(), b.pipelines[0].points_W.size());
  for (std::size_t i = 0; i < a.pipelines[0].points_W.size(); ++i)
    EXPECT_EQ(a.pipelines[0].points_W[i], b.pipelines[0].points_W[i]);
  ASSERT_EQ(a.rocks.size(), b.rocks.size());
  for (std::size_t i = 0; i < a.rocks.size(); ++i) EXPECT_EQ(a.rocks[i].p_W, b.rocks[i].p_W);
  int differing = 0;
  for (std::uint64_t s = 0; s < 10; ++s)
    differing += generate_world(scenes.Sample(1000 + s), base(), 1000 + s).pipelines[0].points_W.back() !=
                 a.pipelines[0].points_W.back();
  EXPECT_EQ(differing, 10);
}

// Over many draws: leg count, run lengths, turn angles, pipe on the seabed within its burial,
// rocks clear of the pipe, a water from the list, the centre line no longer than the polyline.
TEST(WorldGenerator, SampledWorldsStayWithinTheirDistributions) {
  const unav::common::Stochastic<WorldGenerator> scenes(YAML::Load(kScenes), "scenes.yaml");
  int legs_seen[4] = {0, 0, 0, 0};
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    const World w = generate_world(scenes.Sample(seed), base(), seed);
    const auto& pipe = w.pipelines.front();
    const auto& P = pipe.points_W;
    const int legs = static_cast<int>(P.size()) - 2;
    ASSERT_GE(legs, 0);
    ASSERT_LE(legs, 3);
    ++legs_seen[legs];
    for (std::size_t i = 1; i < P.size(); ++i) {
      const double len = (P[i] - P[i - 1]).head<2>().norm();
      EXPECT_GE(len, (i == 1 ? 5.0 : 4.0) - 1e-9);
      EXPECT_LE(len, 9.0 + 1e-9);
    }
    for (std::size_t i = 1; i + 1 < P.size(); ++i) {
      const Eigen::Vector2d d0 = (P[i] - P[i - 1]).head<2>(), d1 = (P[i + 1] - P[i]).head<2>();
      const double turn = std::acos(std::clamp(d0.dot(d1) / (d0.norm() * d1.norm()), -1.0, 1.0)) * 180.0 / M_PI;
      EXPECT_LE(turn, 75.0 + 1e-6);
    }
    EXPECT_GE(pipe.radius_m, 0.15);
    EXPECT_LE(pipe.radius_m, 0.35);
    for (const auto& p : P) {  // centre at seabed - r (1 - 2 burial), burial in [0, 0.5]
      const double z_bed = w.seabed.depth_at(p.x(), p.y());
      EXPECT_LE(p.z(), z_bed + 1e-9);
      EXPECT_GE(p.z(), z_bed - pipe.radius_m - 1e-9);
    }
    EXPECT_GE(w.seabed.depth_m, 8.0);
    EXPECT_LE(w.seabed.depth_m, 14.0);
    EXPECT_TRUE(w.water.name == "jerlov_IB" || w.water.name == "jerlov_3C") << w.water.name;
    for (const auto& rock : w.rocks)
      EXPECT_GT(nearest_pipe_point(w, rock.p_W, true).horizontal_distance_m, pipe.radius_m + 0.4);
    double poly = 0;
    for (std::size_t i = 1; i < P.size(); ++i) poly += (P[i] - P[i - 1]).norm();
    EXPECT_LE(pipe.length_m(), poly + 1e-6);
    EXPECT_GT(pipe.length_m(), 0.8 * poly);
  }
  // Binomial(200, 1/4): mean 50, sigma 6.1; 20 is ~5 sigma below.
  for (int t = 0; t <= 3; ++t) EXPECT_GT(legs_seen[t], 20) << "leg count " << t << " drawn too rarely";
}

TEST(WorldGenerator, BadSpecsAreNamed) {
  WorldGenerator g;
  g.water.preset = "muddy";
  EXPECT_THROW(check_world_generator(g, "s.yaml", "generate."), unav::ConfigError);
  g = WorldGenerator{};
  g.pipeline.radius_m = 0.5;
  g.pipeline.bend_radius_m = 0.3;
  try {
    check_world_generator(g, "s.yaml", "generate.");
    FAIL() << "a bend tighter than the pipe accepted";
  } catch (const unav::ConfigError& e) {
    EXPECT_EQ(e.key(), "generate.pipeline.bend_radius_m");
  }
  g = WorldGenerator{};
  g.objects.count = 2;
  EXPECT_THROW(check_world_generator(g, "s.yaml", "generate."), unav::ConfigError);
  // Through the sampler: a distribution reaching outside a field's rule.
  try {
    const unav::common::Stochastic<WorldGenerator> bad(
        YAML::Load("pipeline: {legs: {repeat: {count: 2, each: {turn_deg: {uniform: [0, 200]}}}}}"), "s.yaml");
    FAIL() << "a 200 deg turn accepted";
  } catch (const unav::ConfigError& e) {
    EXPECT_EQ(e.key(), "pipeline.legs[0].turn_deg");
  }
}

// A scenario with `generate` enabled runs in the generated world, the same for the same seed.
TEST(WorldGenerator, AScenarioGeneratesItsWorldOverTheBase) {
  const YAML::Node root = YAML::Load(std::string(R"(
world: worlds/pipe_inspection/world.yaml
seed: 5
generate:
  enabled: true
  pipeline: {first_length_m: {uniform: [5, 9]}, legs: [{turn_deg: 45, length_m: 6}]}
  seabed: {depth_m: 20}
)"));
  const Scenario s = parse_scenario(root, "gen.yaml", "");
  const World w = scenario_world(s);
  ASSERT_EQ(w.pipelines.size(), 1u);
  EXPECT_EQ(w.pipelines[0].points_W.size(), 3u);
  EXPECT_EQ(w.seabed.depth_m, 20.0);
  EXPECT_EQ(scenario_world(parse_scenario(root, "gen.yaml", "")).pipelines[0].points_W[1], w.pipelines[0].points_W[1]);
  EXPECT_NE(scenario_world(parse_scenario(root, "gen.yaml", "", 6)).pipelines[0].points_W[1],
            w.pipelines[0].points_W[1]);
}
