// One run = one scenario (DESIGN.md section 9): the world, the vehicle and its initial state, the
// physics step, the controller, the cameras, the renderer's realism switches, the mission and the
// seed, as one typed struct whose sections each name their fields once (Serialize). Every run path
// is built from it: the DDS nodes read their part of the same file (`scenario:=FILE`), the
// in-process Episode (gym, `unav run --in-process`) and data generation call the same builders
// (unav_physics/scenario_builder.hpp for the plant, unav_sim's load_episode_setup for the rest).
//
// Any leaf may be a distribution (unav_common/sampling.hpp); load_scenario() checks the file and
// draws the concrete scenario for a seed:
//   scene::Scenario s = scene::load_scenario("scenarios/pipe_hover.yaml");        // the file's seed
//   scene::Scenario t = scene::load_scenario("scenarios/pipe_hover.yaml", 42);    // another draw
// File paths (world, vehicle.model, control.*, cameras.config) are resolved to absolute paths:
// relative to the scenario's folder first, then under the resource roots (config/..., worlds/...).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "unav_common/config.hpp"
#include "unav_scene/camera.hpp"
#include "unav_scene/render_settings.hpp"
#include "unav_scene/world.hpp"
#include "unav_scene/world_generator.hpp"

namespace unav::scene {

struct ScenarioVehicle {
  std::string model = "vehicles/bluerov2_heavy.yaml";  ///< plant YAML (config/vehicles/...)
  Eigen::Vector3d initial_position{0.0, 0.0, 0.0};     ///< m, world NED
  Eigen::Vector3d initial_rpy_deg{0.0, 0.0, 0.0};      ///< roll, pitch, yaw [deg]
  /// Keys of the vehicle file replaced for this run ("key.path=value", checked by the vehicle's
  /// schema), e.g. ["tether.enabled=true", "tether.length_m=40", "sensors.usbl.rate=2"].
  std::vector<std::string> set;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("model", &model).Doc("vehicle YAML: relative to the scenario, config/ or absolute"));
    a->Visit(Field("set", &set).Doc("vehicle-file keys replaced: [key.path=value, ...] (tether, sensors, ...)"));
    a->Visit(Field("initial_position", &initial_position).Range(-1e5, 1e5).Unit("m").Doc("start, world NED"));
    a->Visit(Field("initial_rpy_deg", &initial_rpy_deg).Range(-360.0, 360.0).Unit("deg").Doc("start roll, pitch, yaw"));
  }
};

/// One more vehicle in the same world (Scenario::fleet): its namespace and the vehicle fields.
/// The physics server steps it beside the primary vehicle; its topics are /<name>/..., its body
/// frame <name>/base_link_frd on /tf.
struct ScenarioFleetVehicle {
  std::string name;  ///< namespace of its topics and frames, e.g. "rov2"
  ScenarioVehicle vehicle;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("name", &name).Doc("namespace of its topics and frames (e.g. rov2): letters, digits, _"));
    vehicle.Serialize(a);
  }
};

struct ScenarioPhysics {
  double dt = 0.001;
  std::string integrator = "velocity_verlet";

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("dt", &dt).Above(0.0).Max(0.05).Unit("s").Doc("physics step"));
    a->Visit(Field("integrator", &integrator).OneOf({"velocity_verlet", "rk4"}));
  }
};

struct ScenarioControl {
  std::string mpc = "controllers/mpc.yaml";              ///< mpc_controller params file
  std::string allocator = "controllers/allocator.yaml";  ///< control_allocator params file
  double period = 0.05;                                  ///< s, a whole number of physics steps

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("mpc", &mpc).Doc("mpc_controller params file"));
    a->Visit(Field("allocator", &allocator).Doc("control_allocator params file"));
    a->Visit(Field("period", &period).Above(0.0).Max(1.0).Unit("s").Doc("MPC + allocator period"));
  }
};

