#include "unav_renderer/renderer.hpp"

#include <epoxy/gl.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <deque>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <unordered_map>

#include "gl_util.hpp"
#include "pixel_ops.hpp"
#include "shaders.hpp"
#include "textures.hpp"
#include "unav_renderer/errors.hpp"
#include "unav_scene/noise.hpp"
#include "unav_scene/scene_geometry.hpp"

namespace unav::renderer {
namespace {

using gl::check_fbo;
using gl::check_gl;
using gl::make_tex;
using gl::Program;
using gl::projection_from_K;
using gl::set3;
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// CPU time of this process, all threads [ms] (llvmpipe's rasteriser threads included).
double process_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// A spatially compact run of a mesh's triangles with its bounding box: passes skip the chunks
// outside their view frustum (the seabed patch is ~29k triangles; a lamp sees a few metres).
struct Chunk {
  GLsizei first = 0, count = 0;  // in indices
  Eigen::Vector3f lo = Eigen::Vector3f::Zero(), hi = Eigen::Vector3f::Zero();
  bool sun_free = false;  ///< terrain that nothing can shadow from the sun (mark_sun_free())
  /// Terrain wholly under another terrain mesh (index; -1 none): the far seabed under the patch,
  /// which nobody standing over the patch can see (build_caster_boxes()).
  long under = -1;
};

// Terrain level of detail: a height field on a regular vertex grid is drawn in tiles of
// kTileCells x kTileCells cells, each with its full mesh (its chunks) or a coarser one that keeps
// every 2nd or 4th grid point (kLodLevels: 1x, 2x, 4x the cell). Far seabed seen at a grazing angle
// is sliver triangles a few pixels high, and llvmpipe shades every 4x4 block a triangle touches:
// beyond ~15 m the patch's 1 m cells cost ~20 % of a 640x480 frame for a few % of its pixels.
constexpr int kTileCells = 8;
constexpr int kChunkCells = 2;  // a chunk of a grid terrain: 2 x 2 cells (~kChunkM at 1 m cells)
constexpr int kLodLevels = 3;
struct TerrainTile {
  std::size_t chunk_begin = 0, chunk_end = 0;  // its full mesh: chunks [begin, end) of the mesh
  Chunk box;                                   // all of it, skirts included (culling, shadow bits)
  /// Level k's coarse triangles (k >= 1; level[0] unused) and their largest vertical distance from
  /// the full mesh [m] (infinite where the tile's cells do not divide by 2^k).
  std::array<Chunk, kLodLevels> level;
  std::array<float, kLodLevels> error{};
  /// Level k's skirts by side (-x, +x, -y, +y): vertical strips hanging from the tile's edge, drawn
  /// where the neighbour on that side has another level, so that the two edges (each a different
  /// polyline through the grid points they share) leave no crack between them.
  std::array<std::array<Chunk, 4>, kLodLevels> skirt;
};

// A box as seen from a lamp: its azimuths (mid, half-width; all of them when the lamp stands over
// it) and depression angles below the horizontal (z down), in radians.
struct LampCaster {
  std::size_t mesh = 0;
  float az_mid = 0.0f, az_half = 4.0f, dep_lo = 0.0f, dep_hi = 0.0f;
  float top_z = 0.0f, bottom_z = 0.0f;  // the box's shallowest and deepest z
};

LampCaster seen_from(const Eigen::Vector3f& L, std::size_t mesh, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  LampCaster a;
  a.mesh = mesh;
  a.top_z = lo.z();
  a.bottom_z = hi.z();
  const float cx = std::clamp(L.x(), lo.x(), hi.x()), cy = std::clamp(L.y(), lo.y(), hi.y());
  const float h_near = std::hypot(cx - L.x(), cy - L.y());
  const float h_far = std::hypot(std::max(L.x() - lo.x(), hi.x() - L.x()), std::max(L.y() - lo.y(), hi.y() - L.y()));
  // Steepest below the lamp: deep and near; flattest: shallow and far (above the lamp: near).
  const float top = lo.z() - L.z(), bottom = hi.z() - L.z();
  a.dep_lo = std::atan2(top, top >= 0.0f ? h_far : h_near);
  a.dep_hi = std::atan2(bottom, bottom >= 0.0f ? h_near : h_far);
  if (h_near > 0.0f) {  // the lamp outside the box's footprint: its corners span less than pi
    const float mid = std::atan2(0.5f * (lo.y() + hi.y()) - L.y(), 0.5f * (lo.x() + hi.x()) - L.x());
    float d_lo = 0.0f, d_hi = 0.0f;
    for (int k = 0; k < 4; ++k) {
      const float x = (k & 1 ? hi.x() : lo.x()) - L.x(), y = (k & 2 ? hi.y() : lo.y()) - L.y();
      const float d = std::remainder(std::atan2(y, x) - mid, 2.0f * static_cast<float>(M_PI));
      d_lo = std::min(d_lo, d);
      d_hi = std::max(d_hi, d);
    }
    a.az_mid = mid + 0.5f * (d_lo + d_hi);
    a.az_half = 0.5f * (d_hi - d_lo);
  }
  return a;
}

// Whether caster c can stand on a lamp's ray to some point of receiver r: in azimuth and in
// depression angle, and reaching above r's deepest point (the lamp is above the terrain).
bool may_shadow(const LampCaster& c, const LampCaster& r) {
  if (c.top_z > r.bottom_z) return false;
  if (c.dep_hi < r.dep_lo || r.dep_hi < c.dep_lo) return false;
  return std::abs(std::remainder(c.az_mid - r.az_mid, 2.0f * static_cast<float>(M_PI))) <= c.az_half + r.az_half;
}

// The casters seen from one lamp, bucketed by azimuth: a receiver tests those in its sectors only.
class LampCasters {
 public:
  void add(const LampCaster& c) {
    const auto index = static_cast<std::uint32_t>(all_.size());
    all_.push_back(c);
    for_sectors(c, [&](std::size_t k) { sectors_[k].push_back(index); });
  }
  // Whether a caster of another mesh than `mesh` may shadow receiver r (may_shadow()).
  bool any_may_shadow(const LampCaster& r, std::size_t mesh) const {
    bool hit = false;
    for_sectors(r, [&](std::size_t k) {
      for (std::uint32_t i = 0; i < sectors_[k].size() && !hit; ++i) {
        const LampCaster& c = all_[sectors_[k][i]];
        hit = c.mesh != mesh && may_shadow(c, r);
      }
    });
    return hit;
  }

