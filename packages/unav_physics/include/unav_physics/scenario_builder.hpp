// The plant of a scenario (DESIGN.md section 9): the one place that turns a concrete
// scene::Scenario and its world into a physics::Simulator, for the physics server node and the
// in-process Episode alike: the vehicle file, the step and integrator, the world's seabed (flat,
// or its relief sampled on the render grid) and water current, the initial state.
#pragma once

#include <memory>
#include <string>

#include "unav_physics/seabed.hpp"
#include "unav_physics/simulator.hpp"
#include "unav_physics/vehicle.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_scene/world.hpp"

namespace unav::physics {

/// The physics seabed of a world: flat when the world's is, else its patch sampled on the render
/// grid (bilinear between nodes, nearest edge beyond); nullptr when the world disables its seabed.
std::unique_ptr<Seabed> seabed_from_world(const unav::scene::World& world);

/// The scenario's initial state: at vehicle.initial_position, vehicle.initial_rpy_deg, at rest.
RigidBodyState scenario_initial_state(const unav::scene::Scenario& scenario);
/// The same for one vehicle of the scenario (the primary or a fleet vehicle).
RigidBodyState scenario_initial_state(const unav::scene::ScenarioVehicle& vehicle);

/// physics.dt and physics.integrator; `command_timeout` as the caller runs (0 in-process).
SimulatorOptions scenario_simulator_options(const unav::scene::Scenario& scenario, double command_timeout);

/// The simulator of a scenario in `world` (the world the scenario names, loaded by the caller,
/// who also renders it): vehicle.model, the options above, the world's seabed and current, the
/// initial state. Throws ConfigError naming the file and key on a bad vehicle or current file.
/// The scenario's vehicle: its model file with vehicle.set applied (the same rules and errors as
/// the file's keys; errors name the file and "vehicle.set"). Throws ConfigError.
VehicleParams scenario_vehicle(const unav::scene::Scenario& scenario);
/// The same for one vehicle of the scenario; `key` names it in errors ("vehicle", "fleet[1]").
VehicleParams scenario_vehicle(const unav::scene::ScenarioVehicle& vehicle, const std::string& key);

/// A run path that steps one vehicle (`path`, e.g. "an in-process episode") cannot move a USBL
/// transceiver or a modem's other end carried by another: throws ConfigError naming `file` and
/// vehicle.sensors.usbl.transceiver_vehicle / modem.station_vehicle when one names a carrier.
void require_fixed_usbl(const VehicleParams& vehicle, const std::string& file, const std::string& path);

/// The sound speed of the world's water (Mackenzie at the transceiver's / station's depth) for
/// the USBL and the acoustic modem that leave theirs at 0.
void apply_world_acoustics(const unav::scene::World& world, SensorSuiteParams* sensors);

std::unique_ptr<Simulator> build_simulator(const unav::scene::Scenario& scenario, const unav::scene::World& world,
                                           const SimulatorOptions& options);
/// The same with the vehicle already loaded from scenario.vehicle.model (callers that keep it:
/// no file read per episode).
std::unique_ptr<Simulator> build_simulator(const unav::scene::Scenario& scenario, const unav::scene::World& world,
                                           const SimulatorOptions& options, const VehicleParams& params);
/// The simulator of one of the scenario's vehicles (`which`: scenario.vehicle or a fleet
/// entry's) in the same world and water.
std::unique_ptr<Simulator> build_simulator(const unav::scene::Scenario& scenario, const unav::scene::World& world,
                                           const SimulatorOptions& options, const VehicleParams& params,
                                           const unav::scene::ScenarioVehicle& which);

}  // namespace unav::physics
