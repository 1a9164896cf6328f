#include "unav_renderer/sonar_renderer.hpp"

#include <epoxy/gl.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "gl_util.hpp"
#include "shaders.hpp"
#include "unav_common/frames.hpp"
#include "unav_common/sampling.hpp"
#include "unav_renderer/errors.hpp"
#include "unav_renderer/sonar_speckle.hpp"
#include "unav_scene/scene_geometry.hpp"

namespace unav::renderer {

using unav::scene::CameraModel;
using unav::scene::Pose;
using unav::scene::SonarModel;
using unav::scene::World;

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

constexpr double kMaxSliceRad = 32.0 * M_PI / 180.0;
constexpr int kSideScanColumns = 4;  // along-track samples of a side-scan strip

// The workspace's SplitMix64: a seeded stream for the noise, identical on every platform.
struct SplitMix : unav::common::SplitMix64 {
  double exponential() { return -std::log(1.0 - Uniform01()); }  // mean 1: |Rayleigh|^2
};

struct GpuMesh {
  GLuint vao = 0, vbo[2] = {0, 0}, ebo = 0;
  GLsizei index_count = 0;
  float mu = 0.0f;
};

// One perspective slice of a head's aperture, drawn into columns [x0, x0 + cols) of the FBO.
struct Slice {
  int x0 = 0, cols = 0;
  Eigen::Matrix3d R_HC = Eigen::Matrix3d::Identity();  // slice optical frame in the head frame
  CameraModel cam;                                     // its pinhole (projection_from_K)
};

struct Head {
  Pose X_BH = Pose::Identity();
  int channel0 = 0;  // first message channel of this head
  std::vector<Slice> slices;
};

struct SonarState {
  SonarModel model;
  std::vector<Head> heads;
  int width = 0, rows = 0;
  GLuint fbo = 0, color = 0, depth = 0;
  // Per FBO pixel (row-major, top row first): channel (-1 = outside the aperture) and weight
  // dOmega b(el)^2 / (beam width); the slice each column belongs to (for the footprint).
  std::vector<int> channel;
  std::vector<float> weight;
  std::vector<int> column_slice;
  mutable std::vector<float> speckle;  // the ping's speckle field (reused)
  std::vector<float> readback;         // RGBA32F
};

// Slice geometry and the per-pixel tables of a sonar (no GL).
void plan_sonar(SonarState* st) {
  const SonarModel& m = st->model;
  const std::vector<Pose> heads = m.head_poses();
  const double H = m.horizontal_aperture_rad, V = m.vertical_aperture_rad;
  const int n_slices = m.side_scan() ? 1 : std::max(1, static_cast<int>(std::ceil(H / kMaxSliceRad - 1e-9)));
  const double w = H / n_slices;
  const int cols_per_slice =
      m.side_scan() ? kSideScanColumns : std::max(2, (m.beams * m.beam_oversample + n_slices - 1) / n_slices);
  const int rows = m.vertical_samples > 0
                       ? m.vertical_samples
                       : (m.side_scan() ? std::clamp(m.bins / 2, 64, 1024) : std::clamp(m.bins / 4, 64, 512));
  st->rows = rows;
  st->width = static_cast<int>(heads.size()) * n_slices * cols_per_slice;
  const double tan_w = std::tan(0.5 * w);
  // Rows reach elevation V/2 at the slice's side edges too (there the elevation of a row is lower).
  const double tan_v = std::tan(0.5 * V) * std::sqrt(1.0 + tan_w * tan_w);
  const double far = m.max_range_m * 2.5;
  const double near = std::clamp(0.5 * m.min_range_m, 0.005, 0.05);
  st->heads.clear();
  st->column_slice.assign(static_cast<std::size_t>(st->width), 0);
  int x0 = 0, slice_id = 0;
  for (std::size_t h = 0; h < heads.size(); ++h) {
    Head head;
    head.X_BH = heads[h];
    head.channel0 = m.side_scan() ? static_cast<int>(h) : 0;
    for (int s = 0; s < n_slices; ++s, ++slice_id) {
      Slice sl;
      sl.x0 = x0;
      sl.cols = cols_per_slice;
      const double a = -0.5 * H + (s + 0.5) * w;                         // slice centre azimuth
      sl.R_HC.col(0) = Eigen::Vector3d(-std::sin(a), std::cos(a), 0.0);  // optical x: right
      sl.R_HC.col(1) = Eigen::Vector3d(0.0, 0.0, 1.0);                   // optical y: down
      sl.R_HC.col(2) = Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);   // optical z: the slice axis
      sl.cam.width = cols_per_slice;
      sl.cam.height = rows;
      sl.cam.fx = 0.5 * cols_per_slice / tan_w;
      sl.cam.fy = 0.5 * rows / tan_v;
      sl.cam.cx = 0.5 * cols_per_slice - 0.5;
      sl.cam.cy = 0.5 * rows - 0.5;
      sl.cam.near_m = near;
      sl.cam.far_m = far;
      for (int c = 0; c < cols_per_slice; ++c)
        st->column_slice[static_cast<std::size_t>(x0) + static_cast<std::size_t>(c)] = slice_id;
      head.slices.push_back(sl);
      x0 += cols_per_slice;
    }
    st->heads.push_back(head);
  }
  // Pixel tables.
  const std::size_t npx = static_cast<std::size_t>(st->width) * static_cast<std::size_t>(rows);
  st->channel.assign(npx, -1);
  st->weight.assign(npx, 0.0f);
  const double beam_width = m.side_scan() ? H : H / m.beams;
  const double k_taper = 4.0 * std::log(2.0) / (V * V);
  for (const Head& head : st->heads)
    for (const Slice& sl : head.slices)
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < sl.cols; ++c) {
          const double x = (c - sl.cam.cx) / sl.cam.fx, y = (r - sl.cam.cy) / sl.cam.fy;
          const Eigen::Vector3d d = (sl.R_HC * Eigen::Vector3d(x, y, 1.0)).normalized();
          const double az = std::atan2(d.y(), d.x()), el = -std::asin(std::clamp(d.z(), -1.0, 1.0));
          if (std::abs(el) > 0.5 * V || std::abs(az) > 0.5 * H) continue;
          int ch = head.channel0;
          if (!m.side_scan())
            ch = std::clamp(static_cast<int>(std::floor((az + 0.5 * H) / beam_width)), 0, m.beams - 1);
          const double r2 = 1.0 + x * x + y * y;
          const double d_omega = 1.0 / (sl.cam.fx * sl.cam.fy * r2 * std::sqrt(r2));
          const std::size_t i =
              static_cast<std::size_t>(r) * static_cast<std::size_t>(st->width) + static_cast<std::size_t>(sl.x0 + c);
          st->channel[i] = ch;
          st->weight[i] = static_cast<float>(d_omega * std::exp(-k_taper * el * el) / beam_width);
        }
  st->readback.resize(npx * 4);
}

}  // namespace

