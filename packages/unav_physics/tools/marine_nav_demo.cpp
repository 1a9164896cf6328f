// The marine navigation sensors on a flight, in process: the BlueROV2 Heavy of a scenario, on a
// tether from the support vessel above the origin, pushed round a turning circle by a scripted
// body wrench through a water current, its USBL interrogated from the vessel, its four-beam DVL
// ranging the seabed. Writes the ground truth, every USBL fix, every DVL beam's bottom point and
// snapshots of the tether's shape as CSV, and prints the USBL's and the DVL's errors against the
// truth (scripts/plot_marine_nav.py draws them: docs/gallery/usbl_track.png, dvl_footprints.png,
// tether_shapes.png).
//   unav_marine_nav_demo [--scenario FILE] [--out DIR] [--duration S] [--current M_PER_S]
//                        [--tether-length M]
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"
#include "unav_physics/scenario_builder.hpp"
#include "unav_physics/simulator.hpp"
#include "unav_scene/scenario.hpp"

namespace fs = std::filesystem;
namespace up = unav::physics;

int main(int argc, char** argv) {
  std::string scenario_file = "scenarios/pipe_inspection.yaml", out = "out/marine_nav";
  double duration = 180.0, current = 0.2, tether_length = 25.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool value = i + 1 < argc;
    if (a == "--scenario" && value) {
      scenario_file = argv[++i];
    } else if (a == "--out" && value) {
      out = argv[++i];
    } else if (a == "--duration" && value) {
      duration = std::stod(argv[++i]);
    } else if (a == "--current" && value) {
      current = std::stod(argv[++i]);
    } else if (a == "--tether-length" && value) {
      tether_length = std::stod(argv[++i]);
    } else {
      std::cerr << "usage: unav_marine_nav_demo [--scenario FILE] [--out DIR] [--duration S] [--current M_PER_S] "
                   "[--tether-length M]\n";
      return 2;
    }
  }
  try {
    const std::string path =
        fs::exists(scenario_file) ? scenario_file : unav::common::find_resource("config/" + scenario_file);
    unav::scene::Scenario sc = unav::scene::load_scenario(path);
    sc.vehicle.set.push_back("tether.enabled=true");
    sc.vehicle.set.push_back("tether.length_m=" + std::to_string(tether_length));
    sc.vehicle.set.push_back("sensors.usbl.enabled=true");
    sc.vehicle.set.push_back("sensors.dvl.enabled=true");
    up::VehicleParams vehicle = up::scenario_vehicle(sc);
    const unav::scene::World world = unav::scene::scenario_world(sc);
    up::apply_world_acoustics(world, &vehicle.sensors);
    up::SimulatorOptions options = up::scenario_simulator_options(sc, 0.0);
    up::Simulator sim(vehicle, options, std::make_unique<up::ConstantCurrent>(Eigen::Vector3d(0.0, current, 0.0)),
                      up::seabed_from_world(world), up::scenario_initial_state(sc));
    // Round a wide turning circle: 15 N ahead, 0.03 N m of yaw.
    up::Vector6d push;
    push << 15.0, 0.0, 0.0, 0.0, 0.0, 0.03;
    sim.set_external_wrench_B(push);

    fs::create_directories(out);
    std::ofstream truth(fs::path(out) / "truth.csv"), usbl(fs::path(out) / "usbl.csv"),
        tether(fs::path(out) / "tether.csv"), dvl(fs::path(out) / "dvl.csv");
    truth << "t,x,y,z,tether_force_n\n";
    dvl << "t,beam,valid,x,y,z\n";  // each beam's bottom point (world NED) from its measured range
    std::uint64_t dvl_seq = 0;
    int dvl_readings = 0, dvl_valid = 0;
    double dvl_se = 0.0;
    usbl << "t,ping_t,valid,outlier,range,x,y,z,truth_x,truth_y,truth_z\n";
    tether << "t,node,x,y,z\n";
    std::uint64_t seq = 0;
    int fixes = 0, timeouts = 0;
    double se_h = 0.0, se_3d = 0.0;
    const auto steps = static_cast<long>(std::lround(duration / options.dt));
    for (long k = 0; k <= steps; ++k) {
      if (k > 0) sim.step();
      const double t = sim.time();
      const auto& x = sim.state();
      if (k % 100 == 0)
        truth << t << ',' << x.p_WB_W.x() << ',' << x.p_WB_W.y() << ',' << x.p_WB_W.z() << ','
              << sim.tether_force_W().norm() << '\n';
      if (k % 20000 == 0)
        for (std::size_t i = 0; i < sim.tether()->nodes().size(); ++i) {
          const auto& n = sim.tether()->nodes()[i];
          tether << t << ',' << i << ',' << n.x() << ',' << n.y() << ',' << n.z() << '\n';
        }
      const auto& d = sim.sensors().dvl;
      if (d.seq != dvl_seq) {
        dvl_seq = d.seq;
        ++dvl_readings;
        if (d.valid) {
          ++dvl_valid;
          dvl_se += (d.velocity_B - x.v_WB_B).squaredNorm();
        }
        for (int i = 0; i < 4; ++i) {
          const Eigen::Vector3d hit = x.p_WB_W + x.q_WB * (d.beam_range_m[static_cast<std::size_t>(i)] *
                                                           up::dvl_beam_B(i, vehicle.sensors.dvl.beam_angle_deg));
          dvl << d.stamp << ',' << i << ',' << d.beam_valid[static_cast<std::size_t>(i)] << ',' << hit.x() << ','
              << hit.y() << ',' << hit.z() << '\n';
        }
      }
      const auto& f = sim.sensors().usbl;
      if (f.seq != seq) {
        seq = f.seq;
        usbl << f.stamp << ',' << f.ping_stamp << ',' << f.valid << ',' << f.outlier << ',' << f.range_m << ','
             << f.p_W.x() << ',' << f.p_W.y() << ',' << f.p_W.z() << ',' << f.truth_p_W.x() << ',' << f.truth_p_W.y()
             << ',' << f.truth_p_W.z() << '\n';
        if (f.valid) {
          ++fixes;
          se_h += (f.p_W - f.truth_p_W).head<2>().squaredNorm();
          se_3d += (f.p_W - f.truth_p_W).squaredNorm();
        } else {
          ++timeouts;
        }
      }
    }
    std::printf(
        "unav_marine_nav_demo: %.0f s, %d USBL fixes (%d without a reply), fix error RMS %.3f m horizontal, "
        "%.3f m 3-D; DVL %d readings, %d with bottom lock, velocity error RMS %.4f m/s; tether %.1f m, pull %.1f N "
        "at the end\n  outputs: %s/{truth,usbl,dvl,tether}.csv\n",
        duration, fixes, timeouts, fixes ? std::sqrt(se_h / fixes) : 0.0, fixes ? std::sqrt(se_3d / fixes) : 0.0,
        dvl_readings, dvl_valid, dvl_valid ? std::sqrt(dvl_se / dvl_valid) : 0.0, sim.tether()->length(),
        sim.tether_force_W().norm(), out.c_str());
  } catch (const unav::ConfigError& e) {
    std::cerr << "unav_marine_nav_demo: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
