#include "unav_renderer/renderer.hpp"

#include "renderer_impl.hpp"

#include <algorithm>
#include <stdexcept>

#include "shaders.hpp"
#include "textures.hpp"
#include "unav_renderer/errors.hpp"

namespace unav::renderer {
namespace {

void validate_options(const RenderOptions& o, const std::string& where) {
  if (o.shadow_map_size < 16 || o.shadow_map_size > 8192)
    throw ConfigError(where, "shadow_map_size", std::to_string(o.shadow_map_size), "must be in [16, 8192] px");
  if (!(o.shadow_bias >= 0.0) || !std::isfinite(o.shadow_bias))
    throw ConfigError(where, "shadow_bias", std::to_string(o.shadow_bias), "must be finite and >= 0");
  if (!(o.terrain_lod_px >= 0.0) || !std::isfinite(o.terrain_lod_px))
    throw ConfigError(where, "terrain_lod_px", std::to_string(o.terrain_lod_px),
                      "must be finite and >= 0 (0: terrain always at full detail)");
  if (o.lamp_scatter_downsample < 1)
    throw ConfigError(where, "lamp_scatter_downsample", std::to_string(o.lamp_scatter_downsample), "must be >= 1");
  // A compile-time count in the in-scatter shader (one program per value).
  if (o.lamp_scatter_samples < 0 || o.lamp_scatter_samples > 256)
    throw ConfigError(where, "lamp_scatter_samples", std::to_string(o.lamp_scatter_samples),
                      "must be in [0, 256] (0: no lamp in-scattering)");
}

}  // namespace

void Renderer::Impl::draw(const Pose& X_WB, const CameraModel& out_cam, double stamp_s, std::uint64_t seq,
                          const GLuint* stamps) {
  Targets& t = targets_for(out_cam);
  const CameraModel& c = t.internal;
  const FrameSetup f = setup_frame(X_WB, c);
  timings.internal_width = t.width;
  timings.internal_height = t.height;
  auto tp = Clock::now();
  double cpu = options.profile_passes ? process_cpu_ms() : 0.0;
  int stamp = 0;
  if (stamps) glQueryCounter(stamps[stamp++], GL_TIMESTAMP);
  auto lap = [&](double* out, double* out_cpu) {
    if (stamps) glQueryCounter(stamps[stamp++], GL_TIMESTAMP);
    if (!options.profile_passes) return;
    glFinish();
    *out = ms_since(tp);
    *out_cpu = process_cpu_ms() - cpu;
    tp = Clock::now();
    cpu = process_cpu_ms();
  };
  shadow_pass(f);
  lap(&timings.shadow_pass_ms, &timings.shadow_pass_cpu_ms);
  scene_pass(t, f, stamp_s);
  lap(&timings.scene_pass_ms, &timings.scene_pass_cpu_ms);
  snow_pass(f, c, stamp_s);  // when marine snow is on
  lap(&timings.snow_pass_ms, &timings.snow_pass_cpu_ms);
  float march_max_m = 0.0f;
  const bool do_inscatter = inscatter_pass(t, f, c, &march_max_m);
  lap(&timings.inscatter_pass_ms, &timings.inscatter_pass_cpu_ms);
  post_pass(t, f, c, seq, do_inscatter, march_max_m);
  lap(&timings.post_pass_ms, &timings.post_pass_cpu_ms);
}

Renderer::Renderer(World world, std::vector<CameraModel> cameras, RenderOptions options)
    : Renderer(std::move(world), std::move(cameras), options, nullptr) {}

Renderer::Renderer(World world, std::vector<CameraModel> cameras, RenderOptions options,
                   std::shared_ptr<EglContext> context)
    : impl_(std::make_unique<Impl>()) {
  impl_->world = std::move(world);
  impl_->cameras = std::move(cameras);
  impl_->options = options;
  impl_->water = impl_->world.water;
  validate_options(options, "RenderOptions");
  for (const auto& c : impl_->cameras) c.validate("Renderer");
  for (std::size_t i = 0; i < impl_->cameras.size(); ++i)
    for (std::size_t j = i + 1; j < impl_->cameras.size(); ++j)
      if (impl_->cameras[i].name == impl_->cameras[j].name)
        throw ConfigError("Renderer: duplicate camera name '" + impl_->cameras[i].name + "'");
  // Geometry first: a bad mesh file is reported before any GL work.
  const SceneGeometry geo = build_scene_geometry(impl_->world);
  impl_->ctx = context ? std::move(context) : std::shared_ptr<EglContext>(EglContext::create(options.egl));
  impl_->ctx->make_current();
  impl_->software_gl = impl_->ctx->software();
  glGenVertexArrays(1, &impl_->empty_vao);
  impl_->shadow_nearest = nearest_sampler();
  glSamplerParameteri(impl_->shadow_nearest, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glSamplerParameteri(impl_->shadow_nearest, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  impl_->nearest = nearest_sampler();
  impl_->mip_nearest = mip_nearest_sampler();
  impl_->self_test();
  // Scene programs are compiled per material variant on first use (scene_program()); the plain one now.
  impl_->scene_variants[0] = Program(detail::kSceneVS, detail::kSceneFS, "scene", scene_defines(0));
  // The lamp count's programs now: a shader error shows here, not in the first frame.
  const int nlamps = static_cast<int>(std::min<std::size_t>(4, impl_->world.lamps.size()));
  impl_->snow_program(nlamps);
  // A common one (geometry pixels of a pinhole camera with read noise): a shader error shows here.
  impl_->post_program({false, true, true, false, false, true, false, false, false}, 1);
  if (nlamps > 0) impl_->inscatter_program(nlamps, std::max(1, options.lamp_scatter_samples), true);
  impl_->shadow = Program(detail::kShadowVS, detail::kShadowFS, "lamp_shadow");
  impl_->blur_down = Program(detail::kPostVS, detail::kBlurDownFS, "forward_scatter_blur");
  impl_->upload_scene(geo);
  impl_->upload_snow();
  impl_->slots.resize(static_cast<std::size_t>(std::max(1, options.readback_slots)));
  check_gl("Renderer setup");
}

void Renderer::Impl::release_scene() {
  for (auto& [image, t] : image_textures) glDeleteTextures(1, &t);
  image_textures.clear();
  mesh_images.clear();
  for (auto& m : meshes) {
    glDeleteBuffers(4, m.vbo);
    glDeleteBuffers(1, &m.ebo);
    glDeleteVertexArrays(1, &m.vao);
  }
  meshes.clear();
  if (snow_vao) glDeleteVertexArrays(1, &snow_vao);
  if (snow_vbo) glDeleteBuffers(1, &snow_vbo);
  snow_vao = snow_vbo = 0;
  snow_count = 0;
}

void Renderer::set_world(World world) {
  Impl& I = *impl_;
  // Geometry first: a bad world leaves the current scene in place.
  const SceneGeometry geo = build_scene_geometry(world);
  world.water.validate("Renderer::set_world");
  I.ctx->make_current();
  while (!I.in_flight.empty()) I.collect_oldest();  // frames of the old scene stay collectable
  I.release_scene();
  I.sun_vp_cached.clear();  // a new scene: the sun's shadow map is stale
  I.world = std::move(world);
  I.water = I.world.water;
  I.upload_scene(geo);
  I.upload_snow();
  check_gl("Renderer::set_world");
}

Renderer::~Renderer() {
  if (!impl_ || !impl_->ctx) return;
  try {
    impl_->ctx->make_current();
  } catch (...) {
    return;
  }
  for (auto& s : impl_->slots) {
    if (s.fence) glDeleteSync(s.fence);
    if (s.pbo_rgba) glDeleteBuffers(1, &s.pbo_rgba);
    if (s.pbo_depth) glDeleteBuffers(1, &s.pbo_depth);
    if (s.stamps[0]) glDeleteQueries(kStamps, s.stamps);
  }
  for (auto& [name, t] : impl_->targets) {
    GLuint fbos[6] = {t.scene_fbo, t.post_fbo, t.is_fbo, t.blur_fbo[0], t.blur_fbo[1], t.lin_fbo};
    glDeleteFramebuffers(static_cast<GLsizei>(std::size(fbos)), fbos);
    GLuint texs[11] = {t.scene_color,  t.scene_zc,    t.scene_depth, t.post_rgba, t.post_zc, t.distmap,
                       t.is_water_tex, t.blur_tex[0], t.blur_tex[1], t.is_tex,    t.lin_tex};
    glDeleteTextures(static_cast<GLsizei>(std::size(texs)), texs);
  }
  impl_->release_scene();
  for (auto& [name, maps] : impl_->textures) {
    glDeleteTextures(1, &maps.colour);
    glDeleteTextures(1, &maps.slope);
  }
  glDeleteVertexArrays(1, &impl_->empty_vao);
  glDeleteSamplers(1, &impl_->shadow_nearest);
  glDeleteSamplers(1, &impl_->mip_nearest);
  glDeleteSamplers(1, &impl_->nearest);
  if (impl_->fragment_query) glDeleteQueries(1, &impl_->fragment_query);
  if (impl_->invocation_query) glDeleteQueries(1, &impl_->invocation_query);
  for (const auto& [v, p] : impl_->scene_variants)
    if (p.id()) glDeleteProgram(p.id());
  glDeleteProgram(impl_->shadow.id());
  glDeleteProgram(impl_->blur_down.id());
  if (impl_->shadow_tex) glDeleteTextures(1, &impl_->shadow_tex);
  if (impl_->sun_tex) glDeleteTextures(1, &impl_->sun_tex);
  if (impl_->shadow_fbo) glDeleteFramebuffers(1, &impl_->shadow_fbo);
  for (const auto& kv : impl_->snow_variants) glDeleteProgram(kv.second.id());
  for (const auto& kv : impl_->post_variants) glDeleteProgram(kv.second.id());
  for (const auto& kv : impl_->inscatter_variants) glDeleteProgram(kv.second.id());
}

void Renderer::submit(const Pose& X_WB, const std::string& camera, double stamp_s, const BodyVelocity& velocity) {
  Impl& I = *impl_;
  const CameraModel& c = I.cam(camera);
  I.ctx->make_current();
  if (I.in_flight.size() >= I.slots.size()) I.collect_oldest();
  const auto t0 = Clock::now();
  const std::uint64_t seq = I.sequence++;
  I.velocity = velocity;
  const std::size_t idx = I.next_slot;
  I.next_slot = (I.next_slot + 1) % I.slots.size();
  Slot& s = I.slots[idx];
  s.timed = I.options.gpu_timers;
  if (s.timed && s.stamps[0] == 0) glGenQueries(kStamps, s.stamps);
  I.draw(X_WB, c, stamp_s, seq, s.timed ? s.stamps : nullptr);
  s.meta = Frame{};
  s.meta.camera = c.name;
  s.meta.stamp_s = stamp_s;
  s.meta.sequence = seq;
  s.meta.width = c.width;
  s.meta.height = c.height;
  const Targets& t = I.targets.at(c.name);  // made by draw()
  s.meta.K = t.seen.K();
  s.meta.D = t.seen.distortion;
  s.meta.X_WC = X_WB * c.X_BC;
  s.jpeg_quality = c.jpeg_quality;
  I.start_readback(s, t);
  I.in_flight.push_back(idx);
  I.timings.render_ms = ms_since(t0);
}

std::optional<Frame> Renderer::collect() {
  Impl& I = *impl_;
  if (I.done.empty() && !I.in_flight.empty()) {
    I.ctx->make_current();
    I.collect_oldest();
  }
  if (I.done.empty()) return std::nullopt;
  Frame f = std::move(I.done.front());
  I.done.pop_front();
  return f;
}

void Renderer::recycle(Frame&& frame) {
  Impl& I = *impl_;
  const std::lock_guard<std::mutex> lock(I.spare_mutex);
  if (I.spare.size() >= static_cast<std::size_t>(I.options.readback_slots) + 2) return;
  Frame b;  // the buffers only
  b.rgb = std::move(frame.rgb);
  b.seg = std::move(frame.seg);
  b.depth = std::move(frame.depth);
  I.spare.push_back(std::move(b));
}

std::size_t Renderer::in_flight() const { return impl_->in_flight.size() + impl_->done.size(); }

Frame Renderer::render(const Pose& X_WB, const std::string& camera, double stamp_s, const BodyVelocity& velocity) {
  Impl& I = *impl_;
  I.ctx->make_current();
  while (!I.in_flight.empty()) I.collect_oldest();  // keep earlier async frames for collect()
  submit(X_WB, camera, stamp_s, velocity);
  I.collect_oldest();
  Frame f = std::move(I.done.back());
  I.done.pop_back();
  return f;
}

void Renderer::set_water(const WaterModel& water) {
  water.validate("Renderer::set_water");
  impl_->water = water;
}
const WaterModel& Renderer::water() const { return impl_->water; }
void Renderer::set_next_sequence(std::uint64_t sequence) { impl_->sequence = sequence; }
void Renderer::set_options(const RenderOptions& options) {
  validate_options(options, "Renderer::set_options");
  const EglOptions egl = impl_->options.egl;
  const int tex = impl_->options.texture_size, slots = impl_->options.readback_slots;
  impl_->options = options;
  impl_->options.egl = egl;
  impl_->options.texture_size = tex;
  impl_->options.readback_slots = slots;
}
void Renderer::set_object_pose(const std::string& name, const Pose& X_WO) {
  Impl& I = *impl_;
  const auto it = I.movable.find(name);
  if (it == I.movable.end()) {
    std::string names;
    for (const auto& [n, parts] : I.movable) names += (names.empty() ? "" : ", ") + n;
    throw ConfigError("Renderer::set_object_pose", "name", name,
                      "no movable object of that name in world '" + I.world.name +
                          "' (movable: " + (names.empty() ? "none" : names) + ")");
  }
  if (!X_WO.matrix().allFinite())
    throw ConfigError("Renderer::set_object_pose", name, "non-finite pose", "the pose must be finite");
  I.ctx->make_current();
  I.move_object(it->second, X_WO);
}

const RenderOptions& Renderer::options() const { return impl_->options; }
const World& Renderer::world() const { return impl_->world; }
const CameraModel& Renderer::camera(const std::string& name) const { return impl_->cam(name); }
std::vector<std::string> Renderer::camera_names() const {
  std::vector<std::string> n;
  for (const auto& c : impl_->cameras) n.push_back(c.name);
  return n;
}
const EglContext& Renderer::context() const { return *impl_->ctx; }
std::shared_ptr<EglContext> Renderer::shared_context() const { return impl_->ctx; }
RenderTimings Renderer::last_timings() const { return impl_->timings; }
std::size_t Renderer::triangle_count() const { return impl_->triangles; }
Pose Renderer::camera_pose(const Pose& X_WB, const std::string& camera) const { return X_WB * impl_->cam(camera).X_BC; }

}  // namespace unav::renderer
