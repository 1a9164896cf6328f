#include "unav_physics/scenario_builder.hpp"

#include <cmath>
#include <utility>

#include "unav_common/errors.hpp"
#include "unav_physics/current.hpp"
#include "unav_physics/dynamics.hpp"
#include "unav_physics/vehicle.hpp"
#include "unav_scene/sonar.hpp"

namespace unav::physics {

VehicleParams scenario_vehicle(const unav::scene::Scenario& scenario) {
  return scenario_vehicle(scenario.vehicle, "vehicle");
}

VehicleParams scenario_vehicle(const unav::scene::ScenarioVehicle& v, const std::string& key) {
  const std::string& file = v.model;
  if (v.set.empty()) return load_vehicle(file);
  std::string label = file + " (" + key + ".set:";
  for (const auto& o : v.set) label += " " + o;
  label += ")";
  return parse_vehicle(unav::scene::apply_scenario_overrides(unav::common::detail::ReadYamlFile(file), v.set, label),
                       label);
}

void apply_world_acoustics(const unav::scene::World& world, SensorSuiteParams* sensors) {
  const auto at = [&](double depth) {
    return unav::scene::sound_speed_mackenzie(world.water.temperature_c, world.water.salinity_psu,
                                              std::max(0.0, depth));
  };
  if (!(sensors->usbl.sound_speed_mps > 0.0))
    sensors->usbl.sound_speed_mps = at(sensors->usbl.transceiver_position.z());
  if (!(sensors->modem.sound_speed_mps > 0.0)) sensors->modem.sound_speed_mps = at(sensors->modem.station_position.z());
}

std::unique_ptr<Seabed> seabed_from_world(const unav::scene::World& world) {
  const unav::scene::Seabed& sb = world.seabed;
  if (!sb.enabled) return nullptr;
  if (sb.is_flat()) return std::make_unique<FlatSeabed>(sb.depth_m);
  unav::scene::SeabedGrid g = unav::scene::sample_seabed(sb);
  return std::make_unique<GridSeabed>(g.origin_n, g.origin_e, g.resolution_m, std::move(g.depths_m));
}

RigidBodyState scenario_initial_state(const unav::scene::Scenario& scenario) {
  return scenario_initial_state(scenario.vehicle);
}

RigidBodyState scenario_initial_state(const unav::scene::ScenarioVehicle& v) {
  constexpr double kDeg = M_PI / 180.0;
  RigidBodyState x0;
  x0.p_WB_W = v.initial_position;
  const Eigen::Vector3d rpy = v.initial_rpy_deg * kDeg;
  x0.q_WB = quaternion_from_rpy(rpy.x(), rpy.y(), rpy.z());
  return x0;
}

SimulatorOptions scenario_simulator_options(const unav::scene::Scenario& scenario, double command_timeout) {
  SimulatorOptions so;
  so.dt = scenario.physics.dt;
  if (!parse_integrator(scenario.physics.integrator, &so.integrator))
    throw unav::ConfigError(scenario.name, "physics.integrator", scenario.physics.integrator,
                            "must be one of {velocity_verlet, rk4}");
  so.command_timeout = command_timeout;
  return so;
}

std::unique_ptr<Simulator> build_simulator(const unav::scene::Scenario& scenario, const unav::scene::World& world,
                                           const SimulatorOptions& options) {
  return build_simulator(scenario, world, options, scenario_vehicle(scenario));
}

std::unique_ptr<Simulator> build_simulator(const unav::scene::Scenario& scenario, const unav::scene::World& world,
                                           const SimulatorOptions& options, const VehicleParams& params) {
  return build_simulator(scenario, world, options, params, scenario.vehicle);
}

std::unique_ptr<Simulator> build_simulator(const unav::scene::Scenario& scenario, const unav::scene::World& world,
                                           const SimulatorOptions& options, const VehicleParams& params,
                                           const unav::scene::ScenarioVehicle& which) {
  VehicleParams vehicle = params;
  apply_world_acoustics(world, &vehicle.sensors);
  const std::string& current_file = scenario.current.empty() ? world.current_file : scenario.current;
  std::unique_ptr<CurrentModel> current = current_file.empty() ? nullptr : load_current(current_file);
  return std::make_unique<Simulator>(vehicle, options, std::move(current), seabed_from_world(world),
                                     scenario_initial_state(which));
}

void require_fixed_usbl(const VehicleParams& vehicle, const std::string& file, const std::string& path) {
  const UsblParams& u = vehicle.sensors.usbl;
  const std::string rule =
      path + " steps one vehicle: an end carried by another needs the physics server with both in its scenario (fleet)";
  if (u.enabled && !u.transceiver_vehicle.empty())
    throw unav::ConfigError(file, "vehicle.sensors.usbl.transceiver_vehicle", u.transceiver_vehicle, rule);
  const AcousticModemParams& m = vehicle.sensors.modem;
  if (m.enabled && !m.station_vehicle.empty())
    throw unav::ConfigError(file, "vehicle.sensors.modem.station_vehicle", m.station_vehicle, rule);
}

}  // namespace unav::physics
