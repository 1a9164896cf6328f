// dataset_recorder: writes one camera's rgb/depth/segmentation frames with ground-truth poses and
// IMU in the TUM RGB-D layout (see unav_datagen/dataset_writer.hpp). Every line is flushed as it
// is written, so Ctrl-C loses nothing.
//
// Ports (relative to the node namespace, default /rov):
//   sub  camera/<camera>/image_raw, depth/image_raw, segmentation/image_raw   sensor_msgs/Image
//   sub  camera/<camera>/camera_info   sensor_msgs/CameraInfo
//   sub  ground_truth/odom             nav_msgs/Odometry
//   sub  imu                           sensor_msgs/Imu (sensor_data)
//   pub  /lockstep/ack                 unav_msgs/LockstepAck (lockstep: true; acks every odometry,
//                                      so the physics never outruns the recorder's ground truth)
#include <cmath>
#include <deque>

#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/camera_info.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "sensor_msgs/msg/imu.hpp"
#include "unav_common/resources.hpp"
#include "unav_datagen/dataset_writer.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_runtime/lockstep_ack.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_scene/camera.hpp"

namespace unav_datagen {
namespace {

double stamp_of(const std_msgs::msg::dds_::Header_& h) {
  return unav::Time::from_msg(h.stamp().sec(), h.stamp().nanosec()).seconds();
}

}  // namespace

class DatasetRecorder : public unav::Node {
 public:
  explicit DatasetRecorder(const unav::NodeOptions& options) : Node("dataset_recorder", options, "rov") {
    const std::string out =
        declare_parameter<std::string>("output_dir", "out/dataset", {"dataset folder", {}, {}, false});
    camera_ = declare_parameter<std::string>("camera", "front", {"camera name to record", {}, {}, false});
    const std::string cams_path = declare_parameter<std::string>(
        "cameras_config", unav::common::try_find_resource("config/sensors/bluerov2_cameras.yaml").value_or(""),
        {"camera YAML (for the camera's mount on the body)", {}, {}, false});
    X_BC_ = unav::scene::load_camera(cams_path, camera_).X_BC;  // ConfigError names file and camera
    try {
      writer_ = std::make_unique<DatasetWriter>(out);
    } catch (const DatasetError& e) {
      throw unav::ConfigError(e.what());
    }
    const bool lockstep =
        declare_parameter<bool>("lockstep", false, {"ack every odometry on /lockstep/ack", {}, {}, false});
    ack_name_ =
        declare_parameter<std::string>("lockstep_name", "recorder", {"participant name in acks", {}, {}, false});
    if (lockstep) acker_ = std::make_unique<unav::lockstep::Acker>(*this, ack_name_);  // answers every state
    const std::string base = "camera/" + camera_;
    const unav::QoS q = unav::QoS::reliable(5);
    rgb_sub_ =
        create_subscription<sensor_msgs::msg::Image>(base + "/image_raw", q, [this](const sensor_msgs::msg::Image& m) {
          if (!check(m, "rgb8", 3)) return;
          const double t = stamp_of(m.header());
          writer_->write_rgb(t, static_cast<int>(m.width()), static_cast<int>(m.height()), m.data().data());
          write_pose_at(t);
        });
    depth_sub_ = create_subscription<sensor_msgs::msg::Image>(
        base + "/depth/image_raw", q, [this](const sensor_msgs::msg::Image& m) {
          if (!check(m, "32FC1", 4)) return;
          writer_->write_depth(stamp_of(m.header()), static_cast<int>(m.width()), static_cast<int>(m.height()),
                               reinterpret_cast<const float*>(m.data().data()));
        });
    seg_sub_ = create_subscription<sensor_msgs::msg::Image>(
        base + "/segmentation/image_raw", q, [this](const sensor_msgs::msg::Image& m) {
          if (!check(m, "mono8", 1)) return;
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
                                                                    camera_written_ = true;
                                                                  });
    odom_sub_ = create_subscription<nav_msgs::msg::Odometry>(
        "ground_truth/odom", unav::QoS::reliable(100), [this](const nav_msgs::msg::Odometry& m) {
          on_pose(stamp_of(m.header()), unav::from_msg(m.pose().pose()));
          if (acker_) acker_->ack(m.header());
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
    logger()->info("recording camera '{}' to {}", camera_, out);
  }
  ~DatasetRecorder() override {
    writer_->close();
    logger()->info("dataset closed: {} frames in {}", writer_->frames(), writer_->root());
  }

 private:
  bool check(const sensor_msgs::msg::Image& m, const char* encoding, size_t bpp) {
    if (m.encoding() == encoding && m.data().size() == static_cast<size_t>(m.width()) * m.height() * bpp) return true;
    logger()->warn("skipping an image with encoding '{}' and {} bytes (expected {} {}x{})", m.encoding(),
                   m.data().size(), encoding, m.width(), m.height());
    return false;
  }
  // Ground truth at the image's stamp. The renderer renders at odometry stamps, so the pose with
  // exactly that stamp exists; it may arrive after the image (different writers), in which case
  // the image waits for it.
  void write_pose_at(double t) {
    for (auto it = poses_.rbegin(); it != poses_.rend(); ++it) {
      if (std::abs(it->first - t) < 1e-9) {
        writer_->write_pose(t, it->second * X_BC_, it->second);
        return;
      }
      if (it->first < t) break;
    }
    waiting_.push_back(t);
  }
  void on_pose(double t, const Eigen::Isometry3d& X) {
    poses_.emplace_back(t, X);
    if (poses_.size() > 2000) poses_.pop_front();
    for (auto it = waiting_.begin(); it != waiting_.end();) {
      if (std::abs(*it - t) < 1e-9) {
        writer_->write_pose(t, X * X_BC_, X);
        it = waiting_.erase(it);
      } else {
        ++it;
      }
    }
  }

  std::string camera_;
  Eigen::Isometry3d X_BC_ = Eigen::Isometry3d::Identity();
  std::unique_ptr<DatasetWriter> writer_;
  bool camera_written_ = false;
  std::deque<std::pair<double, Eigen::Isometry3d>> poses_;
  std::vector<double> waiting_;  ///< image stamps whose pose has not arrived yet
  std::string ack_name_;
  std::unique_ptr<unav::lockstep::Acker> acker_;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::Image>> rgb_sub_, depth_sub_, seg_sub_;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::CameraInfo>> info_sub_;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::Imu>> imu_sub_;
};

}  // namespace unav_datagen

int main(int argc, char** argv) { return unav::run_node<unav_datagen::DatasetRecorder>(argc, argv); }