struct SonarRenderer::Impl {
  std::shared_ptr<EglContext> ctx;
  World world;
  SonarOptions options;
  std::vector<SonarState> sonars;
  std::vector<GpuMesh> meshes;
  std::map<std::string, std::vector<unav::scene::MovableMesh>> movable;  // by object name
  gl::Program program;
  std::uint64_t sequence = 0;
  SonarTimings timings;

  void upload(const World& w) {
    const auto geo = unav::scene::build_scene_geometry(w);
    for (const auto& sm : geo.meshes) {
      GpuMesh g;
      const double db = std::isnan(sm.material.acoustic_reflectivity_db)
                            ? unav::scene::acoustic_reflectivity_db(sm.seg_class)
                            : sm.material.acoustic_reflectivity_db;
      g.mu = static_cast<float>(std::pow(10.0, db / 10.0));
      glGenVertexArrays(1, &g.vao);
      glBindVertexArray(g.vao);
      glGenBuffers(2, g.vbo);
      const std::vector<float>* attrs[2] = {&sm.mesh.positions, &sm.mesh.normals};
      for (GLuint a = 0; a < 2; ++a) {
        glBindBuffer(GL_ARRAY_BUFFER, g.vbo[a]);
        glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(attrs[a]->size() * sizeof(float)), attrs[a]->data(),
                     GL_STATIC_DRAW);
        glEnableVertexAttribArray(a);
        glVertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
      }
      glGenBuffers(1, &g.ebo);
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
      glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(sm.mesh.indices.size() * sizeof(std::uint32_t)),
                   sm.mesh.indices.data(), GL_STATIC_DRAW);
      g.index_count = static_cast<GLsizei>(sm.mesh.indices.size());
      glBindVertexArray(0);
      meshes.push_back(g);
    }
    movable = unav::scene::movable_meshes(w, geo);
    gl::check_gl("sonar geometry upload");
  }

  void release_meshes() {
    for (GpuMesh& g : meshes) {
      glDeleteVertexArrays(1, &g.vao);
      glDeleteBuffers(2, g.vbo);
      glDeleteBuffers(1, &g.ebo);
    }
    meshes.clear();
  }

  void make_targets(SonarState* st) {
    glGenFramebuffers(1, &st->fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, st->fbo);
    st->color = gl::make_tex(GL_RGBA32F, st->width, st->rows, GL_RGBA, GL_FLOAT, GL_NEAREST);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, st->color, 0);
    glGenRenderbuffers(1, &st->depth);
    glBindRenderbuffer(GL_RENDERBUFFER, st->depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, st->width, st->rows);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, st->depth);
    gl::check_fbo("sonar");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }

  SonarState& find(const std::string& name) {
    for (auto& s : sonars)
      if (s.model.name == name) return s;
    std::string names;
    for (const auto& s : sonars) names += (names.empty() ? "" : ", ") + s.model.name;
    throw std::invalid_argument("SonarRenderer: no sonar '" + name + "' (sonars: " + names + ")");
  }

  void raster(SonarState& st, const Pose& X_WB);
  void accumulate(const SonarState& st, const Pose& X_WB, SonarPing* out);
};

