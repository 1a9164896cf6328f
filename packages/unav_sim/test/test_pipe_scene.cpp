#include <gtest/gtest.h>

#include <cmath>

#include "unav_common/errors.hpp"
#include "unav_scene/water.hpp"
#include "unav_sim/pipe_scene.hpp"

using namespace unav::sim;
using unav::scene::World;

namespace {
const World& base() {
  static const World w = unav::scene::load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
  return w;
}
}  // namespace

TEST(PipeScene, SameSeedGivesTheSameWorldAndOtherSeedsDiffer) {
  PipeSceneRanges r;
  const World a = generate_pipe_world(r, base(), 42), b = generate_pipe_world(r, base(), 42);
  ASSERT_EQ(a.pipelines.size(), 1u);
  ASSERT_EQ(a.pipelines[0].points_W.size(), b.pipelines[0].points_W.size());
  for (std::size_t i = 0; i < a.pipelines[0].points_W.size(); ++i)
    EXPECT_EQ(a.pipelines[0].points_W[i], b.pipelines[0].points_W[i]);
  ASSERT_EQ(a.rocks.size(), b.rocks.size());
  for (std::size_t i = 0; i < a.rocks.size(); ++i) EXPECT_EQ(a.rocks[i].p_W, b.rocks[i].p_W);
  EXPECT_EQ(a.water.name, b.water.name);
  int differing = 0;
  for (std::uint64_t s = 0; s < 10; ++s) {
    const World c = generate_pipe_world(r, base(), 1000 + s);
    differing += c.pipelines[0].points_W.back() != a.pipelines[0].points_W.back();
  }
  EXPECT_EQ(differing, 10);
}

// Every draw stays inside its range, over many seeds: turn count, segment lengths, turn angles,
// pipe laid on the seabed with its burial, rocks clear of the pipe, a water from the list.
TEST(PipeScene, DrawsStayWithinTheirRanges) {
  PipeSceneRanges r;
  r.waters = {"IB", "3C"};
  int turns_seen[4] = {0, 0, 0, 0};
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    const World w = generate_pipe_world(r, base(), seed);
    const auto& pipe = w.pipelines.front();
    const auto& P = pipe.points_W;
    const int turns = static_cast<int>(P.size()) - 2;
    ASSERT_GE(turns, r.turns[0]);
    ASSERT_LE(turns, r.turns[1]);
    ++turns_seen[turns];
    for (std::size_t i = 1; i < P.size(); ++i) {
      const double len = (P[i] - P[i - 1]).head<2>().norm();
      const Eigen::Vector2d& range = i == 1 ? r.first_segment_m : r.segment_m;
      EXPECT_GE(len, range.x() - 1e-9);
      EXPECT_LE(len, range.y() + 1e-9);
    }
    for (std::size_t i = 1; i + 1 < P.size(); ++i) {
      const Eigen::Vector2d d0 = (P[i] - P[i - 1]).head<2>(), d1 = (P[i + 1] - P[i]).head<2>();
      const double turn = std::acos(std::clamp(d0.dot(d1) / (d0.norm() * d1.norm()), -1.0, 1.0)) * 180.0 / M_PI;
      EXPECT_GE(turn, r.turn_deg.x() - 1e-6);
      EXPECT_LE(turn, r.turn_deg.y() + 1e-6);
    }
    EXPECT_GE(pipe.radius_m, r.pipe_radius_m.x());
    EXPECT_LE(pipe.radius_m, r.pipe_radius_m.y());
    EXPECT_GE(pipe.bend_radius_m, r.bend_radius_m.x());
    // Centre at seabed - radius (1 - 2 burial): between one radius above and below the seabed.
    for (const auto& p : P) {
      const double z_bed = w.seabed.depth_at(p.x(), p.y());
      EXPECT_LE(p.z(), z_bed + pipe.radius_m + 1e-9);
      EXPECT_GE(p.z(), z_bed - pipe.radius_m - 1e-9);
    }
    EXPECT_GE(w.seabed.depth_m, r.seabed_depth_m.x());
    EXPECT_LE(w.seabed.depth_m, r.seabed_depth_m.y());
    EXPECT_TRUE(w.water.name == "jerlov_IB" || w.water.name == "jerlov_3C") << w.water.name;
    for (const auto& rock : w.rocks) {
      const auto q = unav::scene::nearest_pipe_point(w, rock.p_W, true);
      EXPECT_GT(q.horizontal_distance_m, pipe.radius_m + 0.4);  // clearance + rock radius
    }
    // Arc length of the centre line: at most the polyline length (bends cut corners).
    double poly = 0;
    for (std::size_t i = 1; i < P.size(); ++i) poly += (P[i] - P[i - 1]).norm();
    EXPECT_LE(pipe.length_m(), poly + 1e-6);
    EXPECT_GT(pipe.length_m(), 0.8 * poly);
  }
  for (int t = 0; t <= 3; ++t) EXPECT_GT(turns_seen[t], 20) << "turn count " << t << " drawn too rarely";
}

TEST(PipeScene, BadRangesAreRejectedNamingTheKey) {
  PipeSceneRanges r;
  r.segment_m = {9.0, 4.0};
  try {
    r.validate("ranges.yaml");
    FAIL() << "min > max accepted";
  } catch (const unav::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("segment_m"), std::string::npos) << e.what();
  }
  r = PipeSceneRanges{};
  r.waters = {"IB", "muddy"};
  EXPECT_THROW(r.validate("ranges.yaml"), unav::ConfigError);
  r = PipeSceneRanges{};
  r.turns = {3};
  EXPECT_THROW(r.validate("ranges.yaml"), unav::ConfigError);
  r = PipeSceneRanges{};
  r.bend_radius_m = {0.1, 2.0};  // tighter than the thickest pipe
  EXPECT_THROW(r.validate("ranges.yaml"), unav::ConfigError);
}
