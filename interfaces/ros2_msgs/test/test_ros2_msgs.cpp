#include <gtest/gtest.h>

#include "interface_checks.hpp"

#include "geometry_msgs/msg/QuaternionPubSubTypes.h"
#include "nav_msgs/msg/OdometryPubSubTypes.h"
#include "nav_msgs/msg/PathPubSubTypes.h"
#include "rmw_dds_common/msg/ParticipantEntitiesInfoPubSubTypes.h"
#include "sensor_msgs/msg/CameraInfoPubSubTypes.h"
#include "sensor_msgs/msg/ImagePubSubTypes.h"
#include "sensor_msgs/msg/PointCloud2PubSubTypes.h"
#include "std_msgs/msg/HeaderPubSubTypes.h"
#include "tf2_msgs/msg/TFMessagePubSubTypes.h"

using interface_checks::deserialize;
using interface_checks::serialize;

TEST(Ros2Msgs, EveryTypeHasRos2NameAndRoundTrips) { interface_checks::check_all_types_round_trip(); }

TEST(Ros2Msgs, ExpectedTypeSetIsComplete) {
  // DESIGN.md section 2 lists the standard types we mirror; each must be generated.
  const char* required[] = {
      "builtin_interfaces::msg::dds_::Time_", "std_msgs::msg::dds_::Header_", "rosgraph_msgs::msg::dds_::Clock_",
      "geometry_msgs::msg::dds_::Vector3_", "geometry_msgs::msg::dds_::Point_", "geometry_msgs::msg::dds_::Quaternion_",
      "geometry_msgs::msg::dds_::Pose_", "geometry_msgs::msg::dds_::PoseStamped_",
      "geometry_msgs::msg::dds_::PoseWithCovariance_", "geometry_msgs::msg::dds_::Twist_",
      "geometry_msgs::msg::dds_::TwistWithCovariance_", "geometry_msgs::msg::dds_::TwistWithCovarianceStamped_",
      "geometry_msgs::msg::dds_::Wrench_", "geometry_msgs::msg::dds_::WrenchStamped_",
      "geometry_msgs::msg::dds_::Transform_", "geometry_msgs::msg::dds_::TransformStamped_",
      "nav_msgs::msg::dds_::Odometry_", "nav_msgs::msg::dds_::Path_", "sensor_msgs::msg::dds_::Image_",
      "sensor_msgs::msg::dds_::CameraInfo_", "sensor_msgs::msg::dds_::RegionOfInterest_",
      "sensor_msgs::msg::dds_::Imu_", "sensor_msgs::msg::dds_::FluidPressure_", "sensor_msgs::msg::dds_::NavSatFix_",
      "sensor_msgs::msg::dds_::NavSatStatus_", "sensor_msgs::msg::dds_::Range_",
      "sensor_msgs::msg::dds_::MagneticField_", "sensor_msgs::msg::dds_::PointCloud2_",
      "sensor_msgs::msg::dds_::PointField_", "tf2_msgs::msg::dds_::TFMessage_",
      // marine_acoustic_msgs (marine_msgs 2.x): what ROS 2 sonar drivers and viewers speak.
      "marine_acoustic_msgs::msg::dds_::PingInfo_", "marine_acoustic_msgs::msg::dds_::SonarImageData_",
      "marine_acoustic_msgs::msg::dds_::ProjectedSonarImage_", "marine_acoustic_msgs::msg::dds_::RawSonarImage_"};
  for (const char* name : required) {
    bool found = false;
    for (const auto& t : generated_types()) found = found || t.dds_name == name;
    EXPECT_TRUE(found) << name;
  }
}

TEST(Ros2Msgs, HeaderCdrBytesMatchHandComputed) {
  std_msgs::msg::dds_::Header_PubSubType type;
  std_msgs::msg::dds_::Header_ h;
  h.stamp().sec(1);
  h.stamp().nanosec(2);
  h.frame_id("ab");
  // Encapsulation CDR_LE (00 01 00 00), then int32 sec, uint32 nanosec, and the string as a
  // uint32 length that counts the terminating NUL, the characters and the NUL.
  const std::vector<uint8_t> expected = {0x00, 0x01, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x02, 0x00,
                                         0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 'a',  'b',  0x00};
  EXPECT_EQ(serialize(type, &h), expected);
}

TEST(Ros2Msgs, QuaternionDefaultsToIdentityLikeRos2) {
  geometry_msgs::msg::dds_::Quaternion_ q;
  EXPECT_EQ(q.w(), 1.0);
  EXPECT_EQ(q.x(), 0.0);
}