void SonarRenderer::Impl::raster(SonarState& st, const Pose& X_WB) {
  glBindFramebuffer(GL_FRAMEBUFFER, st.fbo);
  glViewport(0, 0, st.width, st.rows);
  const float zero[4] = {0, 0, 0, 0};
  gl::begin_opaque_pass(zero);
  glEnable(GL_SCISSOR_TEST);
  program.use();
  for (const Head& head : st.heads) {
    const Pose X_WH = X_WB * head.X_BH;
    gl::set3(program["u_origin_W"], X_WH.translation());
    for (const Slice& sl : head.slices) {
      Pose X_WC = X_WH;
      X_WC.linear() = X_WH.linear() * sl.R_HC;
      const Eigen::Matrix4f view = X_WC.inverse().matrix().cast<float>();
      const Eigen::Matrix4f proj = gl::projection_from_K(sl.cam);
      glViewport(sl.x0, 0, sl.cols, st.rows);
      glScissor(sl.x0, 0, sl.cols, st.rows);
      glUniformMatrix4fv(program["u_view"], 1, GL_FALSE, view.data());
      glUniformMatrix4fv(program["u_proj"], 1, GL_FALSE, proj.data());
      for (const GpuMesh& g : meshes) {
        glUniform1f(program["u_mu"], g.mu);
        glBindVertexArray(g.vao);
        glDrawElements(GL_TRIANGLES, g.index_count, GL_UNSIGNED_INT, nullptr);
      }
    }
  }
  glDisable(GL_SCISSOR_TEST);
  glBindVertexArray(0);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, st.width, st.rows, GL_RGBA, GL_FLOAT, st.readback.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  gl::check_gl("sonar raster");
}

