// trajectory_evaluator: records ground truth and every estimator's odometry during a run and, on
// shutdown (Ctrl-C included), writes the TUM files, a Table II-style results table (Markdown,
// CSV, JSON: APE/RPE in m and rad after Sim(3) alignment) and a top-view PNG.
//
// Ports (relative to the node namespace, default /rov):
//   sub  ground_truth/odom                 nav_msgs/Odometry
//   sub  localization/<algo>/odom          nav_msgs/Odometry, one per name in `estimates`
//   sub  /tf_static                        tf2_msgs/TFMessage (latched): camera mounts
//   sub  localization/<algo>/path          nav_msgs/Path: when an estimator publishes its
//                                          (corrected) trajectory, whole or its latest poses, each
//                                          stamp is evaluated as the latest path had it, with the
//                                          odometry stamped before and after (PathHistory)
//   sub  any estimator's output, one per entry of `inputs` ("NAME=KIND:SOURCE"):
//          NAME=odom:TOPIC                 nav_msgs/Odometry (e.g. an ORB-SLAM3 wrapper's odometry)
//          NAME=pose:TOPIC                 geometry_msgs/PoseStamped
//          NAME=pose_cov:TOPIC             geometry_msgs/PoseWithCovarianceStamped
//          NAME=tf:PARENT.CHILD            the transform PARENT -> CHILD on /tf
//        so a ROS 2 estimator the user runs joins the same table; relative topics resolve in the
//        node's namespace. An estimate reports `camera`'s optical frame (or body_frame) unless the
//        entry ends with @FRAME (the frame mapping): then FRAME, a frame on the vehicle (body_frame
//        itself, or any frame the vehicle's /tf_static reaches from body_frame).
// Params: estimates (names), output_dir, trajectory_name (table row label), alignment
//         (none|se3|sim3|scale), estimate_alignments (NAME=ALIGNMENT entries overriding
//         `alignment` for one estimate: a metric RGB-D VO and a monocular SLAM in one run, SE(3)
//         and Sim(3)), rpe_delta (frames), max_time_diff (s, association),
//         camera (estimators report that camera's optical frame, as monocular ones do: ground
//         truth is moved from body_frame to it before comparing; the mount body_frame ->
//         <camera>_optical is looked up on /tf_static, where the renderer publishes it, or read
//         from cameras_config when that YAML is given), body_frame (default base_link_frd),
//         combine (several runs share output_dir: files are prefixed with trajectory_name and
//         results.md/csv/json hold the rows of every run, kept in rows/<trajectory_name>.tsv),
//         pipeline_world (world.yaml: also writes pipe_tracking.json, the cross-track error e_p
//         of the ground truth along its first pipeline and the length followed before e_p first
//         exceeded pipe_loss_distance, default 2.5 m: the pipe-following figures); scenario
//         (its world is the pipeline_world).
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "geometry_msgs/msg/pose_stamped.hpp"
#include "geometry_msgs/msg/pose_with_covariance_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "nav_msgs/msg/path.hpp"
#include "tf2_msgs/msg/tf_message.hpp"
#include "unav_common/config.hpp"
#include "unav_evaluation/report.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/tf_static.hpp"
#include "unav_runtime/validation.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_scene/world.hpp"

