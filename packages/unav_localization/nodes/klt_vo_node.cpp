// klt_vo: KLT visual odometry (RGB-D or monocular) as a node.
//
// Ports (relative to the node namespace, default /rov):
//   sub  camera/<camera>/image_raw, camera/<camera>/depth/image_raw   sensor_msgs/Image (rgb8, 32FC1;
//                                                                      depth only in mode rgbd)
//   sub  camera/<camera>/camera_info                                   sensor_msgs/CameraInfo
//   pub  localization/klt_vo/odom   nav_msgs/Odometry, stamped with the image time. Mode rgbd:
//                                   base_link_frd in frame `klt_vo_odom` (the body at the first
//                                   frame). Mode monocular: the camera optical frame
//                                   `<camera>_optical` in frame `klt_vo_odom` (the first camera
//                                   frame): without metric scale the camera's lever arm cannot be
//                                   applied, so the camera itself is reported
//   pub  localization/klt_vo/path   nav_msgs/Path (every 10 frames)
//   pub  /lockstep/ack                 unav_msgs/LockstepAck (lockstep: true): after each processed
//                                   image at t, acks up to t + image_period - 1 ms
// The camera's mount (body_frame -> <camera>_optical on /tf_static, as the renderer publishes it,
// or cameras_config when given) turns camera motion into body motion; frames wait for it. Mode rgbd publishes
// every frame (a lost frame with a constant-velocity prediction); mode monocular publishes only
// frames with an estimate (initialised or tracking), in arbitrary units (the first map's median
// scene depth is 1): compare with ground truth after a Sim(3) alignment.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>

#include <opencv2/imgproc.hpp>

#include "nav_msgs/msg/odometry.hpp"
#include "nav_msgs/msg/path.hpp"
#include "sensor_msgs/msg/camera_info.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "unav_common/config.hpp"
#include "unav_common/resources.hpp"
#include "unav_localization/klt_vo.hpp"
#include "unav_runtime/lockstep_ack.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/tf_static.hpp"
#include "unav_scene/camera.hpp"

namespace unav::localization {

struct KltVoNodeParams {
  std::string camera = "down";
  std::string cameras_config;
  std::string mode = "rgbd";
  unav::lockstep::ParticipantParams lockstep{"klt_vo"};
  double image_period = 0.1;
  std::string body_frame = "base_link_frd";
  int64_t path_max_poses = 3000;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("camera", &camera).Doc("camera name (topics camera/<camera>/...)"));
    a->Visit(Field("cameras_config", &cameras_config)
                 .Doc("camera YAML for the mount (rgbd); empty: body_frame -> <camera>_optical from /tf_static"));
    a->Visit(Field("mode", &mode).OneOf({"rgbd", "monocular"}).Doc("estimator"));
    lockstep.Serialize(a);
    a->Visit(
        Field("image_period", &image_period).Range(1e-3, 10.0).Unit("s").Doc("camera frame period (lockstep acks)"));
    a->Visit(Field("body_frame", &body_frame).Doc("vehicle body frame (tf parent of the camera)"));
    a->Visit(Field("path_max_poses", &path_max_poses)
                 .Range(1, 1e7)
                 .Doc("poses kept in the published path (the latest; odometry has every one): bounds memory "
                      "and the path message on long runs"));
  }
};