void SonarRenderer::Impl::accumulate(const SonarState& st, const Pose& X_WB, SonarPing* out) {
  const SonarModel& m = st.model;
  const int C = m.channels(), B = m.bins, W = st.width, R = st.rows;
  const double r0 = m.min_range_m, dr_bin = m.bin_width_m();
  const auto acoustics = unav::scene::water_acoustics(world.water, (X_WB * m.X_BH).translation().z(), m.frequency_hz);
  const double alpha = acoustics.absorption_db_per_m;
  const double n = m.spreading_exponent;
  std::vector<double> acc(static_cast<std::size_t>(B) * static_cast<std::size_t>(C), 0.0);
  const float* px = st.readback.data();
  auto range_at = [&](int row, int col) -> float {
    const std::size_t i =
        (static_cast<std::size_t>(row) * static_cast<std::size_t>(W) + static_cast<std::size_t>(col)) * 4;
    return px[i + 3] > 0.5f ? px[i] : -1.0f;
  };
  const double max_footprint = 64.0 * dr_bin;
  const double range_exponent = 2.0 - 2.0 * n + (m.tvg ? 0.1 * m.tvg_db_per_decade : 0.0);
  const double absorption_per_m = m.tvg ? 0.0 : alpha * std::log(10.0) / 5.0;  // 10^(-alpha r / 5)
  for (int row = 0; row < R; ++row)
    for (int col = 0; col < W; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * static_cast<std::size_t>(W) + static_cast<std::size_t>(col);
      const int ch = st.channel[i];
      if (ch < 0 || px[i * 4 + 3] < 0.5f) continue;
      const double r = px[i * 4], cos_i = px[i * 4 + 1], mu = px[i * 4 + 2];
      // Range footprint: the smaller one-sided difference to a neighbour of the same slice in
      // each direction (a silhouette edge on one side does not widen it).
      auto one_sided = [&](float a, float b) {
        double d = 1e30;
        if (a >= 0.0f) d = std::min(d, std::abs(r - a));
        if (b >= 0.0f) d = std::min(d, std::abs(r - b));
        return d < 1e29 ? d : 0.0;
      };
      const int slice = st.column_slice[static_cast<std::size_t>(col)];
      const float left =
          col > 0 && st.column_slice[static_cast<std::size_t>(col - 1)] == slice ? range_at(row, col - 1) : -1.0f;
      const float right =
          col + 1 < W && st.column_slice[static_cast<std::size_t>(col) + 1] == slice ? range_at(row, col + 1) : -1.0f;
      const float up = row > 0 ? range_at(row - 1, col) : -1.0f;
      const float down = row + 1 < R ? range_at(row + 1, col) : -1.0f;
      const double footprint = std::min(one_sided(left, right) + one_sided(up, down), max_footprint);
      const double lo = r - 0.5 * footprint, hi = r + 0.5 * footprint;
      if (hi < r0 || lo >= m.max_range_m) continue;
      // Two-way spreading and absorption, then the time-varied gain (its 2 alpha r cancels the
      // absorption exactly): one power of r and one exponential per sample.
      const double e = st.weight[i] * mu * cos_i * std::exp(range_exponent * std::log(r) - absorption_per_m * r);
      double* beam = acc.data() + ch;
      const double x0 = (lo - r0) / dr_bin, x1 = (hi - r0) / dr_bin;
      if (x1 - x0 < 1e-9) {
        const int b = static_cast<int>(std::floor(x0));
        if (b >= 0 && b < B) beam[static_cast<std::size_t>(b) * static_cast<std::size_t>(C)] += e;
        continue;
      }
      const double per_bin = e / (x1 - x0);
      const int b0 = std::max(0, static_cast<int>(std::floor(x0))),
                b1 = std::min(B - 1, static_cast<int>(std::ceil(x1)) - 1);
      for (int b = b0; b <= b1; ++b) {
        const double overlap = std::min(x1, b + 1.0) - std::max(x0, static_cast<double>(b));
        if (overlap > 0.0) beam[static_cast<std::size_t>(b) * static_cast<std::size_t>(C)] += per_bin * overlap;
      }
    }
  // Side lobes of the fan's receive pattern, then noise and display coding.
  if (m.sidelobes && !m.side_scan())
    add_sidelobes(B, C, sidelobe_kernel(C, m.sidelobe_db, m.sidelobe_falloff_db_per_octave), &acc);
  out->channels = C;
  out->bins = B;
  out->intensity.resize(acc.size());
  out->image.resize(acc.size());
  SplitMix rng{{options.seed * 0x9E3779B97F4A7C15ULL ^
                (std::hash<std::string>{}(m.name) + 0x632BE59BD9B4E019ULL * (out->sequence + 1))}};
  const double n0 = std::pow(10.0, (m.noise_floor_db - m.gain_db) / 10.0);
  const double s = m.speckle;
  const double inv_bin = 1.0 / dr_bin;
  if (options.noise && s > 0.0) {
    SpeckleParams sp;
    sp.shape = m.speckle_shape;
    sp.grain_beams = m.side_scan() ? 0.0 : m.speckle_grain_beams;  // port and starboard share nothing
    sp.grain_bins = m.speckle_grain_bins;
    speckle_field(B, C, sp, &rng, &st.speckle);
  }
  const DisplayCoding coding(m.display, m.gain_db, m.dynamic_range_db, m.display_gamma);
  for (std::size_t k = 0; k < acc.size(); ++k) {
    double v = acc[k] * inv_bin;
    if (options.noise) v = v * (s > 0.0 ? (1.0 - s) + s * st.speckle[k] : 1.0) + n0 * rng.exponential();
    out->intensity[k] = static_cast<float>(v);
    out->image[k] = coding(v);
  }
  out->sound_speed_mps = acoustics.sound_speed_mps;
  out->absorption_db_per_m = alpha;
}

