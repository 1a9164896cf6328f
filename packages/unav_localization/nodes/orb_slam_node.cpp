// orb_slam: the monocular ORB SLAM (unav::localization::MonoSlam) as a node.
//
// Ports (relative to the node namespace, default /rov):
//   sub  camera/<camera>/image_raw     sensor_msgs/Image (rgb8, bgr8 or mono8)
//   sub  camera/<camera>/camera_info   sensor_msgs/CameraInfo (K and plumb_bob D are used)
//   pub  localization/orb_slam/odom    nav_msgs/Odometry: the camera optical frame `<camera>_optical`
//                                      in frame `orb_slam_map` (the first keyframe's camera frame;
//                                      monocular scale: arbitrary), stamped with the image time;
//                                      tracked frames only. Without metric scale the camera's lever
//                                      arm on the body cannot be applied, so the camera is reported
//                                      (evaluate against ground truth moved to the camera frame)
//   pub  localization/orb_slam/path    nav_msgs/Path: the latest path_max_poses tracked frames (camera
//                                      poses; 0: every one), as corrected by bundle adjustment and loop
//                                      closing; after each keyframe (bounded: an hour at 10 Hz would be
//                                      36000 poses, 2.3 MB a message; the evaluator keeps the history)
//   sub  imu                           sensor_msgs/Imu (imu: true): angular rate and specific force in
//                                      body_frame; with the camera's mount (body_frame -> <camera>_optical
//                                      on /tf_static) they scale each map to metres (monocular-inertial
//                                      mode): the odometry and path are then metric
//   sub  dvl                           unav_msgs/Dvl (dvl: true): the DVL's bottom velocity in body_frame
//                                      (its frame_id); with the camera's mount it scales each map to
//                                      metres and holds the scale through the bundle adjustments
//                                      (DVL-aided mode; replaces the IMU's scaling when both are on, the
//                                      gyroscope's rotations between keyframes still constrain the map)
//                                      With imu or dvl on, odometry is published once the output is
//                                      metric (the first scaling, ~2 s of keyframes); the path
//                                      covers every tracked frame (the history is rescaled)
//   pub  /lockstep/ack                 unav_msgs/LockstepAck (lockstep: true): after processing the
//                                      image at t, acks up to t + image_period (just under the next
//                                      image), so a lockstep simulation waits for the SLAM
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <optional>

#include <opencv2/imgproc.hpp>

#include "nav_msgs/msg/odometry.hpp"
#include "nav_msgs/msg/path.hpp"
#include "sensor_msgs/msg/camera_info.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "sensor_msgs/msg/imu.hpp"
#include "unav_common/config.hpp"
#include "unav_common/resources.hpp"
#include "unav_localization/mono_slam.hpp"
#include "unav_msgs/msg/dvl.hpp"
#include "unav_runtime/lockstep_ack.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/tf_static.hpp"

