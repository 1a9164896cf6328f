// Node side (DDS): the other vehicles of a scenario as a vehicle's renderer or sonar draws them, a
// movable box each (class vehicle) in the world, moved to its ground-truth pose as it comes.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nav_msgs/msg/odometry.hpp"
#include "unav_common/config.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/validation.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_scene/world.hpp"

namespace unav::renderer {

/// Parameters of a node that draws the other vehicles (embedded: `fleet.Serialize(a)`, the keys at
/// the node's level).
struct FleetBodyParams {
  bool fleet_bodies = true;
  std::string primary_name = "rov";
  Eigen::Vector3d fleet_body_size_m{0.457, 0.575, 0.254};
  Eigen::Vector3d fleet_body_albedo{0.12, 0.12, 0.14};

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("fleet_bodies", &fleet_bodies)
                 .Doc("draw the scenario's other vehicles (its fleet, and the primary vehicle for a fleet vehicle's "
                      "node) as boxes of fleet_body_size_m at their /<name>/ground_truth/odom poses (class vehicle)"));
    a->Visit(Field("primary_name", &primary_name).Doc("namespace of the scenario's primary vehicle"));
    a->Visit(Field("fleet_body_size_m", &fleet_body_size_m)
                 .Above(0.0)
                 .Max(100.0)
                 .Unit("m")
                 .Doc("length, width, height of a drawn vehicle (BlueROV2 Heavy's frame)"));
    a->Visit(Field("fleet_body_albedo", &fleet_body_albedo).Range(0.0, 1.0).Doc("its colour (linear RGB)"));
  }
};

/// Where a sensor node (renderer, sonar) is: the scenario, or a world file with a water override,
/// the vehicle's body frame and the other vehicles drawn (embedded: `scene.Serialize(a)`, the keys
/// at the node's level).
struct SensorSceneParams {
  /// its world and water replace world and water (the node takes its sensors from it too)
  unav::scene::ScenarioParam scenario;
  std::string world;  ///< default: the installed worlds/pipe_inspection/world.yaml
  std::string water;
  std::string body_frame = "base_link_frd";
  FleetBodyParams fleet;  ///< the scenario's other vehicles, drawn

  template <class Archive>
  void Serialize(Archive* a) {
    scenario.Serialize(a);
    a->Visit(unav::common::Field("world", &world).Doc("world.yaml path"));
    a->Visit(unav::common::Field("water", &water)
                 .Doc("Jerlov preset (I, II, 3C, ...) or water YAML path (optics, temperature, salinity); empty = "
                      "the world's"));
    a->Visit(unav::common::Field("body_frame", &body_frame).Doc("vehicle body frame (tf parent of the sensors)"));
    fleet.Serialize(a);
  }
};

/// The world a sensor node draws: the scenario's (when given) or p.world with p.water; with the
/// scenario's other vehicles as movable bodies (their names in *others; the node's own is the
/// last part of node_namespace). Throws what the loaders throw (file and key named).
scene::World load_sensor_world(const SensorSceneParams& p, const std::optional<scene::Scenario>& scenario,
                               const std::string& node_namespace, std::vector<std::string>* others);

/// Adds to `world` a movable box (class vehicle) for every vehicle of `sc` but `own` (the last part
/// of the node's namespace): the fleet's, and the primary's (named p.primary_name) when there is a
/// fleet, each where the scenario starts it. Their names; none when p.fleet_bodies is off.
std::vector<std::string> add_fleet_bodies(const scene::Scenario& sc, const FleetBodyParams& p, const std::string& own,
                                          scene::World* world);

/// The other vehicles' ground truth (/<name>/ground_truth/odom): each state moves its body
/// (`move`). when_current(t, job): in lockstep a frame (ping) at t waits for every vehicle heard
/// before to have its state at t (the server publishes every vehicle's state before its barrier; a
/// vehicle not heard yet is drawn where it starts).
class FleetPoses {
 public:
  FleetPoses(unav::Node& node, const std::vector<std::string>& names,
             const std::function<void(const std::string&, const scene::Pose&)>& move,
             unav::RejectionCounter* rejections);
  /// Runs `job` now when no vehicle heard before is behind t_ns, else once the last one's state at
  /// t_ns has moved its body (a job still waiting is replaced: the same state, repeated).
  void when_current(std::int64_t t_ns, std::function<void()> job);
  std::uint64_t states() const { return states_; }

 private:
  struct Body {
    std::string name;
    std::int64_t stamp_ns = INT64_MIN;  // the latest state's (INT64_MIN: none yet)
    std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> sub;
  };
  bool behind(std::int64_t t_ns) const;
  std::vector<Body> bodies_;
  std::uint64_t states_ = 0;
  std::int64_t waiting_ns_ = 0;
  std::function<void()> waiting_;  // the job when_current() holds back
};

}  // namespace unav::renderer