 private:
  static constexpr int kSectors = 64;
  template <typename F>
  static void for_sectors(const LampCaster& c, F&& f) {
    const float w = 2.0f * static_cast<float>(M_PI) / kSectors;
    if (c.az_half >= static_cast<float>(M_PI)) {
      for (int k = 0; k < kSectors; ++k) f(static_cast<std::size_t>(k));
      return;
    }
    const int a = static_cast<int>(std::floor((c.az_mid - c.az_half) / w));
    const int b = static_cast<int>(std::floor((c.az_mid + c.az_half) / w));
    for (int k = a; k <= b && k < a + kSectors; ++k)
      f(static_cast<std::size_t>(((k % kSectors) + kSectors) % kSectors));
  }
  std::vector<LampCaster> all_;
  std::array<std::vector<std::uint32_t>, kSectors> sectors_;
};

struct GpuMesh {
  GLuint vao = 0, vbo[4] = {0, 0, 0, 0}, ebo = 0;  // positions, normals, uvs, skirt drops (terrain LOD)
  GLsizei index_count = 0;
  std::vector<Chunk> chunks;
  /// Terrain level of detail (a height field on a regular grid, terrain_lod()): its tiles, in the
  /// grid's order (tile_cols a row), and by level how far the shadow lookups of a coarse tile are
  /// lifted (up, metres) to stay above the full mesh the shadow maps hold: its deepest sag below it.
  std::vector<TerrainTile> tiles;
  int tile_cols = 0;
  std::array<float, kLodLevels> lift{};
  /// How far the lamp maps' lookups are lifted by level (the terrain: as `lift`; rocks, whose lamp
  /// maps hold the level drawn: 0).
  std::array<float, kLodLevels> lamp_lift{};
  /// Parts drawn at levels of detail (rocks, SceneMesh::lod_parts): part i's chunk by level (its
  /// finest is chunks[i]) and the level's error [m]. `lift` holds each level's largest error: its
  /// sun lookups are made that far up, over the finest surface the sun's map holds.
  struct LodChunks {
    std::vector<Chunk> level;
    std::vector<float> error_m;
  };
  std::vector<LodChunks> lod;
  SegClass seg_class = SegClass::kOther;
  Material material;
  /// A height field (the seabed patch, the far seabed): it can shadow itself only where the light
  /// comes in flatter than its steepest slope, tan_slope (shadow receiver culling).
  bool terrain = false;
  float tan_slope = 0.0f;
  /// closed_orientation() of the mesh: +-1 a solid (back faces culled: they lie behind its front
  /// faces), 0 open or not consistently wound (both sides drawn).
  int winding = 0;
  bool triplanar = false;
  bool macro = false;
  bool sections = false;  ///< pipe coating: each section shows another part of the texture
  // What the material has; drawn only with RenderOptions::materials (Renderer::Impl::look(), so
  // that set_options() switches them).
  bool bump = false;      ///< relief_m > 0: shaded by the texture's height field
  bool specular = false;  ///< GGX highlights (metals, smooth surfaces; see scene_program())
  bool sediment = false;  ///< sand settled on its upward faces and near the seabed
  float roughness = 0.6f, metallic = 0.0f, relief_m = 0.0f, sediment_cover = 0.0f;
  GLuint texture = 0;
  GLuint gradient = 0;    ///< the relief's slope (ProceduralTexture::gradient), for bump mapping
  GLuint normal_map = 0;  ///< a mesh file's tangent-space normal map (by UVs); 0: none
  GLuint orm_map = 0;     ///< a mesh file's occlusion-roughness-metallic map (by UVs); 0: none
};

struct Targets {
  // The scene is rendered with an "internal" pinhole camera: the output camera's K, enlarged
  // by a margin when distortion pulls in pixels from outside the undistorted field.
  CameraModel internal;
  int margin_x = 0, margin_y = 0;
  int width = 0, height = 0;  // internal size
  int out_width = 0, out_height = 0;
  double out_K[4] = {1, 1, 0, 0};  // the output camera's fx, fy, cx, cy (in air)
  CameraModel seen;                // what the water sees: the fitted model behind a port (Frame::K/D)
  int is_width = 0, is_height = 0, is_scale = 1;
  GLuint is_fbo = 0, is_tex = 0;
  GLuint is_water_tex = 0;  // the in-scattering premultiplied by its upsampling weight for water pixels
  GLuint scene_fbo = 0, scene_color = 0, scene_zc = 0, scene_depth = 0;
  GLuint post_fbo = 0, post_rgba = 0, post_zc = 0;
  GLuint distmap = 0;
  /// Distortion / port: the post pass's radiance at the internal size (RGBA32F: linear I and seg;
  /// scene_depth attached for the geometry / water split), which the remap resamples into post_fbo.
  GLuint lin_fbo = 0, lin_tex = 0;
  /// The forward-scatter blur's levels: scene_color's means over 4 x 4 and 16 x 16 pixels.
  GLuint blur_fbo[2] = {0, 0}, blur_tex[2] = {0, 0};
  int blur_width[2] = {0, 0}, blur_height[2] = {0, 0};
};

// The post program's compiled-in features, in kPostFS's order: REMAP, FWD, INSCATTER, VIGNETTING,
// SHOT, READ_NOISE, SNELL, MOTION, RADIANCE.
constexpr std::size_t kPostFeatures = 9;
using PostFeatures = std::array<bool, kPostFeatures>;

// RenderOptions::gpu_timers: timestamps at a frame's start, after each of its five passes and
// after the readback's copies.
constexpr int kStamps = 7;

struct Slot {
  GLuint pbo_rgba = 0, pbo_depth = 0;
  GLuint stamps[kStamps] = {};  // gpu_timers; `timed` when this slot's frame took them
  bool timed = false;
  std::size_t capacity_px = 0;
  GLsync fence = nullptr;
  Frame meta;  // everything but the pixels
};

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

// A sampler object with these filters and this wrap mode in s and t.
GLuint make_sampler(GLint min_filter, GLint mag_filter, GLint wrap) {
  GLuint s = 0;
  glGenSamplers(1, &s);
  glSamplerParameteri(s, GL_TEXTURE_MIN_FILTER, min_filter);
  glSamplerParameteri(s, GL_TEXTURE_MAG_FILTER, mag_filter);
  glSamplerParameteri(s, GL_TEXTURE_WRAP_S, wrap);
  glSamplerParameteri(s, GL_TEXTURE_WRAP_T, wrap);
  return s;
}

// A sampler object reading bilinear in the nearest mip level, repeating (surface maps).
GLuint mip_nearest_sampler() { return make_sampler(GL_LINEAR_MIPMAP_NEAREST, GL_LINEAR, GL_REPEAT); }

// A sampler object reading one texel, unfiltered, clamped to the edges.
GLuint nearest_sampler() { return make_sampler(GL_NEAREST, GL_NEAREST, GL_CLAMP_TO_EDGE); }

// A bound depth texture as a shadow map: bilinear depth comparison (hardware PCF), clamped.
void shadow_sampling(GLenum target) {
  glTexParameteri(target, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(target, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(target, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glTexParameteri(target, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
}

constexpr int kShadowLayers = 4;          // one per lamp
constexpr double kSunShadowHalfM = 12.0;  // the sun's shadow map covers 24 m x 24 m around the camera
constexpr double kSunSnapM = 2.0;         // its centre moves in 2 m steps: the map is reused in between
constexpr int kSunMapScale = 4;           // its edge: 4 x shadow_map_size (1024 px: 2 cm texels)
// A lamp's shadow map ends there: its light is spent (the in-scattering marches <= 30 m too).
constexpr float kLampFarM = 30.0f;

// The corners of triangle t of mesh.
std::array<Eigen::Vector3f, 3> triangle_corners(const MeshData& mesh, std::size_t t) {
  std::array<Eigen::Vector3f, 3> p;
  for (std::size_t k = 0; k < 3; ++k)
    p[k] = Eigen::Map<const Eigen::Vector3f>(&mesh.positions[std::size_t{3} * mesh.indices[3 * t + k]]);
  return p;
}

// The steepest slope of a mesh's faces, as tan(angle from horizontal) (world_ned, z down).
float steepest_slope(const MeshData& mesh) {
  float best = 0.0f;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto p = triangle_corners(mesh, t);
    const Eigen::Vector3f n = (p[1] - p[0]).cross(p[2] - p[0]);
    const float horizontal = std::hypot(n.x(), n.y());
    if (horizontal == 0.0f) continue;
    if (std::abs(n.z()) < 1e-9f * horizontal) return std::numeric_limits<float>::infinity();
    best = std::max(best, horizontal / std::abs(n.z()));
  }
  return best;
}

// Triangles of a mesh reordered into chunks of about kChunkM x kChunkM (x, y) each.
constexpr double kChunkM = 2.0;
std::vector<std::uint32_t> chunked_indices(const MeshData& mesh, std::vector<Chunk>* chunks) {
  const std::size_t nt = mesh.triangle_count();
  const auto& P = mesh.positions;
  auto centroid = [&](std::size_t t, int axis) {
    double c = 0.0;
    for (int k = 0; k < 3; ++k)
      c += P[std::size_t{3} * mesh.indices[3 * t + static_cast<std::size_t>(k)] + static_cast<std::size_t>(axis)];
    return c / 3.0;
  };
  double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
  for (std::size_t t = 0; t < nt; ++t)
    for (int a = 0; a < 2; ++a) {
      lo[a] = std::min(lo[a], centroid(t, a));
      hi[a] = std::max(hi[a], centroid(t, a));
    }
  int n[2] = {1, 1};
  // At least ~8 triangles a chunk (a coarse mesh over a large area, as the far seabed, in few).
  const int most = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(nt) / 8.0)), 1, 64);
  if (nt > 2000)
    for (int a = 0; a < 2; ++a) n[a] = std::clamp(static_cast<int>(std::ceil((hi[a] - lo[a]) / kChunkM)), 1, most);
  std::vector<std::vector<std::size_t>> cells(static_cast<std::size_t>(n[0] * n[1]));
  for (std::size_t t = 0; t < nt; ++t) {
    int c[2];
    for (int a = 0; a < 2; ++a)
      c[a] =
          n[a] == 1 ? 0 : std::clamp(static_cast<int>((centroid(t, a) - lo[a]) / (hi[a] - lo[a]) * n[a]), 0, n[a] - 1);
    cells[static_cast<std::size_t>(c[0]) * static_cast<std::size_t>(n[1]) + static_cast<std::size_t>(c[1])].push_back(
        t);
  }
  std::vector<std::uint32_t> out;
  out.reserve(mesh.indices.size());
  for (const auto& cell : cells) {
    if (cell.empty()) continue;
    Chunk ch;
    ch.first = static_cast<GLsizei>(out.size());
    ch.lo.setConstant(std::numeric_limits<float>::infinity());
    ch.hi.setConstant(-std::numeric_limits<float>::infinity());
    for (std::size_t t : cell)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = mesh.indices[3 * t + static_cast<std::size_t>(k)];
        out.push_back(v);
        const std::size_t b = std::size_t{3} * v;
        const Eigen::Vector3f p(P[b], P[b + 1], P[b + 2]);
        ch.lo = ch.lo.cwiseMin(p);
        ch.hi = ch.hi.cwiseMax(p);
      }
    ch.count = static_cast<GLsizei>(out.size()) - ch.first;
    chunks->push_back(ch);
  }
  return out;
}

// A height field's vertex grid as make_seabed_mesh lays it out: rows x cols points, vertex (i, j)
// at index i * cols + j, x the same along a row and y along a column, two triangles a cell,
// (i, j) (i, j+1) (i+1, j) and (i, j+1) (i+1, j+1) (i+1, j), cell after cell. False for any other
// mesh (it is then drawn without levels of detail).
bool grid_layout(const MeshData& m, int* rows, int* cols) {
  const auto& P = m.positions;
  const std::size_t nv = m.vertex_count();
  std::size_t c = 1;
  while (c < nv && P[3 * c] == P[0]) ++c;
  if (c < 2 || nv % c != 0 || nv / c < 2 || nv > (std::size_t{1} << 30)) return false;
  const std::size_t r = nv / c;
  for (std::size_t i = 0; i < r; ++i)
    for (std::size_t j = 0; j < c; ++j) {
      const std::size_t v = 3 * (i * c + j);
      if (P[v] != P[3 * i * c] || P[v + 1] != P[3 * j + 1]) return false;
    }
  if (m.indices.size() != 6 * (r - 1) * (c - 1)) return false;
  std::size_t k = 0;
  for (std::size_t i = 0; i + 1 < r; ++i)
    for (std::size_t j = 0; j + 1 < c; ++j) {
      const std::size_t a = i * c + j, b = a + 1, e = a + c, d = e + 1;
      for (const std::size_t v : {a, b, e, b, d, e})
        if (m.indices[k++] != v) return false;
    }
  *rows = static_cast<int>(r);
  *cols = static_cast<int>(c);
  return true;
}

// The index buffer of a grid terrain (grid_layout()) with its level-of-detail tiles (TerrainTile):
// the full mesh in chunks of kChunkCells x kChunkCells cells, tile after tile (a tile's chunks are
// one run), then each tile's coarse levels and skirts. The skirts' lower points are appended to
// `mesh` (copies of the edge's points) with their `drop` below them [m] (0 for the grid's points).
std::vector<std::uint32_t> terrain_lod(MeshData* mesh, int rows, int cols, std::vector<float>* drop,
                                       std::vector<Chunk>* chunks, std::vector<TerrainTile>* tiles, int* tile_cols,
                                       std::array<float, kLodLevels>* lift) {
  const auto id = [cols](int i, int j) { return static_cast<std::uint32_t>(i * cols + j); };
  const auto z = [&](int i, int j) { return mesh->positions[std::size_t{3} * id(i, j) + 2]; };
  std::vector<std::uint32_t> out;
  out.reserve(mesh->indices.size() * 2);
  const auto cell = [&](int i, int j, int s) {
    const std::uint32_t a = id(i, j), b = id(i, j + s), c = id(i + s, j), d = id(i + s, j + s);
    out.insert(out.end(), {a, b, c, b, d, c});
  };
  drop->assign(mesh->vertex_count(), 0.0f);
  // The chunk of indices [first, end), its box as drawn (skirt points dropped).
  const auto close = [&](std::size_t first) {
    Chunk ch;
    ch.first = static_cast<GLsizei>(first);
    ch.count = static_cast<GLsizei>(out.size() - first);
    ch.lo.setConstant(std::numeric_limits<float>::infinity());
    ch.hi.setConstant(-std::numeric_limits<float>::infinity());
    for (std::size_t k = first; k < out.size(); ++k) {
      const std::size_t b = std::size_t{3} * out[k];
      const Eigen::Vector3f p(mesh->positions[b], mesh->positions[b + 1], mesh->positions[b + 2] + (*drop)[out[k]]);
      ch.lo = ch.lo.cwiseMin(p);
      ch.hi = ch.hi.cwiseMax(p);
    }
    return ch;
  };
  const int ni = rows - 1, nj = cols - 1;  // cells
  const int tr = (ni + kTileCells - 1) / kTileCells, tc = (nj + kTileCells - 1) / kTileCells;
  *tile_cols = tc;
  tiles->assign(static_cast<std::size_t>(tr) * static_cast<std::size_t>(tc), TerrainTile{});
  struct Span {
    int i0, i1, j0, j1;  // the tile's cells
  };
  std::vector<Span> span(tiles->size());
  for (int a = 0; a < tr; ++a)
    for (int b = 0; b < tc; ++b) {
      const std::size_t ti = static_cast<std::size_t>(a) * static_cast<std::size_t>(tc) + static_cast<std::size_t>(b);
      Span& sp = span[ti];
      sp = {a * kTileCells, std::min((a + 1) * kTileCells, ni), b * kTileCells, std::min((b + 1) * kTileCells, nj)};
      TerrainTile& t = (*tiles)[ti];
      t.chunk_begin = chunks->size();
      for (int ci = sp.i0; ci < sp.i1; ci += kChunkCells)
        for (int cj = sp.j0; cj < sp.j1; cj += kChunkCells) {
          const std::size_t first = out.size();
          for (int i = ci; i < std::min(ci + kChunkCells, sp.i1); ++i)
            for (int j = cj; j < std::min(cj + kChunkCells, sp.j1); ++j) cell(i, j, 1);
          chunks->push_back(close(first));
        }
      t.chunk_end = chunks->size();
    }
  // Each coarse level's distance from the full mesh. Both are linear over the triangles of the
  // full mesh (a coarse cell's diagonal runs along the fine cells' diagonals), so the largest
  // distance lies at a grid point.
  std::array<float, kLodLevels> sink{};
  float worst = 0.0f;
  for (std::size_t ti = 0; ti < tiles->size(); ++ti) {
    const Span& sp = span[ti];
    TerrainTile& t = (*tiles)[ti];
    for (int k = 1; k < kLodLevels; ++k) {
      const int s = 1 << k;
      t.error[static_cast<std::size_t>(k)] = std::numeric_limits<float>::infinity();
      if ((sp.i1 - sp.i0) % s != 0 || (sp.j1 - sp.j0) % s != 0) continue;
      float e = 0.0f;
      for (int i = sp.i0; i <= sp.i1; ++i)
        for (int j = sp.j0; j <= sp.j1; ++j) {
          const int ci = sp.i0 + std::min((i - sp.i0) / s, (sp.i1 - sp.i0) / s - 1) * s;
          const int cj = sp.j0 + std::min((j - sp.j0) / s, (sp.j1 - sp.j0) / s - 1) * s;
          const float u = static_cast<float>(i - ci) / static_cast<float>(s);
          const float v = static_cast<float>(j - cj) / static_cast<float>(s);
          const float zc = u + v <= 1.0f ? z(ci, cj) + v * (z(ci, cj + s) - z(ci, cj)) + u * (z(ci + s, cj) - z(ci, cj))
                                         : z(ci + s, cj + s) + (1.0f - v) * (z(ci + s, cj) - z(ci + s, cj + s)) +
                                               (1.0f - u) * (z(ci, cj + s) - z(ci + s, cj + s));
          const float dz = zc - z(i, j);  // z down: > 0 where the coarse surface sags below the full one
          e = std::max(e, std::abs(dz));
          sink[static_cast<std::size_t>(k)] = std::max(sink[static_cast<std::size_t>(k)], dz);
        }
      t.error[static_cast<std::size_t>(k)] = e;
      worst = std::max(worst, e);
    }
  }
  // Neighbours at levels a and b part by at most error_a + error_b: skirts twice the worst, 2 cm more.
  const float skirt_m = 2.0f * worst + 0.02f;
  for (int k = 0; k < kLodLevels; ++k)
    (*lift)[static_cast<std::size_t>(k)] = k == 0 ? 0.0f : sink[static_cast<std::size_t>(k)] + 0.005f;
  const auto hang = [&](std::uint32_t v) {  // a copy of point v, drawn skirt_m below it
    const auto n = static_cast<std::uint32_t>(mesh->vertex_count());
    for (int a = 0; a < 3; ++a) mesh->positions.push_back(mesh->positions[std::size_t{3} * v + a]);
    for (int a = 0; a < 3; ++a) mesh->normals.push_back(mesh->normals[std::size_t{3} * v + a]);
    for (int a = 0; a < 2; ++a) mesh->uvs.push_back(mesh->uvs[std::size_t{2} * v + a]);
    drop->push_back(skirt_m);
    return n;
  };
  for (std::size_t ti = 0; ti < tiles->size(); ++ti) {
    const Span& sp = span[ti];
    TerrainTile& t = (*tiles)[ti];
    for (int k = 0; k < kLodLevels; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      if (!std::isfinite(t.error[kk])) continue;
      const int s = 1 << k;
      if (k > 0) {
        const std::size_t first = out.size();
        for (int i = sp.i0; i < sp.i1; i += s)
          for (int j = sp.j0; j < sp.j1; j += s) cell(i, j, s);
        t.level[kk] = close(first);
      }
      for (int side = 0; side < 4; ++side) {
        std::vector<std::uint32_t> top;
        if (side < 2) {
          for (int j = sp.j0; j <= sp.j1; j += s) top.push_back(id(side == 0 ? sp.i0 : sp.i1, j));
        } else {
          for (int i = sp.i0; i <= sp.i1; i += s) top.push_back(id(i, side == 2 ? sp.j0 : sp.j1));
        }
        std::vector<std::uint32_t> bottom;
        bottom.reserve(top.size());
        for (const std::uint32_t v : top) bottom.push_back(hang(v));
        const std::size_t first = out.size();
        for (std::size_t m = 0; m + 1 < top.size(); ++m)
          out.insert(out.end(), {top[m], top[m + 1], bottom[m + 1], top[m], bottom[m + 1], bottom[m]});
        t.skirt[kk][static_cast<std::size_t>(side)] = close(first);
      }
    }
    t.box.lo.setConstant(std::numeric_limits<float>::infinity());
    t.box.hi.setConstant(-std::numeric_limits<float>::infinity());
    for (std::size_t c = t.chunk_begin; c < t.chunk_end; ++c) {
      t.box.lo = t.box.lo.cwiseMin((*chunks)[c].lo);
      t.box.hi = t.box.hi.cwiseMax((*chunks)[c].hi);
    }
    t.box.hi.z() += skirt_m;
  }
  return out;
}

// The index buffer of a mesh drawn by parts at levels of detail: level by level (neighbours at the
// same level merge into one draw), a chunk per part and level, boxed by the part's vertices (a
// coarse level's surface lies inside their hull). Each part's finest chunk goes to `chunks`.
std::vector<std::uint32_t> lod_indices(const SceneMesh& sm, std::vector<Chunk>* chunks,
                                       std::vector<GpuMesh::LodChunks>* lod, std::array<float, kLodLevels>* lift) {
  std::vector<std::uint32_t> out;
  lod->assign(sm.lod_parts.size(), {});
  lift->fill(0.0f);
  std::size_t levels = 0;
  for (const LodPart& p : sm.lod_parts) levels = std::max(levels, p.levels.size());
  if (levels > static_cast<std::size_t>(kLodLevels))
    throw std::invalid_argument(sm.name + ": " + std::to_string(levels) + " levels of detail (at most " +
                                std::to_string(kLodLevels) + ")");
  std::vector<Chunk> boxes(sm.lod_parts.size());  // each part's, shared by its levels
  for (std::size_t i = 0; i < sm.lod_parts.size(); ++i) {
    Chunk& box = boxes[i];
    box.lo.setConstant(std::numeric_limits<float>::infinity());
    box.hi.setConstant(-std::numeric_limits<float>::infinity());
    for (const std::uint32_t v : sm.lod_parts[i].levels[0]) {
      const Eigen::Vector3f q(sm.mesh.positions[3 * std::size_t{v}], sm.mesh.positions[3 * std::size_t{v} + 1],
                              sm.mesh.positions[3 * std::size_t{v} + 2]);
      box.lo = box.lo.cwiseMin(q);
      box.hi = box.hi.cwiseMax(q);
    }
  }
  for (std::size_t k = 0; k < levels; ++k)
    for (std::size_t i = 0; i < sm.lod_parts.size(); ++i) {
      const LodPart& p = sm.lod_parts[i];
      if (k >= p.levels.size()) continue;
      Chunk ch = boxes[i];
      ch.first = static_cast<GLsizei>(out.size());
      ch.count = static_cast<GLsizei>(p.levels[k].size());
      out.insert(out.end(), p.levels[k].begin(), p.levels[k].end());
      (*lod)[i].level.push_back(ch);
      (*lod)[i].error_m.push_back(static_cast<float>(p.error_m[k]));
      (*lift)[k] = std::max((*lift)[k], static_cast<float>(p.error_m[k]));
    }
  chunks->clear();
  for (const auto& l : *lod) chunks->push_back(l.level.front());
  return out;
}

// The coarsest of `levels` levels whose error [m], seen from `eye` with fx pixels per unit of the
// focal plane, stays within px pixels (fx x error / distance to `box`); 0 with px = 0 (levels off).
int coarsest_level(const Chunk& box, const float* error, std::size_t levels, const Eigen::Vector3f& eye, float fx,
                   double px) {
  if (!(px > 0.0)) return 0;
  const float d = (eye.cwiseMax(box.lo).cwiseMin(box.hi) - eye).norm();
  for (std::size_t k = levels; k-- > 1;)
    if (fx * error[k] <= static_cast<float>(px) * d) return static_cast<int>(k);
  return 0;
}

// The level a terrain tile is drawn at (its height error against the full mesh), and a part's
// (a rock's, against its finest level).
int lod_level(const TerrainTile& t, const Eigen::Vector3f& eye, float fx, double px) {
  return coarsest_level(t.box, t.error.data(), t.error.size(), eye, fx, px);
}
std::size_t lod_level(const GpuMesh::LodChunks& p, const Eigen::Vector3f& eye, float fx, double px) {
  return static_cast<std::size_t>(coarsest_level(p.level.front(), p.error_m.data(), p.error_m.size(), eye, fx, px));
}

// False when the box lies entirely outside one plane of the clip volume of vp (conservative):
// each plane (-w <= x, x <= w, ... in clip coordinates) is a half-space of world points, and the
// box is wholly outside it when its corner farthest inside (picked per axis by the plane's normal)
// is outside. Called per chunk and caster box, per pass and lamp: on the thread that feeds the GL.
bool in_frustum(const Eigen::Matrix4f& vp, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  for (int k = 0; k < 6; ++k) {
    const Eigen::Vector4f plane = vp.row(3) + (k & 1 ? -1.0f : 1.0f) * vp.row(k / 2);  // inside: plane . p >= 0
    const float inside = plane.x() * (plane.x() > 0.0f ? hi.x() : lo.x()) +
                         plane.y() * (plane.y() > 0.0f ? hi.y() : lo.y()) +
                         plane.z() * (plane.z() > 0.0f ? hi.z() : lo.z()) + plane.w();
    if (inside < 0.0f) return false;
  }
  return true;
}
bool in_frustum(const Eigen::Matrix4f& vp, const Chunk& ch) { return in_frustum(vp, ch.lo, ch.hi); }

// How far a box seen from a lamp at L must grow to cover what the lamp map's PCF reads for it: two
// texels (texel_per_m at 1 m) at the box's far side, plus 1 cm.
float pcf_pad(float texel_per_m, const Eigen::Vector3f& L, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  const float far = (lo - L).cwiseAbs().cwiseMax((hi - L).cwiseAbs()).norm();
  return 2.0f * texel_per_m * far + 0.01f;
}

// Whether nothing inside the frustum vp_cam can lie in the shadow that box lo..hi casts from a
// lamp at L whose map ends at the plane at distance far_m along its axis: every lamp ray behind
// the box runs inside the hull of the box's corners and of their projections from L onto that
// plane, so when all 16 points lie outside one plane of vp_cam's frustum, the hull does too.
bool shadow_out_of_view(const Eigen::Matrix4f& vp_cam, const Eigen::Vector3f& L, const Eigen::Vector3f& axis,
                        float far_m, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  int outside[6] = {0, 0, 0, 0, 0, 0};
  for (int i = 0; i < 16; ++i) {
    Eigen::Vector3f p(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
    if (i & 8) {
      const float along = (p - L).dot(axis);
      // A corner beside or behind the lamp, or on the far plane or past it (a ray through the box
      // may then leave it sideways before the plane): no such bound.
      if (!(along > 1e-3f) || !(along < far_m)) return false;
      p = L + (p - L) * (far_m / along);
    }
    const Eigen::Vector4f c = vp_cam * p.homogeneous();
    outside[0] += c.x() < -c.w();
    outside[1] += c.x() > c.w();
    outside[2] += c.y() < -c.w();
    outside[3] += c.y() > c.w();
    outside[4] += c.z() < -c.w();
    outside[5] += c.z() > c.w();
  }
  for (int k : outside)
    if (k == 16) return true;
  return false;
}

// Draws the listed chunks (in mesh order; neighbours in one call).
void draw_chunks(const std::vector<const Chunk*>& chunks) {
  GLsizei first = 0, count = 0;
  auto flush = [&] {
    if (count > 0)
      glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT,
                     // NOLINTNEXTLINE(performance-no-int-to-ptr): GL takes a buffer offset as a pointer
                     reinterpret_cast<const void*>(static_cast<std::uintptr_t>(first) * sizeof(std::uint32_t)));
    count = 0;
  };
  for (const Chunk* ch : chunks) {
    if (count > 0 && first + count == ch->first) {
      count += ch->count;
    } else {
      flush();
      first = ch->first;
      count = ch->count;
    }
  }
  flush();
}

double luminance(const Eigen::Vector3d& c) { return 0.2126 * c.x() + 0.7152 * c.y() + 0.0722 * c.z(); }

}  // namespace

