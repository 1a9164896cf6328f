// Frames per second of the underwater renderer on worlds/pipe_inspection, RGB + depth +
// segmentation with readback, at 320x180 and 640x480, synchronous and pipelined (PBO ring).
// Prints a table; also a breakdown by switching effects off, to show what dominates.
//   bench_unav_renderer [frames=40] [world.yaml] [--quick] [--camera NAME] [--config N] [--in-flight N]
//                       [--callgrind]
// --in-flight N: frames in flight in the pipelined runs (RenderOptions::readback_slots, default 2).
// --quick: one configuration's row (--config N, default 0) and the per-pass breakdown only (for A/B
// runs of two builds or two configurations, interleaved: this VM's speed drifts by +-15 % over
// minutes); --camera: that camera only
// (w320x180, w640x480, w640x480_distorted, demo_front, front_lens, front_jpeg). demo_front is the
// demo's front camera as config/sensors/bluerov2_cameras.yaml has it (640x480 behind a flat port,
// lens distortion, shot and read noise, vignetting): what the pipe-inspection demo renders;
// front_lens is it with the camera pipeline's lens on (depth of field of an 8 mm f/1.4 lens focused
// at 0.5 m: a 2-4 px blur disc over the seabed, so every pixel of geometry gathers its 16 taps;
// lateral colour 0.002; auto white balance), front_jpeg with JPEG quality 90. --callgrind: render `frames` frames of
// each camera with callgrind's instrumentation on (after warm-up) and nothing else; run it as
//   valgrind --tool=callgrind --instr-atstart=no bench_unav_renderer 4 --callgrind --camera w640x480
// and divide "Collected" by the frames: instructions per frame compare two builds without this
// VM's timing noise (texture and memory stalls are not counted: check the direction with fps).
// --config N: the N-th configuration of the table (0 default, 1 no materials, ...) for the
// callgrind count, the --quick row and the per-pass breakdown.
// Machine-readable, for the default options' rows: BENCH renderer/<camera>_median_ms,
// renderer/<camera>_sync_fps, renderer/<camera>_pipelined_fps (camera: w320x180, w640x480,
// w640x480_distorted, demo_front, front_lens, front_jpeg), and renderer/node_pattern_{1,2}_workers_ticks_per_s.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <optional>
#include <string>
#include <vector>

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define UNAV_HAVE_CALLGRIND 1
#endif

#include "unav_common/bench.hpp"
#include "unav_common/resources.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_renderer/renderer_pool.hpp"

using namespace unav::renderer;
using Clock = std::chrono::steady_clock;

namespace {

Pose pose_at(int i) {
  // Fly along the first leg of the pipe at 2 m altitude, 0.05 m per frame.
  return pose_from_xyz_rpy({-1.0 + 0.05 * i, 0.3, 8.0}, {0.0, 0.0, 0.05});
}

double process_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct Result {
  double fps_sync, fps_pipelined, median_ms;
  double cpu_ms_pipelined;  // the process's CPU time a frame (all threads) in the pipelined run
};

Result measure(Renderer& r, const std::string& cam, int frames) {
  for (int i = 0; i < 3; ++i) r.render(pose_at(i), cam, 0.0);  // warm-up (shader JIT)
  std::vector<double> ms;
  const auto t0 = Clock::now();
  for (int i = 0; i < frames; ++i) {
    const auto a = Clock::now();
    const Frame f = r.render(pose_at(i), cam, 0.1 * i);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - a).count());
    if (f.rgb.empty()) std::abort();
  }
  const double sync_s = std::chrono::duration<double>(Clock::now() - t0).count();
  const auto t1 = Clock::now();
  const double cpu0 = process_cpu_ms();
  int got = 0;
  for (int i = 0; i < frames; ++i) {
    r.submit(pose_at(i), cam, 0.1 * i);
    if (r.in_flight() >= static_cast<std::size_t>(r.options().readback_slots))
      if (auto f = r.collect()) {
        ++got;
        r.recycle(std::move(*f));  // as the node does
      }
  }
  while (auto f = r.collect()) {
    ++got;
    r.recycle(std::move(*f));
  }
  const double pipe_s = std::chrono::duration<double>(Clock::now() - t1).count();
  return {frames / sync_s, got / pipe_s, median(ms), (process_cpu_ms() - cpu0) / got};
}

