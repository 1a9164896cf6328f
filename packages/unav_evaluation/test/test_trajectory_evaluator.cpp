// trajectory_evaluator over DDS: ground truth and a monocular-like estimate (scaled, shifted,
// rotated copy) in; on destruction: TUM files, results (APE ~0 after Sim(3)), and a PNG.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "trajectory_evaluator.hpp"

using namespace std::chrono_literals;

TEST(TrajectoryEvaluator, WritesTableTumAndPlotOnShutdown) {
  unav::ContextOptions o;
  o.domain_id = 100 + static_cast<int>(getpid() % 100);
  o.handle_signals = false;
  const std::string out = ::testing::TempDir() + "eval_node_out";
  std::filesystem::remove_all(out);
  const std::string p_out = "output_dir:=" + out;
  const char* argv[] = {"trajectory_evaluator", "--ros-args", "-p", p_out.c_str(), "-p", "estimates:=[mono]",
                        "-p", "trajectory_name:=linear"};
  unav::Context node_ctx(8, argv, o);
  auto node = std::make_unique<unav_evaluation::TrajectoryEvaluator>(unav::NodeOptions{&node_ctx});
  unav::Context test_ctx(o);
  unav::Node probe("probe", {&test_ctx});
  auto gt_pub = probe.create_publisher<nav_msgs::msg::Odometry>("/rov/ground_truth/odom", unav::QoS::reliable(100));
  auto est_pub = probe.create_publisher<nav_msgs::msg::Odometry>("/rov/localization/mono/odom", unav::QoS::reliable(100));
  auto spin = [&](std::chrono::milliseconds d, const std::function<bool()>& done) {
    const auto end = std::chrono::steady_clock::now() + d;
    while (!done() && std::chrono::steady_clock::now() < end) {
      node_ctx.spin_some(1ms);
      test_ctx.spin_some(1ms);
    }
    return done();
  };
  ASSERT_TRUE(spin(10s, [&] { return gt_pub->subscription_count() > 0 && est_pub->subscription_count() > 0; }));
  const Eigen::AngleAxisd R(0.4, Eigen::Vector3d::UnitZ());
  for (int i = 0; i < 100; ++i) {
    const double t = 0.1 * i, a = 0.05 * i;
    const Eigen::Vector3d p(5 * std::sin(a), 2 * std::cos(a), 8.0 + 0.1 * std::sin(3 * a));
    const Eigen::Quaterniond q(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()));
    auto msg = [&](const Eigen::Vector3d& pos, const Eigen::Quaterniond& qq) {
      nav_msgs::msg::Odometry m;
      const unav::Time s{std::llround(t * 1e9)};
      m.header().stamp().sec(s.sec());
      m.header().stamp().nanosec(s.nanosec());
      m.pose().pose().position().x(pos.x());
      m.pose().pose().position().y(pos.y());
      m.pose().pose().position().z(pos.z());
      m.pose().pose().orientation().x(qq.x());
      m.pose().pose().orientation().y(qq.y());
      m.pose().pose().orientation().z(qq.z());
      m.pose().pose().orientation().w(qq.w());
      return m;
    };
    gt_pub->publish(msg(p, q));
    est_pub->publish(msg(0.3 * (R * p) + Eigen::Vector3d(1, 2, 3), Eigen::Quaterniond(R) * q));  // Sim(3) copy
    spin(2ms, [] { return false; });
  }
  spin(500ms, [] { return false; });
  node.reset();  // shutdown: writes everything
  for (const char* f : {"ground_truth.tum", "mono.tum", "results.md", "results.csv", "results.json", "top_view.png"})
    EXPECT_TRUE(std::filesystem::exists(out + "/" + f)) << f;
  nlohmann::json j;
  std::ifstream(out + "/results.json") >> j;
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0]["trajectory"], "linear");
  EXPECT_EQ(j[0]["poses"], 100);
  // A Sim(3) copy: zero error after alignment (TUM-free path, doubles over DDS: ~1e-12).
  EXPECT_LT(j[0]["ape_m"]["rmse"].get<double>(), 1e-6);
  EXPECT_LT(j[0]["ape_rad"]["rmse"].get<double>(), 1e-6);
  EXPECT_NEAR(j[0]["scale"].get<double>(), 1.0 / 0.3, 1e-6);
  const cv::Mat png = cv::imread(out + "/top_view.png");
  EXPECT_EQ(png.cols, 800);
}