// rgba8 -> rgb8 + the alpha plane (segmentation ids), four pixels per step as 32-bit words on
// little-endian machines (a third of the byte loop's instructions: 4 -> ~1.3 ms of CPU a VGA frame).
void detail::split_rgba(const std::uint8_t* rgba, std::size_t px, std::uint8_t* rgb, std::uint8_t* alpha) {
  std::size_t i = 0;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  for (; i + 4 <= px; i += 4) {
    std::uint32_t p[4];
    std::memcpy(p, rgba + 4 * i, sizeof p);  // p[k] = r | g << 8 | b << 16 | a << 24
    const std::uint32_t out[3] = {(p[0] & 0xFFFFFFu) | (p[1] << 24), ((p[1] >> 8) & 0xFFFFu) | (p[2] << 16),
                                  ((p[2] >> 16) & 0xFFu) | (p[3] << 8)};
    const std::uint32_t a = (p[0] >> 24) | ((p[1] >> 16) & 0xFF00u) | ((p[2] >> 8) & 0xFF0000u) | (p[3] & 0xFF000000u);
    std::memcpy(rgb + 3 * i, out, sizeof out);
    std::memcpy(alpha + i, &a, sizeof a);
  }
#endif
  for (; i < px; ++i) {
    rgb[3 * i] = rgba[4 * i];
    rgb[3 * i + 1] = rgba[4 * i + 1];
    rgb[3 * i + 2] = rgba[4 * i + 2];
    alpha[i] = rgba[4 * i + 3];
  }
}

struct Renderer::Impl {
  std::shared_ptr<EglContext> ctx;  // shared by every Renderer made with the same context
  bool software_gl = true;          // llvmpipe, softpipe or swrast: fragments cost CPU time
  std::mutex spare_mutex;           // recycle() may come from another thread
  std::vector<Frame> spare;         // frames handed back: their buffers fill later frames
  World world;
  std::vector<CameraModel> cameras;
  RenderOptions options;
  WaterModel water;
  std::vector<GpuMesh> meshes;
  struct SurfaceMaps {
    GLuint colour = 0, slope = 0;  // albedo + relief height; the relief's gradient
  };
  std::map<std::string, SurfaceMaps> textures;                            // procedural, by name
  std::map<std::pair<const TextureImage*, bool>, GLuint> image_textures;  // mesh files' own maps (image, sRGB)
  std::vector<std::shared_ptr<const TextureImage>> mesh_images;           // keeps image_textures' keys alive
  Eigen::Vector3d sediment_albedo{0.7, 0.64, 0.5};  // the seabed's mean albedo (linear): settled sand
  // By material and lamp count (scene_variant()); compiled on first use.
  std::map<unsigned, Program> scene_variants;
  std::map<unsigned, Program> post_variants;  // by feature set (post_program())
  BodyVelocity velocity;                      // of the frame being drawn (motion blur)
  // Marine snow by lamp count, in-scattering by lamps, march samples and shadows (compile-time
  // counts: unrolled loops, constant uniform indices); compiled on first use.
  std::map<unsigned, Program> snow_variants;
  std::map<unsigned, Program> inscatter_variants;
  Program shadow;
  Program blur_down;                      // kBlurDownFS: the forward-scatter blur's levels
  GLuint shadow_tex = 0, shadow_fbo = 0;  // depth array, one layer per lamp
  GLuint shadow_nearest = 0;              // sampler: one depth test per lookup (the in-scatter march, smooth anyway)
  // Sampler: one texel, unfiltered. texture() at a texel's centre through it reads what texelFetch
  // does, for fewer instructions on llvmpipe (texelFetch checks every lane's bounds).
  GLuint nearest = 0;
  GLuint sun_tex = 0;  // the sun's depth map
  // Sampler: bilinear in the nearest mip level, repeating. For the relief's slope and the seabed's
  // macro modulation: llvmpipe's trilinear fetch is two bilinear ones (-6 M and -5 M instructions
  // a 640x480 frame), and a mip level's step in sharpness does not show in either (images: <= 3
  // levels apart for the macro, scattered pixels up to 20 for the slope, no seam).
  GLuint mip_nearest = 0;
  std::vector<float> sun_vp_cached;  // the matrix sun_tex was rendered with (empty: none)
  int shadow_size = 0;
  GLuint snow_vao = 0, snow_vbo = 0;
  GLsizei snow_count = 0;
  GLuint empty_vao = 0;
  GLuint fragment_query = 0;    // GL_SAMPLES_PASSED, for the profile's fragment counts
  GLuint invocation_query = 0;  // GL_FRAGMENT_SHADER_INVOCATIONS where the driver counts them (0: not)
  std::map<std::string, Targets> targets;
  std::vector<Slot> slots;
  std::deque<std::size_t> in_flight;  // slot indices, oldest first
  std::size_t next_slot = 0;
  std::deque<Frame> done;
  std::uint64_t sequence = 0;
  RenderTimings timings;
  std::size_t triangles = 0;

  const CameraModel& cam(const std::string& name) const {
    for (const auto& c : cameras)
      if (c.name == name) return c;
    std::string list;
    for (const auto& c : cameras) list += (list.empty() ? "" : ", ") + c.name;
    throw std::invalid_argument("unknown camera '" + name + "' (cameras: " + list + ")");
  }

  void self_test();
  void upload_scene(const SceneGeometry& geo);
  void upload_snow();
  void release_scene();  // meshes and marine-snow buffers (set_world, destructor)
  const SurfaceMaps& texture(const std::string& name);
  GLuint image_texture(const std::shared_ptr<const TextureImage>& image, bool srgb);
  Targets& targets_for(const CameraModel& c);
  struct FrameSetup;
  void set_lamps_W(Program& p, const FrameSetup& f) const;
  Program& snow_program(int nlamps);
  Program& inscatter_program(int nlamps, int nsamples, bool shadows);
  FrameSetup setup_frame(const Pose& X_WB, const CameraModel& c) const;
  void shadow_pass(const FrameSetup& f);
  void scene_pass(const Targets& t, const FrameSetup& f, double stamp_s);
  Program& scene_program(const GpuMesh& m, unsigned shadow_bits, const FrameSetup& f, double stamp_s,
                         std::set<unsigned>* set_up);
  // A mesh's material features as drawn under the current options (all off without materials).
  struct Look {
    bool bump, specular, sediment, normal_map, orm_map;
  };
  Look look(const GpuMesh& m) const {
    const bool on = options.materials;
    return {on && m.bump, on && m.specular, on && m.sediment, on && m.normal_map != 0, on && m.orm_map != 0};
  }
  // Shadow receiver culling (mark_sun_free(), lamp_shadow_bits()): boxes around what can cast a
  // shadow, by mesh: 0.5 m cells of objects, rocks and pipes; the chunks of the terrain.
  struct CasterBox {
    std::size_t mesh;
    Eigen::Vector3f lo, hi;
    /// A terrain chunk wholly below another terrain mesh (the far seabed under the patch): the
    /// index of that mesh, else -1. A lamp above that mesh and over its footprint cannot see it.
    long under = -1;
  };
  std::vector<CasterBox> caster_boxes;
  std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> terrain_bounds;  // by mesh (terrain only)
  float deepest_z = 0.0f;  // the deepest point of all the scene's geometry (z down) [m]
  void build_caster_boxes(const SceneGeometry& geo);
  /// Shadow caster culling: true when terrain chunk ch of meshes[mi] cannot shadow anything the
  /// camera at `eye` can see from lamp L, so L's map can do without it. Every lamp ray through the
  /// chunk sinks faster than the terrain's steepest slope: where it meets the height field it goes
  /// under it and stays under (the gap grows along the ray) until it leaves the mesh's footprint,
  /// and by then it is deeper than any geometry (deepest_z). What lies behind the chunk from the
  /// lamp is therefore under the terrain, which the eye over the mesh cannot see (the line to it
  /// crosses the surface); water, objects and terrain in front of the chunk are lit with or
  /// without it in the map.
  bool casts_nothing(std::size_t mi, const Chunk& ch, const Eigen::Vector3f& L, const Eigen::Vector3f& eye) const;
  void mark_sun_free();
  /// True when a chunk or caster box `under` a terrain mesh (index, -1 none) lies under it and `eye` stands over that
  /// mesh (inside its footprint, above its shallowest point): every line from the eye to the chunk crosses the mesh
  /// first (a height field over the whole rectangle), so nothing of it can be seen from there.
  bool hidden_under(long under, const Eigen::Vector3f& eye) const {
    return under >= 0 && stands_over(static_cast<std::size_t>(under), eye);
  }
  /// Whether `eye` stands over terrain mesh `mesh`: inside its footprint (a full grid over the
  /// rectangle), above its shallowest point.
  bool stands_over(std::size_t mesh, const Eigen::Vector3f& eye) const {
    const auto& [lo, hi] = terrain_bounds[mesh];
    return eye.x() >= lo.x() && eye.y() >= lo.y() && eye.x() <= hi.x() && eye.y() <= hi.y() && eye.z() < lo.z();
  }
  /// The shadow culls in force: on a hardware GPU only when asked (RenderOptions::shadow_culling_on_gpu).
  bool shadow_culls_pay() const { return software_gl || options.shadow_culling_on_gpu; }
  bool receiver_culling() const { return options.shadow_receiver_culling && shadow_culls_pay(); }
  bool caster_culling() const { return options.shadow_caster_culling && shadow_culls_pay(); }
  /// Back-face culling for a solid (GpuMesh::winding) drawn through vp, else both sides. Where vp
  /// keeps orientation (determinant > 0), a face whose right-hand normal points at the eye points
  /// to -z in normalised device coordinates: clockwise in window x (right), y (up).
  void cull_back_faces(const GpuMesh& m, const Eigen::Matrix4f& vp) const {
    if (!options.occlusion_culling || m.winding == 0) {
      glDisable(GL_CULL_FACE);
      return;
    }
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace((vp.determinant() > 0.0f) == (m.winding > 0) ? GL_CW : GL_CCW);
  }
  unsigned lamp_shadow_bits(std::size_t mesh, const Chunk& ch, const FrameSetup& f,
                            const std::vector<LampCasters>& casters) const;
  Program& post_program(const PostFeatures& features, int pixels = 0);
  void blur_levels(const Targets& t);
  void snow_pass(const FrameSetup& f, const CameraModel& c, double stamp_s);
  bool inscatter_pass(const Targets& t, const FrameSetup& f, const CameraModel& c, float* march_max_out);
  void post_pass(const Targets& t, const FrameSetup& f, const CameraModel& c, std::uint64_t seq, bool do_inscatter,
                 float march_max_m);
  /// color: what u_color reads (the scene's colour, or the radiance a remap resamples).
  void post_draw(Program& post, const Targets& t, GLuint color, const FrameSetup& f, const CameraModel& c,
                 std::uint64_t seq, float march_max_m, bool window, bool motion, const Eigen::Vector3d& v_C,
                 const Eigen::Vector3d& w_C);
  /// stamps: the slot's kStamps timestamp queries (RenderOptions::gpu_timers) or nullptr.
  void draw(const Pose& X_WB, const CameraModel& out_cam, double stamp_s, std::uint64_t seq, const GLuint* stamps);
  void start_readback(Slot& s, const Targets& t);
  Frame finish_readback(Slot& s);
  void collect_oldest();
};

