// robot_description over DDS and its URDF against the files it is made from: a subscriber that
// joins after the node published still gets /robot_description (latched); the URDF parses; every
// thruster's joint sits at its position with the link's z axis along its thrust direction; every
// camera's <cam>_optical and sonar's <sonar>_link joint is exactly the mount the renderer and the
// sonar node publish on /tf_static (CameraModel::X_BC, SonarModel::frame_acoustic(): 1e-9).
#include <gtest/gtest.h>
#include <tinyxml2.h>

#include <map>
#include <random>
#include <sstream>
#include <string>

#include "robot_description_node.hpp"
#include "unav_physics/vehicle_description.hpp"
#include "unav_runtime/testing.hpp"
#include "unav_scene/camera.hpp"
#include "unav_scene/sonar.hpp"

using namespace std::chrono_literals;

namespace {

Eigen::Matrix3d from_rpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d triple(const char* text) {
  std::istringstream in(text ? text : "");
  Eigen::Vector3d v = Eigen::Vector3d::Constant(std::nan(""));
  in >> v.x() >> v.y() >> v.z();
  return v;
}

// Joint origins by child link.
std::map<std::string, Eigen::Isometry3d> joints(const tinyxml2::XMLDocument& doc) {
  std::map<std::string, Eigen::Isometry3d> out;
  for (const auto* j = doc.FirstChildElement("robot")->FirstChildElement("joint"); j != nullptr;
       j = j->NextSiblingElement("joint")) {
    EXPECT_STREQ(j->Attribute("type"), "fixed");
    EXPECT_STREQ(j->FirstChildElement("parent")->Attribute("link"), "base_link_frd");
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    const auto* o = j->FirstChildElement("origin");
    X.translation() = triple(o->Attribute("xyz"));
    X.linear() = from_rpy(triple(o->Attribute("rpy")));
    out[j->FirstChildElement("child")->Attribute("link")] = X;
  }
  return out;
}

}  // namespace

TEST(VehicleDescription, UrdfRpyRoundTripsEveryRotation) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Matrix3d R = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
    EXPECT_LT((from_rpy(unav::physics::urdf_rpy(R)) - R).norm(), 1e-9) << i;
  }
  // Pitch +-90 deg (gimbal lock): roll and yaw are one angle, the rotation still round-trips.
  for (double pitch : {M_PI / 2, -M_PI / 2})
    for (double yaw : {0.0, 0.7, -2.0}) {
      const Eigen::Matrix3d R = from_rpy({0.3, pitch, yaw});
      EXPECT_LT((from_rpy(unav::physics::urdf_rpy(R)) - R).norm(), 1e-9) << pitch << " " << yaw;
    }
}

TEST(RobotDescriptionNode, LatchedUrdfMatchesTheVehicleAndTheMounts) {
  const std::string cfg = UNAV_CONFIG_DIR;
  const std::string v = "vehicle_config:=" + cfg + "/vehicles/bluerov2_heavy.yaml";
  const std::string c = "cameras_config:=" + cfg + "/sensors/bluerov2_cameras.yaml";
  const std::string s = "sonars_config:=" + cfg + "/sensors/bluerov2_sonars.yaml";
  const char* argv[] = {"robot_description", "--ros-args", "-p", v.c_str(), "-p", c.c_str(), "-p", s.c_str()};
  const unav::ContextOptions o = unav::testing::test_context_options();
  unav::Context node_ctx(8, argv, o);
  unav::physics::RobotDescriptionNode node({&node_ctx});  // publishes at once, before anyone listens
  const auto latched = unav::testing::late_latched<std_msgs::msg::String>(node_ctx, "/robot_description");
  ASSERT_TRUE(latched.has_value()) << "no /robot_description for a late subscriber";
  const std::string received = latched->data();
  EXPECT_EQ(received, node.urdf());

  tinyxml2::XMLDocument doc;
  ASSERT_EQ(doc.Parse(received.c_str()), tinyxml2::XML_SUCCESS) << received;
  const unav::physics::VehicleParams vehicle = unav::physics::load_vehicle(cfg + "/vehicles/bluerov2_heavy.yaml");
  EXPECT_EQ(std::string(doc.FirstChildElement("robot")->Attribute("name")), vehicle.name);
  const auto X = joints(doc);
  ASSERT_EQ(vehicle.thrusters.size(), 8u);
  for (const auto& t : vehicle.thrusters) {
    const auto it = X.find("thruster_" + t.name);
    ASSERT_NE(it, X.end()) << t.name;
    EXPECT_LT((it->second.translation() - t.position_B).norm(), 1e-9) << t.name;
    EXPECT_LT((it->second.linear().col(2) - t.direction_B.normalized()).norm(), 1e-8) << t.name;
  }
  const auto cameras = unav::scene::load_cameras(cfg + "/sensors/bluerov2_cameras.yaml");
  const auto sonars = unav::scene::load_sonars(cfg + "/sensors/bluerov2_sonars.yaml");
  ASSERT_FALSE(cameras.empty());
  ASSERT_FALSE(sonars.empty());
  auto expect_mount = [&](const std::string& child, const Eigen::Isometry3d& want) {
    const auto it = X.find(child);
    ASSERT_NE(it, X.end()) << child;
    EXPECT_LT((it->second.translation() - want.translation()).norm(), 1e-9) << child;
    EXPECT_LT((it->second.linear() - want.linear()).norm(), 1e-8) << child;
  };
  for (const auto& cam : cameras) expect_mount(cam.name + "_optical", cam.X_BC);
  for (const auto& son : sonars) expect_mount(son.name + "_link", son.frame_acoustic());
  EXPECT_EQ(X.size(), vehicle.thrusters.size() + cameras.size() + sonars.size());
}