namespace unav::localization {

struct OrbSlamNodeParams {
  std::string camera = "down";
  std::string vocabulary;  ///< default: the installed config/vocabulary/orb_vocabulary.bin
  int features = 1000;
  bool loop_closing = true;
  bool merge_maps = true;
  bool inertial_ba = true;
  double clahe_clip = 3.0;
  unav::lockstep::ParticipantParams lockstep{"orb_slam"};
  double image_period = 0.1;
  std::string frame_id = "orb_slam_map";
  int64_t path_max_poses = 3000;
  bool imu = false;
  bool dvl = false;
  bool dvl_factors = true;
  std::string body_frame = "base_link_frd";
  // Our vehicle's IMU (config/vehicles/bluerov2_heavy.yaml): 0.002 rad/s and 0.02 m/s^2 per
  // sample at 200 Hz, i.e. these densities.
  double imu_gyro_noise_density = 1.414e-4;
  double imu_accel_noise_density = 1.414e-3;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("camera", &camera).Doc("camera name (topics camera/<camera>/...; intrinsics from camera_info)"));
    a->Visit(Field("vocabulary", &vocabulary)
                 .Doc("bag-of-words vocabulary (unav_train_vocabulary); empty: no loop closing or relocalisation"));
    a->Visit(Field("features", &features).Range(100, 10000).Doc("ORB features per 640x480 of image"));
    a->Visit(Field("loop_closing", &loop_closing).Doc("detect and close loops"));
    a->Visit(Field("merge_maps", &merge_maps)
                 .Doc("keep maps lost for good and merge them when their place is seen again (atlas)"));
    a->Visit(Field("clahe_clip", &clahe_clip)
                 .Range(0.0, 40.0)
                 .Doc("CLAHE clip limit before feature extraction (low-contrast frames only), 0 = off"));
    lockstep.Serialize(a);
    a->Visit(
        Field("image_period", &image_period).Range(1e-3, 10.0).Unit("s").Doc("camera frame period (lockstep acks)"));
    a->Visit(Field("frame_id", &frame_id).Doc("odometry frame"));
    a->Visit(Field("path_max_poses", &path_max_poses)
                 .Min(0.0)
                 .Doc("poses in each published path, the latest (corrected); 0 = the whole trajectory"));
    a->Visit(Field("imu", &imu).Doc("monocular-inertial mode: the imu topic scales each map to metres"));
    a->Visit(Field("dvl", &dvl).Doc("DVL-aided mode: the dvl topic scales each map to metres and holds its scale"));
    a->Visit(Field("dvl_factors", &dvl_factors)
                 .Doc("DVL-aided: the DVL's displacements between keyframes constrain the bundle adjustments"));
    a->Visit(Field("body_frame", &body_frame)
                 .Doc("the IMU's and the DVL's frame, parent of the camera mount on /tf_static"));
    a->Visit(Field("inertial_ba", &inertial_ba)
                 .Doc("with imu: visual-inertial bundle adjustment once a map is scaled (velocities, biases)"));
    a->Visit(Field("imu_gyro_noise_density", &imu_gyro_noise_density)
                 .Range(1e-7, 1.0)
                 .Unit("rad/s/sqrt(Hz)")
                 .Doc("gyro white noise (weights the IMU against the map)"));
    a->Visit(Field("imu_accel_noise_density", &imu_accel_noise_density)
                 .Range(1e-6, 10.0)
                 .Unit("m/s^2/sqrt(Hz)")
                 .Doc("accelerometer white noise"));
  }
};

class OrbSlamNode : public unav::Node {
 public:
  explicit OrbSlamNode(const unav::NodeOptions& options) : Node("orb_slam", options, "rov") {
    OrbSlamNodeParams prm;
    prm.vocabulary = unav::common::resource_or_empty("config/vocabulary/orb_vocabulary.bin");
    declare_params(&prm);
    const std::string& cam = prm.camera;
    camera_ = cam;
    const std::string& voc_path = prm.vocabulary;
    options_.orb.features = prm.features;
    options_.loop_closing = prm.loop_closing;
    options_.merge_maps = prm.merge_maps;
    options_.inertial_ba = prm.inertial_ba;
    options_.clahe_clip = prm.clahe_clip;
    options_.dvl_factors = prm.dvl_factors;
    path_max_poses_ = static_cast<std::size_t>(prm.path_max_poses);
    lockstep_ = prm.lockstep.enabled;
    ack_name_ = prm.lockstep.name;
    image_period_ = prm.image_period;
    frame_id_ = prm.frame_id;
    std::string msg;
    if (!options_.IsValid(&msg)) throw unav::ParameterError("node '" + name() + "': " + msg);
    if (!voc_path.empty()) {
      try {
        vocabulary_ = std::make_shared<BowVocabulary>(BowVocabulary::Load(voc_path));
        logger()->info("vocabulary {}: {} words", voc_path, vocabulary_->size());
      } catch (const std::exception& e) {
        throw unav::ConfigError(std::string("parameter 'vocabulary': ") + e.what());
      }
    } else {
      logger()->warn("no vocabulary: loop closing and relocalisation are off");
    }
    want_imu_ = prm.imu;
    want_dvl_ = prm.dvl;
    // The sensors' writers are best effort (sensor_data); the reader keeps every sample of a
    // lockstep burst (the physics steps 0.1 s at once: 20 IMU samples) while an image is tracked.
    unav::QoS burst = unav::QoS::sensor_data();
    burst.depth = 1000;
    if (prm.imu) {
      imu_noise_.gyro_noise_density = prm.imu_gyro_noise_density;
      imu_noise_.accel_noise_density = prm.imu_accel_noise_density;
      imu_sub_ = create_subscription<sensor_msgs::msg::Imu>("imu", burst,
                                                            [this](const sensor_msgs::msg::Imu& m) { on_imu(m); });
    }
    if (prm.dvl)
      dvl_sub_ =
          create_subscription<unav_msgs::msg::Dvl>("dvl", burst, [this](const unav_msgs::msg::Dvl& m) { on_dvl(m); });
    if (prm.imu || prm.dvl) {
      // The mount's owner (the renderer) publishes it latched; the modes start when it is known.
      tf_static_ = std::make_unique<unav::StaticTransformListener>(*this);
      tf_static_->on_update([this, body = prm.body_frame] {
        if (X_BC_) return;
        if (const auto X = tf_static_->lookup(body, camera_ + "_optical")) {
          X_BC_ = *X;
          logger()->info("camera mount {} -> {}_optical from /tf_static", body, camera_);
          enable_sensors();
          flush_pending();
        }
      });
    }
    const std::string base = "camera/" + cam;
    odom_pub_ = create_publisher<nav_msgs::msg::Odometry>("localization/orb_slam/odom", unav::QoS::reliable());
    path_pub_ = create_publisher<nav_msgs::msg::Path>("localization/orb_slam/path", unav::QoS::reliable(1));
    // A frame consumer owes nothing until its next frame: it acks up to 1 ms before it.
    if (lockstep_) acker_ = std::make_unique<unav::lockstep::Acker>(*this, ack_name_, image_period_ - 1e-3);
    info_sub_ = create_subscription<sensor_msgs::msg::CameraInfo>(
        base + "/camera_info", unav::QoS::reliable(5), [this](const sensor_msgs::msg::CameraInfo& m) { on_info(m); });
    image_sub_ =
        create_subscription<sensor_msgs::msg::Image>(base + "/image_raw", unav::QoS::reliable(50).with_data_sharing(),
                                                     [this](const sensor_msgs::msg::Image& m) { on_image(m); });
  }

