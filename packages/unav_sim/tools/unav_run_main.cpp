// unav run SCENARIO.yaml --in-process [--seed N] [--out DIR] [--no-images]: one scenario flown in
// process by the one builder (unav_sim/scenario_run.hpp). Ctrl-C stops after the current control
// period with every file written so far complete. Over DDS the same file runs as the nodes'
// `scenario:=` parameter (physics_server, underwater_renderer).
#include <CLI/CLI.hpp>

#include <signal.h>

#include <atomic>
#include <cstdio>
#include <iostream>

#include "unav_common/errors.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_sim/scenario_run.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"unav run: one scenario, in process (the Episode of the gym and datagen)"};
  std::string file, out;
  std::int64_t seed = -1;
  bool in_process = false, no_images = false;
  app.add_option("scenario", file, "scenario YAML (config/scenarios/*.yaml)")->required();
  app.add_flag("--in-process", in_process, "run the cores in this process (no DDS)");
  app.add_option("--seed", seed, "draw of the scenario's distributions (default: its seed)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--out", out, "output folder (default: out/<scenario name>)");
  app.add_flag("--no-images", no_images, "write the ground truth only");
  CLI11_PARSE(app, argc, argv);
  if (!in_process) {
    std::cerr << "unav run: only --in-process runs here; over DDS: unav launch launch_scripts/scenario.launch.yaml "
                 "scenario:=FILE (see docs/scenarios.md)\n";
    return 2;
  }
  try {
    const unav::scene::Scenario s = unav::scene::load_scenario_param(file, seed);
    if (out.empty()) out = "out/" + s.name;
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