struct ScenarioCameras {
  std::string config = "sensors/bluerov2_cameras.yaml";  ///< camera set (mounts, intrinsics)
  std::vector<std::string> names{"down"};                ///< cameras of `config` rendered
  int width = 0;                                         ///< render size, 0 = the camera's
  int height = 0;
  double rate_hz = 10.0;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("config", &config).Doc("camera set YAML (mounts, intrinsics)"));
    a->Visit(Field("names", &names).Doc("cameras of config to render"));
    a->Visit(Field("width", &width).Range(0, 8192).Unit("px").Doc("render width, 0 = the camera's"));
    a->Visit(Field("height", &height).Range(0, 8192).Unit("px").Doc("render height, 0 = the camera's"));
    a->Visit(Field("rate_hz", &rate_hz).Above(0.0).Max(1000.0).Unit("Hz").Doc("frames per second per camera"));
  }
};

/// The imaging sonars pinged along the run (the sonar node's part): `names` of `config`.
struct ScenarioSonars {
  std::string config = "sensors/bluerov2_sonars.yaml";  ///< sonar set (mounts, beams, bins)
  std::vector<std::string> names;                       ///< sonars of `config` to ping; [] = none

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("config", &config).Doc("sonar set YAML (mounts, beams, bins)"));
    a->Visit(Field("names", &names).Doc("sonars of config to ping; [] = none"));
  }
};

/// A waypoint: the setpoint travels to it from the previous one (or the start) at the mission's
/// speed, then stays on it until `hold_s` seconds after the leg began (world NED, heading).
struct ScenarioWaypoint {
  Eigen::Vector3d position{0.0, 0.0, 0.0};
  double yaw_deg = 0.0;
  double hold_s = 5.0;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("position", &position).Range(-1e5, 1e5).Unit("m").Doc("setpoint, world NED"));
    a->Visit(Field("yaw_deg", &yaw_deg).Range(-360.0, 360.0).Unit("deg").Doc("heading setpoint"));
    a->Visit(Field("hold_s", &hold_s).Above(0.0).Unit("s").Doc("time of this leg: travel, then hold"));
  }
};

/// What the vehicle does: the waypoints in order (each leg hold_s long: the setpoint travels at
/// speed_mps, then holds), then the last one (or the initial pose) until duration_s.
struct ScenarioMission {
  double duration_s = 10.0;
  double speed_mps = 0.5;
  std::vector<ScenarioWaypoint> waypoints;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("duration_s", &duration_s).Above(0.0).Max(1e6).Unit("s").Doc("simulated time of the run"));
    a->Visit(Field("speed_mps", &speed_mps).Above(0.0).Max(10.0).Unit("m/s").Doc("setpoint speed along a leg"));
    a->Visit(Field("waypoints", &waypoints).Doc("setpoints flown in order"));
  }
};

struct Scenario {
  std::string name = "scenario";
  int64_t seed = 0;  ///< draws of the file's distributions and every noise source
  std::string world = "worlds/pipe_inspection/world.yaml";
  std::string water;        ///< Jerlov preset or water YAML replacing the world's; "" = the world's
  std::string current;      ///< water current YAML replacing the world's; "" = the world's
  WorldGenerator generate;  ///< enabled: the world is generated over `world` (the base)
  ScenarioVehicle vehicle;
  std::vector<ScenarioFleetVehicle> fleet;  ///< more vehicles in the world, each under its own namespace
  ScenarioPhysics physics;
  ScenarioControl control;
  ScenarioCameras cameras;
  ScenarioSonars sonars;
  RenderSettings render;
  ScenarioMission mission;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("name", &name).Doc("run name (output folder)"));
    a->Visit(Field("seed", &seed).Min(0.0).Doc("seed of the distributions and the noise sources"));
    a->Visit(Field("world", &world).Doc("world.yaml: relative to the scenario, the resource roots or absolute"));
    a->Visit(Field("water", &water).Doc("Jerlov preset (I, II, 3C, ...) or water YAML; empty = the world's"));
    a->Visit(Field("current", &current).Doc("water current YAML (config/water/currents/); empty = the world's"));
    a->Visit(Field("generate", &generate).Doc("a randomized pipe world over `world` (unav_scene/world_generator.hpp)"));
    a->Visit(Field("vehicle", &vehicle));
    a->Visit(
        Field("fleet", &fleet).Doc("more vehicles in the same world: [{name, model, set, initial_position, ...}]"));
    a->Visit(Field("physics", &physics));
    a->Visit(Field("control", &control));
    a->Visit(Field("cameras", &cameras));
    a->Visit(Field("sonars", &sonars));
    a->Visit(Field("render", &render));
    a->Visit(Field("mission", &mission));
  }
};

