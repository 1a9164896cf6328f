#include "unav_renderer/renderer_pool.hpp"

#include <condition_variable>
#include <deque>
#include <future>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>

#include "unav_renderer/errors.hpp"
#include "unav_renderer/gl_thread.hpp"

namespace unav::renderer {

namespace {

struct Job {
  Pose X_WB = Pose::Identity();
  std::string camera;
  double stamp_s = 0.0;
  BodyVelocity velocity;
  std::uint64_t sequence = 0;
  std::promise<Frame> result;
};

// One renderer and the thread that owns its context (made current there, and only there).
struct Worker {
  std::thread thread;
  std::mutex mutex;
  std::condition_variable wake;
  std::deque<Job> jobs;
  bool stop = false;
  std::unique_ptr<Renderer> renderer;  // built and destroyed on `thread`

  ~Worker() {  // renders what is queued, then stops
    {
      std::lock_guard<std::mutex> lock(mutex);
      stop = true;
    }
    wake.notify_one();
    if (thread.joinable()) thread.join();
  }

  // beside: a context whose rasterizer threads this one should not share (second_llvmpipe_display()).
  void run(const World& world, const std::vector<CameraModel>& cameras, const RenderOptions& options,
           const EglContext* beside, std::promise<void>* ready) {
    try {
      std::shared_ptr<EglContext> ctx = beside ? second_llvmpipe_display(*beside) : nullptr;
      renderer = ctx ? std::make_unique<Renderer>(world, cameras, options, std::move(ctx))
                     : std::make_unique<Renderer>(world, cameras, options);
    } catch (...) {
      ready->set_exception(std::current_exception());
      return;
    }
    ready->set_value();
    for (;;) {
      Job job;
      {
        std::unique_lock<std::mutex> lock(mutex);
        wake.wait(lock, [this] { return stop || !jobs.empty(); });
        if (jobs.empty()) break;  // stop, and nothing left to render
        job = std::move(jobs.front());
        jobs.pop_front();
      }
      try {
        renderer->set_next_sequence(job.sequence);
        job.result.set_value(renderer->render(job.X_WB, job.camera, job.stamp_s, job.velocity));
      } catch (...) {
        job.result.set_exception(std::current_exception());
      }
    }
    renderer.reset();  // its context is current on this thread
  }
};

// Starts a worker and waits for its Renderer (one at a time: each construction - geometry,
// textures, shader compilation - uses the machine's cores); rethrows its construction error.
std::unique_ptr<Worker> start_worker(const World& world, const std::vector<CameraModel>& cameras,
                                     const RenderOptions& options, const EglContext* beside) {
  auto w = std::make_unique<Worker>();
  std::promise<void> ready;
  std::future<void> built = ready.get_future();
  Worker* raw = w.get();
  w->thread = std::thread(
      [raw, &world, &cameras, &options, beside, &ready] { raw->run(world, cameras, options, beside, &ready); });
  built.get();  // on error the thread has returned: ~Worker joins it
  return w;
}

}  // namespace

struct RendererPool::Impl {
  std::vector<std::unique_ptr<Worker>> workers;
  std::deque<std::future<Frame>> pending;  // in submission order
  std::uint64_t sequence = 0;
  std::size_t next_worker = 0;
};

RendererPool::RendererPool(World world, std::vector<CameraModel> cameras, RenderOptions options, int workers)
    : impl_(std::make_unique<Impl>()) {
  if (workers < 1) throw ConfigError("RendererPool", "workers", std::to_string(workers), "must be >= 1");
  impl_->workers.push_back(start_worker(world, cameras, options, nullptr));
  // On llvmpipe the odd workers take a second EGL display, whose rasterizer threads fill the
  // first's idle time (second_llvmpipe_display(); only when the platform was left to choose).
  const EglContext* first = &impl_->workers.front()->renderer->context();
  const bool alternate = options.egl.platform == EglOptions::Platform::kAuto;
  for (int k = 1; k < workers; ++k)
    impl_->workers.push_back(start_worker(world, cameras, options, alternate && k % 2 == 1 ? first : nullptr));
}

RendererPool::~RendererPool() = default;

std::uint64_t RendererPool::submit(const Pose& X_WB, const std::string& camera, double stamp_s,
                                   const BodyVelocity& velocity) {
  Impl& I = *impl_;
  if (I.pending.size() >= 2 * I.workers.size()) I.pending.front().wait();
  Job job;
  job.X_WB = X_WB;
  job.camera = camera;
  job.stamp_s = stamp_s;
  job.velocity = velocity;
  job.sequence = I.sequence++;
  I.pending.push_back(job.result.get_future());
  Worker& w = *I.workers[I.next_worker];
  I.next_worker = (I.next_worker + 1) % I.workers.size();
  {
    std::lock_guard<std::mutex> lock(w.mutex);
    w.jobs.push_back(std::move(job));
  }
  w.wake.notify_one();
  return I.sequence - 1;
}

Frame RendererPool::collect() {
  Impl& I = *impl_;
  if (I.pending.empty()) throw std::logic_error("RendererPool::collect: no frame in flight");
  std::future<Frame> f = std::move(I.pending.front());
  I.pending.pop_front();
  return f.get();
}

std::size_t RendererPool::in_flight() const { return impl_->pending.size(); }
int RendererPool::workers() const { return static_cast<int>(impl_->workers.size()); }
void RendererPool::set_next_sequence(std::uint64_t sequence) { impl_->sequence = sequence; }
const CameraModel& RendererPool::camera(const std::string& name) const {
  return impl_->workers.front()->renderer->camera(name);
}
std::vector<std::string> RendererPool::platforms() const {
  std::vector<std::string> p;
  for (const auto& w : impl_->workers) p.push_back(w->renderer->context().platform());
  return p;
}
std::size_t RendererPool::triangle_count() const { return impl_->workers.front()->renderer->triangle_count(); }
std::string RendererPool::gl_renderer() const { return impl_->workers.front()->renderer->context().gl_renderer(); }

}  // namespace unav::renderer
