// unav run SCENARIO.yaml [--in-process] [--seed N] [--set KEY=VALUE]... [--out DIR] [--no-images]: one scenario, its
// ground truth (OUT/ground_truth.tum) and every camera's frames (OUT/<camera>/<t_ns>.png).
//  - over DDS (default): the scenario is checked here, before any process starts, then this
//    process becomes `unav launch launch_scripts/scenario.launch.yaml scenario:=FILE ...`
//    (physics, MPC, allocator, renderer, mission: one process each, in lockstep);
//  - --in-process: the Episode built by the one builder (unav_sim/scenario_run.hpp).
// Both write the same files, byte for byte (system test scenario_equivalence). Ctrl-C stops with
// every file written so far complete.
#include <CLI/CLI.hpp>

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_sim/scenario_run.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }
// Becomes `unav launch scenario.launch.yaml ...` (exec: Ctrl-C reaches the launch directly).
int run_over_dds(const unav::scene::Scenario& s, const std::string& file, std::int64_t seed,
                 const std::vector<std::string>& sets, const std::string& out, bool no_images) {
  if (no_images) {
    std::cerr << "unav run: --no-images is for --in-process (over DDS the renderer is a lockstep participant)\n";
    return 2;
  }
  const std::string launch = unav::common::find_resource("launch_scripts/scenario.launch.yaml");
  unav::sim::write_concrete_scenario(s, out);
  YAML::Emitter set_list;  // a flow list of quoted strings: values may hold ',', '[' or ':'
  set_list << YAML::Flow << YAML::DoubleQuoted << sets;
  std::vector<std::string> args = {"unav",
                                   "launch",
                                   launch,
                                   "scenario:=" + std::filesystem::absolute(file).string(),
                                   "seed:=" + std::to_string(seed),
                                   std::string("set:=") + set_list.c_str(),
                                   "duration:=" + std::to_string(s.mission.duration_s),
                                   "output_dir:=" + std::filesystem::absolute(out).string()};
  std::printf("unav run: %s (seed %lld) over DDS: %s\n  outputs: %s/ground_truth.tum, %s/<camera>/*.png\n",
              s.name.c_str(), static_cast<long long>(s.seed), launch.c_str(), out.c_str(), out.c_str());
  std::fflush(stdout);
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execvp(argv[0], argv.data());
  std::cerr << "unav run: cannot start 'unav launch' (" << std::strerror(errno) << "); is the workspace sourced?\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"unav run: one scenario, over DDS (one process per node, lockstep) or --in-process"};
  std::string file, out;
  std::int64_t seed = -1;
  bool in_process = false, no_images = false;
  std::vector<std::string> sets;
  app.add_option("scenario", file, "scenario YAML (config/scenarios/*.yaml)")->required();
  app.add_flag("--in-process", in_process, "run the cores in this process (no DDS)");
  app.add_option("--seed", seed, "draw of the scenario's distributions (default: its seed)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--set", sets,
                 "replace a key of the scenario before the draw, key.path=value (repeatable): "
                 "--set water=3C --set 'vehicle.initial_position=[0, 0, 5]'")
      ->allow_extra_args(false);
  app.add_option("--out", out, "output folder (default: out/<scenario name>)");
  app.add_flag("--no-images", no_images, "write the ground truth only");
  CLI11_PARSE(app, argc, argv);
  try {
    const unav::scene::Scenario s = unav::scene::load_scenario_param(file, seed, sets);
    if (out.empty()) out = "out/" + s.name;
    if (!in_process) return run_over_dds(s, file, seed, sets, out, no_images);
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    unav::sim::ScenarioRunOptions o;
    o.images = !no_images;
    o.stop = &g_stop;
    const auto r = unav::sim::run_scenario_in_process(s, out, o);
    std::printf(
        "unav run: %s (seed %lld): %.2f s simulated in %.2f s wall (%.2fx real time), %llu poses, %llu frames, "
        "%d MPC failures%s\n  outputs: %s/ground_truth.tum, %s/<camera>/*.png, %s/scenario.yaml\n",
        s.name.c_str(), static_cast<long long>(s.seed), r.sim_s, r.wall_s, r.sim_s / r.wall_s,
        static_cast<unsigned long long>(r.poses), static_cast<unsigned long long>(r.frames), r.solver_failures,
        r.stopped ? " (stopped early)" : "", out.c_str(), out.c_str(), out.c_str());
    return r.stopped ? 130 : 0;
  } catch (const unav::ConfigError& e) {
    std::cerr << "unav run: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "unav run: " << e.what() << "\n";
    return 1;
  }
}
