// robot_description: the vehicle for 3-D views, as robot_state_publisher gives it in ROS 2.
//   pub  /robot_description  std_msgs/String  latched (transient local): the URDF of the vehicle
//                             file with its thrusters, camera optical frames (<cam>_optical) and
//                             sonar frames (<sonar>_link) on base_link_frd
//                             (unav_physics/vehicle_description.hpp): the same mounts, from the same
//                             files, as the renderer's and the sonar node's /tf_static.
// params: vehicle_config, cameras_config, sonars_config ("" = none; defaults: the installed
//         BlueROV2 Heavy files), or scenario (its vehicle model, camera config and names).
#pragma once

#include <memory>
#include <string>

#include "std_msgs/msg/string.hpp"
#include "unav_common/config.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_scene/scenario.hpp"

namespace unav::physics {

struct RobotDescriptionParams {
  unav::scene::ScenarioParam scenario;  ///< replaces vehicle_config, cameras_config and the cameras
  std::string vehicle_config;
  std::string cameras_config;
  std::string sonars_config;
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    scenario.Serialize(a);
    a->Visit(Field("vehicle_config", &vehicle_config).Doc("vehicle YAML (config/vehicles/*.yaml)"));
    a->Visit(
        Field("cameras_config", &cameras_config).Doc("camera YAML whose mounts become <cam>_optical; empty = none"));
    a->Visit(Field("sonars_config", &sonars_config).Doc("sonar YAML whose mounts become <sonar>_link; empty = none"));
  }
};

class RobotDescriptionNode : public unav::Node {
 public:
  explicit RobotDescriptionNode(const unav::NodeOptions& options);
  const std::string& urdf() const { return urdf_; }

 private:
  std::string urdf_;
  std::shared_ptr<unav::Publisher<std_msgs::msg::String>> pub_;
};

}  // namespace unav::physics
