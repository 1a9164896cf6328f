#include "trajectory_evaluator.hpp"

#include <filesystem>

namespace unav_evaluation {
namespace {

void append(Trajectory& t, const nav_msgs::msg::Odometry& m) {
  const double stamp = unav::Time::from_msg(m.header().stamp().sec(), m.header().stamp().nanosec()).seconds();
  if (!t.empty() && stamp <= t.stamps.back()) return;  // duplicates (re-published states) and reordering
  const auto& p = m.pose().pose();
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = Eigen::Vector3d(p.position().x(), p.position().y(), p.position().z());
  const Eigen::Quaterniond q(p.orientation().w(), p.orientation().x(), p.orientation().y(), p.orientation().z());
  if (!X.translation().allFinite() || !q.coeffs().allFinite() || q.norm() < 1e-6) return;
  X.linear() = q.normalized().toRotationMatrix();
  t.push_back(stamp, X);
}

}  // namespace

TrajectoryEvaluator::TrajectoryEvaluator(const unav::NodeOptions& options) : Node("trajectory_evaluator", options, "rov") {
  const auto names = declare_parameter<std::vector<std::string>>("estimates", {}, {"estimator names", {}, {}, false});
  output_dir_ = declare_parameter<std::string>("output_dir", "out/evaluation", {"results folder", {}, {}, false});
  trajectory_name_ = declare_parameter<std::string>("trajectory_name", "run", {"row label, e.g. linear", {}, {}, false});
  try {
    alignment_ = alignment_from_string(declare_parameter<std::string>("alignment", "sim3", {"none|se3|sim3|scale", {}, {}, false}));
  } catch (const TrajectoryError& e) {
    throw unav::ParameterError("node '" + name() + "': parameter 'alignment': " + e.what());
  }
  rpe_.delta = static_cast<double>(declare_parameter<int64_t>("rpe_delta", 1, {"RPE delta [frames]", 1.0, {}, false}));
  max_diff_ = declare_parameter<double>("max_time_diff", 0.02, {"association max time difference [s]", 1e-6, 10.0, false});
  std::error_code ec;
  std::filesystem::create_directories(output_dir_, ec);
  if (ec) throw unav::ConfigError("output_dir '" + output_dir_ + "': cannot create: " + ec.message());
  subs_.push_back(create_subscription<nav_msgs::msg::Odometry>(
      "ground_truth/odom", unav::QoS::reliable(100), [this](const nav_msgs::msg::Odometry& m) { append(ground_truth_, m); }));
  for (const auto& n : names) {
    estimates_[n];
    subs_.push_back(create_subscription<nav_msgs::msg::Odometry>(
        "localization/" + n + "/odom", unav::QoS::reliable(100),
        [this, n](const nav_msgs::msg::Odometry& m) { append(estimates_[n], m); }));
  }
  logger()->info("evaluating {} estimator(s) against ground truth; results in {}", names.size(), output_dir_);
}

TrajectoryEvaluator::~TrajectoryEvaluator() {
  try {
    write_outputs();
  } catch (const std::exception& e) {
    logger()->error("could not write the evaluation: {}", e.what());
  }
}

std::vector<AlgorithmResult> TrajectoryEvaluator::write_outputs() {
  std::vector<AlgorithmResult> results;
  if (written_) return results;
  written_ = true;
  if (ground_truth_.empty()) {
    logger()->warn("no ground truth received: nothing to evaluate");
    return results;
  }
  write_tum(output_dir_ + "/ground_truth.tum", ground_truth_);
  std::vector<std::pair<std::string, Trajectory>> aligned;
  for (const auto& [name, traj] : estimates_) {
    if (traj.empty()) {
      logger()->warn("estimator '{}' published nothing", name);
      continue;
    }
    write_tum(output_dir_ + "/" + name + ".tum", traj);
    try {
      results.push_back(evaluate(ground_truth_, traj, trajectory_name_, name, alignment_, rpe_, max_diff_));
      auto [ref, est] = associate(ground_truth_, traj, max_diff_);
      align(est, ref, alignment_);
      aligned.emplace_back(name, est);
      logger()->info("{}: APE {:.4f} m, RPE {:.4f} m, APE {:.4f} rad, RPE {:.4f} rad ({} poses)", name,
                     results.back().ape_m.rmse, results.back().rpe_m.rmse, results.back().ape_rad.rmse,
                     results.back().rpe_rad.rmse, results.back().poses);
    } catch (const TrajectoryError& e) {
      logger()->warn("estimator '{}' not evaluated: {}", name, e.what());
    }
  }
  write_results(output_dir_ + "/results", results, alignment_);
  write_top_view_png(output_dir_ + "/top_view.png", ground_truth_, aligned);
  logger()->info("evaluation written to {}", output_dir_);
  return results;
}

}  // namespace unav_evaluation