namespace unav::evaluation {

/// The trajectory_evaluator's parameters (params file or `-p name:=value`; `--help` lists them).
struct TrajectoryEvaluatorParams {
  std::vector<std::string> estimates;
  std::vector<std::string> inputs;
  std::string output_dir = "out/evaluation";
  std::string trajectory_name = "run";
  std::string alignment = "sim3";
  std::vector<std::string> estimate_alignments;
  int64_t rpe_delta = 1;
  double max_time_diff = 0.02;
  bool combine = false;
  std::string camera;
  std::string cameras_config;
  std::string body_frame = "base_link_frd";
  std::string pipeline_world;
  double pipe_loss_distance = 2.5;
  unav::scene::ScenarioParam scenario;  ///< its world replaces pipeline_world

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    scenario.Serialize(a);
    a->Visit(Field("estimates", &estimates).Doc("estimator names (localization/<name>/odom)"));
    a->Visit(
        Field("inputs", &inputs)
            .Doc("more estimators, NAME=odom:TOPIC | NAME=pose:TOPIC | NAME=pose_cov:TOPIC | NAME=tf:PARENT.CHILD"));
    a->Visit(Field("output_dir", &output_dir).Doc("results folder"));
    a->Visit(Field("trajectory_name", &trajectory_name).Doc("row label, e.g. linear"));
    a->Visit(Field("alignment", &alignment).OneOf({"none", "se3", "sim3", "scale"}).Doc("trajectory alignment"));
    a->Visit(Field("estimate_alignments", &estimate_alignments)
                 .Doc("NAME=none|se3|sim3|scale: another alignment for one estimate"));
    a->Visit(Field("rpe_delta", &rpe_delta).Min(1.0).Doc("RPE delta [frames]"));
    a->Visit(Field("max_time_diff", &max_time_diff).Range(1e-6, 10.0).Unit("s").Doc("association max time difference"));
    a->Visit(Field("combine", &combine).Doc("share output_dir with other runs (prefixed files, one combined table)"));
    a->Visit(Field("camera", &camera).Doc("estimators report this camera's optical frame (empty: body_frame)"));
    a->Visit(Field("cameras_config", &cameras_config)
                 .Doc("camera YAML with `camera` (empty: the mount comes from /tf_static)"));
    a->Visit(Field("body_frame", &body_frame).Doc("vehicle body frame"));
    a->Visit(Field("pipeline_world", &pipeline_world)
                 .Doc("world.yaml: also report cross-track error along its first pipeline"));
    a->Visit(
        Field("pipe_loss_distance", &pipe_loss_distance).Range(0.01, 100.0).Unit("m").Doc("pipe lost beyond this e_p"));
  }
};

class TrajectoryEvaluator : public unav::Node {
 public:
  explicit TrajectoryEvaluator(const unav::NodeOptions& options);
  ~TrajectoryEvaluator() override;
  /// Writes every output now (also called by the destructor); returns the results.
  std::vector<AlgorithmResult> write_outputs();
  /// Poses rejected (NaN/Inf, not a unit quaternion), by estimator name or "ground_truth/odom".
  const unav::RejectionCounter& rejections() const { return rejections_; }

 private:
  void write_pipe_tracking(const std::string& path, const Trajectory& ground_truth);
  void drop_spool();
  void check(const std::string& problem, const std::string& source) {
    if (!problem.empty()) rejections_.reject(source, problem);
  }
  unav::RejectionCounter rejections_{logger()};
  std::unique_ptr<unav::scene::World> pipe_world_;
  double pipe_loss_m_ = 2.5;

 private:
  std::string output_dir_, trajectory_name_;
  Alignment alignment_ = Alignment::kSim3;
  std::map<std::string, Alignment> estimate_alignment_;  ///< overrides of alignment_ by name
  Alignment alignment_for(const std::string& name) const {
    const auto it = estimate_alignment_.find(name);
    return it == estimate_alignment_.end() ? alignment_ : it->second;
  }
  RpeOptions rpe_;
  double max_diff_ = 0.02;
  bool written_ = false, combine_ = false;
  std::string spool_dir_;  ///< output_dir_/.spool_<trajectory>_<pid>: the poses received so far
  TrajectorySpool ground_truth_;
  Eigen::Isometry3d X_BE_ = Eigen::Isometry3d::Identity();  ///< estimated frame on the body
  std::string camera_frame_, body_frame_;                   ///< tf lookup of X_BE_ (camera_frame_ empty: not needed)
  bool have_mount_ = true;                                  ///< false until the camera mount is known
  std::unique_ptr<unav::StaticTransformListener> tf_static_;
  std::map<std::string, TrajectorySpool> estimates_;
  std::map<std::string, PathHistory> paths_;  ///< each estimator's corrected history from its paths
  std::vector<std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>>> subs_;
  std::vector<std::shared_ptr<unav::Subscription<nav_msgs::msg::Path>>> path_subs_;
  std::vector<std::shared_ptr<unav::Subscription<geometry_msgs::msg::PoseStamped>>> pose_subs_;
  std::vector<std::shared_ptr<unav::Subscription<geometry_msgs::msg::PoseWithCovarianceStamped>>> pose_cov_subs_;
  std::shared_ptr<unav::Subscription<tf2_msgs::msg::TFMessage>> tf_sub_;
  std::map<std::pair<std::string, std::string>, std::string> tf_inputs_;  ///< (parent, child) -> name
  std::map<std::string, std::string> input_frames_;                       ///< estimate -> the frame it reports (@FRAME)
};

}  // namespace unav::evaluation