SonarRenderer::SonarRenderer(World world, std::vector<SonarModel> sonars, SonarOptions options,
                             std::shared_ptr<EglContext> context)
    : impl_(std::make_unique<Impl>()) {
  if (sonars.empty()) throw ConfigError("SonarRenderer: no sonars");
  for (std::size_t i = 0; i < sonars.size(); ++i) {
    sonars[i].validate("SonarRenderer");
    for (std::size_t j = 0; j < i; ++j)
      if (sonars[j].name == sonars[i].name)
        throw ConfigError("SonarRenderer: duplicate sonar name '" + sonars[i].name + "'");
  }
  impl_->world = std::move(world);
  impl_->options = options;
  impl_->ctx = context ? std::move(context) : std::shared_ptr<EglContext>(EglContext::create(options.egl));
  impl_->ctx->make_current();
  impl_->program = gl::Program(detail::kSonarVS, detail::kSonarFS, "sonar");
  impl_->upload(impl_->world);
  for (auto& m : sonars) {
    SonarState st;
    st.model = m;
    plan_sonar(&st);
    impl_->make_targets(&st);
    impl_->sonars.push_back(std::move(st));
  }
  gl::check_gl("SonarRenderer setup");
}

SonarRenderer::~SonarRenderer() {
  if (!impl_ || !impl_->ctx) return;
  impl_->ctx->make_current();
  impl_->release_meshes();
  for (auto& st : impl_->sonars) {
    glDeleteFramebuffers(1, &st.fbo);
    glDeleteTextures(1, &st.color);
    glDeleteRenderbuffers(1, &st.depth);
  }
  glDeleteProgram(impl_->program.id());
}

SonarPing SonarRenderer::ping(const Pose& X_WB, const std::string& name, double stamp_s) {
  SonarState& st = impl_->find(name);
  impl_->ctx->make_current();
  SonarPing out;
  out.sonar = name;
  out.side_scan = st.model.side_scan();
  out.stamp_s = stamp_s;
  out.sequence = impl_->sequence++;
  out.frequency_hz = st.model.frequency_hz;
  out.X_WS = X_WB * st.model.frame_acoustic();
  const auto t0 = Clock::now();
  impl_->raster(st, X_WB);
  impl_->timings.raster_ms = ms_since(t0);
  const auto t1 = Clock::now();
  impl_->accumulate(st, X_WB, &out);
  impl_->timings.accumulate_ms = ms_since(t1);
  out.ranges_m.resize(static_cast<std::size_t>(st.model.bins));
  for (int b = 0; b < st.model.bins; ++b)
    out.ranges_m[static_cast<std::size_t>(b)] = static_cast<float>(st.model.bin_center_m(b));
  if (st.model.side_scan()) {
    out.azimuth_rad = {static_cast<float>(-M_PI / 2), static_cast<float>(M_PI / 2)};
  } else {
    out.azimuth_rad.resize(static_cast<std::size_t>(st.model.beams));
    for (int k = 0; k < st.model.beams; ++k)
      out.azimuth_rad[static_cast<std::size_t>(k)] = static_cast<float>(st.model.beam_azimuth_rad(k));
  }
  return out;
}

void SonarRenderer::set_world(World world) {
  impl_->ctx->make_current();
  unav::scene::build_scene_geometry(world);  // a bad mesh throws before the scene is touched
  impl_->release_meshes();
  impl_->world = std::move(world);
  impl_->upload(impl_->world);
}

