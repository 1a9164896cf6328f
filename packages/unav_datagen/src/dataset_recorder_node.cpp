// dataset_recorder: writes one camera's rgb/depth/segmentation frames with ground-truth poses and
// IMU in a dataset layout: `format` tum (TUM RGB-D, default), euroc (EuRoC/ASL) or kitti (KITTI
// odometry); see unav_datagen/dataset_writer.hpp, euroc_writer.hpp, kitti_writer.hpp. Every line
// is flushed as it is written, so Ctrl-C loses nothing. On shutdown (Ctrl-C included) it writes
// manifest.json (unav_datagen/manifest.hpp): camera, mount, counts, labels, depth units, source,
// software commit and the SHA-256 of every file.
//
// Ports (relative to the node namespace, default /rov):
//   sub  camera/<camera>/image_raw, depth/image_raw, segmentation/image_raw   sensor_msgs/Image
//   sub  camera/<camera>/camera_info   sensor_msgs/CameraInfo
//   sub  ground_truth/odom             nav_msgs/Odometry
//   sub  /tf_static                    tf2_msgs/TFMessage (latched): the camera mount body_frame ->
//                                      <camera>_optical, published by the renderer (unless
//                                      cameras_config names a camera YAML)
//   sub  imu                           sensor_msgs/Imu (sensor_data)
//   pub  /lockstep/ack                 unav_msgs/LockstepAck (lockstep: true). It acks the latest
//                                      odometry, but never past the next rgb frame it has not
//                                      written: min(odometry stamp, last frame + image_period -
//                                      1 ms). The physics never outruns the recorder's ground truth,
//                                      and a frame that was lost (published before this reader
//                                      matched, or by a renderer killed before delivering it) holds
//                                      the barrier until the renderer sends it (again).
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <optional>

#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/camera_info.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "sensor_msgs/msg/imu.hpp"
#include "unav_common/config.hpp"
#include "unav_common/resources.hpp"
#include "unav_datagen/dataset_writer.hpp"
#include "unav_datagen/manifest.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_runtime/lockstep_ack.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/synchronizer.hpp"
#include "unav_runtime/tf_static.hpp"
#include "unav_runtime/validation.hpp"
#include "unav_scene/camera.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_scene/world.hpp"

namespace unav::datagen {
namespace {

double stamp_of(const std_msgs::msg::dds_::Header_& h) {
  return unav::Time::from_msg(h.stamp().sec(), h.stamp().nanosec()).seconds();
}

}  // namespace

struct DatasetRecorderParams {
  std::string output_dir = "out/dataset";
  std::string format = "tum";
  std::string camera = "front";
  std::string cameras_config;
  std::string body_frame = "base_link_frd";
  unav::lockstep::ParticipantParams lockstep{"recorder"};
  double image_period = 0.1;
  std::string world;
  /// recorded in manifest.json; its world and cameras.rate_hz replace world and image_period
  unav::scene::ScenarioParam scenario;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    scenario.Serialize(a);
    a->Visit(Field("output_dir", &output_dir).Doc("dataset folder"));
    a->Visit(Field("format", &format).OneOf(sequence_formats()).Doc("dataset layout: tum, euroc or kitti"));
    a->Visit(Field("camera", &camera).Doc("camera name to record"));
    a->Visit(Field("cameras_config", &cameras_config)
                 .Doc("camera YAML for the mount; empty: body_frame -> <camera>_optical from /tf_static"));
    a->Visit(Field("body_frame", &body_frame).Doc("vehicle body frame (tf parent of the camera)"));
    lockstep.Serialize(a);
    a->Visit(Field("image_period", &image_period)
                 .Range(1e-3, 10.0)
                 .Unit("s")
                 .Doc("the renderer's frame period (1 / its rate): lockstep acks wait for every frame"));
    a->Visit(Field("world", &world).Doc("world file of the run, recorded in manifest.json (not read)"));
  }
};