TEST(Ros2Msgs, ImageRoundTripKeepsPixels) {
  sensor_msgs::msg::dds_::Image_PubSubType type;
  sensor_msgs::msg::dds_::Image_ img;
  img.header().frame_id("front_optical");
  img.header().stamp().sec(12);
  img.height(480);
  img.width(640);
  img.encoding("rgb8");
  img.step(640 * 3);
  img.data().resize(std::size_t{640} * 480 * 3);
  for (size_t i = 0; i < img.data().size(); ++i) img.data()[i] = static_cast<uint8_t>(i * 31u);
  const auto bytes = serialize(type, &img);
  // 4 encapsulation + header (8 + 4 + 14 incl. NUL, padded to 28) + 2 uint32 + "rgb8" (4 + 5)
  // + uint8 + pad(3) + uint32 step + uint32 length + pixels.
  EXPECT_EQ(bytes.size(), 4u + 28u + 8u + 9u + 1u + 2u + 4u + 4u + 921600u);
  sensor_msgs::msg::dds_::Image_ back;
  deserialize(type, bytes, &back);
  EXPECT_EQ(back.data(), img.data());
  EXPECT_EQ(back.encoding(), "rgb8");
  EXPECT_EQ(back.header().frame_id(), "front_optical");
}

TEST(Ros2Msgs, NestedSequencesRoundTrip) {
  nav_msgs::msg::dds_::Path_PubSubType type;
  nav_msgs::msg::dds_::Path_ path;
  path.header().frame_id("world_ned");
  for (int i = 0; i < 5; ++i) {
    geometry_msgs::msg::dds_::PoseStamped_ p;
    p.pose().position().x(i * 1.5);
    p.pose().orientation().z(0.1 * i);
    path.poses().push_back(p);
  }
  nav_msgs::msg::dds_::Path_ back;
  deserialize(type, serialize(type, &path), &back);
  ASSERT_EQ(back.poses().size(), 5u);
  EXPECT_EQ(back.poses()[4].pose().position().x(), 6.0);
  EXPECT_EQ(back.poses()[3].pose().orientation().w(), 1.0);

  tf2_msgs::msg::dds_::TFMessage_PubSubType tf_type;
  tf2_msgs::msg::dds_::TFMessage_ tf;
  tf.transforms().resize(2);
  tf.transforms()[1].child_frame_id("base_link_frd");
  tf.transforms()[1].transform().translation().z(-3.0);
  tf2_msgs::msg::dds_::TFMessage_ tf_back;
  deserialize(tf_type, serialize(tf_type, &tf), &tf_back);
  EXPECT_EQ(tf_back.transforms()[1].child_frame_id(), "base_link_frd");
  EXPECT_EQ(tf_back.transforms()[1].transform().translation().z(), -3.0);
}

TEST(Ros2Msgs, OdometryCovarianceAndCameraInfoArraysRoundTrip) {
  nav_msgs::msg::dds_::Odometry_PubSubType type;
  nav_msgs::msg::dds_::Odometry_ odom;
  for (size_t i = 0; i < 36; ++i) odom.pose().covariance()[i] = static_cast<double>(i);
  odom.twist().twist().angular().z(0.25);
  odom.child_frame_id("base_link_frd");
  nav_msgs::msg::dds_::Odometry_ back;
  deserialize(type, serialize(type, &odom), &back);
  EXPECT_EQ(back.pose().covariance()[35], 35.0);
  EXPECT_EQ(back.twist().twist().angular().z(), 0.25);

  sensor_msgs::msg::dds_::CameraInfo_PubSubType ci_type;
  sensor_msgs::msg::dds_::CameraInfo_ ci;
  ci.distortion_model("plumb_bob");
  ci.d({-0.1, 0.01, 0.0, 0.0, 0.0});
  ci.k()[0] = 500.0;
  ci.p()[11] = 7.0;
  ci.roi().do_rectify(true);
  sensor_msgs::msg::dds_::CameraInfo_ ci_back;
  deserialize(ci_type, serialize(ci_type, &ci), &ci_back);
  EXPECT_EQ(ci_back.d().size(), 5u);
  EXPECT_EQ(ci_back.k()[0], 500.0);
  EXPECT_EQ(ci_back.p()[11], 7.0);
  EXPECT_TRUE(ci_back.roi().do_rectify());
}

TEST(Ros2Msgs, DiscoveryInfoGidIs24Bytes) {
  // ROS 2 Humble's rmw_dds_common/Gid is char[24]: a 16-byte GUID padded with zeros.
  rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_PubSubType type;
  rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_ info;
  EXPECT_EQ(serialize(type, &info).size(), 4u + 24u + 4u);
}
