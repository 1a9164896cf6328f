#include "trajectory_evaluator.hpp"
#include "unav_scene/pipe_tracking.hpp"

#include <fstream>
#include <nlohmann/json.hpp>

#include <sys/file.h>

#include <fcntl.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <optional>

#include "unav_runtime/conversions.hpp"
#include "unav_scene/camera.hpp"

namespace unav::evaluation {
namespace {

// Appends the pose unless its stamp is not after the last one (re-published states, reordering);
// returns why it cannot be used (NaN/Inf, not a unit quaternion), empty otherwise.
// (T: a Trajectory in memory, or the TrajectorySpool of a topic.)
double last_stamp(const Trajectory& t) { return t.stamps.back(); }
double last_stamp(const TrajectorySpool& t) { return t.last_stamp(); }
template <class T>
std::string append_pose(T& t, const std_msgs::msg::Header& h, const geometry_msgs::msg::Pose& p) {
  if (std::string why = unav::pose_problem(p); !why.empty()) return why;
  const double stamp = unav::Time::from_msg(h.stamp().sec(), h.stamp().nanosec()).seconds();
  if (!t.empty() && stamp <= last_stamp(t)) return "";
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = unav::from_msg(p.position());
  X.linear() = unav::from_msg(p.orientation()).normalized().toRotationMatrix();
  t.push_back(stamp, X);
  return "";
}

template <class T>
std::string append(T& t, const nav_msgs::msg::Odometry& m) {
  return append_pose(t, m.header(), m.pose().pose());
}

std::string strip_slash(std::string f) {
  while (!f.empty() && f.front() == '/') f.erase(0, 1);
  return f;
}

Trajectory from_path(const nav_msgs::msg::Path& m) {
  Trajectory t;
  for (const auto& ps : m.poses()) {
    nav_msgs::msg::Odometry o;
    o.header() = ps.header();
    o.pose().pose() = ps.pose();
    append(t, o);
  }
  return t;
}

// An exclusive lock on a file for the scope (several evaluators may share one folder).
class FolderLock {
 public:
  explicit FolderLock(const std::string& path) : fd_(::open(path.c_str(), O_CREAT | O_RDWR, 0644)) {
    if (fd_ < 0) throw TrajectoryError(path + ": cannot open lock file: " + std::strerror(errno));
    ::flock(fd_, LOCK_EX);
  }
  ~FolderLock() {
    ::flock(fd_, LOCK_UN);
    ::close(fd_);
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_;
};

}  // namespace

TrajectoryEvaluator::TrajectoryEvaluator(const unav::NodeOptions& options)
    : Node("trajectory_evaluator", options, "rov") {
  TrajectoryEvaluatorParams prm;
  declare_params(&prm);
  const std::vector<std::string>& names = prm.estimates;
  output_dir_ = prm.output_dir;
  trajectory_name_ = prm.trajectory_name;
  try {
    alignment_ = alignment_from_string(prm.alignment);
  } catch (const TrajectoryError& e) {
    throw unav::ParameterError("node '" + name() + "': parameter 'alignment': " + e.what());
  }
  rpe_.delta = static_cast<double>(prm.rpe_delta);
  max_diff_ = prm.max_time_diff;
  combine_ = prm.combine;
  if (combine_ && (trajectory_name_.empty() || trajectory_name_.find_first_of("/\t") != std::string::npos))
    throw unav::ParameterError("node '" + name() + "': trajectory_name '" + trajectory_name_ +
                               "' must be a non-empty file name with combine");
  const std::string& camera = prm.camera;
  const std::string& cams_path = prm.cameras_config;
  body_frame_ = prm.body_frame;
  const std::string& pipe_world = prm.pipeline_world;
  pipe_loss_m_ = prm.pipe_loss_distance;
  if (!pipe_world.empty() || prm.scenario.given())  // the scenario's world, else pipeline_world
    pipe_world_ = std::make_unique<unav::scene::World>(unav::scene::pipeline_world(prm.scenario, pipe_world));
  if (!camera.empty() && cams_path.empty()) {
    // The mount's owner (the renderer) publishes it once, latched: look it up like tf2 does.
    camera_frame_ = camera + "_optical";
    have_mount_ = false;
    tf_static_ = std::make_unique<unav::StaticTransformListener>(*this);
    tf_static_->on_update([this] {
      if (have_mount_) return;
      if (const auto X = tf_static_->lookup(body_frame_, camera_frame_)) {
        X_BE_ = *X;
        have_mount_ = true;
        logger()->info("camera mount {} -> {} from /tf_static", body_frame_, camera_frame_);
      }
    });
  } else if (!camera.empty()) {
    X_BE_ = unav::scene::load_camera(cams_path, camera).X_BC;  // ConfigError names file and camera
  }
  std::error_code ec;
  std::filesystem::create_directories(output_dir_, ec);
  if (ec) throw unav::ConfigError("output_dir '" + output_dir_ + "': cannot create: " + ec.message());
  // The poses received are recorded on disk as they come (hours of ground truth at 100 Hz would
  // otherwise grow the node without bound) and read back once, to evaluate.
  spool_dir_ = output_dir_ + "/.spool_" + trajectory_name_ + "_" + std::to_string(::getpid());
  std::filesystem::create_directories(spool_dir_, ec);
  if (ec)
    throw unav::ConfigError("output_dir '" + output_dir_ + "': cannot create " + spool_dir_ + ": " + ec.message());
  ground_truth_ = TrajectorySpool(spool_dir_ + "/ground_truth.bin");
  auto spool_of = [this](const std::string& n) {
    std::string file = n;
    std::replace(file.begin(), file.end(), '/', '_');
    return TrajectorySpool(spool_dir_ + "/" + file + ".bin");
  };
  subs_.push_back(create_subscription<nav_msgs::msg::Odometry>(
      "ground_truth/odom", unav::QoS::reliable(100),
      [this](const nav_msgs::msg::Odometry& m) { check(append(ground_truth_, m), "ground_truth/odom"); }));
  for (const auto& n : names) {
    estimates_.emplace(n, spool_of(n));
    subs_.push_back(create_subscription<nav_msgs::msg::Odometry>(
        "localization/" + n + "/odom", unav::QoS::reliable(100),
        [this, n](const nav_msgs::msg::Odometry& m) { check(append(estimates_.at(n), m), n); }));
    path_subs_.push_back(create_subscription<nav_msgs::msg::Path>(
        "localization/" + n + "/path", unav::QoS::reliable(2),
        [this, n](const nav_msgs::msg::Path& m) { paths_[n].update(from_path(m)); }));
  }
  for (std::string in : prm.inputs) {
    // NAME=KIND:SOURCE[@FRAME]
    std::string frame;
    if (const size_t at = in.rfind('@'); at != std::string::npos) {
      frame = strip_slash(in.substr(at + 1));
      in = in.substr(0, at);
      if (frame.empty())
        throw unav::ParameterError("node '" + name() + "': parameter 'inputs': '" + in + "@': empty frame after @");
    }
    const size_t eq = in.find('='), colon = in.find(':', eq == std::string::npos ? 0 : eq);
    const std::string rule = "expected NAME=odom:TOPIC, NAME=pose:TOPIC, NAME=pose_cov:TOPIC or NAME=tf:PARENT.CHILD";
    if (eq == std::string::npos || eq == 0 || colon == std::string::npos || colon + 1 == in.size())
      throw unav::ParameterError("node '" + name() + "': parameter 'inputs': '" + in + "': " + rule);
    const std::string n = in.substr(0, eq), kind = in.substr(eq + 1, colon - eq - 1), src = in.substr(colon + 1);
    if (estimates_.count(n))
      throw unav::ParameterError("node '" + name() + "': parameter 'inputs': estimator name '" + n + "' used twice");
    estimates_.emplace(n, spool_of(n));
    if (!frame.empty()) {
      input_frames_[n] = frame;
      if (!tf_static_) tf_static_ = std::make_unique<unav::StaticTransformListener>(*this);
    }
    if (kind == "odom") {
      subs_.push_back(create_subscription<nav_msgs::msg::Odometry>(
          src, unav::QoS::reliable(100),
          [this, n](const nav_msgs::msg::Odometry& m) { check(append(estimates_.at(n), m), n); }));
    } else if (kind == "pose") {
      pose_subs_.push_back(create_subscription<geometry_msgs::msg::PoseStamped>(
          src, unav::QoS::reliable(100), [this, n](const geometry_msgs::msg::PoseStamped& m) {
            check(append_pose(estimates_.at(n), m.header(), m.pose()), n);
          }));
    } else if (kind == "pose_cov") {
      pose_cov_subs_.push_back(create_subscription<geometry_msgs::msg::PoseWithCovarianceStamped>(
          src, unav::QoS::reliable(100), [this, n](const geometry_msgs::msg::PoseWithCovarianceStamped& m) {
            check(append_pose(estimates_.at(n), m.header(), m.pose().pose()), n);
          }));
    } else if (kind == "tf") {
      const size_t dot = src.find('.');
      if (dot == std::string::npos || dot == 0 || dot + 1 == src.size())
        throw unav::ParameterError("node '" + name() + "': parameter 'inputs': '" + in + "': " + rule);
      tf_inputs_[{strip_slash(src.substr(0, dot)), strip_slash(src.substr(dot + 1))}] = n;
    } else {
      throw unav::ParameterError("node '" + name() + "': parameter 'inputs': '" + in + "': kind '" + kind +
                                 "' is unknown; " + rule);
    }
  }
  if (!tf_inputs_.empty()) {
    tf_sub_ = create_subscription<tf2_msgs::msg::TFMessage>(
        "/tf", unav::QoS::reliable(100), [this](const tf2_msgs::msg::TFMessage& m) {
          for (const auto& tr : m.transforms()) {
            const auto it = tf_inputs_.find({strip_slash(tr.header().frame_id()), strip_slash(tr.child_frame_id())});
            if (it == tf_inputs_.end()) continue;
            geometry_msgs::msg::Pose p;
            p.position().x(tr.transform().translation().x());
            p.position().y(tr.transform().translation().y());
            p.position().z(tr.transform().translation().z());
            p.orientation(tr.transform().rotation());
            check(append_pose(estimates_.at(it->second), tr.header(), p), it->second);
          }
        });
  }
  for (const std::string& entry : prm.estimate_alignments) {
    const size_t eq = entry.find('=');
    const std::string what = "node '" + name() + "': parameter 'estimate_alignments': '" + entry + "': ";
    if (eq == std::string::npos || eq == 0) throw unav::ParameterError(what + "expected NAME=none|se3|sim3|scale");
    const std::string n = entry.substr(0, eq);
    if (!estimates_.count(n)) throw unav::ParameterError(what + "'" + n + "' is not in estimates or inputs");
    try {
      estimate_alignment_[n] = alignment_from_string(entry.substr(eq + 1));
    } catch (const TrajectoryError& e) {
      throw unav::ParameterError(what + e.what());
    }
  }
  logger()->info("evaluating {} estimator(s) against ground truth; results in {}", estimates_.size(), output_dir_);
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
    drop_spool();
    return results;
  }
  if (!have_mount_) {
    logger()->error(
        "no {} -> {} transform on /tf_static (is the renderer running?): estimates are compared "
        "with the body frame",
        body_frame_, camera_frame_);
  }
  const std::string prefix = output_dir_ + "/" + (combine_ ? trajectory_name_ + "_" : "");
  const Trajectory ground_truth = ground_truth_.load();
  if (pipe_world_) write_pipe_tracking(prefix + "pipe_tracking.json", ground_truth);
  // Ground truth of the frame the estimators report (the body, or a camera on it).
  Trajectory truth = ground_truth;
  for (auto& X : truth.poses) X = X * X_BE_;
  write_tum(prefix + "ground_truth.tum", truth);
  std::vector<std::pair<std::string, Trajectory>> aligned;
  for (auto& [name, spool] : estimates_) {
    // The corrected history from the paths (each stamp as the latest path had it; a path may
    // hold only the latest poses), the odometry before and after it.
    const Trajectory odom = spool.load();
    const auto p = paths_.find(name);
    const Trajectory traj = p != paths_.end() ? p->second.over(odom) : odom;
    if (traj.empty()) {
      logger()->warn("estimator '{}' published nothing", name);
      continue;
    }
    write_tum(prefix + name + ".tum", traj);
    // The frame mapping of an input (@FRAME): ground truth of that frame instead.
    Trajectory mapped;
    if (const auto f = input_frames_.find(name); f != input_frames_.end()) {
      std::optional<Eigen::Isometry3d> X_BF;
      if (f->second == body_frame_) X_BF = Eigen::Isometry3d::Identity();
      if (!X_BF && tf_static_) X_BF = tf_static_->lookup(body_frame_, f->second);
      if (!X_BF) {
        logger()->warn("estimator '{}' reports frame '{}', which /tf_static does not connect to {}: not evaluated",
                       name, f->second, body_frame_);
        continue;
      }
      mapped = ground_truth;
      for (auto& X : mapped.poses) X = X * *X_BF;
    }
    const Trajectory& ref_truth = input_frames_.count(name) ? mapped : truth;
    try {
      results.push_back(evaluate(ref_truth, traj, trajectory_name_, name, alignment_for(name), rpe_, max_diff_));
      auto [ref, est] = associate(ref_truth, traj, max_diff_);
      align(est, ref, alignment_for(name));
      aligned.emplace_back(name, est);
      logger()->info("{}: APE {:.4f} m, RPE {:.4f} m, APE {:.4f} rad, RPE {:.4f} rad ({} poses)", name,
                     results.back().ape_m.rmse, results.back().rpe_m.rmse, results.back().ape_rad.rmse,
                     results.back().rpe_rad.rmse, results.back().poses);
    } catch (const TrajectoryError& e) {
      logger()->warn("estimator '{}' not evaluated: {}", name, e.what());
    }
  }
  write_top_view_png(prefix + "top_view.png", truth, aligned);
  if (!combine_) {
    write_results(output_dir_ + "/results", results, alignment_);
  } else {
    FolderLock lock(output_dir_ + "/.results.lock");
    std::filesystem::create_directories(output_dir_ + "/rows");
    write_result_rows(output_dir_ + "/rows/" + trajectory_name_ + ".tsv", results);
    std::vector<AlgorithmResult> all;
    std::vector<std::string> files;
    for (const auto& e : std::filesystem::directory_iterator(output_dir_ + "/rows"))
      if (e.path().extension() == ".tsv") files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      const auto rows = read_result_rows(f);
      all.insert(all.end(), rows.begin(), rows.end());
    }
    write_results(output_dir_ + "/results", all, alignment_);
  }
  logger()->info("evaluation written to {}", output_dir_);
  drop_spool();  // everything is in the outputs now
  return results;
}