class DatasetRecorder : public unav::Node {
 public:
  explicit DatasetRecorder(const unav::NodeOptions& options) : Node("dataset_recorder", options, "rov") {
    DatasetRecorderParams prm;
    declare_params(&prm);
    const std::string& out = prm.output_dir;
    camera_ = prm.camera;
    manifest_.format = prm.format;
    manifest_.camera = camera_;
    manifest_.parent_frame = prm.body_frame;
    if (prm.scenario.given()) {
      const unav::scene::Scenario sc = prm.scenario.load();
      prm.world = sc.world;
      prm.image_period = 1.0 / sc.cameras.rate_hz;  // the renderer's rate is the scenario's
      manifest_.source["scenario"] = prm.scenario.file;
      manifest_.source["scenario_seed"] = std::to_string(sc.seed);
      for (std::size_t i = 0; i < prm.scenario.overrides.size(); ++i)
        manifest_.source["scenario_set_" + std::to_string(i)] = prm.scenario.overrides[i];
    }
    if (!prm.world.empty()) manifest_.source["world"] = prm.world;
    manifest_.labels = unav::scene::seg_class_labels();
    try {
      writer_ = make_sequence_writer(prm.format, out);
    } catch (const DatasetError& e) {
      throw unav::ConfigError(e.what());
    }
    if (!prm.cameras_config.empty()) {
      X_BC_ = unav::scene::load_camera(prm.cameras_config, camera_).X_BC;  // ConfigError names file and camera
      have_mount_ = true;
      writer_->set_camera_mount(X_BC_);
    } else {
      // The mount's owner (the renderer) publishes it on /tf_static, latched; poses wait for it.
      tf_static_ = std::make_unique<unav::StaticTransformListener>(*this);
      tf_static_->on_update([this, body = prm.body_frame] {
        if (have_mount_) return;
        if (const auto X = tf_static_->lookup(body, camera_ + "_optical")) {
          X_BC_ = *X;
          have_mount_ = true;
          writer_->set_camera_mount(X_BC_);
          logger()->info("camera mount {} -> {}_optical from /tf_static", body, camera_);
          for (const auto& [t, X_WB] : unmounted_) writer_->write_pose(t, X_WB * X_BC_, X_WB);
          unmounted_.clear();
        }
      });
    }
    ack_name_ = prm.lockstep.name;
    if (prm.lockstep.enabled) {
      acker_ = std::make_unique<unav::lockstep::Acker>(*this, ack_name_);
      frame_lead_ns_ = std::llround(prm.image_period * 1e9) - 1000000;  // just under the next frame
      stall_timer_ = create_wall_timer(std::chrono::seconds(1), [this] { check_frame_stall(); });
    }
    const std::string base = "camera/" + camera_;
    const unav::QoS q = unav::QoS::reliable(5);
    const unav::QoS images = q.with_data_sharing();  // from the renderer's shared pool, on one host
    rgb_sub_ = create_subscription<sensor_msgs::msg::Image>(
        base + "/image_raw", images, [this](const sensor_msgs::msg::Image& m) {
          if (!check(m, "rgb8", 3)) return;
          if (!fresh(last_rgb_t_, m)) {  // sent again while the lockstep held: acked again
            ack();
            return;
          }
          const double t = stamp_of(m.header());
          writer_->write_rgb(t, static_cast<int>(m.width()), static_cast<int>(m.height()), m.data().data());
          pose_sync_.add_first(unav::nanoseconds(m.header()), t);
          last_frame_ns_ = unav::nanoseconds(m.header());
          stall_reported_ = false;
          ack();
        });
    depth_sub_ = create_subscription<sensor_msgs::msg::Image>(
        base + "/depth/image_raw", images, [this](const sensor_msgs::msg::Image& m) {
          if (!check(m, "32FC1", 4) || !fresh(last_depth_t_, m)) return;
          writer_->write_depth(stamp_of(m.header()), static_cast<int>(m.width()), static_cast<int>(m.height()),
                               reinterpret_cast<const float*>(m.data().data()));
        });
    seg_sub_ = create_subscription<sensor_msgs::msg::Image>(
        base + "/segmentation/image_raw", images, [this](const sensor_msgs::msg::Image& m) {
          if (!check(m, "mono8", 1) || !fresh(last_seg_t_, m)) return;
          writer_->write_segmentation(stamp_of(m.header()), static_cast<int>(m.width()), static_cast<int>(m.height()),
                                      m.data().data());
        });
    info_sub_ = create_subscription<sensor_msgs::msg::CameraInfo>(base + "/camera_info", q,
                                                                  [this](const sensor_msgs::msg::CameraInfo& m) {
                                                                    if (camera_written_) return;
                                                                    CameraIntrinsics k;
                                                                    k.width = static_cast<int>(m.width());
                                                                    k.height = static_cast<int>(m.height());
                                                                    k.fx = m.k()[0];
                                                                    k.fy = m.k()[4];
                                                                    k.cx = m.k()[2];
                                                                    k.cy = m.k()[5];
                                                                    k.distortion = m.d();
                                                                    writer_->write_camera(k);
                                                                    manifest_.intrinsics = k;
                                                                    camera_written_ = true;
                                                                  });
    odom_sub_ = create_subscription<nav_msgs::msg::Odometry>(
        "ground_truth/odom", unav::QoS::reliable(100), [this](const nav_msgs::msg::Odometry& m) {
          if (const std::string why = unav::odometry_problem(m); !why.empty()) {
            rejections_.reject(odom_sub_->topic_name(), why);  // not in the dataset, not acked
            return;
          }
          pose_sync_.add_second(unav::nanoseconds(m.header()), unav::from_msg(m.pose().pose()));
          latest_odom_ns_ = std::max(latest_odom_ns_, unav::nanoseconds(m.header()));
          ack();
        });
    // Best effort to match the IMU publisher (sensor_data), but a deep history: physics runs in
    // bursts in lockstep and every sample belongs in the dataset.
    imu_sub_ = create_subscription<sensor_msgs::msg::Imu>(
        "imu", unav::QoS{unav::QoS::Reliability::kBestEffort, unav::QoS::Durability::kVolatile, 1000},
        [this](const sensor_msgs::msg::Imu& m) {
          writer_->write_imu(
              stamp_of(m.header()),
              Eigen::Vector3d(m.angular_velocity().x(), m.angular_velocity().y(), m.angular_velocity().z()),
              Eigen::Vector3d(m.linear_acceleration().x(), m.linear_acceleration().y(), m.linear_acceleration().z()));
        });
    logger()->info("recording camera '{}' to {} ({} layout)", camera_, out, prm.format);
  }
  ~DatasetRecorder() override {
    if (!unmounted_.empty())
      logger()->error(
          "no {}_optical mount arrived on /tf_static (is the renderer running?): {} ground-truth "
          "poses not written (give cameras_config to record without the renderer's tf)",
          camera_, unmounted_.size());
    writer_->close();
    manifest_.mount_known = have_mount_;
    manifest_.X_BC = X_BC_;
    try {
      unav::datagen::write_manifest(*writer_, manifest_);
    } catch (const std::exception& e) {
      logger()->error("manifest.json not written: {}", e.what());
    }
    for (const auto& w : writer_->warnings()) logger()->warn("{}", w);
    logger()->info("dataset closed: {} frames in {}", writer_->frames(), writer_->root());
  }

