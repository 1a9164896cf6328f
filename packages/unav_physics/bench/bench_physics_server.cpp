// physics_server in lockstep with no participants (no camera, no controller), all sensors of
// the Heavy config publishing: simulated seconds per wall second. Prints one table, then
// BENCH physics/server_lockstep_x_real_time and physics/server_lockstep_odom_subscriber_x_real_time.
// Usage: bench_physics_server VEHICLE_YAML [wall_seconds]
#include <unistd.h>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "physics_server_node.hpp"
#include "unav_common/bench.hpp"

namespace {

double run(const std::string& vehicle, double wall_s, bool with_subscriber) {
  unav::ContextOptions o;
  o.domain_id = 200 + static_cast<int>(getpid() % 30);
  o.handle_signals = false;
  const std::string p = "vehicle_config:=" + vehicle;
  const char* argv[] = {"bench", "--ros-args", "-p", p.c_str(), "-p", "mode:=lockstep"};
  unav::Context server_ctx(6, argv, o);
  unav::physics::PhysicsServer server({&server_ctx});
  unav::Context sub_ctx(o);
  unav::Node sub_node("bench_sub", {&sub_ctx});
  size_t received = 0;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> sub;
  std::thread sub_thread;
  if (with_subscriber) {
    sub = sub_node.create_subscription<nav_msgs::msg::Odometry>("/rov/ground_truth/odom", unav::QoS::reliable(),
                                                                [&](const nav_msgs::msg::Odometry&) { ++received; });
    sub_thread = std::thread([&] { sub_ctx.spin(); });
    server_ctx.spin_until([&] { return sub->publisher_count() > 0; }, std::chrono::seconds(5));
  }
  const double t0 = server.simulator().time();
  const auto start = std::chrono::steady_clock::now();
  server_ctx.spin_until([] { return false; },
                        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(wall_s)));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double ratio = (server.simulator().time() - t0) / wall;
  if (with_subscriber) {
    sub_ctx.shutdown();
    sub_thread.join();
    std::printf("(odometry messages received by the subscriber: %zu)\n", received);
  }
  return ratio;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s VEHICLE_YAML [wall_seconds]\n", argv[0]);
    return 2;
  }
  const double wall_s = argc > 2 ? std::atof(argv[2]) : 5.0;
  const double alone = run(argv[1], wall_s, false);
  const double with_sub = run(argv[1], wall_s, true);
  std::printf("| physics_server lockstep, 1 kHz, all sensors | simulated s per wall s |\n|---|---|\n");
  std::printf("| no subscribers | %.1f |\n| odometry subscriber in another participant | %.1f |\n", alone, with_sub);
  unav::common::print_bench("physics/server_lockstep_x_real_time", alone, "x_real_time");
  unav::common::print_bench("physics/server_lockstep_odom_subscriber_x_real_time", with_sub, "x_real_time");
  return 0;
}
