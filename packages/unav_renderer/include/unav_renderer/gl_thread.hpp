// A thread that owns GL work. An EGL context is current on one thread at a time, so work for a
// context (creating it, renderers on it, their frames, their destruction) goes to the thread
// that made it current: run() executes a function there and waits for it; post() does not wait.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "unav_renderer/egl_context.hpp"

namespace unav::renderer {

class GlThread {
 public:
  GlThread();
  ~GlThread();  ///< runs what was posted, then joins
  GlThread(const GlThread&) = delete;
  GlThread& operator=(const GlThread&) = delete;

  /// Runs `fn` on this thread and waits; rethrows what it throws.
  void run(std::function<void()> fn);
  /// Queues `fn` (in order); the future carries its exception.
  std::future<void> post(std::function<void()> fn);

 private:
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::packaged_task<void()>> jobs_;
  bool stop_ = false;
  std::thread thread_;
};

/// On llvmpipe every context of one EGL display shares one set of rasterizer threads, which runs
/// the scenes of all of them one after the other; Mesa's surfaceless display has a set of its own.
/// For renderers that should run beside those of `first` (made with EglOptions::Platform::kAuto):
/// a context on the surfaceless display when `first` is llvmpipe on another display and the
/// surfaceless one is the same driver (the same images), else nullptr (use `first`'s display).
/// Call it on the thread that will own the new context.
std::shared_ptr<EglContext> second_llvmpipe_display(const EglContext& first);

}  // namespace unav::renderer