  ~OrbSlamNode() override {
    if (slam_) {
      const auto st = slam_->stats();
      logger()->info(
          "{} frames ({} tracked, {} lost), {} keyframes, {} points, {} loops, {} relocalisations, {} "
          "re-initialisations, {} maps merged",
          st.frames, st.tracked_frames, st.lost_frames, st.keyframes, st.points, st.loops, st.relocalizations,
          st.reinitializations, st.merges);
      if (dvl_on_)
        logger()->info(
            "DVL-aided: {} map(s) scaled to metres, {} refinement(s), {} scaling(s) refused, {} displacement factors, "
            "{} DVL readings rejected",
            st.dvl_inits, st.dvl_refinements, st.dvl_rejections, st.dvl_factors, st.dvl_samples_rejected);
      if (inertial_on_)
        logger()->info(
            "inertial: {} map(s) scaled to metres by the IMU, {} refinement(s), {} initialisation(s) refused, {} "
            "gyroscope rotation factors, {} inertial factors, {} frames tracked from the IMU's prediction ({} "
            "predictions missed), {} IMU samples rejected",
            st.inertial_inits, st.inertial_refinements, st.inertial_rejections, st.gyro_factors, st.inertial_factors,
            st.imu_predicted_frames, st.motion_model_misses, st.imu_samples_rejected);
    }
  }

 private:
  void on_info(const sensor_msgs::msg::CameraInfo& m) {
    if (slam_) return;
    PinholeCamera c;
    c.fx = m.k()[0];
    c.cx = m.k()[2];
    c.fy = m.k()[4];
    c.cy = m.k()[5];
    c.width = static_cast<int>(m.width());
    c.height = static_cast<int>(m.height());
    try {
      slam_ = std::make_unique<MonoSlam>(c, m.d(), options_, vocabulary_);
    } catch (const std::exception& e) {
      logger()->error("camera_info rejected: {}", e.what());
      return;
    }
    enable_sensors();
    flush_pending();
  }

  // The camera, and the mount when the IMU or the DVL is wanted: images wait until both are known
  // (a lockstep simulation waits for their acks), so every run feeds the same samples from the
  // same first image on.
  bool ready() const { return slam_ && (!(want_imu_ || want_dvl_) || X_BC_); }
  void flush_pending() {
    if (!ready()) return;
    while (!pending_.empty()) {
      process(pending_.front());
      pending_.pop_front();
    }
  }