class KltVoNode : public unav::Node {
 public:
  explicit KltVoNode(const unav::NodeOptions& options) : Node("klt_vo", options, "rov") {
    KltVoNodeParams prm;
    declare_params(&prm);
    const std::string& cam = prm.camera;
    camera_ = cam;
    if (prm.mode == "monocular") options_.mode = KltVoOptions::Mode::kMonocular;
    lockstep_ = prm.lockstep.enabled;
    ack_name_ = prm.lockstep.name;
    image_period_ = prm.image_period;
    path_max_poses_ = static_cast<size_t>(prm.path_max_poses);
    if (!prm.cameras_config.empty()) {
      X_BC_ = unav::scene::load_camera(prm.cameras_config, cam).X_BC;  // ConfigError names file and camera
      have_mount_ = true;
    } else if (!monocular()) {
      // The mount's owner (the renderer) publishes it on /tf_static, latched; frames wait for it.
      tf_static_ = std::make_unique<unav::StaticTransformListener>(*this);
      tf_static_->on_update([this, body = prm.body_frame] {
        if (have_mount_) return;
        if (const auto X = tf_static_->lookup(body, camera_ + "_optical")) {
          X_BC_ = *X;
          have_mount_ = true;
          logger()->info("camera mount {} -> {}_optical from /tf_static", body, camera_);
          try_process();
        }
      });
    } else {
      have_mount_ = true;  // monocular reports the camera frame itself
    }
    // A frame consumer owes nothing until its next frame: it acks up to 1 ms before it.
    if (lockstep_) acker_ = std::make_unique<unav::lockstep::Acker>(*this, ack_name_, image_period_ - 1e-3);
    const std::string base = "camera/" + cam;
    odom_pub_ = create_publisher<nav_msgs::msg::Odometry>("localization/klt_vo/odom", unav::QoS::reliable());
    path_pub_ = create_publisher<nav_msgs::msg::Path>("localization/klt_vo/path", unav::QoS::reliable(1));
    info_sub_ = create_subscription<sensor_msgs::msg::CameraInfo>(base + "/camera_info", unav::QoS::reliable(5),
                                                                  [this](const sensor_msgs::msg::CameraInfo& m) {
                                                                    if (vo_) return;
                                                                    Eigen::Matrix3d K;
                                                                    for (int i = 0; i < 9; ++i)
                                                                      K(i / 3, i % 3) = m.k()[static_cast<size_t>(i)];
                                                                    vo_ = std::make_unique<KltVo>(K, options_);
                                                                    try_process();
                                                                  });
    rgb_sub_ = create_subscription<sensor_msgs::msg::Image>(
        base + "/image_raw", unav::QoS::reliable(20).with_data_sharing(), [this](const sensor_msgs::msg::Image& m) {
          if (m.encoding() != "rgb8") return;
          if (key(m.header()) <= done_ns_) {  // sent again (the lockstep held): processed already
            ack(m.header());
            return;
          }
          cv::Mat rgb(static_cast<int>(m.height()), static_cast<int>(m.width()), CV_8UC3,
                      const_cast<uint8_t*>(m.data().data()));
          cv::Mat gray;
          cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
          grays_[key(m.header())] = {gray, m.header()};
          try_process();
        });
    if (!monocular()) {
      depth_sub_ = create_subscription<sensor_msgs::msg::Image>(
          base + "/depth/image_raw", unav::QoS::reliable(20).with_data_sharing(),
          [this](const sensor_msgs::msg::Image& m) {
            if (m.encoding() != "32FC1" || key(m.header()) <= done_ns_) return;
            depths_[key(m.header())] = cv::Mat(static_cast<int>(m.height()), static_cast<int>(m.width()), CV_32FC1,
                                               const_cast<uint8_t*>(m.data().data()))
                                           .clone();
            try_process();
          });
    }
    path_.header().frame_id("klt_vo_odom");
  }

