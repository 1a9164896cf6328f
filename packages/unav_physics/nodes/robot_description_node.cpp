#include "robot_description_node.hpp"

#include <Eigen/Geometry>

#include "unav_common/resources.hpp"
#include "unav_physics/vehicle_description.hpp"
#include "unav_scene/camera.hpp"
#include "unav_scene/sonar.hpp"

namespace unav::physics {

RobotDescriptionNode::RobotDescriptionNode(const unav::NodeOptions& options)
    : Node("robot_description", options, "rov") {
  RobotDescriptionParams p;
  p.vehicle_config = unav::common::resource_or_empty("config/vehicles/bluerov2_heavy.yaml");
  p.cameras_config = unav::common::resource_or_empty("config/sensors/bluerov2_cameras.yaml");
  p.sonars_config = unav::common::resource_or_empty("config/sensors/bluerov2_sonars.yaml");
  declare_params(&p);
  std::vector<unav::scene::CameraModel> cameras;
  if (p.scenario.given()) {  // the scenario's vehicle and cameras, as the physics server and renderer take them
    const unav::scene::Scenario sc = p.scenario.load();
    p.vehicle_config = sc.vehicle.model;
    cameras = unav::scene::scenario_cameras(sc);
  } else if (!p.cameras_config.empty()) {
    cameras = unav::scene::load_cameras(p.cameras_config);
  }
  if (p.vehicle_config.empty())
    throw unav::ParameterError("node '" + name() + "': 'vehicle_config' is required (unav_resources is not installed)");
  std::vector<MountedFrame> mounts;
  mounts.reserve(cameras.size() + 4);
  for (const auto& c : cameras) mounts.push_back({c.name + "_optical", c.X_BC});
  if (!p.sonars_config.empty())
    for (const auto& s : unav::scene::load_sonars(p.sonars_config))
      mounts.push_back({s.name + "_link", s.frame_acoustic()});
  const VehicleParams vehicle = load_vehicle(p.vehicle_config);
  urdf_ = vehicle_urdf(vehicle, mounts);
  pub_ = create_publisher<std_msgs::msg::String>("/robot_description", unav::QoS::static_latched());
  std_msgs::msg::String msg;
  msg.data(urdf_);
  pub_->publish(msg);
  logger()->info("/robot_description: {} ({} thrusters, {} mounted frames)", vehicle.name, vehicle.thrusters.size(),
                 mounts.size());
}

}  // namespace unav::physics
