// The renderer's inside (not installed): the GPU-side scene (meshes in chunks, terrain levels of
// detail, shadow casters), the render targets and readback slots, Renderer::Impl and the per-frame
// setup its passes share. One file per pass: pass_shadow.cpp, pass_scene.cpp, pass_water.cpp
// (marine snow, lamp in-scattering), pass_post.cpp, readback.cpp; scene_upload.cpp (meshes,
// textures, shadow caster boxes), scene_chunks.cpp (chunking, levels of detail, frustum tests),
// targets.cpp (render targets per camera); renderer.cpp orchestrates a frame.
#pragma once

#include <epoxy/gl.h>

#include <array>
#include <chrono>
#include <cmath>
#include <ctime>
#include <deque>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "gl_util.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_scene/scene_geometry.hpp"

namespace unav::renderer {

using gl::check_fbo;
using gl::check_gl;
using gl::make_tex;
using gl::Program;
using gl::projection_from_K;
using gl::set3;
using Clock = std::chrono::steady_clock;
inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// CPU time of this process, all threads [ms] (llvmpipe's rasteriser threads included).
inline double process_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// outside their view frustum (the seabed patch is ~29k triangles; a lamp sees a few metres).
struct Chunk {
  GLsizei first = 0, count = 0;  // in indices
  Eigen::Vector3f lo = Eigen::Vector3f::Zero(), hi = Eigen::Vector3f::Zero();
  bool sun_free = false;         ///< terrain that nothing can shadow from the sun (mark_sun_free())
  bool sun_free_static = false;  ///< the same for the scene without its movable objects
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

inline LampCaster seen_from(const Eigen::Vector3f& L, std::size_t mesh, const Eigen::Vector3f& lo,
                            const Eigen::Vector3f& hi) {
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
inline bool may_shadow(const LampCaster& c, const LampCaster& r) {
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
constexpr std::size_t kPostFeatures = 11;
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
  Frame meta;            // everything but the pixels
  int jpeg_quality = 0;  // the camera's: compressed after the readback when > 0
};

// A sampler object with these filters and this wrap mode in s and t.
inline GLuint make_sampler(GLint min_filter, GLint mag_filter, GLint wrap) {
  GLuint s = 0;
  glGenSamplers(1, &s);
  glSamplerParameteri(s, GL_TEXTURE_MIN_FILTER, min_filter);
  glSamplerParameteri(s, GL_TEXTURE_MAG_FILTER, mag_filter);
  glSamplerParameteri(s, GL_TEXTURE_WRAP_S, wrap);
  glSamplerParameteri(s, GL_TEXTURE_WRAP_T, wrap);
  return s;
}

// A sampler object reading bilinear in the nearest mip level, repeating (surface maps).
inline GLuint mip_nearest_sampler() { return make_sampler(GL_LINEAR_MIPMAP_NEAREST, GL_LINEAR, GL_REPEAT); }

// A sampler object reading one texel, unfiltered, clamped to the edges.
inline GLuint nearest_sampler() { return make_sampler(GL_NEAREST, GL_NEAREST, GL_CLAMP_TO_EDGE); }

// A bound depth texture as a shadow map: bilinear depth comparison (hardware PCF), clamped.
inline void shadow_sampling(GLenum target) {
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
std::array<Eigen::Vector3f, 3> triangle_corners(const MeshData& mesh, std::size_t t);
// The steepest slope of a mesh's faces, as tan(angle from horizontal) (world_ned, z down).
float steepest_slope(const MeshData& mesh);
std::vector<std::uint32_t> chunked_indices(const MeshData& mesh, std::vector<Chunk>* chunks);
// A height field's vertex grid as make_seabed_mesh lays it out: rows x cols points, vertex (i, j)
// at index i * cols + j, x the same along a row and y along a column, two triangles a cell,
// (i, j) (i, j+1) (i+1, j) and (i, j+1) (i+1, j+1) (i+1, j), cell after cell. False for any other
// mesh (it is then drawn without levels of detail).
bool grid_layout(const MeshData& m, int* rows, int* cols);
// The index buffer of a grid terrain (grid_layout()) with its level-of-detail tiles (TerrainTile):
// the full mesh in chunks of kChunkCells x kChunkCells cells, tile after tile (a tile's chunks are
// one run), then each tile's coarse levels and skirts. The skirts' lower points are appended to
// `mesh` (copies of the edge's points) with their `drop` below them [m] (0 for the grid's points).
std::vector<std::uint32_t> terrain_lod(MeshData* mesh, int rows, int cols, std::vector<float>* drop,
                                       std::vector<Chunk>* chunks, std::vector<TerrainTile>* tiles, int* tile_cols,
                                       std::array<float, kLodLevels>* lift);
// The index buffer of a mesh drawn by parts at levels of detail: level by level (neighbours at the
// same level merge into one draw), a chunk per part and level, boxed by the part's vertices (a
// coarse level's surface lies inside their hull). Each part's finest chunk goes to `chunks`.
std::vector<std::uint32_t> lod_indices(const SceneMesh& sm, std::vector<Chunk>* chunks,
                                       std::vector<GpuMesh::LodChunks>* lod, std::array<float, kLodLevels>* lift);
// The coarsest of `levels` levels whose error [m], seen from `eye` with fx pixels per unit of the
// focal plane, stays within px pixels (fx x error / distance to `box`); 0 with px = 0 (levels off).
int coarsest_level(const Chunk& box, const float* error, std::size_t levels, const Eigen::Vector3f& eye, float fx,
                   double px);
// The level a terrain tile is drawn at (its height error against the full mesh), and a part's
// (a rock's, against its finest level).
int lod_level(const TerrainTile& t, const Eigen::Vector3f& eye, float fx, double px);
std::size_t lod_level(const GpuMesh::LodChunks& p, const Eigen::Vector3f& eye, float fx, double px);
// False when the box lies entirely outside one plane of the clip volume of vp (conservative):
// each plane (-w <= x, x <= w, ... in clip coordinates) is a half-space of world points, and the
// box is wholly outside it when its corner farthest inside (picked per axis by the plane's normal)
// is outside. Called per chunk and caster box, per pass and lamp: on the thread that feeds the GL.
bool in_frustum(const Eigen::Matrix4f& vp, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi);
bool in_frustum(const Eigen::Matrix4f& vp, const Chunk& ch);
// How far a box seen from a lamp at L must grow to cover what the lamp map's PCF reads for it: two
// texels (texel_per_m at 1 m) at the box's far side, plus 1 cm.
float pcf_pad(float texel_per_m, const Eigen::Vector3f& L, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi);
// Whether nothing inside the frustum vp_cam can lie in the shadow that box lo..hi casts from a
// lamp at L whose map ends at the plane at distance far_m along its axis: every lamp ray behind
// the box runs inside the hull of the box's corners and of their projections from L onto that
// plane, so when all 16 points lie outside one plane of vp_cam's frustum, the hull does too.
bool shadow_out_of_view(const Eigen::Matrix4f& vp_cam, const Eigen::Vector3f& L, const Eigen::Vector3f& axis,
                        float far_m, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi);
// Draws the listed chunks (in mesh order; neighbours in one call).
void draw_chunks(const std::vector<const Chunk*>& chunks);

inline double luminance(const Eigen::Vector3d& c) { return 0.2126 * c.x() + 0.7152 * c.y() + 0.0722 * c.z(); }

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
  /// Movable objects (Object::movable, Renderer::set_object_pose): by object name, its meshes
  /// (the parts of a mesh file) with their vertices in the object's frame, indices in chunk order.
  struct MovablePart {
    std::size_t mesh = 0;
    MeshData local;
    MeshData world;  ///< at the pose set last (caster boxes)
  };
  std::map<std::string, std::vector<MovablePart>> movable;
  std::vector<bool> mesh_movable;            ///< by mesh
  std::array<Eigen::Vector3f, 3> sun_frame;  ///< across the sunlight (u, v) and along it (s): mark_sun_free()
  float sun_pad = 0.0f;                      ///< the casters' growth for the sun map's PCF
  /// A box's extent along the sun frame's axes, and its shallowest and deepest z.
  struct SunExtent {
    std::array<std::pair<float, float>, 3> along;
    float top_z, bottom_z;
  };
  SunExtent sun_extent(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) const;
  bool may_shade(const SunExtent& caster, const SunExtent& receiver) const;
  void move_object(std::vector<MovablePart>& parts, const Pose& X_WO);
  /// Caster boxes of a non-terrain mesh: its triangles binned into 0.5 m cells.
  void add_object_casters(std::size_t mi, const MeshData& mesh);
  /// Terrain chunks' (and tiles') sun_free: the static result of mark_sun_free() and no movable
  /// object's caster box in the way.
  void refresh_sun_free();
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

/// The scene program's #defines for material variant v (pass_scene.cpp's variant bits).
std::string scene_defines(unsigned v);

// The program of `variants` under `key`, compiled on first use with the defines make_defines()
// returns (built only then, not every frame).
template <typename MakeDefines>
Program& program_variant(std::map<unsigned, Program>& variants, unsigned key, const char* vs, const char* fs,
                         const char* name, MakeDefines&& make_defines) {
  auto it = variants.find(key);
  if (it == variants.end()) it = variants.emplace(key, Program(vs, fs, name, make_defines())).first;
  return it->second;
}

}  // namespace unav::renderer
