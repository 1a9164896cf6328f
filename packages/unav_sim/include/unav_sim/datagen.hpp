// Synthetic data at scale, in process: one randomized sample of a RandomizationSpec rendered by
// an Episode (physics + MPC + renderer, no DDS) into a dataset folder with its manifest.
//
//   <out>/sample_000003/            a finished sample: the dataset layout (tum/euroc/kitti),
//       world/world.yaml            the sample's world (and current.yaml), re-runnable over DDS
//       manifest.json               written last; its presence marks the sample finished
//   <out>/.sample_000003.partial/   a sample being written (or interrupted: never counted)
//
// The vehicle flies the sample's path closed loop: a setpoint moving along the path at
// trajectory.speed_mps, the MPC + allocator + physics following it (currents included), the
// camera rendering at output.rate_hz. The IMU (noise-free, at the control rate) is the
// simulator's specific force and angular rate.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "unav_datagen/randomization.hpp"

namespace unav::sim {

struct SampleResult {
  bool finished = false;  ///< false: stopped by `stop` (the partial folder is left, marked incomplete)
  std::uint64_t frames = 0;
  std::string dir;      ///< the finished sample's folder
  double wall_s = 0.0;  ///< time spent on this sample
  int solver_failures = 0;
};

/// Folder name of sample `index`: "sample_000003".
std::string sample_name(std::uint64_t index);
/// True when `<out>/sample_<index>/manifest.json` exists (the sample is finished).
bool sample_finished(const std::string& out, std::uint64_t index);

/// Generates sample `index` into `out`. `stop` (may be null) is polled between frames;
/// `on_frame(frames_done)` is called after each frame (may be empty). Throws ConfigError /
/// DatasetError / renderer errors; an interrupted or failed sample leaves no finished folder.
SampleResult generate_sample(const unav::datagen::RandomizationSpec& spec, std::uint64_t index, const std::string& out,
                             const std::atomic<bool>* stop = nullptr,
                             const std::function<void(std::uint64_t)>& on_frame = {});

}  // namespace unav::sim
