// Per-packet cost of ArduPilot's JSON backend (ardupilot_json.hpp), in process: decode a servo
// packet, map the PWM, one 1 ms physics step, format the JSON reply. Prints percentiles as
// machine-readable lines: BENCH autopilot/ardupilot_json_handle_{p50,p99}_us and
// autopilot/ardupilot_json_max_sim_rate_x_real_time (1 ms of physics a packet, at the p50).
//   bench_ardupilot_json [packets=20000] [scenario=config/scenarios/ardusub_pipe.yaml]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "unav_autopilot/ardupilot_json.hpp"
#include "unav_common/bench.hpp"
#include "unav_common/resources.hpp"

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::stoi(argv[1]) : 20000;
  const std::string scenario = argc > 2 ? argv[2] : unav::common::find_resource("config/scenarios/ardusub_pipe.yaml");
  const std::string map = unav::common::find_resource("config/autopilot/ardusub_bluerov2_heavy.yaml");
  const auto sc = unav::scene::load_scenario(scenario);
  unav::autopilot::JsonBackend b(sc, unav::scene::scenario_world(sc), unav::autopilot::load_motor_map(map), map);
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(n));
  std::size_t bytes = 0;
  for (int f = 0; f < n; ++f) {
    std::vector<std::uint16_t> pwm(16, 1500);
    pwm[static_cast<std::size_t>(f % 8)] = static_cast<std::uint16_t>(1500 + 100 * (f % 4));
    const auto p = unav::autopilot::encode_servo_packet(1000, static_cast<std::uint32_t>(f), pwm);
    const auto t0 = std::chrono::steady_clock::now();
    bytes += b.handle(p.data(), p.size()).size();
    us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(us.begin(), us.end());
  auto q = [&](double x) { return us[static_cast<std::size_t>(x * static_cast<double>(us.size() - 1))]; };
  unav::common::print_bench("autopilot/ardupilot_json_handle_p50_us", q(0.5), "us");
  unav::common::print_bench("autopilot/ardupilot_json_handle_p99_us", q(0.99), "us");
  unav::common::print_bench("autopilot/ardupilot_json_max_sim_rate_x_real_time", 1000.0 / q(0.5), "x_real_time");
  std::printf("# %d packets, %.1f bytes a reply, simulated %.3f s\n", n, static_cast<double>(bytes) / n,
              b.simulator().time());
  return 0;
}
