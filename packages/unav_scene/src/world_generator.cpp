#include "unav_scene/world_generator.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <set>

#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"
#include "unav_common/sampling.hpp"
#include "unav_scene/water.hpp"

namespace fs = std::filesystem;

namespace unav::scene {
namespace {

constexpr double kDeg = M_PI / 180.0;

std::uint32_t part_seed(std::uint64_t seed, const char* part) {
  return static_cast<std::uint32_t>(unav::common::KeySeed(seed, std::string("generate.") + part) >> 32U);
}

// Meshes assimp reads, in `folder` (sorted: the placement is by index).
std::vector<std::string> meshes_in(const std::string& folder) {
  static const std::set<std::string> exts = {".obj", ".ply", ".stl", ".gltf", ".glb", ".fbx", ".dae"};
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(folder, ec)) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
    if (exts.count(ext) != 0) out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

double bend_radius(const PipelineSpec& p) {
  return p.bend_radius_m > 0.0 ? p.bend_radius_m : std::max(1.5, 4.0 * p.radius_m);
}

}  // namespace

void check_world_generator(const WorldGenerator& g, const std::string& file, const std::string& prefix) {
  if (!g.water.preset.empty()) {
    try {
      (void)jerlov_preset(g.water.preset);
    } catch (const std::exception&) {
      std::string names;
      for (const auto& n : jerlov_preset_names()) names += (names.empty() ? "" : ", ") + n.substr(n.find('_') + 1);
      throw ConfigError(file, prefix + "water.preset", g.water.preset,
                        "must be one of the Jerlov presets " + names + " (or with the jerlov_ prefix)");
    }
  }
  const auto& r = g.rocks.radius_m;
  if (!(r.x() <= r.y()))
    throw ConfigError(file, prefix + "rocks.radius_m", "[" + std::to_string(r.x()) + ", " + std::to_string(r.y()) + "]",
                      "need smallest <= largest");
  if (bend_radius(g.pipeline) < g.pipeline.radius_m)
    throw ConfigError(
        file, prefix + "pipeline.bend_radius_m", std::to_string(g.pipeline.bend_radius_m),
        "must be >= pipeline.radius_m (" + std::to_string(g.pipeline.radius_m) + " m): a tighter bend folds the tube");
  if (g.objects.count > 0 && g.objects.folder.empty())
    throw ConfigError(file, prefix + "objects.count", std::to_string(g.objects.count), "needs objects.folder");
}

void resolve_world_generator_paths(WorldGenerator* g, const std::string& dir, const std::string& file,
                                   const std::string& prefix) {
  std::string& folder = g->objects.folder;
  if (folder.empty()) return;
  const std::string key = prefix + "objects.folder";
  if (!fs::path(folder).is_absolute()) {
    if (!dir.empty() && fs::is_directory(fs::path(dir) / folder))
      folder = fs::absolute(fs::path(dir) / folder).lexically_normal().string();
    else if (auto found = unav::common::try_find_resource(folder))
      folder = fs::absolute(*found).lexically_normal().string();
  }
  if (!fs::is_directory(folder)) throw ConfigError(file, key, folder, "must be a folder");
  if (meshes_in(folder).empty())
    throw ConfigError(file, key, folder, "holds no mesh (.obj .ply .stl .gltf .glb .fbx .dae)");
}

World generate_world(const WorldGenerator& g, const World& base, std::uint64_t seed) {
  World w = base;
  w.name = base.name + "_generated_" + std::to_string(seed);
  w.rocks.clear();  // the base's hand-placed rocks and objects belong to its own pipeline
  w.objects.clear();
  w.pipelines.clear();

  // Pipeline polyline in the north-east plane from (0, 0).
  const PipelineSpec& ps = g.pipeline;
  double heading = ps.heading_deg * kDeg;
  std::vector<Eigen::Vector2d> ne{Eigen::Vector2d::Zero()};
  ne.push_back(ps.first_length_m * Eigen::Vector2d(std::cos(heading), std::sin(heading)));
  for (const auto& leg : ps.legs) {
    heading += leg.turn_deg * kDeg;
    ne.push_back(ne.back() + leg.length_m * Eigen::Vector2d(std::cos(heading), std::sin(heading)));
  }
  Eigen::Vector2d lo = ne.front(), hi = ne.front();
  for (const auto& p : ne) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }

  // Seabed: square around the pipeline, a whole number of the base's cells.
  const SeabedSpec& ss = g.seabed;
  Seabed& sb = w.seabed;
  sb.heightmap_file.clear();
  sb.hm_values.clear();
  sb.hm_width = sb.hm_height = 0;
  const double res = sb.resolution_m;
  const double side = std::ceil(((hi - lo).maxCoeff() + 2.0 * ss.margin_m) / res) * res;
  sb.center_ne = 0.5 * (lo + hi);
  sb.size_m = Eigen::Vector2d(side, side);
  sb.depth_m = ss.depth_m;
  sb.relief_amplitude_m = ss.relief_m;
  sb.relief_wavelength_m = ss.relief_wavelength_m;
  sb.relief_seed = part_seed(seed, "seabed.relief");
  if (!ss.texture.empty()) sb.material.texture = ss.texture;
  sb.material.albedo = (sb.material.albedo * ss.albedo).cwiseMin(1.0);