void Renderer::Impl::self_test() {
  // Throwaway tiny frame: catches a context that renders nothing (no silent black images),
  // and avoids llvmpipe's "first framebuffer stays slow" oddity (TOOLCHAIN.md).
  Program p(detail::kPostVS, detail::kConstFS, "self-test");
  GLuint fbo = 0;
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  GLuint tex = make_tex(GL_RGBA8, 8, 8, GL_RGBA, GL_UNSIGNED_BYTE, GL_NEAREST);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
  check_fbo("self-test");
  glViewport(0, 0, 8, 8);
  glClearColor(0, 0, 0, 0);
  glClear(GL_COLOR_BUFFER_BIT);
  p.use();
  glBindVertexArray(empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  std::uint8_t px[8 * 8 * 4] = {};
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, 8, 8, GL_RGBA, GL_UNSIGNED_BYTE, px);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(1, &fbo);
  glDeleteTextures(1, &tex);
  glDeleteProgram(p.id());
  constexpr std::size_t kPx = std::size_t{4} * 27;  // pixel (3, 3) of the 8x8 test frame
  const int r = px[kPx], g = px[kPx + 1], b = px[kPx + 2];
  if (std::abs(r - 64) > 2 || std::abs(g - 128) > 2 || std::abs(b - 191) > 2)
    throw GlError("OpenGL context on '" + ctx->gl_renderer() + "' (" + ctx->platform() +
                  ") renders nothing usable: read back (" + std::to_string(r) + ", " + std::to_string(g) + ", " +
                  std::to_string(b) + ") instead of (64, 128, 191)");
}

const Renderer::Impl::SurfaceMaps& Renderer::Impl::texture(const std::string& name) {
  auto it = textures.find(name);
  if (it != textures.end()) return it->second;
  const int size = name == "none" ? 1 : std::max(16, options.texture_size);
  const auto tex = detail::make_texture(name, size);
  SurfaceMaps& maps = textures[name];
  // Albedo in sRGB, the relief height (alpha) linear; its slope mipmapped: a footprint's mean.
  maps.colour = gl::make_tiled_tex(GL_SRGB8_ALPHA8, size, size, GL_RGBA, GL_UNSIGNED_BYTE, tex.rgba.data());
  maps.slope = gl::make_tiled_tex(GL_RG16F, size, size, GL_RG, GL_FLOAT, tex.gradient.data());
  return maps;
}

// Alpha reads 1 (a relief is never drawn from a mesh file's map: GpuMesh::bump is off).
// A mesh file's map as a mipmapped, repeating texture: sRGB (base colour) or linear (normal, ORM).
GLuint Renderer::Impl::image_texture(const std::shared_ptr<const TextureImage>& image, bool srgb) {
  const std::pair<const TextureImage*, bool> key{image.get(), srgb};
  auto it = image_textures.find(key);
  if (it != image_textures.end()) return it->second;
  mesh_images.push_back(image);
  return image_textures[key] = gl::make_tiled_tex(srgb ? GL_SRGB8 : GL_RGB8, image->width, image->height, GL_RGB,
                                                  GL_UNSIGNED_BYTE, image->rgb.data());
}

void Renderer::Impl::upload_scene(const SceneGeometry& geo) {
  triangles = geo.triangle_count();
  {  // Sediment is the seabed's own sand: its texture's mean (linear) times its albedo.
    const auto px = detail::make_texture(world.seabed.material.texture, 64).rgba;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    const std::size_t n = px.size() / 4;
    for (std::size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) {
        const double e = px[i * 4 + c] / 255.0;
        sum[c] += e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
      }
    sediment_albedo = (sum / static_cast<double>(n)).cwiseProduct(world.seabed.material.albedo);
  }
  for (const auto& sm : geo.meshes) {
    GpuMesh g;
    g.seg_class = sm.seg_class;
    g.material = sm.material;
    g.triplanar = sm.triplanar;
    g.winding = closed_orientation(sm.mesh);
    g.terrain = sm.name == "seabed" || sm.name == "seabed_far";
    if (g.terrain) g.tan_slope = steepest_slope(sm.mesh);
    g.macro = g.terrain && sm.material.texture != "none";
    g.sections = sm.material.texture == "pipe_coating" && !sm.triplanar;
    g.texture = texture(sm.material.texture).colour;
    g.roughness = static_cast<float>(material_roughness(sm.material));
    g.metallic = static_cast<float>(sm.material.metallic);
    g.relief_m = static_cast<float>(material_relief_m(sm.material));
    g.bump = g.relief_m > 0.0f && sm.material.texture != "none";
    if (sm.maps.any()) {  // the mesh file's own maps, by its UVs (one repeat per unit)
      g.texture = sm.maps.base_color ? image_texture(sm.maps.base_color, true) : texture("none").colour;
      g.material.uv_scale_m = 1.0;
      g.macro = g.sections = false;
      g.bump = false;  // the file's normal map, if any, instead of the procedural relief
      if (sm.maps.normal) g.normal_map = image_texture(sm.maps.normal, false);
      if (sm.maps.orm) {
        // The map times the factors: the world's roughness / metallic when it sets them, else the file's.
        g.orm_map = image_texture(sm.maps.orm, false);
        g.roughness =
            static_cast<float>(std::isnan(sm.material.roughness) ? sm.maps.roughness_factor : sm.material.roughness);
        g.metallic = static_cast<float>(sm.material.metallic > 0.0 ? sm.material.metallic : sm.maps.metallic_factor);
      }
    }
    if (g.bump) g.gradient = texture(sm.material.texture).slope;
    // A dielectric's highlight in water is faint (F0 = 0.0032 for index 1.5 against 1.34): only
    // smooth ones show it (roughness 0.45: +4..30 % over the diffuse at the peak; 0.8: < 1 %). An
    // ORM map varies both per pixel.
    g.specular = g.metallic > 0.0f || g.roughness < 0.7f || g.orm_map != 0;
    g.sediment_cover = static_cast<float>(material_sediment(sm.material));
    g.sediment = !g.macro && sm.seg_class != SegClass::kSeabed && g.sediment_cover > 0.0f;
    // A height field on a grid is drawn by tiles at levels of detail (the skirts' points appended
    // to a copy of its mesh); any other mesh in chunks.
    MeshData lod_mesh;
    const MeshData* mesh = &sm.mesh;
    std::vector<float> drop;
    std::vector<std::uint32_t> indices;
    int rows = 0, cols = 0;
    if (g.terrain && grid_layout(sm.mesh, &rows, &cols)) {
      lod_mesh = sm.mesh;
      indices = terrain_lod(&lod_mesh, rows, cols, &drop, &g.chunks, &g.tiles, &g.tile_cols, &g.lift);
      g.lamp_lift = g.lift;
      mesh = &lod_mesh;
    } else if (!sm.lod_parts.empty()) {
      indices = lod_indices(sm, &g.chunks, &g.lod, &g.lift);
    } else {
      indices = chunked_indices(sm.mesh, &g.chunks);
    }
    glGenVertexArrays(1, &g.vao);
    glBindVertexArray(g.vao);
    glGenBuffers(4, g.vbo);
    const std::vector<float>* attr[4] = {&mesh->positions, &mesh->normals, &mesh->uvs, &drop};
    const int comps[4] = {3, 3, 2, 1};
    for (int a = 0; a < 4; ++a) {
      if (a == 3 && drop.empty()) continue;  // no skirts: a_drop is the generic attribute's 0
      glBindBuffer(GL_ARRAY_BUFFER, g.vbo[a]);
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(attr[a]->size() * sizeof(float)), attr[a]->data(),
                   GL_STATIC_DRAW);
      glEnableVertexAttribArray(static_cast<GLuint>(a));
      glVertexAttribPointer(static_cast<GLuint>(a), comps[a], GL_FLOAT, GL_FALSE, 0, nullptr);
    }
    glGenBuffers(1, &g.ebo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
                 indices.data(), GL_STATIC_DRAW);
    g.index_count = static_cast<GLsizei>(indices.size());
    glBindVertexArray(0);
    meshes.push_back(g);
  }
  build_caster_boxes(geo);
  mark_sun_free();
  for (GpuMesh& m : meshes) {
    bool mixed = false;               // a tile partly under another terrain mesh
    for (TerrainTile& t : m.tiles) {  // sun-free and under another mesh when all its chunks are
      t.box.sun_free = true;
      t.box.under = t.chunk_begin < t.chunk_end ? m.chunks[t.chunk_begin].under : -1;
      for (std::size_t c = t.chunk_begin; c < t.chunk_end; ++c) {
        t.box.sun_free = t.box.sun_free && m.chunks[c].sun_free;
        mixed = mixed || m.chunks[c].under != t.box.under;
      }
    }
    // Terrain partly under other terrain (the far seabed, whose part under the patch occlusion
    // culling leaves out chunk by chunk): drawn by chunks, without levels of detail.
    if (mixed) m.tiles.clear();
  }
  check_gl("scene upload");
}

namespace {

constexpr double kCasterCellM = 0.5;  // caster boxes of objects, rocks and pipes: 0.5 m cells

// The box's extent along the unit axis a.
std::pair<float, float> box_interval(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, const Eigen::Vector3f& a) {
  const Eigen::Vector3f mid = 0.5f * (lo + hi), half = 0.5f * (hi - lo);
  const float m = a.dot(mid), r = half.dot(a.cwiseAbs());
  return {m - r, m + r};
}

}  // namespace

void Renderer::Impl::build_caster_boxes(const SceneGeometry& geo) {
  caster_boxes.clear();
  terrain_bounds.assign(meshes.size(), {Eigen::Vector3f::Constant(1e30f), Eigen::Vector3f::Constant(-1e30f)});
  deepest_z = -1e30f;
  for (const GpuMesh& m : meshes)
    for (const Chunk& c : m.chunks) deepest_z = std::max(deepest_z, c.hi.z());
  for (std::size_t mi = 0; mi < meshes.size(); ++mi)
    if (meshes[mi].terrain)
      for (const Chunk& c : meshes[mi].chunks) {
        terrain_bounds[mi].first = terrain_bounds[mi].first.cwiseMin(c.lo);
        terrain_bounds[mi].second = terrain_bounds[mi].second.cwiseMax(c.hi);
      }
  for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
    if (meshes[mi].terrain) {  // the terrain casts on other terrain only (the patch's edge on the far seabed)
      for (Chunk& c : meshes[mi].chunks) {
        CasterBox box{mi, c.lo, c.hi};
        // Under another terrain mesh: inside its footprint (a full grid: its bounding rectangle)
        // and deeper than its deepest point.
        for (std::size_t pi = 0; pi < meshes.size(); ++pi) {
          const auto& [plo, phi] = terrain_bounds[pi];
          if (pi != mi && meshes[pi].terrain && c.lo.x() >= plo.x() && c.lo.y() >= plo.y() && c.hi.x() <= phi.x() &&
              c.hi.y() <= phi.y() && c.lo.z() > phi.z())
            box.under = static_cast<long>(pi);
        }
        c.under = box.under;
        caster_boxes.push_back(box);
      }
      continue;
    }
    const MeshData& mesh = geo.meshes[mi].mesh;
    std::map<std::pair<long, long>, std::size_t> cell_box;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      const auto p = triangle_corners(mesh, t);
      const Eigen::Vector3f c = (p[0] + p[1] + p[2]) / 3.0f;
      const std::pair<long, long> key{std::lround(std::floor(c.x() / kCasterCellM)),
                                      std::lround(std::floor(c.y() / kCasterCellM))};
      auto [it, fresh] = cell_box.try_emplace(key, caster_boxes.size());
      if (fresh) caster_boxes.push_back({mi, p[0], p[0]});
      CasterBox& box = caster_boxes[it->second];
      for (const auto& q : p) {
        box.lo = box.lo.cwiseMin(q);
        box.hi = box.hi.cwiseMax(q);
      }
    }
  }
}

bool Renderer::Impl::casts_nothing(std::size_t mi, const Chunk& ch, const Eigen::Vector3f& L,
                                   const Eigen::Vector3f& eye) const {
  const GpuMesh& m = meshes[mi];
  if (!m.terrain) return false;
  if (!stands_over(mi, eye)) return false;
  const auto& [lo, hi] = terrain_bounds[mi];
  // The flattest lamp ray through the chunk: from the lamp to its shallowest, farthest corner.
  const float drop = ch.lo.z() - L.z();
  const float h_far =
      std::hypot(std::max(L.x() - ch.lo.x(), ch.hi.x() - L.x()), std::max(L.y() - ch.lo.y(), ch.hi.y() - L.y()));
  if (!(drop > 0.0f) || !(drop > m.tan_slope * h_far)) return false;
  const float sink = drop / std::max(h_far, 1e-6f);  // metres down per metre across, every ray
  // Leaving the footprint at least this far from the chunk, below all geometry (1 cm to spare).
  const float to_edge = std::min({ch.lo.x() - lo.x(), hi.x() - ch.hi.x(), ch.lo.y() - lo.y(), hi.y() - ch.hi.y()});
  return ch.lo.z() + sink * std::max(to_edge, 0.0f) >= deepest_z + 0.01f;
}