void SonarRenderer::set_object_pose(const std::string& name, const Pose& X_WO) {
  const auto it = impl_->movable.find(name);
  if (it == impl_->movable.end())
    throw ConfigError("SonarRenderer::set_object_pose", "name", name,
                      "no movable object of that name in world '" + impl_->world.name + "'");
  if (!X_WO.matrix().allFinite())
    throw ConfigError("SonarRenderer::set_object_pose", name, "non-finite pose", "the pose must be finite");
  impl_->ctx->make_current();
  for (const unav::scene::MovableMesh& part : it->second) {
    unav::scene::MeshData m = part.local;
    m.transform(X_WO);
    const GpuMesh& g = impl_->meshes[part.mesh];
    const std::vector<float>* attrs[2] = {&m.positions, &m.normals};
    for (int a = 0; a < 2; ++a) {
      glBindBuffer(GL_ARRAY_BUFFER, g.vbo[a]);
      glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(attrs[a]->size() * sizeof(float)), attrs[a]->data());
    }
  }
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  gl::check_gl("moving an object");
}

void SonarRenderer::set_next_sequence(std::uint64_t sequence) { impl_->sequence = sequence; }

const SonarModel& SonarRenderer::sonar(const std::string& name) const { return impl_->find(name).model; }

std::vector<std::string> SonarRenderer::sonar_names() const {
  std::vector<std::string> names;
  names.reserve(impl_->sonars.size());
  for (const auto& s : impl_->sonars) names.push_back(s.model.name);
  return names;
}

const World& SonarRenderer::world() const { return impl_->world; }
const EglContext& SonarRenderer::context() const { return *impl_->ctx; }
SonarTimings SonarRenderer::last_timings() const { return impl_->timings; }

std::vector<ProfilePoint> detect_profile(const SonarPing& ping, double detection_db) {
  if (ping.side_scan) throw std::invalid_argument("detect_profile: a side-scan ping has no fan of beams");
  std::vector<ProfilePoint> out;
  const double ratio = std::pow(10.0, detection_db / 10.0);
  std::vector<float> column(static_cast<std::size_t>(ping.bins));
  for (int c = 0; c < ping.channels; ++c) {
    int peak = 0;
    for (int b = 0; b < ping.bins; ++b) {
      column[static_cast<std::size_t>(b)] = ping.at(b, c);
      if (ping.at(b, c) > ping.at(peak, c)) peak = b;
    }
    const float top = ping.at(peak, c);
    std::nth_element(column.begin(), column.begin() + ping.bins / 2, column.end());
    const float median = column[static_cast<std::size_t>(ping.bins / 2)];
    if (!(top > 0.0f) || static_cast<double>(top) < ratio * static_cast<double>(median)) continue;
    double offset = 0.0;  // sub-bin: the vertex of the parabola through the three log levels
    if (peak > 0 && peak + 1 < ping.bins && ping.at(peak - 1, c) > 0.0f && ping.at(peak + 1, c) > 0.0f) {
      const double l0 = std::log(ping.at(peak - 1, c)), l1 = std::log(top), l2 = std::log(ping.at(peak + 1, c));
      const double den = l0 - 2.0 * l1 + l2;
      if (den < 0.0) offset = std::clamp(0.5 * (l0 - l2) / den, -0.5, 0.5);
    }
    const double dr = ping.bins > 1 ? ping.ranges_m[1] - ping.ranges_m[0] : 0.0;
    ProfilePoint p;
    p.beam = c;
    p.range_m = ping.ranges_m[static_cast<std::size_t>(peak)] + offset * dr;
    const double az = ping.azimuth_rad[static_cast<std::size_t>(c)];
    p.p_S = p.range_m * Eigen::Vector3d(0.0, std::sin(az), std::cos(az));
    p.intensity = top;
    out.push_back(p);
  }
  return out;
}

