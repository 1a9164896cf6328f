#include "fleet_bodies_node.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "unav_runtime/conversions.hpp"

namespace unav::renderer {

scene::World load_sensor_world(const SensorSceneParams& p, const std::optional<scene::Scenario>& scenario,
                               const std::string& node_namespace, std::vector<std::string>* others) {
  if (!scenario) {
    scene::World world = scene::load_world(p.world);
    if (!p.water.empty()) world.water = scene::load_water_spec(p.water);
    return world;
  }
  scene::World world = scene::scenario_world(*scenario);
  *others = add_fleet_bodies(*scenario, p.fleet, node_namespace.substr(node_namespace.rfind('/') + 1), &world);
  return world;
}

std::vector<std::string> add_fleet_bodies(const scene::Scenario& sc, const FleetBodyParams& p, const std::string& own,
                                          scene::World* world) {
  std::vector<std::string> names;
  if (!p.fleet_bodies || sc.fleet.empty()) return names;
  auto add = [&](const std::string& name, const scene::ScenarioVehicle& v) {
    if (name == own) return;
    scene::Object body;
    body.name = name;
    body.shape = "box";
    body.size_m = p.fleet_body_size_m;
    body.X_WO = scene::pose_from_xyz_rpy(v.initial_position, v.initial_rpy_deg * M_PI / 180.0);
    body.seg_class = scene::SegClass::kVehicle;
    body.material.albedo = p.fleet_body_albedo;
    body.movable = true;
    world->objects.push_back(body);
    names.push_back(name);
  };
  add(p.primary_name, sc.vehicle);
  for (const auto& f : sc.fleet) add(f.name, f.vehicle);
  return names;
}

FleetPoses::FleetPoses(unav::Node& node, const std::vector<std::string>& names,
                       const std::function<void(const std::string&, const scene::Pose&)>& move,
                       unav::RejectionCounter* rejections) {
  bodies_.reserve(names.size());  // the callbacks hold their element's index
  for (std::size_t i = 0; i < names.size(); ++i) {
    bodies_.push_back({names[i], INT64_MIN, nullptr});
    bodies_.back().sub = node.create_subscription<nav_msgs::msg::Odometry>(
        "/" + names[i] + "/ground_truth/odom", unav::QoS::reliable(),
        [this, i, move, rejections](const nav_msgs::msg::Odometry& odom) {
          Body& b = bodies_[i];
          if (const std::string why = unav::odometry_problem(odom); !why.empty()) {
            rejections->reject(b.sub->topic_name(), why);
            return;
          }
          move(b.name, unav::from_msg(odom.pose().pose()));
          b.stamp_ns = std::max(b.stamp_ns, unav::nanoseconds(odom.header()));
          ++states_;
          if (waiting_ && !behind(waiting_ns_)) std::exchange(waiting_, nullptr)();
        });
  }
}

void FleetPoses::when_current(std::int64_t t_ns, std::function<void()> job) {
  if (!behind(t_ns)) {
    waiting_ = nullptr;
    job();
    return;
  }
  waiting_ns_ = t_ns;
  waiting_ = std::move(job);
}

bool FleetPoses::behind(std::int64_t t_ns) const {
  return std::any_of(bodies_.begin(), bodies_.end(),
                     [&](const Body& b) { return b.stamp_ns != INT64_MIN && b.stamp_ns < t_ns; });
}

}  // namespace unav::renderer
