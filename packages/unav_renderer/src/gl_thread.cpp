#include "unav_renderer/gl_thread.hpp"

#include <utility>

#include "unav_renderer/errors.hpp"

namespace unav::renderer {

GlThread::GlThread() {
  thread_ = std::thread([this] {
    for (;;) {
      std::packaged_task<void()> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
        if (jobs_.empty()) return;  // stopped, nothing left
        job = std::move(jobs_.front());
        jobs_.pop_front();
      }
      job();  // its exception goes to its future
    }
  });
}

GlThread::~GlThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

std::future<void> GlThread::post(std::function<void()> fn) {
  std::packaged_task<void()> job(std::move(fn));
  std::future<void> done = job.get_future();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_.push_back(std::move(job));
  }
  wake_.notify_one();
  return done;
}

void GlThread::run(std::function<void()> fn) { post(std::move(fn)).get(); }

std::shared_ptr<EglContext> second_llvmpipe_display(const EglContext& first) {
  if (first.gl_renderer().find("llvmpipe") == std::string::npos || first.platform() == "surfaceless") return nullptr;
  EglOptions o;
  o.platform = EglOptions::Platform::kSurfaceless;
  std::shared_ptr<EglContext> second;
  try {
    second = EglContext::create(o);
  } catch (const EglError&) {
    return nullptr;  // no surfaceless platform here
  }
  if (second->gl_renderer() != first.gl_renderer()) return nullptr;
  return second;
}

}  // namespace unav::renderer
