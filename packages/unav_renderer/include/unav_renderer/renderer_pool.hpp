// Several Renderers at once, each with its own EGL context on its own thread, for throughput.
//
// On llvmpipe one context leaves cores idle: every pass that reads the previous pass's output
// (the scene reads the shadow maps, the post pass the scene) waits for the rasterizer threads to
// finish, and the next pass's vertex work and binning then run on one thread while they idle.
// Two contexts fill those gaps with each other's work (measured on the 2-core machine: about
// +30 % frames per second at 640x480; see the renderer README). On a GPU it overlaps the CPU-side
// work (readback copies, PNG encoding by the caller) with rendering.
//
// Frames come back in submission order, and each is the same, bit for bit, as one Renderer's
// frame for the same pose, camera, stamp, velocity and sequence number (the noise is a function
// of the seed and the sequence number only): a dataset rendered by a pool is the dataset
// rendered by one Renderer.
//
// Threading: submit()/collect() from one thread. Each worker builds its Renderer (its context,
// meshes and textures: the memory of one Renderer per worker) on its own thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "unav_renderer/renderer.hpp"

namespace unav::renderer {

class RendererPool {
 public:
  /// `workers` >= 1 renderers (ConfigError otherwise); a Renderer's construction error (bad world,
  /// no EGL) is thrown here.
  RendererPool(const World& world, const std::vector<CameraModel>& cameras, const RenderOptions& options = {},
               int workers = 2);
  ~RendererPool();  ///< waits for the frames in flight, then stops the workers
  RendererPool(const RendererPool&) = delete;
  RendererPool& operator=(const RendererPool&) = delete;

  /// Queues a frame on the next worker (round robin) with the next sequence number; returns that
  /// number. With 2 x workers() frames or more in flight, first waits until the oldest is
  /// rendered (collect() them: the frames wait in the pool until then).
  std::uint64_t submit(const Pose& X_WB, const std::string& camera, double stamp_s = 0.0,
                       const BodyVelocity& velocity = {});
  /// The oldest frame submitted, waiting for it; rethrows the error its worker met. Throws
  /// std::logic_error when nothing is in flight.
  Frame collect();
  /// Optional: a frame's pixel buffers back to a worker, for a later frame (Renderer::recycle()).
  void recycle(Frame&& frame);
  std::size_t in_flight() const;
  /// True when a frame is in flight and the oldest is rendered: collect() returns at once.
  bool ready() const;
  int workers() const;
  /// The sequence number of the next submit() (the noise's frame index), as Renderer's.
  void set_next_sequence(std::uint64_t sequence);
  /// Renderer::set_object_pose on every worker, for the frames submitted from now on. Throws
  /// ConfigError (as Renderer's) on the calling thread.
  void set_object_pose(const std::string& name, const Pose& X_WO);
  /// The first worker's renderer info (GL renderer string, cameras): all workers are alike.
  const CameraModel& camera(const std::string& name) const;
  std::string gl_renderer() const;
  std::size_t triangle_count() const;
  /// Each worker's EGL platform ("device[0]", "surfaceless"): on llvmpipe, left to choose
  /// (EglOptions::Platform::kAuto), the odd workers take Mesa's surfaceless display, whose
  /// rasterizer threads are not the device display's (see renderer_pool.cpp).
  std::vector<std::string> platforms() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace unav::renderer