 private:
  // Lockstep: acks the latest odometry, capped just under the first frame instant it has no rgb
  // frame for. Nothing before the first frame (the barrier at the run's first instant waits for
  // it); acks never go backwards (Participant); a repeated state is acked again.
  void ack() {
    if (!acker_ || latest_odom_ns_ == kNone || last_frame_ns_ == kNone) return;
    acker_->ack(std::min(latest_odom_ns_, last_frame_ns_ + frame_lead_ns_));
  }
  // A state at (or past) the next frame instant with no frame for 5 s: the renderer is down, slow,
  // or renders at another rate than image_period says. Said once per stall; the physics server
  // names the recorder as the participant it waits for.
  void check_frame_stall() {
    const bool waiting =
        latest_odom_ns_ != kNone && last_frame_ns_ != kNone && latest_odom_ns_ > last_frame_ns_ + frame_lead_ns_;
    const auto now = std::chrono::steady_clock::now();
    if (!waiting) {
      waiting_since_.reset();
      return;
    }
    if (!waiting_since_) waiting_since_ = now;
    if (!stall_reported_ && now - *waiting_since_ >= std::chrono::seconds(5)) {
      stall_reported_ = true;
      logger()->warn(
          "lockstep: no rgb frame after t = {:.3f} s on '{}' for 5 s, though odometry reached t = {:.3f} s: is the "
          "renderer running, at 1 / image_period = {:.2f} Hz?",
          static_cast<double>(last_frame_ns_) * 1e-9, rgb_sub_->topic_name(),
          static_cast<double>(latest_odom_ns_) * 1e-9, 1e9 / static_cast<double>(frame_lead_ns_ + 1000000));
    }
  }
  // A frame at or before the stream's last one is not written twice: a renderer respawned while
  // the lockstep barrier held renders the held instant again.
  bool fresh(double& last_t, const sensor_msgs::msg::Image& m) {
    const double t = stamp_of(m.header());
    if (t <= last_t) {
      logger()->info("frame at t = {:.3f} s on '{}' is not after the last one ({:.3f} s): not written again", t,
                     m.header().frame_id(), last_t);
      return false;
    }
    last_t = t;
    return true;
  }
  bool check(const sensor_msgs::msg::Image& m, const char* encoding, size_t bpp) {
    if (m.encoding() == encoding && m.data().size() == static_cast<size_t>(m.width()) * m.height() * bpp) return true;
    logger()->warn("skipping an image with encoding '{}' and {} bytes (expected {} {}x{})", m.encoding(),
                   m.data().size(), encoding, m.width(), m.height());
    return false;
  }
  // Ground truth of an image: the renderer renders at odometry stamps, so the pose with exactly
  // the image's stamp exists (it may arrive before or after the image: different writers).
  void on_image_pose(double t, const Eigen::Isometry3d& X_WB) {
    if (!have_mount_) {
      unmounted_.emplace_back(t, X_WB);
      return;
    }
    writer_->write_pose(t, X_WB * X_BC_, X_WB);
  }