  void enable_sensors() {
    if (!slam_ || !X_BC_) return;
    if (want_imu_ && !inertial_on_) {
      slam_->EnableInertial(*X_BC_, imu_noise_);
      inertial_on_ = true;
      for (const auto& m : imu_waiting_) on_imu(m);
      imu_waiting_.clear();
    }
    if (want_dvl_ && !dvl_on_) {
      slam_->EnableDvl(*X_BC_);  // the DVL reports in body_frame
      dvl_on_ = true;
      for (const auto& m : dvl_waiting_) on_dvl(m);
      dvl_waiting_.clear();
    }
  }

  void on_dvl(const unav_msgs::msg::Dvl& m) {
    if (!dvl_on_) {  // before the camera and its mount are known: kept (the last minute at most)
      dvl_waiting_.push_back(m);
      if (dvl_waiting_.size() > 600) dvl_waiting_.pop_front();
      return;
    }
    slam_->AddDvl(unav::Time::from_msg(m.header().stamp().sec(), m.header().stamp().nanosec()).seconds(),
                  Eigen::Vector3d(m.velocity().x(), m.velocity().y(), m.velocity().z()), m.valid());
  }

  void on_imu(const sensor_msgs::msg::Imu& m) {
    if (!inertial_on_) {  // before the camera and its mount are known: kept (the last minute at most)
      imu_waiting_.push_back(m);
      if (imu_waiting_.size() > 12000) imu_waiting_.pop_front();
      return;
    }
    const double t = unav::Time::from_msg(m.header().stamp().sec(), m.header().stamp().nanosec()).seconds();
    slam_->AddImu(
        t, Eigen::Vector3d(m.angular_velocity().x(), m.angular_velocity().y(), m.angular_velocity().z()),
        Eigen::Vector3d(m.linear_acceleration().x(), m.linear_acceleration().y(), m.linear_acceleration().z()));
  }

  void on_image(const sensor_msgs::msg::Image& m) {
    // A frame the renderer sends again while the lockstep holds: acked, not tracked twice.
    const int64_t t_ns = unav::nanoseconds(m.header());
    if (t_ns <= received_ns_) {
      ack(m.header());
      return;
    }
    received_ns_ = t_ns;
    if (!ready()) {
      if (slam_ && !mount_wait_said_) {  // the camera is known: only the mount is missing
        logger()->warn("imu/dvl mode: images wait for the camera mount {}_optical on /tf_static (is the renderer up?)",
                       camera_);
        mount_wait_said_ = true;
      }
      pending_.push_back(m);
      if (pending_.size() > 100) pending_.pop_front();
      return;
    }
    process(m);
  }

  void process(const sensor_msgs::msg::Image& m) {
    const int h = static_cast<int>(m.height()), w = static_cast<int>(m.width());
    cv::Mat gray;
    auto* data = const_cast<uint8_t*>(m.data().data());
    if (m.encoding() == "rgb8" && m.data().size() >= static_cast<size_t>(w) * static_cast<size_t>(h) * 3) {
      cv::cvtColor(cv::Mat(h, w, CV_8UC3, data, m.step()), gray, cv::COLOR_RGB2GRAY);
    } else if (m.encoding() == "bgr8" && m.data().size() >= static_cast<size_t>(w) * static_cast<size_t>(h) * 3) {
      cv::cvtColor(cv::Mat(h, w, CV_8UC3, data, m.step()), gray, cv::COLOR_BGR2GRAY);
    } else if (m.encoding() == "mono8" && m.data().size() >= static_cast<size_t>(w) * static_cast<size_t>(h)) {
      gray = cv::Mat(h, w, CV_8UC1, data, m.step()).clone();
    } else {
      logger()->warn("image encoding '{}' ({}x{}, {} bytes) is not rgb8/bgr8/mono8: skipped", m.encoding(), w, h,
                     m.data().size());
      ack(m.header());
      return;
    }
    const double t = unav::Time::from_msg(m.header().stamp().sec(), m.header().stamp().nanosec()).seconds();
    const SlamFrameSummary s = slam_->Track(gray, t);
    if (s.state == SlamState::kLost || s.state == SlamState::kInvalidInput) {
      if (!was_lost_) logger()->warn("{} at t = {:.3f}: {}", to_string(s.state), t, s.message);
      was_lost_ = true;
    } else if (s.state == SlamState::kTracking || s.state == SlamState::kRelocalized) {
      if (was_lost_) logger()->info("{} again at t = {:.3f}", to_string(s.state), t);
      was_lost_ = false;
      // With the IMU or the DVL on, only metric poses: the first seconds' poses are in the first
      // map's arbitrary units, a jump of ~1.5x at the scaling for anyone who navigates on them.
      if (!(dvl_on_ || inertial_on_) || slam_->metric()) publish_odometry(m.header(), s.T_wc);
    }
    if (s.reinitialized) logger()->warn("re-initialising: a new map will continue from the last good pose");
    if (s.loop_closed)
      logger()->info("loop closed at t = {:.3f} ({} loops): {}", t, slam_->stats().loops, s.message);
    else if (s.keyframe && !s.message.empty())
      logger()->info("t = {:.3f}: {}", t, s.message);
    if (s.keyframe || s.loop_closed) publish_path(m.header());
    ack(m.header());
  }

