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
// The camera's mount (cameras_config) turns camera motion into body motion. Mode rgbd publishes
// every frame (a lost frame with a constant-velocity prediction); mode monocular publishes only
// frames with an estimate (initialised or tracking), in arbitrary units (the first map's median
// scene depth is 1): compare with ground truth after a Sim(3) alignment.
#include <cmath>
#include <map>

#include <opencv2/imgproc.hpp>

#include "nav_msgs/msg/odometry.hpp"
#include "nav_msgs/msg/path.hpp"
#include "sensor_msgs/msg/camera_info.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "unav_common/resources.hpp"
#include "unav_localization/klt_vo.hpp"
#include "unav_runtime/lockstep_ack.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_scene/camera.hpp"

namespace unav_localization {

class KltVoNode : public unav::Node {
 public:
  explicit KltVoNode(const unav::NodeOptions& options) : Node("klt_vo", options, "rov") {
    const std::string cam = declare_parameter<std::string>("camera", "down", {"camera name", {}, {}, false});
    camera_ = cam;
    const std::string cams_path = declare_parameter<std::string>(
        "cameras_config", unav::common::try_find_resource("config/sensors/bluerov2_cameras.yaml").value_or(""),
        {"camera YAML", {}, {}, false});
    X_BC_ = unav::scene::load_camera(cams_path, cam).X_BC;  // ConfigError names file and camera
    const std::string mode = declare_parameter<std::string>("mode", "rgbd", {"rgbd | monocular", {}, {}, false});
    if (mode == "monocular") {
      options_.mode = KltVoOptions::Mode::kMonocular;
    } else if (mode != "rgbd") {
      throw unav::ParameterError("node '" + name() + "': parameter 'mode' must be 'rgbd' or 'monocular', got '" + mode +
                                 "'");
    }
    lockstep_ =
        declare_parameter<bool>("lockstep", false, {"ack every processed image on /lockstep/ack", {}, {}, false});
    ack_name_ = declare_parameter<std::string>("lockstep_name", "klt_vo", {"participant name in acks", {}, {}, false});
    image_period_ =
        declare_parameter<double>("image_period", 0.1, {"camera frame period [s] (lockstep acks)", 1e-3, 10.0, false});
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
        base + "/image_raw", unav::QoS::reliable(20), [this](const sensor_msgs::msg::Image& m) {
          if (m.encoding() != "rgb8") return;
          cv::Mat rgb(static_cast<int>(m.height()), static_cast<int>(m.width()), CV_8UC3,
                      const_cast<uint8_t*>(m.data().data()));
          cv::Mat gray;
          cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
          grays_[key(m.header())] = {gray, m.header()};
          try_process();
        });
    if (!monocular()) {
      depth_sub_ = create_subscription<sensor_msgs::msg::Image>(
          base + "/depth/image_raw", unav::QoS::reliable(20), [this](const sensor_msgs::msg::Image& m) {
            if (m.encoding() != "32FC1") return;
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
    }
    grays_.clear();
  }
  // Processes, in time order, every frame whose rgb and depth have both arrived.
  void try_process() {
    if (!vo_) return;
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
        grays_.erase(it);  // depth lost: skip the frame
        continue;
      }
      Eigen::Isometry3d T_C0C;
      const VoSummary s = vo_->ProcessFrame(it->second.gray, d->second, &T_C0C);
      if (s.status == VoStatus::kLost)
        logger()->warn("tracking lost ({}), predicting; re-initialising on new corners", s.message);
      publish(it->second.header, X_BC_ * T_C0C * X_BC_.inverse());
      ack(it->second.header);
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
    path_.poses().push_back(ps);
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
  std::string camera_, ack_name_;
  bool lockstep_ = false;
  double image_period_ = 0.1;
  std::unique_ptr<unav::lockstep::Acker> acker_;
  KltVoOptions options_;
  std::unique_ptr<KltVo> vo_;
  VoStatus last_status_ = VoStatus::kInitializing;
  std::map<int64_t, GrayFrame> grays_;
  std::map<int64_t, cv::Mat> depths_;
  nav_msgs::msg::Path path_;
  uint64_t frames_ = 0;
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Odometry>> odom_pub_;
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Path>> path_pub_;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::CameraInfo>> info_sub_;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::Image>> rgb_sub_, depth_sub_;
};

}  // namespace unav_localization

int main(int argc, char** argv) { return unav::run_node<unav_localization::KltVoNode>(argc, argv); }