/// Reads, checks and samples the scenario file `path` with `seed` (default: the file's `seed`,
/// which must then be a fixed value), and resolves its file paths (see above). `overrides`
/// ("key.path=value", the value as YAML: "water=3C", "vehicle.initial_position=[0, 0, 5]",
/// "render.shadows=false", "mission.duration_s={uniform: [20, 40]}") replace or add keys of the
/// file before it is checked and drawn, so they obey the same rules. Throws
/// ConfigError(file, key path, value, rule) on any problem: missing file, unknown key, a value
/// or a distribution's support outside its field's rule, a referenced file that does not exist,
/// an override that is not key.path=value (the file is then named with its overrides).
Scenario load_scenario(const std::string& path, std::optional<std::uint64_t> seed = std::nullopt,
                       const std::vector<std::string>& overrides = {});
/// load_scenario() as a node parameter or command-line option gives the seed: < 0 = the file's.
Scenario load_scenario_param(const std::string& path, int64_t seed, const std::vector<std::string>& overrides = {});

/// `root` (a scenario's YAML, not changed) with `overrides` applied (see load_scenario()).
YAML::Node apply_scenario_overrides(const YAML::Node& root, const std::vector<std::string>& overrides,
                                    const std::string& file);

/// The `scenario` and `scenario_seed` parameters of a node that takes its part of a scenario
/// (physics_server, underwater_renderer, mpc_controller, control_allocator, ardusub_bridge,
/// scenario_mission): Serialize() visits both at the caller's level, so a node's params struct
/// embeds it as `ScenarioParam scenario;` and calls `scenario.Serialize(a)`.
struct ScenarioParam {
  std::string file;
  int64_t seed = -1;
  std::vector<std::string> overrides;
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("scenario", &file)
                 .Doc("scenario YAML (config/scenarios/*.yaml) whose part this node takes; "
                      "empty = none (the node's own parameters)"));
    a->Visit(Field("scenario_seed", &seed).Min(-1.0).Doc("draw of the scenario's distributions; -1 = its seed"));
    a->Visit(Field("scenario_set", &overrides)
                 .Doc("scenario keys replaced before the draw: [key.path=value, ...], e.g. "
                      "['water=3C', 'vehicle.initial_position=[0, 0, 5]']"));
  }
  bool given() const { return !file.empty(); }
  /// load_scenario_param(file, seed, overrides).
  Scenario load() const;
};

/// The same for a scenario given as YAML (`file` names it in errors; relative paths resolve
/// against `dir`).
Scenario parse_scenario(const YAML::Node& root, const std::string& file, const std::string& dir,
                        std::optional<std::uint64_t> seed = std::nullopt);
/// A scenario file named in another config (`file`, key `key`): `value` as an absolute path,
/// relative to `dir`, then under the resource roots' config/ and top. Throws ConfigError.
std::string find_scenario_file(const std::string& value, const std::string& dir, const std::string& file,
                               const std::string& key);
/// Resolves the scenario's file paths as load_scenario() does (for scenarios built in code).
void resolve_scenario_paths(Scenario* s, const std::string& file, const std::string& dir);

/// The scenario's cameras: cameras.names of cameras.config, scaled to cameras.width x height.
/// Throws ConfigError (no camera, an unknown name: the error lists the file's cameras).
std::vector<CameraModel> scenario_cameras(const Scenario& s);

/// The scenario's world, built the one way every run path builds it: `world` loaded, generated
/// over when generate.enabled (generate_world with the scenario's seed), its water replaced by
/// `water` when given. Throws ConfigError.
World scenario_world(const Scenario& s);
/// The world whose first pipeline a node follows or scores (waypoint_follower,
/// trajectory_evaluator): the scenario's (scenario_world()) when `scenario` is given, else
/// `world_file`. Throws ConfigError naming the file (also when the world has no pipeline).
World pipeline_world(const ScenarioParam& scenario, const std::string& world_file);

/// The concrete scenario as YAML (what a run records in its output folder).
YAML::Node scenario_yaml(const Scenario& s);

}  // namespace unav::scene
