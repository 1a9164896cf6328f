// `unav run --in-process` (scenario_run.hpp): the mission schedule, the files a run writes, and
// that the same scenario and seed give the same files byte for byte.
#include "unav_sim/scenario_run.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

namespace fs = std::filesystem;
using unav::scene::Scenario;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Scenario short_run() {
  Scenario s = unav::scene::load_scenario(std::string(UNAV_REPO_ROOT) + "/config/scenarios/pipe_inspection.yaml");
  s.cameras.names = {"down"};
  s.cameras.width = 80;  // small frames: the test checks files and repeatability, not looks
  s.cameras.height = 45;
  s.cameras.rate_hz = 5.0;
  s.mission.duration_s = 1.0;
  return s;
}

}  // namespace

TEST(ScenarioRun, MissionTravelsEachLegAtItsSpeedThenHolds) {
  Scenario s = short_run();
  s.mission.speed_mps = 0.5;
  s.mission.waypoints = {{Eigen::Vector3d(0.0, 0.0, 8.35), 0.0, 4.0}, {Eigen::Vector3d(4.0, 0.0, 8.35), 90.0, 10.0}};
  const auto at = [&](double t) { return unav::sim::mission_setpoint(s, t).p_W; };
  EXPECT_TRUE(at(0.0).isApprox(Eigen::Vector3d(-1.5, 0.0, 8.35)));  // from the start (-1.5, 0, 8.35)
  EXPECT_TRUE(at(1.0).isApprox(Eigen::Vector3d(-1.0, 0.0, 8.35)));  // 0.5 m/s
  EXPECT_EQ(at(3.5), Eigen::Vector3d(0.0, 0.0, 8.35));              // reached after 3 s, held
  EXPECT_TRUE(at(6.0).isApprox(Eigen::Vector3d(1.0, 0.0, 8.35)));   // the second leg began at 4 s
  EXPECT_EQ(at(13.0), Eigen::Vector3d(4.0, 0.0, 8.35));
  EXPECT_EQ(at(99.0), Eigen::Vector3d(4.0, 0.0, 8.35));  // the last, held
  EXPECT_NEAR(unav::sim::mission_setpoint(s, 5.0).q_WB.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()))),
              0.0, 1e-12);
  Scenario hover = s;
  hover.mission.waypoints.clear();
  EXPECT_EQ(unav::sim::mission_setpoint(hover, 3.0).p_W, s.vehicle.initial_position);
}

TEST(ScenarioRun, WritesGroundTruthImagesAndTheScenarioAndRepeatsExactly) {
  const fs::path base = fs::path(::testing::TempDir()) / ("unav_run_" + std::to_string(::getpid()));
  const Scenario s = short_run();
  const auto a = unav::sim::run_scenario_in_process(s, (base / "a").string());
  // 1 s at 20 Hz control: t = 0, 0.05, ..., 1.0; frames at 5 Hz: t = 0, 0.2, ..., 1.0.
  EXPECT_EQ(a.poses, 21u);
  EXPECT_EQ(a.frames, 6u);
  EXPECT_NEAR(a.sim_s, 1.0, 1e-9);
  EXPECT_FALSE(a.stopped);
  EXPECT_EQ(a.solver_failures, 0);
  std::ifstream gt(base / "a" / "ground_truth.tum");
  double t = 0, x = 0, y = 0, z = 0, qx = 0, qy = 0, qz = 0, qw = 0;
  int lines = 0;
  while (gt >> t >> x >> y >> z >> qx >> qy >> qz >> qw) {
    EXPECT_NEAR(t, 0.05 * lines, 1e-9);
    EXPECT_NEAR(qx * qx + qy * qy + qz * qz + qw * qw, 1.0, 1e-8);
    ++lines;
  }
  EXPECT_EQ(lines, 21);
  EXPECT_GT(x, -1.5 + 0.05) << "the first waypoint (1.5 m ahead) pulls the vehicle north";
  const cv::Mat first = cv::imread((base / "a" / "down" / "0000000000000000000.png").string());
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(first.cols, 80);
  EXPECT_EQ(first.rows, 45);
  EXPECT_TRUE(fs::exists(base / "a" / "down" / "0000000001000000000.png"));
  // The recorded scenario is the concrete one: it loads back to the same run.
  const Scenario back = unav::scene::load_scenario((base / "a" / "scenario.yaml").string());
  EXPECT_EQ(back.cameras.width, 80);
  EXPECT_EQ(back.world, s.world);
  const auto b = unav::sim::run_scenario_in_process(back, (base / "b").string());
  EXPECT_EQ(b.frames, a.frames);
  EXPECT_EQ(slurp(base / "a" / "ground_truth.tum"), slurp(base / "b" / "ground_truth.tum"));
  EXPECT_EQ(slurp(base / "a" / "down" / "0000000000600000000.png"),
            slurp(base / "b" / "down" / "0000000000600000000.png"));
  fs::remove_all(base);
}
