// Underwater camera renderer (no DDS): renders RGB, depth and segmentation of a World for a
// vehicle pose and a camera, with the image formation of REFERENCE.md section 3:
//   I = D + F + B + L_s
//   D = J exp(-beta_D z)                     direct signal (per pixel, per channel)
//   F = range-dependent blur of D            forward scattering (post pass)
//   B = B_inf (1 - exp(-beta_B z))           backscatter of ambient light, B_inf decays with depth
//   L_s = single-scattered lamp light        ray-marched, Schlick phase function (post pass)
// J: albedo x (sunlight E0 exp(-K_d d) + lamp light attenuated lamp -> surface), then marine
// snow particles, plumb_bob distortion, sensor noise, sRGB encoding.
//
// Threading: a Renderer owns its EGL context; call it from one thread.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "unav_renderer/egl_context.hpp"
#include "unav_scene/camera.hpp"
#include "unav_scene/frames.hpp"
#include "unav_scene/render_settings.hpp"
#include "unav_scene/water.hpp"
#include "unav_scene/world.hpp"

namespace unav::renderer {

// The scene (world, water, cameras, frames) is described by unav_scene; the renderer draws it.
using namespace unav::scene;  // NOLINT(google-build-using-namespace): World, CameraModel, Pose, ...

/// The realism switches (scene::RenderSettings: forward_scatter, marine_snow, noise, lamps,
/// lamp_scatter_samples, shadows, caustics, materials, snell_window, auto_exposure; declared once,
/// in the scenario) and the engine's own knobs. What the switches do:
/// - shadows: a depth map per lamp (its cone as a perspective frustum, to 30 m) and one for the
///   sun (orthographic along the sunlight, 24 m x 24 m around the camera, 4x the edge), looked up
///   with bilinear PCF (soft edges) by the surfaces; the lamp maps also by the lamp in-scattering
///   (shafts cut by objects). The sun's shadow removes its direct share (1 - ambient_fraction) only.
/// - caustics: the sun's direct light on the seabed is focused by the moving surface into a
///   drifting network of bright lines, modulation 1 + A g(x, t) with g of mean ~0 and
///   A = caustic_strength exp(-d (2 K_d + 1 / 15 m)) at depth d (green K_d): clear shallow water
///   shows them, depth and turbidity wash them out. Animated with the frame stamp.
/// - snell_window: water rays within asin(1 / n) of the zenith leave through the surface and see
///   the sky (radiance n^2 x the diffuse share of E0, Fresnel-weighted) and the sun's glint,
///   attenuated over the path to the surface; beyond it total internal reflection (the veil).
/// - materials: physically based materials (world Material keys roughness, metallic, relief_m,
///   sediment): the texture's relief shaded by bump mapping (height in its alpha, screen-space
///   surface gradient: any UV or triplanar mapping), GGX specular (Cook-Torrance, Smith-Schlick
///   G, Schlick F, F0 = mix(0.0032: index 1.5 in water, albedo, metallic)) from the sun and the
///   lamps, and sand settled on upward faces and near the seabed. false: Lambertian, flat, clean.
/// - auto_exposure: deterministic metering of the ambient light at the camera depth: gain =
///   clamp(0.45 / luminance(E0 exp(-K_d d)), 0.25, 5), times CameraModel::exposure.
struct RenderOptions : scene::RenderSettings {
  int lamp_scatter_downsample = 4;  ///< in-scattering is computed at 1/N resolution (smooth)
  int shadow_map_size = 256;        ///< edge [px] of each lamp's shadow map, 16..8192
  /// Shadow receiver culling: terrain chunks that nothing can shadow (no caster between them and
  /// the light, and the light steeper than the terrain's steepest slope) are drawn without the
  /// shadow lookups. Same image (conservative tests); false only to measure or to check that.
  bool shadow_receiver_culling = true;
  /// Shadow caster culling: what cannot shadow anything the camera sees stays out of the lamps'
  /// shadow maps: chunks whose shadow (the hull of the chunk and of its projection from the lamp
  /// onto the map's far plane) lies outside the camera's view frustum, and terrain chunks whose
  /// every lamp ray sinks faster than the terrain's steepest slope (what they hide from the lamp
  /// lies under the terrain). Same image (conservative tests); false only to measure or to check.
  bool shadow_caster_culling = true;
  /// The two shadow culls above trade CPU work for fragment work, which llvmpipe lacks and a
  /// hardware GPU has to spare: there (GL_RENDERER not llvmpipe/softpipe/swrast) a frame is
  /// CPU-bound and the culls cost more than they save (H100, 640x480: submit() 1.14 -> 0.47 ms,
  /// GPU 0.87 -> 0.62 ms a frame), so they run on a hardware GPU only when this is true. Same
  /// pixels either way.
  bool shadow_culling_on_gpu = false;
  /// Occlusion culling: what cannot be seen is not drawn. Back faces of solids (closed,
  /// consistently wound meshes: pipes, rocks, boxes, closed mesh files) in the camera's view: seen
  /// from outside a solid they lie behind its front faces, yet llvmpipe shades a face that a later
  /// one hides. Terrain under other terrain (the far seabed under the patch) for a camera or lamp
  /// standing over it. No pixel changes (a camera inside a solid would see through it); false only
  /// to measure or to check that.
  bool occlusion_culling = true;
  /// Terrain level of detail: a seabed height field (a regular grid of points) is drawn in tiles
  /// of 8 x 8 cells, each with every point or every 2nd or 4th, the coarsest whose largest height
  /// difference from the full mesh, seen from the camera (fx x difference / distance to the tile),
  /// stays within terrain_lod_px pixels; skirts close the seams between levels. The far seabed seen
  /// at a grazing angle is sliver triangles, each shaded in whole 4x4 blocks by llvmpipe. Shadow
  /// maps hold the full mesh. 0: always the full mesh (depth exact to the mesh). >= 0, finite.
  /// The same bound picks the level of each procedural rock (its icosphere subdivided 2, 1 or 0
  /// times: 320, 80, 20 triangles; the coarse levels' corners lie on the finest surface, their
  /// error is the farthest finest vertex from them): a rock a few pixels wide is no longer
  /// hundreds of sub-pixel triangles. Its lamp maps hold the level drawn, the sun's the finest.
  double terrain_lod_px = 2.0;
  /// Scale of the shadow maps' depth bias (slope-scaled polygon offset) against self-shadowing
  /// ("acne"): larger removes acne on steep terrain and detaches contact shadows. >= 0.
  double shadow_bias = 1.0;
  double caustic_strength = 0.8;
  bool srgb_output = true;  ///< encode rgb8 as sRGB (false: linear 0..1 -> 0..255)
  int texture_size = 512;   ///< procedural texture edge [px]
  int readback_slots = 2;   ///< PBO ring depth for submit()/collect()
  std::uint64_t seed = 1;   ///< noise seed (frame noise = f(seed, sequence))
  /// glFinish after each pass to time them (RenderTimings::*_pass_ms); serialises the GPU.
  bool profile_passes = false;
  /// GL timestamp queries between the passes (no glFinish, nothing serialised): the GPU time of each
  /// pass of the frame last collected (RenderTimings::gpu_*_ms). Where the GPU waits for the CPU
  /// between passes, that wait is in the next pass's share.
  bool gpu_timers = false;
  EglOptions egl;
};

/// One rendered image set. Images are row-major, top row first (as sensor_msgs/Image).
struct Frame {
  std::string camera;
  double stamp_s = 0.0;
  std::uint64_t sequence = 0;
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< rgb8, width*height*3
  std::vector<float> depth;       ///< 32FC1, metres along the optical axis; +inf: water only
  std::vector<std::uint8_t> seg;  ///< SegClass id per pixel (mono8)
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 5, 1> D = Eigen::Matrix<double, 5, 1>::Zero();  ///< plumb_bob
  Pose X_WC = Pose::Identity();                                         ///< optical frame in world_ned
};

struct RenderTimings {
  double render_ms = 0;    ///< submit(): issuing the passes and the readback
  double readback_ms = 0;  ///< collect(): waiting for the fence, PBO map, copy, split rgb/seg
  // Only with RenderOptions::profile_passes: wall time of each pass, and the CPU time the process
  // spent in it (all threads; on llvmpipe the rendering work itself, much less disturbed by
  // other load on the machine than the wall time).
  double shadow_pass_ms = 0, scene_pass_ms = 0, snow_pass_ms = 0, inscatter_pass_ms = 0, post_pass_ms = 0;
  double shadow_pass_cpu_ms = 0, scene_pass_cpu_ms = 0, snow_pass_cpu_ms = 0, inscatter_pass_cpu_ms = 0,
         post_pass_cpu_ms = 0;
  /// Shadow receiver culling in the last frame: visible terrain chunks times the shadow maps in
  /// use (sun, lamps), drawn with the lookup and drawn without it (nothing can shadow them).
  std::size_t shadow_lookups_drawn = 0, shadow_lookups_skipped = 0;
  /// Only with RenderOptions::gpu_timers: the GPU's time for each pass of the frame last collected
  /// (differences of GL timestamps taken as the GPU reached each pass's end), and from the end of the
  /// post pass to the readback's copies done.
  double gpu_shadow_ms = 0, gpu_scene_ms = 0, gpu_snow_ms = 0, gpu_inscatter_ms = 0, gpu_post_ms = 0,
         gpu_readback_ms = 0;
  /// Triangles drawn into the lamps' shadow maps (all lamps), and those shadow caster culling left out.
  std::size_t lamp_map_triangles = 0, lamp_map_culled = 0;
  /// Only with profile_passes (occlusion queries): fragments the scene pass shaded, and how many
  /// of them looked up the sun's shadow map and the lamps' (a deterministic measure of the work).
  std::size_t scene_fragments = 0, sun_lookup_fragments = 0, lamp_lookup_fragments = 0;
  /// Only with profile_passes, where the driver counts them (GL 4.6 or ARB_pipeline_statistics_query;
  /// else 0): fragment shader invocations of the scene pass. llvmpipe shades 4x4 blocks, so a block
  /// a triangle's edge crosses costs 16, and a face hidden by a later one was shaded anyway.
  std::size_t scene_invocations = 0;
  /// Terrain tiles in the camera's view in the last frame by level of detail (every point, every
  /// 2nd, every 4th; RenderOptions::terrain_lod_px).
  std::size_t terrain_tiles[3] = {0, 0, 0};
  /// Parts drawn at levels of detail (procedural rocks) in the camera's view in the last frame, by
  /// level (finest first; RenderOptions::terrain_lod_px).
  std::size_t object_parts[3] = {0, 0, 0};
  /// Size of the internal image the last frame's scene was rendered at [px]: the undistorted
  /// (water-side) pinhole view the post pass resamples; larger than the output where distortion
  /// pulls in rays from beyond its field, cropped where the field stays inside it (flat port).
  int internal_width = 0, internal_height = 0;
};

/// The vehicle's velocity in base_link_frd (nav_msgs/Odometry's twist) at a frame's stamp: for
/// motion blur over a camera's exposure_time_s (zero: a sharp frame).
struct BodyVelocity {
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();   ///< [m/s]
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();  ///< [rad/s]
};

class Renderer {
 public:
  /// Creates the EGL context, compiles shaders, builds and uploads the scene geometry and
  /// procedural textures. Throws EglError / GlError / ConfigError with the cause.
  Renderer(World world, std::vector<CameraModel> cameras, RenderOptions options = {});
  /// Same, drawing in an existing context (several renderers, one context: vectorised
  /// environments). `context` null = create one from options.egl. All renderers sharing a
  /// context must be used from the same thread.
  Renderer(World world, std::vector<CameraModel> cameras, RenderOptions options, std::shared_ptr<EglContext> context);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Render synchronously. X_WB: body (FRD) pose in world_ned. Throws std::invalid_argument
  /// for an unknown camera name.
  /// `velocity`: the body's, for the motion blur of cameras with an exposure_time_s.
  Frame render(const Pose& X_WB, const std::string& camera, double stamp_s = 0.0, const BodyVelocity& velocity = {});