void TrajectoryEvaluator::drop_spool() {
  ground_truth_.remove();
  for (auto& [name, spool] : estimates_) spool.remove();
  std::error_code ec;
  std::filesystem::remove_all(spool_dir_, ec);
}

void TrajectoryEvaluator::write_pipe_tracking(const std::string& path, const Trajectory& ground_truth) {
  std::vector<Eigen::Vector3d> p;
  for (const auto& X : ground_truth.poses) p.push_back(X.translation());
  const unav::scene::PipeTracking t = unav::scene::track_pipe(*pipe_world_, p, pipe_loss_m_);
  nlohmann::json j{{"trajectory", trajectory_name_},
                   {"poses", ground_truth.size()},
                   {"duration_s", ground_truth.stamps.back() - ground_truth.stamps.front()},
                   {"mean_e_p_m", t.mean_e_p_m},
                   {"rms_e_p_m", t.rms_e_p_m},
                   {"max_e_p_m", t.max_e_p_m},
                   {"followed_m", t.followed_m},
                   {"pipe_length_m", t.pipe_length_m},
                   {"followed_fraction", t.followed_fraction},
                   {"lost", t.lost},
                   {"completed", t.completed},
                   {"loss_distance_m", pipe_loss_m_}};
  if (t.lost) j["lost_at_s"] = ground_truth.stamps[static_cast<std::size_t>(t.lost_at_index)];
  std::ofstream(path) << j.dump(2) << "\n";
  logger()->info("pipe tracking: mean e_p {:.3f} m, max {:.3f} m, followed {:.1f} of {:.1f} m ({:.0f} %){}",
                 t.mean_e_p_m, t.max_e_p_m, t.followed_m, t.pipe_length_m, 100.0 * t.followed_fraction,
                 t.lost ? ", pipe lost" : (t.completed ? ", end reached" : ""));
}

}  // namespace unav::evaluation