  std::string camera_;
  Eigen::Isometry3d X_BC_ = Eigen::Isometry3d::Identity();
  std::unique_ptr<SequenceWriter> writer_;
  bool camera_written_ = false;
  unav::datagen::ManifestInput manifest_;
  bool have_mount_ = false;
  std::unique_ptr<unav::StaticTransformListener> tf_static_;
  std::vector<std::pair<double, Eigen::Isometry3d>> unmounted_;  ///< image poses before the mount arrived
  // Image stamps paired with the odometry of the same stamp; odometry runs ahead of the images
  // by up to a lockstep burst, hence the deep queue.
  unav::sync::ExactTime<double, Eigen::Isometry3d> pose_sync_{
      4000, [this](const double& t, const Eigen::Isometry3d& X_WB) { on_image_pose(t, X_WB); }};
  std::string ack_name_;
  std::unique_ptr<unav::lockstep::Acker> acker_;
  static constexpr int64_t kNone = INT64_MIN;
  int64_t latest_odom_ns_ = kNone, last_frame_ns_ = kNone;  ///< stamps for the lockstep acks
  int64_t frame_lead_ns_ = 0;
  std::shared_ptr<unav::Timer> stall_timer_;
  std::optional<std::chrono::steady_clock::time_point> waiting_since_;
  bool stall_reported_ = false;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::Image>> rgb_sub_, depth_sub_, seg_sub_;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::CameraInfo>> info_sub_;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  unav::RejectionCounter rejections_{logger()};
  double last_rgb_t_ = -1.0, last_depth_t_ = -1.0,
         last_seg_t_ = -1.0;  // stamps start at 0  // odometry with NaN/Inf or a non-rotation
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::Imu>> imu_sub_;
};

}  // namespace unav::datagen

#ifndef UNAV_DATASET_RECORDER_NO_MAIN
int main(int argc, char** argv) { return unav::run_node<unav::datagen::DatasetRecorder>(argc, argv); }
#endif