  void fill_pose(const Eigen::Isometry3d& X, geometry_msgs::msg::dds_::Pose_* p) const {
    const Eigen::Quaterniond q(X.linear());
    p->position().x(X.translation().x());
    p->position().y(X.translation().y());
    p->position().z(X.translation().z());
    p->orientation().x(q.x());
    p->orientation().y(q.y());
    p->orientation().z(q.z());
    p->orientation().w(q.w());
  }

  void publish_odometry(const std_msgs::msg::dds_::Header_& h, const Eigen::Isometry3d& T_wc) {
    nav_msgs::msg::Odometry o;
    o.header().stamp() = h.stamp();
    o.header().frame_id(frame_id_);
    o.child_frame_id(camera_ + "_optical");
    fill_pose(T_wc, &o.pose().pose());
    odom_pub_->publish(o);
  }

  void publish_path(const std_msgs::msg::dds_::Header_& h) {
    nav_msgs::msg::Path path;
    path.header().stamp() = h.stamp();
    path.header().frame_id(frame_id_);
    for (const auto& p : slam_->Trajectory(path_max_poses_)) {
      geometry_msgs::msg::dds_::PoseStamped_ ps;
      const unav::Time t = unav::Time{static_cast<int64_t>(std::llround((p.stamp) * 1e9))};
      ps.header().stamp().sec(t.sec());
      ps.header().stamp().nanosec(t.nanosec());
      ps.header().frame_id(frame_id_);
      fill_pose(p.T_wc, &ps.pose());
      path.poses().push_back(ps);
    }
    path_pub_->publish(path);
  }

  void ack(const std_msgs::msg::Header& h) {
    if (acker_) acker_->ack(h);
  }

  MonoSlamOptions options_;
  std::shared_ptr<const BowVocabulary> vocabulary_;
  std::unique_ptr<MonoSlam> slam_;
  std::deque<sensor_msgs::msg::Image> pending_;
  std::deque<sensor_msgs::msg::Imu> imu_waiting_;
  std::deque<unav_msgs::msg::Dvl> dvl_waiting_;
  bool mount_wait_said_ = false;
  bool lockstep_ = false, was_lost_ = false;
  std::string ack_name_, frame_id_, camera_;
  double image_period_ = 0.1;
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Odometry>> odom_pub_;
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Path>> path_pub_;
  std::unique_ptr<unav::lockstep::Acker> acker_;
  int64_t received_ns_ = INT64_MIN;  ///< the newest image stamp received
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::CameraInfo>> info_sub_;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::Image>> image_sub_;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::Imu>> imu_sub_;
  std::shared_ptr<unav::Subscription<unav_msgs::msg::Dvl>> dvl_sub_;
  std::unique_ptr<unav::StaticTransformListener> tf_static_;
  std::optional<Eigen::Isometry3d> X_BC_;
  ImuNoise imu_noise_;
  bool inertial_on_ = false;
  bool want_imu_ = false, want_dvl_ = false, dvl_on_ = false;
  std::size_t path_max_poses_ = 3000;
};

}  // namespace unav::localization

#ifndef UNAV_ORB_SLAM_NO_MAIN
int main(int argc, char** argv) { return unav::run_node<unav::localization::OrbSlamNode>(argc, argv); }
#endif
