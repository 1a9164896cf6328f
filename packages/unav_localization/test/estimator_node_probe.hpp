// The DDS side of the estimator node tests (klt_vo, orb_slam): publishes rendered down-camera
// frames (camera_info, rgb8 and, for RGB-D, 32FC1 depth) stamped as given, and collects what the
// node sends back: odometry positions by stamp, the latest path, and lockstep acks (the acked
// stamp by 100 ms frame index). Constructed in place (its callbacks hold `this`).
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "nav_msgs/msg/odometry.hpp"
#include "nav_msgs/msg/path.hpp"
#include "sensor_msgs/msg/camera_info.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "unav_msgs/msg/lockstep_ack.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/testing.hpp"

struct EstimatorProbe {
  /// `estimator`: the node's name (topics /rov/localization/<estimator>/odom and /path, ack
  /// participant); its odometry must come in `odom_frame` with child `child_frame`.
  EstimatorProbe(unav::Node& probe, const std::string& estimator, const std::string& odom_frame,
                 const std::string& child_frame, bool with_depth) {
    info_pub =
        probe.create_publisher<sensor_msgs::msg::CameraInfo>("/rov/camera/down/camera_info", unav::QoS::reliable(5));
    img_pub = probe.create_publisher<sensor_msgs::msg::Image>("/rov/camera/down/image_raw", unav::QoS::reliable(50));
    if (with_depth)
      depth_pub =
          probe.create_publisher<sensor_msgs::msg::Image>("/rov/camera/down/depth/image_raw", unav::QoS::reliable(50));
    odom_sub = probe.create_subscription<nav_msgs::msg::Odometry>(
        "/rov/localization/" + estimator + "/odom", unav::QoS::reliable(100),
        [this, odom_frame, child_frame](const nav_msgs::msg::Odometry& m) {
          EXPECT_EQ(m.header().frame_id(), odom_frame);
          EXPECT_EQ(m.child_frame_id(), child_frame);
          const auto& p = m.pose().pose().position();
          ++odom_msgs;
          odom[ns_of(m.header())] = Eigen::Vector3d(p.x(), p.y(), p.z());
        });
    path_sub = probe.create_subscription<nav_msgs::msg::Path>(
        "/rov/localization/" + estimator + "/path", unav::QoS::reliable(2), [this](const nav_msgs::msg::Path& m) {
          last_path = m;
          ++paths;
        });
    ack_sub = probe.create_subscription<unav_msgs::msg::LockstepAck>(
        "/lockstep/ack", unav::QoS::reliable(100), [this, estimator](const unav_msgs::msg::LockstepAck& m) {
          EXPECT_EQ(m.participant(), estimator);
          const int64_t ns = ns_of(m.header());
          acks[ns / 100000000] = ns;
          ++ack_msgs;
        });
  }

  /// Both sides of every link to and from `node`.
  std::vector<unav::testing::Link> links(const unav::Node& node) const {
    using unav::testing::make_link;
    std::vector<unav::testing::Link> l = {make_link(*info_pub, node), make_link(*img_pub, node),
                                          make_link(node, *odom_sub), make_link(node, *path_sub),
                                          make_link(node, *ack_sub)};
    if (depth_pub) l.push_back(make_link(*depth_pub, node));
    return l;
  }

  /// A frame (RGB, CV_8UC3; its depth CV_32FC1 [m] when the probe publishes depth) at time t with
  /// the pinhole K (no distortion).
  void publish(const cv::Mat& rgb, const cv::Mat& depth, const unav::Time& t, const Eigen::Matrix3d& K) {
    sensor_msgs::msg::CameraInfo info;
    info.header().stamp().sec(t.sec());
    info.header().stamp().nanosec(t.nanosec());
    info.width(static_cast<uint32_t>(rgb.cols));
    info.height(static_cast<uint32_t>(rgb.rows));
    for (int i = 0; i < 9; ++i) info.k()[static_cast<size_t>(i)] = K(i / 3, i % 3);
    info.distortion_model("plumb_bob");
    info.d({0, 0, 0, 0, 0});
    info_pub->publish(info);
    last_img = sensor_msgs::msg::Image();
    last_img.header().stamp() = info.header().stamp();
    last_img.width(static_cast<uint32_t>(rgb.cols));
    last_img.height(static_cast<uint32_t>(rgb.rows));
    last_img.encoding("rgb8");
    last_img.step(static_cast<uint32_t>(3 * rgb.cols));
    last_img.data().assign(rgb.data, rgb.data + rgb.total() * rgb.elemSize());
    img_pub->publish(last_img);
    if (depth_pub) {
      last_depth = last_img;
      last_depth.encoding("32FC1");
      last_depth.step(static_cast<uint32_t>(4 * depth.cols));
      last_depth.data().resize(depth.total() * sizeof(float));
      std::memcpy(last_depth.data().data(), depth.data, last_depth.data().size());
      depth_pub->publish(last_depth);
    }
  }
  /// The last frame again (the renderer does so while a lockstep barrier holds).
  void republish_last() {
    img_pub->publish(last_img);
    if (depth_pub) depth_pub->publish(last_depth);
  }

  static int64_t ns_of(const std_msgs::msg::dds_::Header_& h) {
    return unav::Time::from_msg(h.stamp().sec(), h.stamp().nanosec()).ns;
  }

  std::shared_ptr<unav::Publisher<sensor_msgs::msg::CameraInfo>> info_pub;
  std::shared_ptr<unav::Publisher<sensor_msgs::msg::Image>> img_pub, depth_pub;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> odom_sub;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Path>> path_sub;
  std::shared_ptr<unav::Subscription<unav_msgs::msg::LockstepAck>> ack_sub;
  sensor_msgs::msg::Image last_img, last_depth;
  std::map<int64_t, Eigen::Vector3d> odom;  ///< position by stamp [ns]
  int odom_msgs = 0;
  nav_msgs::msg::Path last_path;
  int paths = 0;
  std::map<int64_t, int64_t> acks;  ///< acked stamp by frame index
  int ack_msgs = 0;
};