 private:
  static int64_t key(const std_msgs::msg::dds_::Header_& h) {
    return unav::Time::from_msg(h.stamp().sec(), h.stamp().nanosec()).ns;
  }
  bool monocular() const { return options_.mode == KltVoOptions::Mode::kMonocular; }
  // Monocular: processes the frames in time order.
  void process_monocular() {
    for (const auto& entry : grays_) {
      const GrayFrame& frame = entry.second;
      Eigen::Isometry3d T_C0C;
      const VoSummary s = vo_->ProcessFrame(frame.gray, &T_C0C);
      if (s.status != last_status_) {
        if (s.status == VoStatus::kLost)
          logger()->warn("tracking lost ({}); re-initialising", s.message);
        else if (s.status == VoStatus::kInitialized)
          logger()->info("monocular map initialised ({})", s.message);
        else if (s.status == VoStatus::kInvalidInput)
          logger()->warn("frame rejected: {}", s.message);
      }
      last_status_ = s.status;
      if (s.status == VoStatus::kInitialized || s.status == VoStatus::kTracking) publish(frame.header, T_C0C);
      ack(frame.header);
      done_ns_ = std::max(done_ns_, key(frame.header));
    }
    grays_.clear();
  }
  // Processes, in time order, every frame whose rgb and depth have both arrived.
  void try_process() {
    if (!vo_ || !have_mount_) return;
    if (monocular()) {
      process_monocular();
      return;
    }
    while (!grays_.empty()) {
      const auto it = grays_.begin();
      const auto d = depths_.find(it->first);
      if (d == depths_.end()) {
        if (depths_.empty() || depths_.rbegin()->first < it->first) return;  // its depth may still come
        ack(it->second.header);
        done_ns_ = std::max(done_ns_, it->first);
        grays_.erase(it);  // depth lost: skip the frame
        continue;
      }
      Eigen::Isometry3d T_C0C;
      const VoSummary s = vo_->ProcessFrame(it->second.gray, d->second, &T_C0C);
      if (s.status == VoStatus::kLost)
        logger()->warn("tracking lost ({}), predicting; re-initialising on new corners", s.message);
      publish(it->second.header, X_BC_ * T_C0C * X_BC_.inverse());
      ack(it->second.header);
      done_ns_ = std::max(done_ns_, it->first);
      depths_.erase(depths_.begin(), std::next(d));
      grays_.erase(it);
    }
  }
  // Lockstep: after the image at t, acks up to just under the next image (t + image_period).
  void ack(const std_msgs::msg::Header& h) {
    if (acker_) acker_->ack(h);
  }
  void publish(const std_msgs::msg::dds_::Header_& h, const Eigen::Isometry3d& T_OB) {
    nav_msgs::msg::Odometry o;
    o.header().stamp() = h.stamp();
    o.header().frame_id("klt_vo_odom");
    o.child_frame_id(monocular() ? camera_ + "_optical" : "base_link_frd");
    const Eigen::Quaterniond q(T_OB.linear());
    auto& p = o.pose().pose();
    p.position().x(T_OB.translation().x());
    p.position().y(T_OB.translation().y());
    p.position().z(T_OB.translation().z());
    p.orientation().x(q.x());
    p.orientation().y(q.y());
    p.orientation().z(q.z());
    p.orientation().w(q.w());
    odom_pub_->publish(o);
    geometry_msgs::msg::dds_::PoseStamped_ ps;
    ps.header() = o.header();
    ps.pose() = p;
    auto& poses = path_.poses();
    poses.push_back(ps);
    // Keep the latest path_max_poses_; trim in batches of a quarter so the cost stays O(1) per pose.
    if (poses.size() > path_max_poses_ + path_max_poses_ / 4)
      poses.erase(poses.begin(), poses.end() - static_cast<std::ptrdiff_t>(path_max_poses_));
    if (++frames_ % 10 == 0) {
      path_.header().stamp() = h.stamp();
      path_pub_->publish(path_);
    }
  }

  struct GrayFrame {
    cv::Mat gray;
    std_msgs::msg::dds_::Header_ header;
  };
  Eigen::Isometry3d X_BC_ = Eigen::Isometry3d::Identity();
  bool have_mount_ = false;  ///< rgbd only: X_BC_ known (monocular reports the camera frame)
  std::unique_ptr<unav::StaticTransformListener> tf_static_;
  std::string camera_, ack_name_;
  bool lockstep_ = false;
  double image_period_ = 0.1;
  std::unique_ptr<unav::lockstep::Acker> acker_;
  // The newest frame stamp processed (or skipped): a frame the renderer sends again while the
  // lockstep holds is acked, not processed twice.
  int64_t done_ns_ = INT64_MIN;
  KltVoOptions options_;
  std::unique_ptr<KltVo> vo_;
  VoStatus last_status_ = VoStatus::kInitializing;
  std::map<int64_t, GrayFrame> grays_;
  std::map<int64_t, cv::Mat> depths_;
  nav_msgs::msg::Path path_;
  size_t path_max_poses_ = 3000;
  uint64_t frames_ = 0;
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Odometry>> odom_pub_;
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Path>> path_pub_;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::CameraInfo>> info_sub_;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::Image>> rgb_sub_, depth_sub_;
};

}  // namespace unav::localization

#ifndef UNAV_KLT_VO_NO_MAIN
int main(int argc, char** argv) { return unav::run_node<unav::localization::KltVoNode>(argc, argv); }
#endif