  /// Asynchronous pipeline: submit() renders and starts a PBO readback, collect() returns the
  /// oldest submitted frame. With readback_slots = N, up to N frames are in flight; submit()
  /// on a full ring first completes the oldest (retrieve it with collect()).
  void submit(const Pose& X_WB, const std::string& camera, double stamp_s = 0.0, const BodyVelocity& velocity = {});
  std::optional<Frame> collect();
  /// Optional: hands a frame's pixel buffers (rgb, depth, seg) back for a later frame to fill. A
  /// frame's fresh 2.4 MB (640x480) cost more than the readback itself: the allocation, zeroing
  /// and first-touch page faults (measured on the 2-core VM: 2.3 ms a frame, 0.6 ms with
  /// recycled buffers). Keeps up to readback_slots + 2 frames' buffers. Thread-safe: may be
  /// called while another thread renders.
  void recycle(Frame&& frame);
  std::size_t in_flight() const;

  /// Replace the scene (new episode, domain randomisation) keeping the context, the shaders, the
  /// textures and the render targets: only the geometry and the particles are re-uploaded. The
  /// water becomes the world's. Frames still in flight are completed first (collect() returns
  /// them). Throws ConfigError for a bad world, leaving the current scene unchanged.
  void set_world(World world);
  /// The sequence number of the next frame (frame noise = f(options.seed, sequence)): set it
  /// back to 0 with a new seed and an episode's images repeat.
  void set_next_sequence(std::uint64_t sequence);
  /// Change the water (domain randomisation, test sweeps) without rebuilding the scene.
  void set_water(const WaterModel& water);
  const WaterModel& water() const;
  void set_options(const RenderOptions& options);  ///< egl/texture fields are ignored
  /// Moves the world's movable object `name` (Object::movable: another vehicle of the fleet) to
  /// X_WO for the frames submitted from now on (its shadows too). Throws ConfigError naming the
  /// object when the world has no movable object of that name, or X_WO is not finite.
  void set_object_pose(const std::string& name, const Pose& X_WO);
  const RenderOptions& options() const;

  const World& world() const;
  const CameraModel& camera(const std::string& name) const;
  std::vector<std::string> camera_names() const;
  const EglContext& context() const;
  std::shared_ptr<EglContext> shared_context() const;  ///< for more renderers in this context
  RenderTimings last_timings() const;
  std::size_t triangle_count() const;

  /// Pose of the optical frame in the world for a body pose.
  Pose camera_pose(const Pose& X_WB, const std::string& camera) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Write frame.rgb as PNG (OpenCV). Throws ConfigError when writing fails.
void write_png_rgb(const Frame& frame, const std::string& path);
/// Read a PNG as rgb8 (width, height out). Throws ConfigError naming the file.
std::vector<std::uint8_t> read_png_rgb(const std::string& path, int* width, int* height);

}  // namespace unav::renderer