// Shadow receiver culling for the sun (static scene, fixed sun): a terrain chunk needs the sun's
// shadow lookup only if a caster can stand between it and the sun: a caster box of another mesh
// whose extent, seen along the sunlight, overlaps the chunk's and lies up-sun of some of it; or
// the terrain itself, when its steepest slope is at least the sun's elevation (from any point of a
// height field whose slopes are all flatter than the light, the ray to the sun rises faster than
// the ground can).
void Renderer::Impl::mark_sun_free() {
  // Casters grow by two texels of the sun's map: the PCF lookup reads the next texel too.
  const float pad = 4.0f * static_cast<float>(kSunShadowHalfM) /
                    static_cast<float>(std::min(4096, kSunMapScale * options.shadow_map_size));
  const Eigen::Vector3f s = world.sun.direction_W.normalized().cast<float>();
  const Eigen::Vector3f a = std::abs(s.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
  const Eigen::Vector3f u = (a - s * a.dot(s)).normalized(), v = s.cross(u);
  const float tan_elevation = s.z() > 1e-6f ? s.z() / std::hypot(s.x(), s.y()) : 0.0f;  // inf overhead
  // Each caster's extent along u, v (across the sunlight) and s (along it), once.
  using Interval = std::pair<float, float>;
  std::vector<std::array<Interval, 3>> seen;
  seen.reserve(caster_boxes.size());
  for (const CasterBox& c : caster_boxes)
    seen.push_back({box_interval(c.lo, c.hi, u), box_interval(c.lo, c.hi, v), box_interval(c.lo, c.hi, s)});
  for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
    GpuMesh& m = meshes[mi];
    for (Chunk& r : m.chunks) r.sun_free = false;
    if (!m.terrain || !(m.tan_slope < tan_elevation)) continue;
    for (Chunk& r : m.chunks) {
      const auto ru = box_interval(r.lo, r.hi, u), rv = box_interval(r.lo, r.hi, v), rs = box_interval(r.lo, r.hi, s);
      bool blocked = false;
      for (std::size_t ci = 0; ci < caster_boxes.size(); ++ci) {
        const CasterBox& c = caster_boxes[ci];
        if (c.mesh == mi) continue;
        const auto& [cu, cv, cs] = seen[ci];
        if (cu.first <= ru.second + pad && ru.first <= cu.second + pad && cv.first <= rv.second + pad &&
            rv.first <= cv.second + pad && cs.first < rs.second + pad && c.lo.z() - pad <= r.hi.z()) {
          blocked = true;
          break;
        }
      }
      r.sun_free = !blocked;
    }
  }
}

void Renderer::Impl::upload_snow() {
  const auto& ms = world.marine_snow;
  const double n = ms.density_per_m3 * ms.box_m * ms.box_m * ms.box_m;
  snow_count = static_cast<GLsizei>(std::min(200000.0, std::max(0.0, n)));
  if (snow_count == 0) return;
  std::vector<float> seeds(static_cast<std::size_t>(snow_count) * 3);
  for (GLsizei i = 0; i < snow_count; ++i)
    for (int k = 0; k < 3; ++k) seeds[3 * i + k] = static_cast<float>(noise::lattice(i, k, 3, ms.seed));
  glGenVertexArrays(1, &snow_vao);
  glBindVertexArray(snow_vao);
  glGenBuffers(1, &snow_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, snow_vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(seeds.size() * sizeof(float)), seeds.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glBindVertexArray(0);
}

namespace {

// The internal image's margin on each side of the output frame [px] for a field that reaches
// `over` pixels beyond the frame (negative: stays inside it), with 2 px to spare for the bilinear
// read. A field inside the frame (behind a flat port, whose magnification narrows the view) gives a
// negative margin: the internal image is cropped to what the post pass reads, in steps of 4 px, so
// that the pixels kept lie at the same place relative to the principal point, and the in-scatter's
// low-resolution texels (4 x 4 by default) and the forward-scatter blur's 4 x 4 means group the same
// pixels as without the crop (its 16 x 16 means may not; demo front camera, measured before those
// replaced a mip chain: mean difference 0.03 of 255, at most 9 levels).
int internal_margin(float over, int size) {
  const int need = static_cast<int>(std::ceil(std::max(over, -0.5f * size))) + 2;
  if (need >= 2) return std::min(need, size / 2);
  const int crop = 4 * ((2 - need) / 4);
  return 2 - std::min(crop, 4 * ((size / 2 - 16) / 4));
}

}  // namespace

Targets& Renderer::Impl::targets_for(const CameraModel& c) {
  auto it = targets.find(c.name);
  if (it != targets.end()) return it->second;
  Targets t;
  t.out_width = c.width;
  t.out_height = c.height;
  t.out_K[0] = c.fx;
  t.out_K[1] = c.fy;
  t.out_K[2] = c.cx;
  t.out_K[3] = c.cy;
  std::vector<cv::Point2f> dst;
  // Behind a refracting port the scene is rendered with the water-side paraxial focal length
  // (1:1 sampling at the image centre); each output pixel's ray is undistorted in air, then
  // refracted by the port, then projected into that pinhole.
  t.seen = c.water_equivalent();  // a least-squares fit behind a port: once per camera
  const double magnification = t.seen.fx / c.fx;
  if (c.has_distortion() || c.port.refracts()) {
    // For every output (distorted) pixel, the undistorted pixel it sees.
    std::vector<cv::Point2f> src(static_cast<std::size_t>(c.width) * c.height);
    for (int v = 0; v < c.height; ++v)
      for (int u = 0; u < c.width; ++u) src[static_cast<std::size_t>(v) * c.width + u] = cv::Point2f(u, v);
    cv::Mat K(3, 3, CV_64F), D(1, 5, CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) K.at<double>(r, q) = c.K()(r, q);
    for (int k = 0; k < 5; ++k) D.at<double>(0, k) = c.distortion[k];
    cv::undistortPoints(src, dst, K, D, cv::noArray(), c.port.refracts() ? cv::Mat::eye(3, 3, CV_64F) : K,
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 1e-6));
    if (c.port.refracts())
      for (auto& p : dst) {  // normalized air ray -> water ray -> pixel of the water pinhole
        const Eigen::Vector3d w = c.port.to_water({p.x, p.y, 1.0});
        p = cv::Point2f(static_cast<float>(c.fx * magnification * w.x() / w.z() + c.cx),
                        static_cast<float>(c.fy * magnification * w.y() / w.z() + c.cy));
      }
    // How far the undistorted field reaches beyond the output frame (negative: how far inside it
    // stays), on the worse side of the principal point.
    float over_x = -1e9f, over_y = -1e9f;
    for (const auto& p : dst) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
      over_x = std::max({over_x, -p.x, p.x - (c.width - 1)});
      over_y = std::max({over_y, -p.y, p.y - (c.height - 1)});
    }
    t.margin_x = internal_margin(over_x, c.width);
    t.margin_y = internal_margin(over_y, c.height);
    for (auto& p : dst) p += cv::Point2f(static_cast<float>(t.margin_x), static_cast<float>(t.margin_y));
  }
  t.internal = c;
  t.internal.fx *= magnification;
  t.internal.fy *= magnification;
  t.internal.width = c.width + 2 * t.margin_x;
  t.internal.height = c.height + 2 * t.margin_y;
  t.internal.cx += t.margin_x;
  t.internal.cy += t.margin_y;
  t.width = t.internal.width;
  t.height = t.internal.height;

  const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glGenFramebuffers(1, &t.scene_fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, t.scene_fbo);
  t.scene_color = make_tex(GL_RGBA16F, t.width, t.height, GL_RGBA, GL_FLOAT, GL_LINEAR);
  t.scene_zc = make_tex(GL_R32F, t.width, t.height, GL_RED, GL_FLOAT, GL_NEAREST);
  t.scene_depth = make_tex(GL_DEPTH_COMPONENT32F, t.width, t.height, GL_DEPTH_COMPONENT, GL_FLOAT, GL_NEAREST);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.scene_color, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, t.scene_zc, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, t.scene_depth, 0);
  glDrawBuffers(2, bufs);
  check_fbo("scene");

  t.is_scale = std::max(1, options.lamp_scatter_downsample);
  t.is_width = (t.width + t.is_scale - 1) / t.is_scale;
  t.is_height = (t.height + t.is_scale - 1) / t.is_scale;
  glGenFramebuffers(1, &t.is_fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, t.is_fbo);
  // 32-bit floats: llvmpipe reads them without a half-float conversion per texel (the post pass
  // reads four a pixel), and they are small (1/16 of the image).
  t.is_tex = make_tex(GL_RGBA32F, t.is_width, t.is_height, GL_RGBA, GL_FLOAT, GL_NEAREST);
  t.is_water_tex = make_tex(GL_RGBA32F, t.is_width, t.is_height, GL_RGBA, GL_FLOAT, GL_LINEAR);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.is_tex, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, t.is_water_tex, 0);
  glDrawBuffers(2, bufs);
  check_fbo("in-scatter");

  // 32-bit floats: the post pass reads two a pixel, without a half-float conversion each.
  for (int k = 0; k < 2; ++k) {
    const int step = k == 0 ? 4 : 16;
    t.blur_width[k] = (t.width + step - 1) / step;
    t.blur_height[k] = (t.height + step - 1) / step;
    t.blur_tex[k] = make_tex(GL_RGBA32F, t.blur_width[k], t.blur_height[k], GL_RGBA, GL_FLOAT, GL_LINEAR);
    glGenFramebuffers(1, &t.blur_fbo[k]);
    glBindFramebuffer(GL_FRAMEBUFFER, t.blur_fbo[k]);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.blur_tex[k], 0);
    glDrawBuffers(1, bufs);
    check_fbo("forward-scatter blur");
  }

  glGenFramebuffers(1, &t.post_fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, t.post_fbo);
  t.post_rgba = make_tex(GL_RGBA8, c.width, c.height, GL_RGBA, GL_UNSIGNED_BYTE, GL_NEAREST);
  t.post_zc = make_tex(GL_R32F, c.width, c.height, GL_RED, GL_FLOAT, GL_NEAREST);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.post_rgba, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, t.post_zc, 0);
  // The post pass draws geometry and water apart, by a depth test against scene_depth: attached
  // to post_fbo where it reads pixel for pixel, else to the radiance target it remaps from.
  if (dst.empty()) glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, t.scene_depth, 0);
  glDrawBuffers(2, bufs);
  check_fbo("post");
  if (!dst.empty()) {
    t.distmap = make_tex(GL_RG32F, c.width, c.height, GL_RG, GL_FLOAT, GL_NEAREST);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, c.width, c.height, GL_RG, GL_FLOAT, dst.data());
    glGenFramebuffers(1, &t.lin_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, t.lin_fbo);
    // 32-bit floats: the remap reads them without a half-float conversion, and seg exactly.
    t.lin_tex = make_tex(GL_RGBA32F, t.width, t.height, GL_RGBA, GL_FLOAT, GL_LINEAR);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.lin_tex, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, t.scene_depth, 0);
    glDrawBuffers(1, bufs);
    check_fbo("post radiance");
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  check_gl("render targets");
  return targets.emplace(c.name, t).first->second;
}

// Per-frame camera and lamp quantities shared by the passes.
struct Renderer::Impl::FrameSetup {
  Pose X_WB, X_WC, X_CW;
  Eigen::Matrix4f view, proj;
  Eigen::Vector3d cam_W;
  int nl = 0;  ///< lamps used (at most 4)
  float lamp_pos_W[12], lamp_dir_W[12], lamp_pos_C[12], lamp_dir_C[12], lamp_I[12], lamp_cos[8];
  bool shadows = false;
  float shadow_vp_W[64], shadow_vp_C[64];  // per lamp: world -> lamp clip, optical -> lamp clip
  float lamp_texel_per_m[4];               // per lamp: its shadow map's texel at 1 m [m]
  bool sun_shadow = false;
  float sun_vp[16];  // world -> sun clip (orthographic)
  float lod_fx = 0;  // the internal camera's larger focal length [px]: levels of detail
};

