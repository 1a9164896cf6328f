// Model steps per second on one core (target >= 2,000,000 steps/s for the dynamics step).
// Run: bench_physics [--benchmark_filter=...]; items_per_second = steps per second.
// Machine-readable: Google Benchmark's own `--benchmark_format=json`; scripts/bench_compare.sh
// reads each run's CPU time per step as BENCH physics/{dynamics,simulator}_step_{verlet,rk4}_ns.
#include <benchmark/benchmark.h>

#include "unav_physics/simulator.hpp"

namespace up = unav::physics;

namespace {

up::DynamicsInputs busy_inputs() {
  up::DynamicsInputs in;
  in.tau_B << 20.0, 5.0, -3.0, 0.5, -0.4, 1.0;  // a thrusting, turning vehicle
  in.v_c_W = Eigen::Vector3d(0.2, 0.1, 0.0);    // and a current, so every term is exercised
  return in;
}

up::RigidBodyState moving_state() {
  up::RigidBodyState x;
  x.p_WB_W = Eigen::Vector3d(0.0, 0.0, 10.0);
  x.q_WB = up::quaternion_from_rpy(0.1, -0.05, 0.3);
  x.v_WB_B = Eigen::Vector3d(0.5, 0.1, 0.05);
  x.w_WB_B = Eigen::Vector3d(0.05, 0.02, 0.2);
  return x;
}

void BM_DynamicsStep(benchmark::State& state, up::Integrator integrator) {
  const up::VehicleDynamics dyn(up::bluerov2_heavy_params());
  const up::DynamicsInputs in = busy_inputs();
  up::RigidBodyState x = moving_state();
  for (auto _ : state) {
    dyn.step(x, 1e-3, in, integrator);
    benchmark::DoNotOptimize(x);
  }
  state.SetItemsProcessed(state.iterations());
}

// Full facade step: failsafe, 8 thruster lags, dynamics, current, seabed contact check, sensors.
// One Simulator step (lagged thrusters, current, seabed) with every sensor of the vehicle (IMU,
// pressure, the 4-beam DVL ray-casting the seabed at 10 Hz, altimeter, magnetometer, GPS), with
// the DVL alone off, or with no sensor: the figures split the step's cost.
enum class Sensors { kAll, kNoDvl, kNone, kAllUsblTether };
void BM_SimulatorStep(benchmark::State& state, up::Integrator integrator, Sensors sensors) {
  up::VehicleParams v = up::bluerov2_heavy_params();
  if (sensors != Sensors::kNone) {
    v.sensors.imu.enabled = v.sensors.pressure.enabled = v.sensors.dvl.enabled = true;
    v.sensors.altimeter.enabled = v.sensors.magnetometer.enabled = v.sensors.gps.enabled = true;
    v.sensors.dvl.enabled = sensors == Sensors::kAll || sensors == Sensors::kAllUsblTether;
  }
  if (sensors == Sensors::kAllUsblTether) {  // the marine navigation additions: USBL and a 30 m tether
    v.sensors.usbl.enabled = true;
    v.tether.enabled = true;
    v.tether.anchor_position = Eigen::Vector3d(0.0, 0.0, 0.5);
  }
  v.sensors.imu.accel.noise_stddev = 0.02;
  up::SimulatorOptions o;
  o.integrator = integrator;
  o.command_timeout = 0.0;
  up::Simulator sim(
      v, o, std::make_unique<up::SinusoidalCurrent>(Eigen::Vector3d(0.1, 0, 0), Eigen::Vector3d(0.1, 0.05, 0), 0.05),
      std::make_unique<up::FlatSeabed>(30.0), moving_state());
  sim.set_command(0.0, std::vector<double>{0.3, 0.3, -0.3, -0.3, 0.1, 0.1, 0.1, 0.1});
  for (auto _ : state) {
    sim.step();
    benchmark::DoNotOptimize(sim.state());
  }
  state.SetItemsProcessed(state.iterations());
}

}  // namespace

BENCHMARK_CAPTURE(BM_DynamicsStep, velocity_verlet, up::Integrator::kVelocityVerlet);
BENCHMARK_CAPTURE(BM_DynamicsStep, rk4, up::Integrator::kRk4);
BENCHMARK_CAPTURE(BM_SimulatorStep, velocity_verlet, up::Integrator::kVelocityVerlet, Sensors::kAll);
BENCHMARK_CAPTURE(BM_SimulatorStep, rk4, up::Integrator::kRk4, Sensors::kAll);
BENCHMARK_CAPTURE(BM_SimulatorStep, verlet_no_dvl, up::Integrator::kVelocityVerlet, Sensors::kNoDvl);
BENCHMARK_CAPTURE(BM_SimulatorStep, verlet_no_sensors, up::Integrator::kVelocityVerlet, Sensors::kNone);
BENCHMARK_CAPTURE(BM_SimulatorStep, verlet_usbl_tether, up::Integrator::kVelocityVerlet, Sensors::kAllUsblTether);
BENCHMARK_MAIN();