FanImage fan_image(const SonarPing& ping, int width) {
  if (ping.side_scan || ping.channels < 2 || ping.bins < 2)
    throw std::invalid_argument("fan_image: needs a forward-looking ping");
  if (width < 16) throw std::invalid_argument("fan_image: width must be >= 16");
  FanImage img;
  const double a0 = ping.azimuth_rad.front(), a1 = ping.azimuth_rad.back();
  const double step_a = (a1 - a0) / (ping.channels - 1);
  const double half = std::max(std::abs(a0), std::abs(a1)) + 0.5 * step_a;
  const double r_min = ping.ranges_m.front(), r_max = ping.ranges_m.back();
  const double step_r = (r_max - r_min) / (ping.bins - 1);
  const double r_out = r_max + 0.5 * step_r;
  const double half_width_m = half < M_PI / 2 ? r_out * std::sin(half) : r_out;
  img.width = width;
  img.metres_per_pixel = 2.0 * half_width_m / width;
  const double y_low = half < M_PI / 2 ? 0.0 : r_out * std::cos(half);  // below the apex for > 180 deg
  img.height = static_cast<int>(std::ceil((r_out - y_low) / img.metres_per_pixel));
  img.pixels.assign(static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height), 0);
  for (int v = 0; v < img.height; ++v)
    for (int u = 0; u < img.width; ++u) {
      const double x = (u + 0.5) * img.metres_per_pixel - half_width_m;  // starboard
      const double y = r_out - (v + 0.5) * img.metres_per_pixel;         // forward
      const double r = std::hypot(x, y), a = std::atan2(x, y);
      const double fb = (a - a0) / step_a, fr = (r - r_min) / step_r;
      if (fb < -0.5 || fb > ping.channels - 0.5 || fr < -0.5 || fr > ping.bins - 0.5) continue;
      const double cb = std::clamp(fb, 0.0, ping.channels - 1.0), cr = std::clamp(fr, 0.0, ping.bins - 1.0);
      const int b0 = std::min(static_cast<int>(cb), ping.channels - 2),
                k0 = std::min(static_cast<int>(cr), ping.bins - 2);
      const double tb = cb - b0, tr = cr - k0;
      auto at = [&](int k, int b) {
        return static_cast<double>(ping.image[static_cast<std::size_t>(k) * static_cast<std::size_t>(ping.channels) +
                                              static_cast<std::size_t>(b)]);
      };
      const double val = (1 - tr) * ((1 - tb) * at(k0, b0) + tb * at(k0, b0 + 1)) +
                         tr * ((1 - tb) * at(k0 + 1, b0) + tb * at(k0 + 1, b0 + 1));
      img.pixels[static_cast<std::size_t>(v) * static_cast<std::size_t>(img.width) + static_cast<std::size_t>(u)] =
          static_cast<std::uint8_t>(std::lround(std::clamp(val, 0.0, 255.0)));
    }
  return img;
}

Waterfall::Waterfall(int bins, int lines) : bins_(bins), lines_(lines) {
  if (bins < 1 || lines < 1) throw std::invalid_argument("Waterfall: bins and lines must be >= 1");
  pixels_.assign(static_cast<std::size_t>(2 * bins) * static_cast<std::size_t>(lines), 0);
}

void Waterfall::add(const SonarPing& ping) {
  if (!ping.side_scan || ping.channels != 2 || ping.bins != bins_)
    throw std::invalid_argument("Waterfall::add: needs a side-scan ping of " + std::to_string(bins_) + " bins");
  const std::size_t w = static_cast<std::size_t>(width());
  std::move_backward(pixels_.begin(), pixels_.end() - static_cast<std::ptrdiff_t>(w), pixels_.end());
  for (int k = 0; k < bins_; ++k) {
    const std::size_t src = static_cast<std::size_t>(k) * 2;
    pixels_[static_cast<std::size_t>(bins_ - 1 - k)] = ping.image[src];                            // port, mirrored
    pixels_[static_cast<std::size_t>(bins_) + static_cast<std::size_t>(k)] = ping.image[src + 1];  // starboard
  }
  ++pings_;
}

void write_png_mono(const std::vector<std::uint8_t>& pixels, int width, int height, const std::string& path) {
  const cv::Mat m(height, width, CV_8UC1, const_cast<std::uint8_t*>(pixels.data()));
  bool ok = false;
  try {
    ok = cv::imwrite(path, m);
  } catch (const cv::Exception& e) {
    throw ConfigError(path + ": cannot write PNG: " + e.what());
  }
  if (!ok) throw ConfigError(path + ": cannot write PNG");
}

}  // namespace unav::renderer