Renderer::Impl::FrameSetup Renderer::Impl::setup_frame(const Pose& X_WB, const CameraModel& c) const {
  FrameSetup f;
  f.X_WB = X_WB;
  f.X_WC = X_WB * c.X_BC;
  f.X_CW = f.X_WC.inverse();
  f.view = f.X_CW.matrix().cast<float>();
  f.proj = projection_from_K(c);
  f.cam_W = f.X_WC.translation();
  f.lod_fx = static_cast<float>(std::max(c.fx, c.fy));
  // Lamps in world and camera frames.
  f.nl = options.lamps ? static_cast<int>(std::min<std::size_t>(4, world.lamps.size())) : 0;
  for (int i = 0; i < f.nl; ++i) {
    const Lamp& L = world.lamps[i];
    const Pose X_WL = f.X_WB * L.X_BL;
    const Eigen::Vector3d pW = X_WL.translation(), dW = X_WL.linear().col(0).normalized();
    const Eigen::Vector3d pC = f.X_CW * pW, dC = f.X_CW.linear() * dW;
    for (int k = 0; k < 3; ++k) {
      f.lamp_pos_W[3 * i + k] = static_cast<float>(pW[k]);
      f.lamp_dir_W[3 * i + k] = static_cast<float>(dW[k]);
      f.lamp_pos_C[3 * i + k] = static_cast<float>(pC[k]);
      f.lamp_dir_C[3 * i + k] = static_cast<float>(dC[k]);
      f.lamp_I[3 * i + k] = static_cast<float>(L.intensity[k]);
    }
    f.lamp_cos[static_cast<std::size_t>(2 * i)] = static_cast<float>(std::cos(L.cone_half_angle_rad));
    f.lamp_cos[static_cast<std::size_t>(2 * i) + 1] = static_cast<float>(std::cos(0.55 * L.cone_half_angle_rad));
    // The lamp's shadow frustum: its cone (plus a margin) as a square perspective view.
    CameraModel lc;
    lc.width = lc.height = std::max(16, options.shadow_map_size);
    const double half = std::min(1.05 * L.cone_half_angle_rad + 0.02, 1.45);
    f.lamp_texel_per_m[i] = static_cast<float>(2.0 * std::tan(half) / std::max(16, options.shadow_map_size));
    lc.fx = lc.fy = 0.5 * lc.width / std::tan(half);
    lc.cx = lc.cy = 0.5 * lc.width - 0.5;
    lc.near_m = 0.05;
    lc.far_m = kLampFarM;
    Pose X_WLo = X_WL;
    X_WLo.linear() = X_WL.linear() * R_camera_body_to_optical();
    const Eigen::Matrix4f vp_W = projection_from_K(lc) * X_WLo.inverse().matrix().cast<float>();
    const Eigen::Matrix4f vp_C = vp_W * f.X_WC.matrix().cast<float>();
    std::copy(vp_W.data(), vp_W.data() + 16, f.shadow_vp_W + std::ptrdiff_t{16} * i);
    std::copy(vp_C.data(), vp_C.data() + 16, f.shadow_vp_C + std::ptrdiff_t{16} * i);
  }
  // The sun's shadow map: an orthographic view along the sunlight over a square of
  // 2 kSunShadowHalfM around the camera, its centre snapped to whole texels (no shimmering
  // as the camera moves).
  const Eigen::Vector3d sdir = world.sun.direction_W.normalized();
  f.sun_shadow = options.shadows && sdir.z() > 0.05 && world.sun.ambient_fraction < 1.0;
  if (f.sun_shadow) {
    const Eigen::Vector3d a = std::abs(sdir.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d xl = (a - sdir * a.dot(sdir)).normalized(), yl = sdir.cross(xl);
    const double cx = std::round(xl.dot(f.cam_W) / kSunSnapM) * kSunSnapM;
    const double cy = std::round(yl.dot(f.cam_W) / kSunSnapM) * kSunSnapM;
    // Along the light too, in steps: the matrix changes only when the camera has moved.
    const double cz = std::round(sdir.dot(f.cam_W) / kSunSnapM) * kSunSnapM;
    const Eigen::Vector3d centre = xl * cx + yl * cy + sdir * cz;
    const Eigen::Vector3d eye = centre - sdir * 60.0;  // a tight depth range: a small bias in metres
    Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
    view.block<1, 3>(0, 0) = xl.transpose();
    view.block<1, 3>(1, 0) = yl.transpose();
    view.block<1, 3>(2, 0) = sdir.transpose();
    view.block<3, 1>(0, 3) = -view.block<3, 3>(0, 0) * eye;
    const double n = 1.0, far = 140.0;
    Eigen::Matrix4d proj = Eigen::Matrix4d::Zero();
    proj(0, 0) = proj(1, 1) = 1.0 / kSunShadowHalfM;
    proj(2, 2) = 2.0 / (far - n);
    proj(2, 3) = -(far + n) / (far - n);
    proj(3, 3) = 1.0;
    const Eigen::Matrix4f vp = (proj * view).cast<float>();
    std::copy(vp.data(), vp.data() + 16, f.sun_vp);
  }
  f.shadows = options.shadows && f.nl > 0;

  return f;
}

// Depth of the scene seen from each lamp (its shadow map), with a slope-scaled offset against
// self-shadowing. Both sides of every face: culling a solid's back faces here would let the front
// faces' offset decide the texels on its silhouette (-2 % of a frame's instructions, but shadow
// edges move by a texel at contact lines).
void Renderer::Impl::shadow_pass(const FrameSetup& f) {
  timings.lamp_map_triangles = timings.lamp_map_culled = 0;
  if (!f.shadows && !f.sun_shadow) return;
  const int size = options.shadow_map_size;
  if (shadow_size != size) {
    if (shadow_tex) glDeleteTextures(1, &shadow_tex);
    glGenTextures(1, &shadow_tex);
    glBindTexture(GL_TEXTURE_2D_ARRAY, shadow_tex);
    glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_DEPTH_COMPONENT32F, size, size, kShadowLayers, 0, GL_DEPTH_COMPONENT,
                 GL_FLOAT, nullptr);
    shadow_sampling(GL_TEXTURE_2D_ARRAY);
    if (sun_tex) glDeleteTextures(1, &sun_tex);
    sun_vp_cached.clear();
    glGenTextures(1, &sun_tex);
    glBindTexture(GL_TEXTURE_2D, sun_tex);
    const int sun_size = std::min(4096, kSunMapScale * size);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, sun_size, sun_size, 0, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    shadow_sampling(GL_TEXTURE_2D);
    if (!shadow_fbo) glGenFramebuffers(1, &shadow_fbo);
    shadow_size = size;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
  glDrawBuffer(GL_NONE);
  glReadBuffer(GL_NONE);
  glViewport(0, 0, size, size);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glEnable(GL_POLYGON_OFFSET_FILL);
  const auto bias = static_cast<float>(options.shadow_bias);
  glPolygonOffset(2.0f * bias, 4.0f * bias);
  shadow.use();
  const float one = 1.0f;
  const Eigen::Vector3f cam = f.cam_W.cast<float>();
  const Eigen::Matrix4f cam_vp = f.proj * f.view;
  // The sun's map depends on the static scene and its matrix only: reused until either changes.
  const bool sun_fresh =
      f.sun_shadow && sun_vp_cached.size() == 16 && std::equal(sun_vp_cached.begin(), sun_vp_cached.end(), f.sun_vp);
  for (int i = 0; i < (f.shadows ? f.nl : 0) + (f.sun_shadow && !sun_fresh ? 1 : 0); ++i) {
    const bool sun = f.sun_shadow && i == (f.shadows ? f.nl : 0);
    if (sun) sun_vp_cached.assign(f.sun_vp, f.sun_vp + 16);
    if (sun) {
      const int sun_size = std::min(4096, kSunMapScale * size);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, sun_tex, 0);
      glViewport(0, 0, sun_size, sun_size);
      glPolygonOffset(1.5f * bias, 2.0f * bias);
    } else {
      glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, shadow_tex, 0, i);
    }
    check_fbo("shadow map");
    glClearBufferfv(GL_DEPTH, 0, &one);
    const float* vp_data = sun ? f.sun_vp : f.shadow_vp_W + std::ptrdiff_t{16} * i;
    glUniformMatrix4fv(shadow["u_vp"], 1, GL_FALSE, vp_data);
    const Eigen::Matrix4f vp = Eigen::Map<const Eigen::Matrix4f>(vp_data);
    // The sun has no position: its map keeps the terrain hidden under other terrain (and is cached).
    const Eigen::Vector3f lamp =
        sun ? Eigen::Vector3f::Zero()
            : Eigen::Vector3f(Eigen::Map<const Eigen::Vector3f>(f.lamp_pos_W + std::ptrdiff_t{3} * i));
    const Eigen::Vector3f axis =
        sun ? Eigen::Vector3f::Zero()
            : Eigen::Vector3f(Eigen::Map<const Eigen::Vector3f>(f.lamp_dir_W + std::ptrdiff_t{3} * i));
    for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
      const GpuMesh& m = meshes[mi];
      glBindVertexArray(m.vao);
      std::vector<const Chunk*> visible;
      visible.reserve(m.chunks.size());
      for (std::size_t ci = 0; ci < m.chunks.size(); ++ci) {
        const Chunk& ch = m.chunks[ci];
        if (!in_frustum(vp, ch)) continue;
        if (sun) {  // the finest (the map is kept while the sun stands still; see GpuMesh::lift)
          visible.push_back(&ch);
          continue;
        }
        if (options.occlusion_culling && hidden_under(ch.under, lamp)) continue;
        // A part at levels of detail: the level the camera sees (the lamps ride with it), which its
        // lookups of the lamp maps then find there.
        const Chunk& draw =
            m.lod.empty() ? ch : m.lod[ci].level[lod_level(m.lod[ci], cam, f.lod_fx, options.terrain_lod_px)];
        bool culled = false;
        if (caster_culling()) {
          const float pad = pcf_pad(f.lamp_texel_per_m[i], lamp, ch.lo, ch.hi);
          culled = (m.terrain && casts_nothing(mi, ch, lamp, cam)) ||
                   shadow_out_of_view(cam_vp, lamp, axis, kLampFarM, ch.lo.array() - pad, ch.hi.array() + pad);
        }
        (culled ? timings.lamp_map_culled : timings.lamp_map_triangles) += static_cast<std::size_t>(draw.count) / 3;
        if (!culled) visible.push_back(&draw);
      }
      draw_chunks(visible);
    }
  }
  glDisable(GL_POLYGON_OFFSET_FILL);
}

namespace {

// Scene variant bits: triplanar 1, macro 2, sections 4, bump 8, specular 16, sediment 32, sun shadow 64,
// lamp shadows 128, normal map 256, ORM map 512, lamps << 10. The shadow bits come per chunk
// (shadow receiver culling).
constexpr unsigned kSunShadowBit = 64, kLampShadowBit = 128, kShadowShift = 6, kNormalMapBit = 256, kOrmBit = 512,
                   kLampShift = 10;
std::string scene_defines(unsigned v) {
  const auto bit = [v](unsigned b) { return (v & b) ? "1" : "0"; };
  return std::string("#define TRIPLANAR ") + bit(1) + "\n#define MACRO " + bit(2) + "\n#define SECTIONS " + bit(4) +
         "\n#define BUMP " + bit(8) + "\n#define SPECULAR " + bit(16) + "\n#define SEDIMENT " + bit(32) +
         "\n#define SUN_SHADOW " + bit(kSunShadowBit) + "\n#define LAMP_SHADOWS " + bit(kLampShadowBit) +
         "\n#define NORMAL_MAP " + bit(kNormalMapBit) + "\n#define ORM_MAP " + bit(kOrmBit) + "\n#define NLAMPS " +
         std::to_string(v >> kLampShift) + "\n";
}

}  // namespace

// The scene program of a material variant (compiled on first use), with this frame's uniforms
// set the first time it is used in the pass.
// shadow_bits: 1 the sun's shadow map, 2 the lamps'.
namespace {

// The program of `variants` under `key`, compiled on first use with the defines make_defines()
// returns (built only then, not every frame).
template <typename MakeDefines>
Program& program_variant(std::map<unsigned, Program>& variants, unsigned key, const char* vs, const char* fs,
                         const char* name, MakeDefines&& make_defines) {
  auto it = variants.find(key);
  if (it == variants.end()) it = variants.emplace(key, Program(vs, fs, name, make_defines())).first;
  return it->second;
}

}  // namespace

Program& Renderer::Impl::scene_program(const GpuMesh& m, unsigned shadow_bits, const FrameSetup& f, double stamp_s,
                                       std::set<unsigned>* set_up) {
  const Look k = look(m);
  const unsigned v = (m.triplanar ? 1u : 0u) | (m.macro ? 2u : 0u) | (m.sections ? 4u : 0u) | (k.bump ? 8u : 0u) |
                     (k.specular ? 16u : 0u) | (k.sediment ? 32u : 0u) | (shadow_bits << kShadowShift) |
                     (k.normal_map ? kNormalMapBit : 0u) | (k.orm_map ? kOrmBit : 0u) |
                     (static_cast<unsigned>(f.nl) << kLampShift);
  Program& p =
      program_variant(scene_variants, v, detail::kSceneVS, detail::kSceneFS, "scene", [v] { return scene_defines(v); });
  p.use();
  if (!set_up->insert(v).second) return p;
  glUniformMatrix4fv(p["u_view"], 1, GL_FALSE, f.view.data());
  glUniformMatrix4fv(p["u_proj"], 1, GL_FALSE, f.proj.data());
  set3(p["u_cam_W"], f.cam_W);
  set3(p["u_sun_dir_W"], world.sun.direction_W);
  set3(p["u_E0"], world.sun.surface_irradiance);
  glUniform1f(p["u_ambient"], static_cast<float>(world.sun.ambient_fraction));
  glUniform1f(p["u_caustics"], options.caustics ? static_cast<float>(options.caustic_strength) : 0.0f);
  glUniform1f(p["u_time"], static_cast<float>(std::fmod(stamp_s, 1.0e4)));
  set3(p["u_Kd"], water.K_d);
  set3(p["u_betaD"], water.beta_D);
  set_lamps_W(p, f);
  if (v & kSunShadowBit) {
    glUniformMatrix4fv(p["u_sun_vp"], 1, GL_FALSE, f.sun_vp);
    glUniform1i(p["u_sun_map"], 6);
  }
  if (v & kLampShadowBit) {
    glUniformMatrix4fv(p["u_shadow_vp[0]"], f.nl, GL_FALSE, f.shadow_vp_W);
    glUniform1i(p["u_shadow"], 5);
  }
  glUniform1i(p["u_tex"], 0);
  if (v & 2u) glUniform1i(p["u_tex_macro"], 4);
  if (v & 8u) glUniform1i(p["u_grad"], 1);
  if (v & kNormalMapBit) glUniform1i(p["u_normal_map"], 2);
  if (v & kOrmBit) glUniform1i(p["u_orm"], 3);
  if (v & 32u) {
    set3(p["u_sediment_albedo"], sediment_albedo);
    // No seabed: nothing is buried.
    glUniform1f(p["u_seabed_z"], world.seabed.enabled ? static_cast<float>(world.seabed.depth_m) : 1e9f);
  }
  return p;
}

// The lamps' world-frame uniforms (position, beam axis, intensity, cone) of the scene and the
// marine snow programs.
void Renderer::Impl::set_lamps_W(Program& p, const FrameSetup& f) const {
  if (f.nl == 0) return;
  glUniform3fv(p["u_lamp_pos_W[0]"], f.nl, f.lamp_pos_W);
  glUniform3fv(p["u_lamp_dir_W[0]"], f.nl, f.lamp_dir_W);
  glUniform3fv(p["u_lamp_I[0]"], f.nl, f.lamp_I);
  glUniform2fv(p["u_lamp_cos[0]"], f.nl, f.lamp_cos);
}

// Shadow receiver culling for the lamps (per frame): bit 2 when some lamp's shadow map can darken
// the terrain chunk ch of meshes[mesh]: it lies in the lamp's shadow frustum, and either the
// terrain itself can cut the lamp's rays to it (the flattest ray from the lamp to the chunk is not
// steeper than the terrain's steepest slope), or a caster box of another mesh overlaps it as seen
// from the lamp, in azimuth and in depression angle (a ray through both needs both).
unsigned Renderer::Impl::lamp_shadow_bits(std::size_t mesh, const Chunk& ch, const FrameSetup& f,
                                          const std::vector<LampCasters>& casters) const {
  const GpuMesh& m = meshes[mesh];
  for (int i = 0; i < f.nl; ++i) {
    const Eigen::Map<const Eigen::Matrix4f> vp(f.shadow_vp_W + std::ptrdiff_t{16} * i);
    if (!in_frustum(vp, ch)) continue;
    const Eigen::Vector3f L = Eigen::Map<const Eigen::Vector3f>(f.lamp_pos_W + 3 * static_cast<std::ptrdiff_t>(i));
    const LampCaster r = seen_from(L, mesh, ch.lo, ch.hi);
    if (!(std::tan(r.dep_lo) > m.tan_slope)) return 2u;
    if (casters[static_cast<std::size_t>(i)].any_may_shadow(r, mesh)) return 2u;
  }
  return 0u;
}