// The oldest frame of the pool, its buffers handed back as the node does.
void take(RendererPool& pool) {
  Frame f = pool.collect();
  if (f.rgb.empty()) std::abort();
  pool.recycle(std::move(f));
}

// Frames per second of a RendererPool: `frames` frames in flight two per worker, collected in order.
double pool_fps(RendererPool& pool, const std::string& cam, int frames) {
  const auto run = [&](int n, int first) {
    for (int i = 0; i < n; ++i) {
      pool.submit(pose_at(first + i), cam, 0.1 * (first + i));
      if (pool.in_flight() >= 2 * static_cast<std::size_t>(pool.workers())) take(pool);
    }
    while (pool.in_flight() > 0) take(pool);
  };
  run(3 * pool.workers(), 0);  // warm-up: every worker compiles its shaders
  const auto t0 = Clock::now();
  run(frames, 0);
  return frames / std::chrono::duration<double>(Clock::now() - t0).count();
}

// Ticks per second of the underwater_renderer node's pattern: each tick renders the 640x480 and
// the 320x180 camera at one pose (submitted together, collected in order).
double pool_ticks_per_s(RendererPool& pool, int ticks) {
  const auto run = [&](int n) {
    for (int i = 0; i < n; ++i) {
      pool.submit(pose_at(i), "demo_front", 0.1 * i);  // the demo's two cameras
      pool.submit(pose_at(i), "w320x180", 0.1 * i);
      take(pool);
      take(pool);
    }
  };
  run(3);  // warm-up
  const auto t0 = Clock::now();
  run(ticks);
  return ticks / std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // each row as it comes (a run cut short keeps them)
  bool quick = false, callgrind = false;
  int config_index = 0;  // --callgrind and the per-pass table: which configuration (0 = default options)
  int in_flight = 2;     // pipelined runs: frames in flight (RenderOptions::readback_slots)
  std::string only;
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--quick")
      quick = true;
    else if (std::string(argv[i]) == "--callgrind")
      callgrind = true;
    else if (std::string(argv[i]) == "--camera" && i + 1 < argc)
      only = argv[++i];
    else if (std::string(argv[i]) == "--in-flight" && i + 1 < argc)
      in_flight = std::atoi(argv[++i]);
    else if (std::string(argv[i]) == "--config" && i + 1 < argc)
      config_index = std::atoi(argv[++i]);
    else
      args.emplace_back(argv[i]);
  }
  auto skip = [&](const char* cam) { return !only.empty() && only != cam; };
  const int frames = !args.empty() ? std::atoi(args[0].c_str()) : 40;
  const std::string world_path =
      args.size() > 1 ? args[1] : unav::common::find_resource("worlds/pipe_inspection/world.yaml");
  World world = load_world(world_path);
  CameraModel small = CameraModel::from_hfov("w320x180", 320, 180, 90.0 * M_PI / 180.0);
  small.X_BC.linear() = rotation_from_rpy(0, -M_PI / 2, 0) * R_camera_body_to_optical();
  CameraModel vga = CameraModel::from_hfov("w640x480", 640, 480, 80.0 * M_PI / 180.0);
  vga.X_BC.linear() = R_camera_body_to_optical();
  CameraModel vga_dist = vga;
  vga_dist.name = "w640x480_distorted";
  vga_dist.distortion << -0.05, 0.01, 0, 0, 0;
  CameraModel demo_front = load_camera(unav::common::find_resource("config/sensors/bluerov2_cameras.yaml"), "front");
  demo_front.name = "demo_front";
  CameraModel front_lens = demo_front;
  front_lens.name = "front_lens";
  front_lens.lens.f_number = 1.4;
  front_lens.lens.focal_length_mm = 8.0;
  front_lens.lens.focus_distance_m = 0.5;
  front_lens.lens.lateral_chromatic = 0.002;
  front_lens.white_balance.mode = "auto";
  CameraModel front_jpeg = demo_front;
  front_jpeg.name = "front_jpeg";
  front_jpeg.jpeg_quality = 90;
  const std::vector<CameraModel> cameras = {small, vga, vga_dist, demo_front, front_lens, front_jpeg};
  const char* const names[] = {"w320x180", "w640x480", "w640x480_distorted", "demo_front", "front_lens", "front_jpeg"};
  auto first_row_only = [](const std::string& cam) {
    return cam == "w640x480_distorted" || cam == "demo_front" || cam == "front_lens" || cam == "front_jpeg";
  };
  if (in_flight < 1) {
    std::fprintf(stderr, "bench_unav_renderer: --in-flight must be >= 1\n");
    return 2;
  }
  RenderOptions opt;
  opt.readback_slots = in_flight;
  Renderer r(world, cameras, opt);
  std::printf("unav_renderer bench: %s via %s, GL %s, %zu triangles, %d frames each, %d in flight when pipelined\n",
              r.context().gl_renderer().c_str(), r.context().platform().c_str(), r.context().gl_version().c_str(),
              r.triangle_count(), frames, in_flight);
  std::printf("%-34s %-20s %10s %10s %12s %10s\n", "configuration", "camera", "fps sync", "fps pipe", "median ms",
              "cpu ms/fr");
  struct Config {
    const char* name;
    RenderOptions o;
  };
  std::vector<Config> configs;
  const char* const kDefaultOptions = "full (default options)";  // its rows give the BENCH lines
  configs.push_back({kDefaultOptions, opt});
  RenderOptions o = opt;
  o.materials = false;
  configs.push_back({"no materials (flat Lambertian)", o});
  o = opt;
  o.shadow_receiver_culling = false;
  configs.push_back({"no shadow receiver culling", o});
  o = opt;
  o.shadow_caster_culling = false;
  configs.push_back({"no shadow caster culling", o});
  o = opt;
  o.occlusion_culling = false;
  configs.push_back({"no occlusion culling", o});
  o = opt;
  o.shadows = false;
  configs.push_back({"no shadows (sun, lamps)", o});
  o = opt;
  o.lamp_scatter_samples = 0;
  configs.push_back({"no lamp in-scatter", o});
  o.forward_scatter = false;
  configs.push_back({"+ no forward scatter", o});
  o.marine_snow = false;
  o.noise = false;
  configs.push_back({"+ no snow, no noise", o});
  o = opt;
  o.terrain_lod_px = 0.0;
  configs.push_back({"no LOD (full terrain, rocks)", o});
  o = opt;
  o.noise = false;
  configs.push_back({"no sensor noise", o});
  // The three culls trade CPU work for fragments (what llvmpipe lacks); none changes a pixel.
  o = opt;
  o.shadow_receiver_culling = false;
  o.shadow_caster_culling = false;
  o.occlusion_culling = false;
  configs.push_back({"no CPU culling (receiver/caster/occl.)", o});
  if (config_index < 0 || config_index >= static_cast<int>(configs.size())) {
    std::fprintf(stderr, "bench_unav_renderer: --config must be 0..%zu\n", configs.size() - 1);
    return 2;
  }
  if (callgrind) {
#ifdef UNAV_HAVE_CALLGRIND
    r.set_options(configs[static_cast<std::size_t>(config_index)].o);
    std::printf("configuration: %s\n", configs[static_cast<std::size_t>(config_index)].name);
    for (const char* cam : names) {
      if (skip(cam)) continue;
      for (int i = 0; i < 3; ++i) r.render(pose_at(i), cam, 0.1 * i);  // warm-up (shader JIT)
      CALLGRIND_START_INSTRUMENTATION;
      for (int i = 0; i < frames; ++i) r.render(pose_at(i), cam, 0.1 * i);
      CALLGRIND_STOP_INSTRUMENTATION;
      std::printf("%s: %d frames instrumented\n", cam, frames);
    }
    return 0;
#else
    (void)config_index;
    std::fprintf(stderr, "bench_unav_renderer: built without valgrind/callgrind.h (apt-get install valgrind)\n");
    return 2;
#endif
  }
  if (quick) configs = {configs[static_cast<std::size_t>(config_index)]};
  for (const auto& c : configs) {
    r.set_options(c.o);
    for (const char* cam : names) {
      if ((c.name != configs.front().name && first_row_only(cam)) || skip(cam)) continue;
      const Result res = measure(r, cam, frames);
      std::printf("%-34s %-20s %10.1f %10.1f %12.2f %10.2f\n", c.name, cam, res.fps_sync, res.fps_pipelined,
                  res.median_ms, res.cpu_ms_pipelined);
      if (c.name != kDefaultOptions) continue;
      const std::string id = std::string("renderer/") + cam;
      unav::common::print_bench(id + "_median_ms", res.median_ms, "ms");
      unav::common::print_bench(id + "_sync_fps", res.fps_sync, "fps");
      unav::common::print_bench(id + "_pipelined_fps", res.fps_pipelined, "fps");
    }
  }
  // Throughput with several contexts at once (RendererPool), alternated with one context so that
  // both see the same machine (this VM's speed drifts).
  {
    const Config& c = configs[quick ? 0 : static_cast<std::size_t>(config_index)];
    std::printf("\nframes per second of a RendererPool (%s; one EGL context and thread per worker, frames in order):\n",
                c.name);
    RendererPool one(world, cameras, c.o, 1);
    RendererPool two(world, cameras, c.o, 2);
    std::printf("(2 workers on EGL platforms %s and %s)\n", two.platforms()[0].c_str(), two.platforms()[1].c_str());
    std::printf("%-20s %10s %10s %10s\n", "camera", "1 worker", "2 workers", "gain");
    for (const char* cam : names) {
      if (skip(cam) || std::string(cam).rfind("front_", 0) == 0) continue;  // the pipeline's rows: above
      const double f1 = pool_fps(one, cam, frames), f2 = pool_fps(two, cam, frames);
      const double g1 = pool_fps(one, cam, frames), g2 = pool_fps(two, cam, frames);
      std::printf("%-20s %10.1f %10.1f %9.0f %%\n", cam, 0.5 * (f1 + g1), 0.5 * (f2 + g2),
                  100.0 * ((f2 + g2) / (f1 + g1) - 1.0));
    }
    if (only.empty()) {  // the node's ticks: both cameras at each pose
      const double f1 = pool_ticks_per_s(one, frames), f2 = pool_ticks_per_s(two, frames);
      const double g1 = pool_ticks_per_s(one, frames), g2 = pool_ticks_per_s(two, frames);
      std::printf("%-20s %10.1f %10.1f %9.0f %%   (ticks/s: demo_front + 320x180 at each pose)\n", "node pattern",
                  0.5 * (f1 + g1), 0.5 * (f2 + g2), 100.0 * ((f2 + g2) / (f1 + g1) - 1.0));
      if (c.name == kDefaultOptions) {
        unav::common::print_bench("renderer/node_pattern_1_workers_ticks_per_s", 0.5 * (f1 + g1), "ticks_per_s");
        unav::common::print_bench("renderer/node_pattern_2_workers_ticks_per_s", 0.5 * (f2 + g2), "ticks_per_s");
      }
    }
  }
  // The GPU's time for each pass (timestamp queries, nothing serialised) and the calling thread's
  // time in submit() and collect(), pipelined as a node runs it.
  {
    RenderOptions timed = configs[static_cast<std::size_t>(config_index)].o;
    timed.gpu_timers = true;
    r.set_options(timed);
    std::printf(
        "\nGPU time per pass (%s; timestamp queries, pipelined, median of %d frames) [ms], then the calling"
        " thread's wall time in submit() and collect():\n",
        configs[static_cast<std::size_t>(config_index)].name, frames);
    std::printf("%-20s %8s %8s %8s %10s %8s %10s %9s | %8s %8s\n", "camera", "shadows", "scene", "snow", "inscatter",
                "post", "readback", "gpu sum", "submit", "collect");
    for (const char* cam : names) {
      if (skip(cam)) continue;
      for (int i = 0; i < 3; ++i) r.render(pose_at(i), cam, 0.0);
      std::vector<double> g[6], sum, sub, col;
      for (int i = 0; i < frames; ++i) {
        r.submit(pose_at(i), cam, 0.1 * i);
        sub.push_back(r.last_timings().render_ms);
        if (r.in_flight() < static_cast<std::size_t>(r.options().readback_slots)) continue;
        std::optional<Frame> f = r.collect();
        if (!f) std::abort();
        r.recycle(std::move(*f));
        const RenderTimings& t = r.last_timings();
        const double v[6] = {t.gpu_shadow_ms,    t.gpu_scene_ms, t.gpu_snow_ms,
                             t.gpu_inscatter_ms, t.gpu_post_ms,  t.gpu_readback_ms};
        double s6 = 0;
        for (int k = 0; k < 6; ++k) {
          g[k].push_back(v[k]);
          s6 += v[k];
        }
        sum.push_back(s6);
        col.push_back(t.readback_ms);
      }
      while (r.collect()) {
      }
      std::printf("%-20s %8.3f %8.3f %8.3f %10.3f %8.3f %10.3f %9.3f | %8.3f %8.3f\n", cam, median(g[0]), median(g[1]),
                  median(g[2]), median(g[3]), median(g[4]), median(g[5]), median(sum), median(sub), median(col));
    }
  }
  // Where the time goes (glFinish after each pass; default options, or those of --config N).
  RenderOptions prof = configs[static_cast<std::size_t>(config_index)].o;
  prof.profile_passes = true;
  r.set_options(prof);
  std::printf(
      "\nper-pass time (%s), median of %d frames [ms] (glFinish after each pass); wall, then process CPU time:\n",
      configs[static_cast<std::size_t>(config_index)].name, frames);
  std::printf("%-20s %8s %8s %8s %10s %8s %10s | %8s %8s %8s %10s %8s %9s\n", "camera", "shadows", "scene", "snow",
              "inscatter", "post", "readback", "cpu shad", "scene", "snow", "inscatter", "post", "cpu sum");
  std::vector<std::string> lookups;
  for (const char* cam : names) {
    if (skip(cam)) continue;
    std::vector<RenderTimings> t;
    for (int i = 0; i < frames; ++i) {
      r.render(pose_at(i), cam, 0.1 * i);
      t.push_back(r.last_timings());
    }
    auto med = [&](double RenderTimings::*m) {
      std::vector<double> v;
      v.reserve(t.size());
      for (const auto& x : t) v.push_back(x.*m);
      return median(std::move(v));
    };
    auto medz = [&](std::size_t RenderTimings::*m) {
      std::vector<double> v;
      v.reserve(t.size());
      for (const auto& x : t) v.push_back(static_cast<double>(x.*m));
      return median(std::move(v));
    };
    const double cpu[5] = {med(&RenderTimings::shadow_pass_cpu_ms), med(&RenderTimings::scene_pass_cpu_ms),
                           med(&RenderTimings::snow_pass_cpu_ms), med(&RenderTimings::inscatter_pass_cpu_ms),
                           med(&RenderTimings::post_pass_cpu_ms)};
    std::printf("%-20s %8.2f %8.2f %8.2f %10.2f %8.2f %10.2f | %8.2f %8.2f %8.2f %10.2f %8.2f %9.2f\n", cam,
                med(&RenderTimings::shadow_pass_ms), med(&RenderTimings::scene_pass_ms),
                med(&RenderTimings::snow_pass_ms), med(&RenderTimings::inscatter_pass_ms),
                med(&RenderTimings::post_pass_ms), med(&RenderTimings::readback_ms), cpu[0], cpu[1], cpu[2], cpu[3],
                cpu[4], cpu[0] + cpu[1] + cpu[2] + cpu[3] + cpu[4]);
    const RenderTimings& last = t.back();
    char line[280];
    std::snprintf(
        line, sizeof line,
        "%-20s %10.0f %12.0f %10.0f (%4.1f %%) %10.0f (%4.1f %%) %10.0f %10.0f %5zu/%zu/%zu %6zu/%zu/%zu %6dx%d", cam,
        medz(&RenderTimings::scene_fragments), medz(&RenderTimings::scene_invocations),
        medz(&RenderTimings::sun_lookup_fragments),
        100.0 * medz(&RenderTimings::sun_lookup_fragments) / medz(&RenderTimings::scene_fragments),
        medz(&RenderTimings::lamp_lookup_fragments),
        100.0 * medz(&RenderTimings::lamp_lookup_fragments) / medz(&RenderTimings::scene_fragments),
        medz(&RenderTimings::lamp_map_triangles), medz(&RenderTimings::lamp_map_culled), last.terrain_tiles[0],
        last.terrain_tiles[1], last.terrain_tiles[2], last.object_parts[0], last.object_parts[1], last.object_parts[2],
        last.internal_width, last.internal_height);
    lookups.emplace_back(line);
  }
  std::printf(
      "\nscene fragments per frame (median; shaded: fragment shader invocations, llvmpipe counts 4x4 blocks)"
      " and those with shadow lookups (receiver culling on); triangles drawn into the lamps' shadow maps and those"
      " caster culling left out; terrain tiles in view (last frame) by level of detail, every point / 2nd / 4th,"
      " and rocks by level (320 / 80 / 20 triangles);"
      " the internal (undistorted, water-side) image the scene is rendered at:\n");
  std::printf("%-20s %10s %12s %19s %19s %10s %10s %s %s %s\n", "camera", "fragments", "shaded", "sun lookups",
              "lamp lookups", "lamp map", "culled", "   LOD tiles", "  rocks LOD", "  internal");
  for (const auto& l : lookups) std::puts(l.c_str());
  return 0;
}