  Pipeline pipe;
  pipe.name = "main";
  if (!base.pipelines.empty()) pipe.material = base.pipelines.front().material;
  pipe.radius_m = ps.radius_m;
  pipe.bend_radius_m = bend_radius(ps);
  const Eigen::Vector3d growth(1.0 - 0.65 * ps.growth, 1.0 - 0.55 * ps.growth, 1.0 - 0.75 * ps.growth);
  pipe.material.albedo = pipe.material.albedo.cwiseProduct(growth);
  for (const auto& p : ne)
    pipe.points_W.emplace_back(p.x(), p.y(),
                               sb.depth_at(p.x(), p.y()) - ps.radius_m * (1.0 - 2.0 * ps.burial_fraction));
  build_centerline(&pipe);
  w.pipelines.push_back(std::move(pipe));

  // Rocks in the box around the pipe.
  RockField field;
  field.region_lo_ne = lo.array() - 8.0;
  field.region_hi_ne = hi.array() + 8.0;
  const Eigen::Vector2d extent = field.region_hi_ne - field.region_lo_ne;
  field.count = static_cast<int>(std::lround(g.rocks.per_100m2 * extent.prod() / 100.0));
  field.seed = part_seed(seed, "rocks");
  field.radius_m = g.rocks.radius_m;
  field.clearance_from_pipe_m = ps.radius_m + 0.4;
  if (!base.rocks.empty()) field.material = base.rocks.front().material;
  add_rock_field(&w, field);

  // Meshes scattered around the pipe, on the seabed.
  if (g.objects.count > 0) {
    const auto meshes = meshes_in(g.objects.folder);
    unav::common::SplitMix64 rng{unav::common::KeySeed(seed, "generate.objects")};
    for (int i = 0; i < g.objects.count && !meshes.empty(); ++i) {
      Object o;
      o.name = "object_" + std::to_string(i);
      o.mesh_file = meshes[rng.Next() % meshes.size()];
      const double n = lo.x() - 5.0 + (hi.x() - lo.x() + 10.0) * rng.Uniform01();
      const double e = lo.y() - 5.0 + (hi.y() - lo.y() + 10.0) * rng.Uniform01();
      o.X_WO = Pose::Identity();
      o.X_WO.translation() = Eigen::Vector3d(n, e, sb.depth_at(n, e) - 0.1);
      o.X_WO.linear() = Eigen::AngleAxisd(2.0 * M_PI * rng.Uniform01(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      o.scale = Eigen::Vector3d::Constant(g.objects.scale);
      o.seg_class = SegClass::kOther;
      o.material.texture = "rock";
      w.objects.push_back(std::move(o));
    }
  }

  // Water: the preset (or the base's) scaled by the turbidity; marine snow.
  const WaterSpec& ws = g.water;
  if (!ws.preset.empty()) w.water = jerlov_preset(ws.preset);
  w.water.beta_D *= ws.turbidity;
  w.water.beta_B *= ws.turbidity;
  w.water.K_d *= ws.turbidity;
  w.water.b_scatter *= ws.turbidity;
  if (ws.marine_snow_per_m3 >= 0.0) w.marine_snow.density_per_m3 = ws.marine_snow_per_m3;
  w.marine_snow.seed = part_seed(seed, "marine_snow");

  // Light: the sun from elevation and azimuth, the base's colour; the lamps.
  const LightSpec& ls = g.light;
  const double el = ls.sun_elevation_deg * kDeg, az = ls.sun_azimuth_deg * kDeg;
  w.sun.direction_W = Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  w.sun.surface_irradiance *= ls.sun_irradiance;
  if (ls.lamp_count >= 0) {
    const Lamp tmpl = base.lamps.empty() ? Lamp{} : base.lamps.front();
    w.lamps.clear();
    for (int i = 0; i < ls.lamp_count; ++i) {  // spread across the bow, 0.3 m wide
      Lamp l = tmpl;
      l.name = "lamp_" + std::to_string(i);
      l.X_BL.translation().y() = ls.lamp_count == 1 ? 0.0 : -0.15 + 0.3 * i / (ls.lamp_count - 1);
      w.lamps.push_back(l);
    }
  }
  for (auto& l : w.lamps) {
    l.intensity *= ls.lamp_intensity;
    if (ls.lamp_half_angle_deg > 0.0) l.cone_half_angle_rad = ls.lamp_half_angle_deg * kDeg;
  }
  return w;
}

}  // namespace unav::scene