// Scene geometry into colour (direct signal), camera-space depth and segmentation.
void Renderer::Impl::scene_pass(const Targets& t, const FrameSetup& f, double stamp_s) {
  glBindFramebuffer(GL_FRAMEBUFFER, t.scene_fbo);
  glViewport(0, 0, t.width, t.height);
  const float zero[4] = {0, 0, 0, 0};
  const float inf = std::numeric_limits<float>::infinity();
  const float inf4[4] = {inf, inf, inf, inf};
  const float one = 1.0f;
  glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_TRUE);
  glClearBufferfv(GL_COLOR, 0, zero);
  glClearBufferfv(GL_COLOR, 1, inf4);
  glClearBufferfv(GL_DEPTH, 0, &one);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glActiveTexture(GL_TEXTURE6);
  glBindTexture(GL_TEXTURE_2D, f.sun_shadow ? sun_tex : 0);
  glActiveTexture(GL_TEXTURE5);
  glBindTexture(GL_TEXTURE_2D_ARRAY, f.shadows ? shadow_tex : 0);
  glActiveTexture(GL_TEXTURE0);
  glBindSampler(1, mip_nearest);  // u_grad
  glBindSampler(4, mip_nearest);  // u_tex_macro
  const Eigen::Matrix4f vp = f.proj * f.view;
  const Eigen::Vector3f cam = f.cam_W.cast<float>();
  std::set<unsigned> set_up;  // variants whose frame uniforms are set
  const unsigned all_shadows = (f.sun_shadow ? 1u : 0u) | (f.shadows ? 2u : 0u);
  // Shadow receiver culling: the terrain's visible chunks by the shadow lookups they need (llvmpipe
  // pays for a lookup on every pixel of a draw that compiles it, lit or not).
  const bool cull = receiver_culling() && all_shadows != 0;
  std::vector<LampCasters> casters;  // per lamp: the caster boxes in its frustum, seen from it
  if (cull && f.shadows) {
    casters.resize(static_cast<std::size_t>(f.nl));
    for (int i = 0; i < f.nl; ++i) {
      const Eigen::Map<const Eigen::Matrix4f> lvp(f.shadow_vp_W + std::ptrdiff_t{16} * i);
      const Eigen::Vector3f L = Eigen::Map<const Eigen::Vector3f>(f.lamp_pos_W + 3 * static_cast<std::ptrdiff_t>(i));
      for (const CasterBox& c : caster_boxes) {
        if (!in_frustum(lvp, c.lo, c.hi)) continue;
        if (hidden_under(c.under, L)) continue;  // under a terrain mesh the lamp stands over: never in its map
        const float pad = pcf_pad(f.lamp_texel_per_m[i], L, c.lo, c.hi);
        casters[static_cast<std::size_t>(i)].add(seen_from(L, c.mesh, c.lo.array() - pad, c.hi.array() + pad));
      }
    }
  }
  // What to draw by level of detail (the shadow lift; non-terrain and full meshes: 0), then by
  // the shadow lookups needed.
  std::array<std::array<std::vector<const Chunk*>, 4>, std::size_t{2} * kLodLevels> bins;  // skirts: kLodLevels + level
  const float fx = f.lod_fx;
  std::vector<int> levels;
  for (std::size_t& n : timings.terrain_tiles) n = 0;
  for (std::size_t& n : timings.object_parts) n = 0;
  timings.shadow_lookups_drawn = timings.shadow_lookups_skipped = 0;
  timings.scene_fragments = timings.sun_lookup_fragments = timings.lamp_lookup_fragments = 0;
  timings.scene_invocations = 0;
  if (options.profile_passes && fragment_query == 0) {
    glGenQueries(1, &fragment_query);
    if (epoxy_gl_version() >= 46 || epoxy_has_gl_extension("GL_ARB_pipeline_statistics_query"))
      glGenQueries(1, &invocation_query);
  }
  // The terrain last: what stands on it hides part of it, and llvmpipe skips the shading of
  // blocks whose depth test fails (the image is the same in any order).
  std::vector<std::size_t> order;
  order.reserve(meshes.size());
  for (const bool terrain : {false, true})
    for (std::size_t mi = 0; mi < meshes.size(); ++mi)
      if (meshes[mi].terrain == terrain) order.push_back(mi);
  for (const std::size_t mi : order) {
    const GpuMesh& m = meshes[mi];
    for (auto& level : bins)
      for (auto& b : level) b.clear();
    // Chunk `draw` at `level` (a skirt: kLodLevels + level), its shadow lookups decided by `box`
    // (the chunk, or its tile).
    const auto add = [&](const Chunk& draw, const Chunk& box, int level) {
      unsigned bits = all_shadows;
      if (cull && m.terrain) {
        bits = (f.sun_shadow && !box.sun_free ? 1u : 0u) | (f.shadows ? lamp_shadow_bits(mi, box, f, casters) : 0u);
        for (unsigned b : {1u, 2u}) {
          if (!(all_shadows & b)) continue;
          ++((bits & b) ? timings.shadow_lookups_drawn : timings.shadow_lookups_skipped);
        }
      }
      bins[static_cast<std::size_t>(level)][bits].push_back(&draw);
    };
    const auto seen = [&](const Chunk& ch) {
      return in_frustum(vp, ch) && !(options.occlusion_culling && hidden_under(ch.under, cam));
    };
    if (!m.lod.empty()) {
      for (std::size_t ci = 0; ci < m.chunks.size(); ++ci) {
        if (!seen(m.chunks[ci])) continue;
        const std::size_t k = lod_level(m.lod[ci], cam, fx, options.terrain_lod_px);
        ++timings.object_parts[k];
        add(m.lod[ci].level[k], m.chunks[ci], static_cast<int>(k));
      }
    } else if (m.tiles.empty()) {
      for (const Chunk& ch : m.chunks)
        if (seen(ch)) add(ch, ch, 0);
    } else {
      levels.resize(m.tiles.size());
      for (std::size_t ti = 0; ti < m.tiles.size(); ++ti)
        levels[ti] = lod_level(m.tiles[ti], cam, fx, options.terrain_lod_px);
      const auto tc = static_cast<std::size_t>(m.tile_cols);
      for (std::size_t ti = 0; ti < m.tiles.size(); ++ti) {
        const TerrainTile& tile = m.tiles[ti];
        if (!seen(tile.box)) continue;
        const int k = levels[ti];
        const auto kk = static_cast<std::size_t>(k);
        ++timings.terrain_tiles[kk];
        if (k == 0) {
          for (std::size_t c = tile.chunk_begin; c < tile.chunk_end; ++c)
            if (seen(m.chunks[c])) add(m.chunks[c], m.chunks[c], 0);
        } else {
          add(tile.level[kk], tile.box, k);
        }
        // Skirts towards the neighbours (-x, +x, -y, +y) drawn at another level. After all the
        // surfaces: they lie under them but where the seam between two levels opens, and llvmpipe
        // skips the shading of blocks whose depth test fails.
        const std::size_t r = ti / tc, c = ti % tc;
        const bool has[4] = {r > 0, (r + 1) * tc<m.tiles.size(), c> 0, c + 1 < tc};
        const std::size_t nb[4] = {ti - tc, ti + tc, ti - 1, ti + 1};
        for (std::size_t side = 0; side < 4; ++side)
          if (has[side] && levels[nb[side]] != k) add(tile.skirt[kk][side], tile.box, kLodLevels + k);
      }
    }
    for (std::size_t b = 0; b < bins.size() * 4; ++b) {
      const std::size_t level = b / 4;
      const unsigned bits = b % 4;
      const auto& bin = bins[level][bits];
      if (bin.empty()) continue;
      Program& scene = scene_program(m, bits, f, stamp_s, &set_up);
      glUniform2f(scene["u_shadow_lift"], m.lift[level % kLodLevels], m.lamp_lift[level % kLodLevels]);
      set3(scene["u_albedo"], m.material.albedo);
      glUniform1f(scene["u_uv_scale"], static_cast<float>(m.material.uv_scale_m));
      const Look k = look(m);
      if (k.bump) glUniform1f(scene["u_relief"], m.relief_m);
      if (k.specular) {
        glUniform1f(scene["u_roughness"], m.roughness);
        glUniform1f(scene["u_metallic"], m.metallic);
      }
      if (k.sediment) glUniform1f(scene["u_sediment"], m.sediment_cover);
      glUniform1f(scene["u_seg"], static_cast<float>(m.seg_class));
      if (k.bump) {
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, m.gradient);
      }
      if (k.normal_map) {
        glActiveTexture(GL_TEXTURE2);
        glBindTexture(GL_TEXTURE_2D, m.normal_map);
      }
      if (k.orm_map) {
        glActiveTexture(GL_TEXTURE3);
        glBindTexture(GL_TEXTURE_2D, m.orm_map);
      }
      glActiveTexture(GL_TEXTURE0);
      glBindTexture(GL_TEXTURE_2D, m.texture);
      if (m.macro) {  // the same texture at a larger scale, through mip_nearest
        glActiveTexture(GL_TEXTURE4);
        glBindTexture(GL_TEXTURE_2D, m.texture);
        glActiveTexture(GL_TEXTURE0);
      }
      glBindVertexArray(m.vao);
      cull_back_faces(m, vp);
      if (options.profile_passes) {
        glBeginQuery(GL_SAMPLES_PASSED, fragment_query);
        if (invocation_query) glBeginQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB, invocation_query);
      }
      draw_chunks(bin);
      if (options.profile_passes) {  // fragments shaded (the depth test passed) with and without lookups
        glEndQuery(GL_SAMPLES_PASSED);
        GLuint n = 0, inv = 0;
        glGetQueryObjectuiv(fragment_query, GL_QUERY_RESULT, &n);
        if (invocation_query) {
          glEndQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB);
          glGetQueryObjectuiv(invocation_query, GL_QUERY_RESULT, &inv);
        }
        timings.scene_invocations += inv;
        timings.scene_fragments += n;
        if (bits & 1u) timings.sun_lookup_fragments += n;
        if (bits & 2u) timings.lamp_lookup_fragments += n;
      }
    }
  }
  glDisable(GL_CULL_FACE);
  glBindSampler(1, 0);
  glBindSampler(4, 0);
}

Program& Renderer::Impl::snow_program(int nlamps) {
  return program_variant(snow_variants, static_cast<unsigned>(nlamps), detail::kSnowVS, detail::kSnowFS, "marine_snow",
                         [nlamps] { return "#define NLAMPS " + std::to_string(nlamps) + "\n"; });
}

Program& Renderer::Impl::inscatter_program(int nlamps, int nsamples, bool shadows) {
  const auto key = (static_cast<unsigned>(nlamps) << 16) | (static_cast<unsigned>(nsamples) << 1) | (shadows ? 1u : 0u);
  return program_variant(inscatter_variants, key, detail::kPostVS, detail::kInscatterFS, "lamp_inscatter", [&] {
    return "#define NLAMPS " + std::to_string(nlamps) + "\n#define NSAMPLES " + std::to_string(nsamples) +
           "\n#define SHADOWS " + (shadows ? "1" : "0") + "\n";
  });
}

// Marine snow: additive into the colour only (depth and segmentation untouched).
void Renderer::Impl::snow_pass(const FrameSetup& f, const CameraModel& c, double stamp_s) {
  if (options.marine_snow && snow_count > 0) {
    Program& snow = snow_program(f.nl);
    snow.use();
    glUniformMatrix4fv(snow["u_view"], 1, GL_FALSE, f.view.data());
    glUniformMatrix4fv(snow["u_proj"], 1, GL_FALSE, f.proj.data());
    set3(snow["u_cam_W"], f.cam_W);
    glUniform1f(snow["u_box"], static_cast<float>(world.marine_snow.box_m));
    glUniform1f(snow["u_time"], static_cast<float>(std::fmod(stamp_s, 1.0e4)));
    glUniform1f(snow["u_size_m"], static_cast<float>(world.marine_snow.size_m));
    glUniform1f(snow["u_fx"], static_cast<float>(c.fx));
    set3(snow["u_E0"], world.sun.surface_irradiance);
    set3(snow["u_Kd"], water.K_d);
    set3(snow["u_betaD"], water.beta_D);
    set_lamps_W(snow, f);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glDepthMask(GL_FALSE);
    glEnablei(GL_BLEND, 0);
    glBlendFunc(GL_ONE, GL_ONE);
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_FALSE);
    glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glBindVertexArray(snow_vao);
    glDrawArrays(GL_POINTS, 0, snow_count);
    glDisablei(GL_BLEND, 0);
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthMask(GL_TRUE);
  }
}

// Lamp in-scattering at low resolution (and the forward-scatter mip chain). Returns whether
// in-scattering was drawn; *march_max_m: the march length the post pass must use too.
bool Renderer::Impl::inscatter_pass(const Targets& t, const FrameSetup& f, const CameraModel& c, float* march_max_out) {
  const int nsamples = std::max(0, options.lamp_scatter_samples);
  const bool do_inscatter = f.nl > 0 && nsamples > 0;
  // March until the lamp light has dropped to ~3% (3.5 attenuation lengths).
  const auto march_max_m = static_cast<float>(std::min(30.0, 3.5 / std::max(1e-3, water.beta_D.minCoeff())));
  glDisable(GL_DEPTH_TEST);
  if (do_inscatter) {
    glBindFramebuffer(GL_FRAMEBUFFER, t.is_fbo);
    glViewport(0, 0, t.is_width, t.is_height);
    Program& inscatter = inscatter_program(f.nl, nsamples, f.shadows);
    inscatter.use();
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, t.scene_color);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, t.scene_zc);
    glActiveTexture(GL_TEXTURE0);
    glUniform1i(inscatter["u_color"], 0);
    glUniform1i(inscatter["u_depth"], 1);
    glUniform4f(inscatter["u_K"], static_cast<float>(c.fx), static_cast<float>(c.fy), static_cast<float>(c.cx),
                static_cast<float>(c.cy));
    glUniform2i(inscatter["u_size"], t.width, t.height);
    glUniform1f(inscatter["u_scale"], static_cast<float>(t.is_scale));
    set3(inscatter["u_betaD"], water.beta_D);
    glUniform3fv(inscatter["u_lamp_pos_C[0]"], f.nl, f.lamp_pos_C);
    glUniform3fv(inscatter["u_lamp_dir_C[0]"], f.nl, f.lamp_dir_C);
    glUniform3fv(inscatter["u_lamp_I[0]"], f.nl, f.lamp_I);
    glUniform2fv(inscatter["u_lamp_cos[0]"], f.nl, f.lamp_cos);
    glUniform1i(inscatter["u_shadow"], 5);
    glActiveTexture(GL_TEXTURE5);
    glBindTexture(GL_TEXTURE_2D_ARRAY, f.shadows ? shadow_tex : 0);
    glActiveTexture(GL_TEXTURE0);
    if (f.shadows) glUniformMatrix4fv(inscatter["u_shadow_vp_C[0]"], f.nl, GL_FALSE, f.shadow_vp_C);
    // The march's samples lie centimetres to metres apart and the result is upsampled: nearest
    // depth tests instead of 2x2 PCF (a quarter of the cost of the pass's costliest lookup).
    glBindSampler(5, shadow_nearest);
    glBindSampler(0, nearest);  // u_color: the segmentation of one pixel
    set3(inscatter["u_b_scatter"], water.b_scatter);
    glUniform1f(inscatter["u_schlick_k"], static_cast<float>(water.schlick_k()));
    glUniform1f(inscatter["u_back_frac"], static_cast<float>(water.phase_backscatter_fraction));
    glUniform1f(inscatter["u_march_max_m"], march_max_m);
    glBindVertexArray(empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindSampler(5, 0);
    glBindSampler(0, 0);
  }

  if (options.forward_scatter) blur_levels(t);
  *march_max_out = march_max_m;
  return do_inscatter;
}

