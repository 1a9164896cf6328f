#include "unav_renderer/renderer_pool.hpp"

#include <algorithm>
#include <chrono>
#include <deque>
#include <future>
#include <stdexcept>
#include <utility>

#include "unav_renderer/errors.hpp"
#include "unav_renderer/gl_thread.hpp"

namespace unav::renderer {

namespace {

// One renderer and the GL thread that owns its context: built, used and destroyed there.
struct Worker {
  GlThread gl;  // declared first: joined last, after the renderer is gone
  std::unique_ptr<Renderer> renderer;

  // beside: a context whose rasterizer threads this one should not share (second_llvmpipe_display()).
  // Rethrows the Renderer's construction error.
  Worker(const World& world, const std::vector<CameraModel>& cameras, const RenderOptions& options,
         const EglContext* beside) {
    gl.run([&] {
      std::shared_ptr<EglContext> ctx = beside ? second_llvmpipe_display(*beside) : nullptr;
      renderer = ctx ? std::make_unique<Renderer>(world, cameras, options, std::move(ctx))
                     : std::make_unique<Renderer>(world, cameras, options);
    });
  }
  ~Worker() {
    gl.run([this] { renderer.reset(); });  // after the frames queued before it
  }
};

}  // namespace

struct RendererPool::Impl {
  std::vector<std::unique_ptr<Worker>> workers;
  std::deque<std::future<Frame>> pending;  // in submission order
  std::uint64_t sequence = 0;
  std::size_t next_worker = 0;
  std::size_t next_recycle = 0;
};

RendererPool::RendererPool(const World& world, const std::vector<CameraModel>& cameras, const RenderOptions& options,
                           int workers)
    : impl_(std::make_unique<Impl>()) {
  if (workers < 1) throw ConfigError("RendererPool", "workers", std::to_string(workers), "must be >= 1");
  // One at a time: each construction (geometry, textures, shader compilation) uses the machine's
  // cores, and an error stops the rest.
  impl_->workers.push_back(std::make_unique<Worker>(world, cameras, options, nullptr));
  // On llvmpipe the odd workers take a second EGL display, whose rasterizer threads fill the
  // first's idle time (second_llvmpipe_display(); only when the platform was left to choose).
  const EglContext* first = &impl_->workers.front()->renderer->context();
  const bool alternate = options.egl.platform == EglOptions::Platform::kAuto;
  for (int k = 1; k < workers; ++k)
    impl_->workers.push_back(
        std::make_unique<Worker>(world, cameras, options, alternate && k % 2 == 1 ? first : nullptr));
}

RendererPool::~RendererPool() = default;

std::uint64_t RendererPool::submit(const Pose& X_WB, const std::string& camera, double stamp_s,
                                   const BodyVelocity& velocity) {
  Impl& I = *impl_;
  if (I.pending.size() >= 2 * I.workers.size()) I.pending.front().wait();
  const std::uint64_t seq = I.sequence++;
  Worker& w = *I.workers[I.next_worker];
  I.next_worker = (I.next_worker + 1) % I.workers.size();
  auto result = std::make_shared<std::promise<Frame>>();  // std::function needs a copyable job
  I.pending.push_back(result->get_future());
  w.gl.post([r = w.renderer.get(), X_WB, camera, stamp_s, velocity, seq, result] {
    try {
      r->set_next_sequence(seq);
      result->set_value(r->render(X_WB, camera, stamp_s, velocity));
    } catch (...) {
      result->set_exception(std::current_exception());
    }
  });
  return seq;
}

Frame RendererPool::collect() {
  Impl& I = *impl_;
  if (I.pending.empty()) throw std::logic_error("RendererPool::collect: no frame in flight");
  std::future<Frame> f = std::move(I.pending.front());
  I.pending.pop_front();
  return f.get();
}

void RendererPool::recycle(Frame&& frame) {
  Impl& I = *impl_;
  I.workers[I.next_recycle]->renderer->recycle(std::move(frame));  // thread-safe
  I.next_recycle = (I.next_recycle + 1) % I.workers.size();
}

std::size_t RendererPool::in_flight() const { return impl_->pending.size(); }

bool RendererPool::ready() const {
  const auto& p = impl_->pending;
  return !p.empty() && p.front().wait_for(std::chrono::seconds(0)) == std::future_status::ready;
}
int RendererPool::workers() const { return static_cast<int>(impl_->workers.size()); }
void RendererPool::set_next_sequence(std::uint64_t sequence) { impl_->sequence = sequence; }
void RendererPool::set_object_pose(const std::string& name, const Pose& X_WO) {
  // Checked here, so that the workers' queued moves cannot fail (their world is this one).
  const World& world = impl_->workers.front()->renderer->world();
  const bool known = std::any_of(world.objects.begin(), world.objects.end(),
                                 [&](const Object& o) { return o.movable && o.name == name; });
  if (!known)
    throw ConfigError("RendererPool::set_object_pose", "name", name,
                      "no movable object of that name in world '" + world.name + "'");
  if (!X_WO.matrix().allFinite())
    throw ConfigError("RendererPool::set_object_pose", name, "non-finite pose", "the pose must be finite");
  for (auto& w : impl_->workers)  // queued before the frames submitted after this call
    w->gl.post([r = w->renderer.get(), name, X_WO] { r->set_object_pose(name, X_WO); });
}
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