namespace {

// kPostFS's pcg() on the CPU: the frame's seed is hashed once here, not once per pixel.
GLuint pcg_seed(std::uint32_t v) {
  const std::uint32_t state = v * 747796405u + 2891336453u;
  const std::uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

// Largest upward component (-z in world_ned) of the unit view rays of a pinhole camera with
// rotation R_WC: 1 when the zenith is in view, else the maximum along the image border (sampled
// every few pixels; the function is smooth there).
double max_up_component(const CameraModel& c, const Eigen::Matrix3d& R_WC) {
  const Eigen::Vector3d zenith_C = R_WC.transpose() * Eigen::Vector3d(0.0, 0.0, -1.0);
  if (zenith_C.z() > 0.0) {
    const double u = c.fx * zenith_C.x() / zenith_C.z() + c.cx, v = c.fy * zenith_C.y() / zenith_C.z() + c.cy;
    if (u >= -0.5 && v >= -0.5 && u <= c.width - 0.5 && v <= c.height - 0.5) return 1.0;
  }
  double best = -1.0;
  auto up = [&](double u, double v) {
    const Eigen::Vector3d d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
    best = std::max(best, -(R_WC * d.normalized()).z());
  };
  const double w = c.width - 0.5, h = c.height - 0.5;
  for (int k = 0; k <= 128; ++k) {
    const double s = k / 128.0;
    up(-0.5 + s * (w + 0.5), -0.5);
    up(-0.5 + s * (w + 0.5), h);
    up(-0.5, -0.5 + s * (h + 0.5));
    up(w, -0.5 + s * (h + 0.5));
  }
  return best;
}

}  // namespace

// The forward-scatter blur's levels: scene_color -> its 4 x 4 means -> their 4 x 4 means.
void Renderer::Impl::blur_levels(const Targets& t) {
  blur_down.use();
  glUniform1i(blur_down["u_src"], 0);
  glActiveTexture(GL_TEXTURE0);
  glBindVertexArray(empty_vao);
  for (int k = 0; k < 2; ++k) {
    const GLuint src = k == 0 ? t.scene_color : t.blur_tex[0];
    const int sw = k == 0 ? t.width : t.blur_width[0], sh = k == 0 ? t.height : t.blur_height[0];
    glBindFramebuffer(GL_FRAMEBUFFER, t.blur_fbo[k]);
    glViewport(0, 0, t.blur_width[k], t.blur_height[k]);
    glBindTexture(GL_TEXTURE_2D, src);
    glUniform2f(blur_down["u_src_texel"], 1.0f / static_cast<float>(sw), 1.0f / static_cast<float>(sh));
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
}

// The post program with these features compiled in (compiled on first use).
// pixels: 0 every pixel, 1 those with geometry, 2 the water (see PIXELS in kPostFS).
Program& Renderer::Impl::post_program(const PostFeatures& features, int pixels) {
  static constexpr std::array<const char*, kPostFeatures> kNames = {
      "REMAP", "FWD", "INSCATTER", "VIGNETTING", "SHOT", "READ_NOISE", "SNELL", "MOTION", "RADIANCE"};
  unsigned key = 0;
  for (std::size_t i = 0; i < features.size(); ++i) key |= (features[i] ? 1u : 0u) << i;
  key |= static_cast<unsigned>(pixels) << features.size();
  return program_variant(post_variants, key, detail::kPostVS, detail::kPostFS, "post", [&] {
    std::string defines = "#define PIXELS " + std::to_string(pixels) + "\n";
    for (std::size_t i = 0; i < features.size(); ++i)
      defines += std::string("#define ") + kNames[i] + (features[i] ? " 1\n" : " 0\n");
    return defines;
  });
}

// Post pass: forward scatter, backscatter, + in-scatter, distortion, noise, encoding.
void Renderer::Impl::post_pass(const Targets& t, const FrameSetup& f, const CameraModel& c, std::uint64_t seq,
                               bool do_inscatter, float march_max_m) {
  const bool shot = options.noise && c.shot_noise > 0.0, read_noise = options.noise && c.noise_stddev > 0.0;
  // Motion over the exposure (ending at the stamp), in the optical frame: a world point P (camera
  // coordinates now) was at P + w x P + v when the shutter opened.
  const Eigen::Matrix3d R_CB = c.X_BC.linear().transpose();
  const Eigen::Vector3d v_C =
      c.exposure_time_s * (R_CB * (velocity.linear + velocity.angular.cross(c.X_BC.translation())));
  const Eigen::Vector3d w_C = c.exposure_time_s * (R_CB * velocity.angular);
  const bool motion = c.exposure_time_s > 0.0 && (v_C.norm() > 1e-9 || w_C.norm() > 1e-9);
  // Snell's window costs every pixel once compiled in (llvmpipe): only when a ray can reach it.
  const double critical_up = std::sqrt(1.0 - 1.0 / (water.refractive_index * water.refractive_index));
  const bool window =
      options.snell_window && f.cam_W.z() > 0.0 && max_up_component(c, f.X_WC.linear()) > critical_up - 1e-3;
  const bool remap = t.lin_fbo != 0;
  // REMAP, FWD, INSCATTER, VIGNETTING, SHOT, READ_NOISE, SNELL, MOTION, RADIANCE (kPostFS). With a
  // remap, the sensor's stage (vignetting, noise) runs there, per output pixel.
  const bool vignetting = c.vignetting > 0.0;
  const PostFeatures features{false,          options.forward_scatter, do_inscatter, vignetting && !remap,
                              shot && !remap, read_noise && !remap,    window,       motion,
                              remap};
  glBindFramebuffer(GL_FRAMEBUFFER, remap ? t.lin_fbo : t.post_fbo);
  glViewport(0, 0, t.width, t.height);  // the internal size (the output's without a remap)
  // Geometry and water apart: the water's pixels (depth still at its clear value 1) skip the
  // forward scatter and the depth read, the geometry's skip Snell's window; llvmpipe shades only
  // the blocks whose depth test passes. Every pixel is drawn by exactly one of the two.
  glEnable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  PostFeatures geometry = features, water_only = features;
  geometry[6] = false;      // no Snell's window
  water_only[1] = false;    // no forward scatter
  glDepthFunc(GL_GREATER);  // the triangle lies at depth 1: passes where the scene drew
  post_draw(post_program(geometry, 1), t, t.scene_color, f, c, seq, march_max_m, false, motion, v_C, w_C);
  glDepthFunc(GL_EQUAL);  // where it did not
  post_draw(post_program(water_only, 2), t, t.scene_color, f, c, seq, march_max_m, window, motion, v_C, w_C);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_DEPTH_TEST);
  if (remap) {  // each output pixel resamples the radiance through the distortion map, + the sensor
    glBindFramebuffer(GL_FRAMEBUFFER, t.post_fbo);
    glViewport(0, 0, t.out_width, t.out_height);
    const PostFeatures sensor{true, false, false, vignetting, shot, read_noise, false, false, false};
    post_draw(post_program(sensor), t, t.lin_tex, f, c, seq, march_max_m, false, false, v_C, w_C);
  }
}

// One draw of the post pass with program `post` (post_pass()).
void Renderer::Impl::post_draw(Program& post, const Targets& t, GLuint color, const FrameSetup& f, const CameraModel& c,
                               std::uint64_t seq, float march_max_m, bool window, bool motion,
                               const Eigen::Vector3d& v_C, const Eigen::Vector3d& w_C) {
  post.use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, color);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, t.scene_zc);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, t.distmap);
  glActiveTexture(GL_TEXTURE3);
  glBindTexture(GL_TEXTURE_2D, t.is_tex);
  glActiveTexture(GL_TEXTURE4);
  glBindTexture(GL_TEXTURE_2D, t.is_water_tex);
  glActiveTexture(GL_TEXTURE7);
  glBindTexture(GL_TEXTURE_2D, color);
  glBindSampler(7, nearest);
  glActiveTexture(GL_TEXTURE8);
  glBindTexture(GL_TEXTURE_2D, t.blur_tex[0]);
  glActiveTexture(GL_TEXTURE9);
  glBindTexture(GL_TEXTURE_2D, t.blur_tex[1]);
  glActiveTexture(GL_TEXTURE0);
  glUniform1i(post["u_blur4"], 8);
  glUniform1i(post["u_blur16"], 9);
  glUniform4f(post["u_blur_uv"], 1.0f / static_cast<float>(4 * t.blur_width[0]),
              1.0f / static_cast<float>(4 * t.blur_height[0]), 1.0f / static_cast<float>(16 * t.blur_width[1]),
              1.0f / static_cast<float>(16 * t.blur_height[1]));
  glUniform1i(post["u_color"], 0);
  glUniform1i(post["u_color_px"], 7);
  glUniform1i(post["u_depth"], 1);
  glUniform1i(post["u_distmap"], 2);
  glUniform1i(post["u_inscatter"], 3);
  glUniform1i(post["u_inscatter_water"], 4);
  glUniform1f(post["u_march_max_m"], march_max_m);
  glUniform4f(post["u_K"], static_cast<float>(c.fx), static_cast<float>(c.fy), static_cast<float>(c.cx),
              static_cast<float>(c.cy));
  glUniform2i(post["u_size"], t.width, t.height);
  set3(post["u_betaD"], water.beta_D);
  set3(post["u_betaB"], water.beta_B);
  set3(post["u_Binf"], water.veiling_light_at(f.cam_W.z(), world.sun.surface_irradiance));
  glUniform1f(post["u_veil_gradient"], static_cast<float>(water.veiling_light_gradient));
  const Eigen::Matrix3f R_WC = f.X_WC.linear().cast<float>();
  glUniformMatrix3fv(post["u_R_WC"], 1, GL_FALSE, R_WC.data());
  glUniform1f(post["u_fwd_per_m"], static_cast<float>(water.forward_scatter_per_m));
  glUniform1f(post["u_blur_px_per_m"], static_cast<float>(water.forward_blur_rad_per_m * c.fx));
  double gain = c.exposure;
  if (options.auto_exposure) {
    const Eigen::Vector3d Ed =
        (world.sun.surface_irradiance.array() * (-water.K_d.array() * std::max(0.0, f.cam_W.z())).exp()).matrix();
    gain *= std::clamp(0.45 / std::max(luminance(Ed), 1e-6), 0.25, 5.0);
  }
  glUniform1f(post["u_gain"], static_cast<float>(gain));
  glUniform1f(post["u_noise_std"], options.noise ? static_cast<float>(c.noise_stddev) : 0.0f);
  glUniform1f(post["u_shot"], options.noise ? static_cast<float>(c.shot_noise) : 0.0f);
  glUniform1f(post["u_vignetting"], static_cast<float>(c.vignetting));
  // The output (in-air) camera's pinhole for the field angle of the vignetting.
  glUniform4f(post["u_Kout"], static_cast<float>(t.out_K[0]), static_cast<float>(t.out_K[1]),
              static_cast<float>(t.out_K[2]), static_cast<float>(t.out_K[3]));
  glUniform1ui(post["u_seed"], pcg_seed(noise::hash32(static_cast<std::uint32_t>(options.seed) ^
                                                      static_cast<std::uint32_t>(seq * 2654435761ULL))));
  glUniform1i(post["u_srgb"], options.srgb_output ? 1 : 0);
  if (motion) {
    set3(post["u_motion_v"], v_C);
    set3(post["u_motion_w"], w_C);
  }
  if (window) {
    const double n = water.refractive_index;
    const double t0 = 1.0 - std::pow((n - 1.0) / (n + 1.0), 2);  // Fresnel transmittance at normal incidence
    const Eigen::Vector3d& E0 = world.sun.surface_irradiance;
    const double amb = world.sun.ambient_fraction;
    glUniform1f(post["u_cam_depth"], static_cast<float>(f.cam_W.z()));
    glUniform1f(post["u_n_water"], static_cast<float>(n));
    set3(post["u_sky"], n * n * amb / t0 * E0);
    set3(post["u_sun_glow"], M_PI * (1.0 - amb) / t0 * E0);
    set3(post["u_sun_dir_W"], world.sun.direction_W);
  }
  glBindVertexArray(empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindSampler(7, 0);
}

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

void Renderer::Impl::start_readback(Slot& s, const Targets& t) {
  const std::size_t px = static_cast<std::size_t>(t.out_width) * t.out_height;
  if (s.pbo_rgba == 0) {
    glGenBuffers(1, &s.pbo_rgba);
    glGenBuffers(1, &s.pbo_depth);
  }
  if (s.capacity_px < px) {
    glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_rgba);
    glBufferData(GL_PIXEL_PACK_BUFFER, static_cast<GLsizeiptr>(px * 4), nullptr, GL_STREAM_READ);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_depth);
    glBufferData(GL_PIXEL_PACK_BUFFER, static_cast<GLsizeiptr>(px * 4), nullptr, GL_STREAM_READ);
    s.capacity_px = px;
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, t.post_fbo);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_rgba);
  glReadPixels(0, 0, t.out_width, t.out_height, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_depth);
  glReadPixels(0, 0, t.out_width, t.out_height, GL_RED, GL_FLOAT, nullptr);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  if (s.timed) glQueryCounter(s.stamps[kStamps - 1], GL_TIMESTAMP);
  s.fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  glFlush();
  check_gl("readback");
}

Frame Renderer::Impl::finish_readback(Slot& s) {
  Frame f = s.meta;
  const std::size_t px = static_cast<std::size_t>(f.width) * f.height;
  {
    const std::lock_guard<std::mutex> lock(spare_mutex);
    if (!spare.empty()) {  // its buffers: resize() below keeps their pages (same size: no writes)
      Frame& b = spare.back();
      f.rgb.swap(b.rgb);
      f.seg.swap(b.seg);
      f.depth.swap(b.depth);
      spare.pop_back();
    }
  }
  if (s.fence) {
    glClientWaitSync(s.fence, GL_SYNC_FLUSH_COMMANDS_BIT, 10'000'000'000ULL);
    glDeleteSync(s.fence);
    s.fence = nullptr;
  }
  if (s.timed) {  // all done with the fence: the results wait for nothing
    GLuint64 ns[kStamps] = {};
    for (int i = 0; i < kStamps; ++i) glGetQueryObjectui64v(s.stamps[i], GL_QUERY_RESULT, &ns[i]);
    double* const out[kStamps - 1] = {&timings.gpu_shadow_ms,    &timings.gpu_scene_ms, &timings.gpu_snow_ms,
                                      &timings.gpu_inscatter_ms, &timings.gpu_post_ms,  &timings.gpu_readback_ms};
    for (int i = 0; i + 1 < kStamps; ++i) *out[i] = 1e-6 * static_cast<double>(ns[i + 1] - ns[i]);
  }
  f.rgb.resize(px * 3);
  f.seg.resize(px);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_rgba);
  const auto* rgba = static_cast<const std::uint8_t*>(
      glMapBufferRange(GL_PIXEL_PACK_BUFFER, 0, static_cast<GLsizeiptr>(px * 4), GL_MAP_READ_BIT));
  if (!rgba) throw GlError("glMapBufferRange failed for the colour readback");
  detail::split_rgba(rgba, px, f.rgb.data(), f.seg.data());
  glUnmapBuffer(GL_PIXEL_PACK_BUFFER);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_depth);
  const auto* dz = static_cast<const float*>(
      glMapBufferRange(GL_PIXEL_PACK_BUFFER, 0, static_cast<GLsizeiptr>(px * 4), GL_MAP_READ_BIT));
  if (!dz) throw GlError("glMapBufferRange failed for the depth readback");
  f.depth.assign(dz, dz + px);  // one pass (a resize would zero it first)
  glUnmapBuffer(GL_PIXEL_PACK_BUFFER);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  return f;
}

void Renderer::Impl::collect_oldest() {
  const auto t0 = Clock::now();
  const std::size_t idx = in_flight.front();
  in_flight.pop_front();
  done.push_back(finish_readback(slots[idx]));
  timings.readback_ms = ms_since(t0);
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

void write_png_rgb(const Frame& frame, const std::string& path) {
  cv::Mat rgb(frame.height, frame.width, CV_8UC3, const_cast<std::uint8_t*>(frame.rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  if (!cv::imwrite(path, bgr, {cv::IMWRITE_PNG_COMPRESSION, 9})) throw ConfigError(path + ": cannot write PNG");
}

std::vector<std::uint8_t> read_png_rgb(const std::string& path, int* width, int* height) {
  cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  if (bgr.empty()) throw ConfigError(path + ": cannot read PNG");
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  *width = rgb.cols;
  *height = rgb.rows;
  return std::vector<std::uint8_t>(rgb.data, rgb.data + rgb.total() * 3);
}

}  // namespace unav::renderer
