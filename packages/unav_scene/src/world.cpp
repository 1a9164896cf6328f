#include "unav_scene/world.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "unav_scene/errors.hpp"
#include "unav_scene/noise.hpp"
#include "yaml_util.hpp"

namespace unav::scene {
namespace detail {
WaterModel parse_water(const YamlCtx& c, const YAML::Node& node, const std::string& path, bool in_world);
}  // namespace detail

namespace fs = std::filesystem;
using detail::check_keys;
using detail::get_bool;
using detail::get_double;
using detail::get_string;
using detail::get_vec;
using detail::join_key;
using detail::YamlCtx;

namespace {

// The procedural textures and what their materials look like unless told: roughness, relief [m].
struct TextureLook {
  const char* name;
  double roughness, relief_m;
};
constexpr TextureLook kTextureLooks[] = {
    {"none", 0.6, 0.0}, {"sand", 0.9, 0.02}, {"rock", 0.8, 0.03}, {"pipe_coating", 0.45, 0.006}, {"checker", 0.6, 0.0}};

const TextureLook* texture_look(const std::string& texture) {
  for (const TextureLook& t : kTextureLooks)
    if (texture == t.name) return &t;
  return nullptr;
}

}  // namespace

double material_roughness(const Material& m) {
  if (!std::isnan(m.roughness)) return m.roughness;
  const TextureLook* t = texture_look(m.texture);
  return t ? t->roughness : 0.6;
}

double material_relief_m(const Material& m) {
  if (!std::isnan(m.relief_m)) return m.relief_m;
  const TextureLook* t = texture_look(m.texture);
  return t ? t->relief_m : 0.0;
}

double material_sediment(const Material& m) { return std::isnan(m.sediment) ? 0.5 : m.sediment; }

bool same_look(const Material& a, const Material& b) {
  return a.texture == b.texture && a.albedo == b.albedo && a.uv_scale_m == b.uv_scale_m &&
         material_roughness(a) == material_roughness(b) && a.metallic == b.metallic &&
         material_relief_m(a) == material_relief_m(b) && material_sediment(a) == material_sediment(b);
}

double acoustic_reflectivity_db(SegClass seg_class) {
  switch (seg_class) {
    case SegClass::kSeabed:
      return -27.0;
    case SegClass::kPipeline:
      return -12.0;
    case SegClass::kRock:
      return -17.0;
    case SegClass::kWater:
      return -80.0;
    case SegClass::kVehicle:
      return -10.0;  // a hard frame, thrusters and housings: a bright target
    case SegClass::kOther:
      break;
  }
  return -20.0;
}

std::vector<std::pair<int, std::string>> seg_class_labels() {
  return {{static_cast<int>(SegClass::kWater), "water"},       {static_cast<int>(SegClass::kSeabed), "seabed"},
          {static_cast<int>(SegClass::kPipeline), "pipeline"}, {static_cast<int>(SegClass::kRock), "rock"},
          {static_cast<int>(SegClass::kOther), "other"},       {static_cast<int>(SegClass::kVehicle), "vehicle"}};
}

double Seabed::depth_at(double n_m, double e_m) const {
  double d = depth_m;
  if (relief_amplitude_m > 0.0 && relief_wavelength_m > 0.0) {
    const double f = noise::fbm2(n_m / relief_wavelength_m, e_m / relief_wavelength_m, relief_seed, 4);
    d += relief_amplitude_m * (2.0 * f - 1.0);
  }
  if (hm_width > 1 && hm_height > 1) {
    // The heightmap spans the seabed patch: row 0 = north edge, column 0 = west edge.
    const double u = ((e_m - center_ne.y()) / size_m.y() + 0.5) * (hm_width - 1);
    const double v = (0.5 - (n_m - center_ne.x()) / size_m.x()) * (hm_height - 1);
    const double uc = std::clamp(u, 0.0, hm_width - 1.0), vc = std::clamp(v, 0.0, hm_height - 1.0);
    const int i = std::min(static_cast<int>(uc), hm_width - 2), j = std::min(static_cast<int>(vc), hm_height - 2);
    const double fu = uc - i, fv = vc - j;
    auto H = [&](int a, int b) { return static_cast<double>(hm_values[b * hm_width + a]); };
    const double h =
        (H(i, j) * (1 - fu) + H(i + 1, j) * fu) * (1 - fv) + (H(i, j + 1) * (1 - fu) + H(i + 1, j + 1) * fu) * fv;
    d -= heightmap_range_m * h;  // white = shallower
  }
  return d;
}

SeabedGrid sample_seabed(const Seabed& seabed) {
  SeabedGrid g;
  g.resolution_m = seabed.resolution_m;
  g.origin_n = seabed.center_ne.x() - 0.5 * seabed.size_m.x();
  g.origin_e = seabed.center_ne.y() - 0.5 * seabed.size_m.y();
  // Cover the whole patch (the last row/column may lie up to one cell beyond it).
  const int rows = std::max(2, static_cast<int>(std::ceil(seabed.size_m.x() / seabed.resolution_m - 1e-9)) + 1);
  const int cols = std::max(2, static_cast<int>(std::ceil(seabed.size_m.y() / seabed.resolution_m - 1e-9)) + 1);
  g.depths_m.assign(static_cast<std::size_t>(rows), std::vector<double>(static_cast<std::size_t>(cols)));
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      g.depths_m[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] =
          seabed.depth_at(g.origin_n + i * g.resolution_m, g.origin_e + j * g.resolution_m);
  return g;
}

std::vector<Eigen::Vector3d> bent_centerline(const std::vector<Eigen::Vector3d>& P, double bend_radius_m,
                                             double step_m) {
  std::vector<Eigen::Vector3d> out;
  if (P.size() < 2) return P;
  auto add_line = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const double L = (b - a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(L / step_m)));
    for (int k = out.empty() ? 0 : 1; k <= n; ++k) out.push_back(a + (b - a) * (double(k) / n));
  };
  Eigen::Vector3d cursor = P[0];
  for (std::size_t i = 1; i + 1 < P.size(); ++i) {
    const Eigen::Vector3d din = (P[i] - P[i - 1]).normalized();
    const Eigen::Vector3d dout = (P[i + 1] - P[i]).normalized();
    const double c = std::clamp(din.dot(dout), -1.0, 1.0);
    const double theta = std::acos(c);
    if (theta < 1e-6 || bend_radius_m <= 0.0) {
      add_line(cursor, P[i]);
      cursor = P[i];
      continue;
    }
    double t = bend_radius_m * std::tan(0.5 * theta);
    t = std::min({t, 0.5 * (P[i] - P[i - 1]).norm(), 0.5 * (P[i + 1] - P[i]).norm()});
    const double R = t / std::tan(0.5 * theta);
    const Eigen::Vector3d A = P[i] - din * t;
    add_line(cursor, A);
    Eigen::Vector3d nrm = dout - din * c;
    nrm = nrm.norm() > 1e-12 ? nrm.normalized() : Eigen::Vector3d::Zero();
    const int n = std::max(2, static_cast<int>(std::ceil(R * theta / step_m)));
    for (int k = 1; k <= n; ++k) {
      const double s = theta * k / n;
      out.push_back(A + R * (std::sin(s) * din + (1.0 - std::cos(s)) * nrm));
    }
    cursor = out.back();
  }
  add_line(cursor, P.back());
  return out;
}

namespace {

Material parse_material(const YamlCtx& c, const YAML::Node& n, const std::string& path, Material def) {
  if (!n) return def;
  check_keys(
      c, n, path,
      {"texture", "albedo", "uv_scale_m", "acoustic_reflectivity_db", "roughness", "metallic", "relief_m", "sediment"});
  def.texture = get_string(c, n, path, "texture", def.texture);
  if (!texture_look(def.texture))
    c.fail(join_key(path, "texture"),
           "unknown texture '" + def.texture + "' (valid: none, sand, rock, pipe_coating, checker)");
  def.albedo = get_vec<3>(c, n, path, "albedo", def.albedo, true);
  for (int i = 0; i < 3; ++i)
    if (!(def.albedo[i] >= 0.0 && def.albedo[i] <= 1.0)) c.fail(join_key(path, "albedo"), "values must be in [0, 1]");
  def.uv_scale_m = get_double(c, n, path, "uv_scale_m", def.uv_scale_m);
  if (!(def.uv_scale_m > 0.0)) c.fail(join_key(path, "uv_scale_m"), "must be > 0");
  if (n["roughness"]) {
    def.roughness = get_double(c, n, path, "roughness", 0.0);
    if (!(def.roughness >= 0.05 && def.roughness <= 1.0)) c.fail(join_key(path, "roughness"), "must be in [0.05, 1]");
  }
  def.metallic = get_double(c, n, path, "metallic", def.metallic);
  if (!(def.metallic >= 0.0 && def.metallic <= 1.0)) c.fail(join_key(path, "metallic"), "must be in [0, 1]");
  if (n["relief_m"]) {
    def.relief_m = get_double(c, n, path, "relief_m", 0.0);
    if (!(def.relief_m >= 0.0 && def.relief_m <= 0.5 * def.uv_scale_m))
      c.fail(join_key(path, "relief_m"), "must be in [0, uv_scale_m / 2] (a relief taller than half its tile)");
  }
  if (n["sediment"]) {
    def.sediment = get_double(c, n, path, "sediment", 0.0);
    if (!(def.sediment >= 0.0 && def.sediment <= 1.0)) c.fail(join_key(path, "sediment"), "must be in [0, 1]");
  }
  if (n["acoustic_reflectivity_db"]) {
    def.acoustic_reflectivity_db = get_double(c, n, path, "acoustic_reflectivity_db", 0.0);
    if (!(def.acoustic_reflectivity_db >= -80.0 && def.acoustic_reflectivity_db <= 0.0))
      c.fail(join_key(path, "acoustic_reflectivity_db"), "must be in [-80, 0] dB (Lambert mu)");
  }
  return def;
}

Pose parse_pose(const YamlCtx& c, const YAML::Node& n, const std::string& path) {
  if (!n) return Pose::Identity();
  check_keys(c, n, path, {"xyz_m", "rpy_deg"});
  return pose_from_xyz_rpy(get_vec<3>(c, n, path, "xyz_m", Eigen::Vector3d::Zero()),
                           get_vec<3>(c, n, path, "rpy_deg", Eigen::Vector3d::Zero()) * M_PI / 180.0);
}

std::string resolve(const std::string& dir, const std::string& p) {
  const fs::path fp(p);
  return fp.is_absolute() ? p : (fs::path(dir) / fp).lexically_normal().string();
}

void require_readable(const YamlCtx& c, const std::string& key, const std::string& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) c.fail(key, "file not found: " + file);
  std::ifstream f(file, std::ios::binary);
  if (!f.good()) c.fail(key, "file not readable: " + file);
}

// Points of a pipeline: points_ne (placed on the seabed) or points_ned (explicit depth).
std::vector<Eigen::Vector3d> parse_points(const YamlCtx& c, const YAML::Node& n, const std::string& path,
                                          const Seabed& seabed, double radius, double burial) {
  std::vector<Eigen::Vector3d> pts;
  const bool ne = static_cast<bool>(n["points_ne"]);
  const YAML::Node list = ne ? n["points_ne"] : n["points_ned"];
  const std::string key = join_key(path, ne ? "points_ne" : "points_ned");
  if (!list || !list.IsSequence() || list.size() < 2)
    c.fail(key, "need a list of at least 2 points (points_ne or points_ned)");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const auto& v = list[i];
    const std::size_t dim = ne ? 2 : 3;
    if (!v.IsSequence() || v.size() != dim)
      c.fail(key + "[" + std::to_string(i) + "]", "expected " + std::to_string(dim) + " numbers");
    Eigen::Vector3d p;
    try {
      p.x() = v[0].as<double>();
      p.y() = v[1].as<double>();
      p.z() = ne ? seabed.depth_at(p.x(), p.y()) - radius * (1.0 - 2.0 * burial) : v[2].as<double>();
    } catch (const YAML::Exception&) {
      c.fail(key + "[" + std::to_string(i) + "]", "expected numbers");
    }
    if (!pts.empty() && (p - pts.back()).norm() < 1e-6)
      c.fail(key + "[" + std::to_string(i) + "]", "repeats the previous point");
    pts.push_back(p);
  }
  return pts;
}

SegClass parse_class(const YamlCtx& c, const std::string& key, const std::string& s) {
  if (s == "seabed") return SegClass::kSeabed;
  if (s == "pipeline") return SegClass::kPipeline;
  if (s == "rock") return SegClass::kRock;
  if (s == "other") return SegClass::kOther;
  if (s == "vehicle") return SegClass::kVehicle;
  c.fail(key, "unknown class '" + s + "' (valid: seabed, pipeline, rock, other, vehicle)");
}

}  // namespace

namespace {

// Water.
void parse_water_section(const YamlCtx& c, const YAML::Node& root, World& w) {
  if (const YAML::Node wn = root["water"]) {
    if (wn["file"]) {
      const std::string f = resolve(w.dir, get_string(c, wn, "water", "file", ""));
      require_readable(c, "water.file", f);
      w.water = load_water_file(f);
      check_keys(c, wn, "water", {"file", "marine_snow"});
    } else {
      w.water = detail::parse_water(c, wn, "water", true);
    }
    if (const YAML::Node s = wn["marine_snow"]) {
      check_keys(c, s, "water.marine_snow", {"density_per_m3", "size_m", "box_m", "seed"});
      auto& ms = w.marine_snow;
      ms.density_per_m3 = get_double(c, s, "water.marine_snow", "density_per_m3", ms.density_per_m3);
      ms.size_m = get_double(c, s, "water.marine_snow", "size_m", ms.size_m);
      ms.box_m = get_double(c, s, "water.marine_snow", "box_m", ms.box_m);
      ms.seed = static_cast<std::uint32_t>(get_double(c, s, "water.marine_snow", "seed", ms.seed));
      if (!(ms.density_per_m3 >= 0.0 && ms.density_per_m3 <= 2000.0))
        c.fail("water.marine_snow.density_per_m3", "must be in [0, 2000]");
      if (!(ms.size_m > 0.0) || !(ms.box_m > 0.0)) c.fail("water.marine_snow", "size_m and box_m must be > 0");
    }
  }
}

// Seabed.
void parse_seabed(const YamlCtx& c, const YAML::Node& root, World& w) {
  if (const YAML::Node s = root["seabed"]) {
    const std::string p = "seabed";
    check_keys(c, s, p,
               {"enabled", "depth_m", "center_ne", "size_m", "resolution_m", "far_extent_m", "relief", "heightmap",
                "material"});
    auto& sb = w.seabed;
    sb.enabled = get_bool(c, s, p, "enabled", true);
    sb.depth_m = get_double(c, s, p, "depth_m", sb.depth_m);
    if (!(sb.depth_m > 0.0)) c.fail("seabed.depth_m", "must be > 0 (NED depth below the surface)");
    sb.center_ne = get_vec<2>(c, s, p, "center_ne", sb.center_ne);
    sb.size_m = get_vec<2>(c, s, p, "size_m", sb.size_m);
    if (!(sb.size_m.minCoeff() > 0.0)) c.fail("seabed.size_m", "must be > 0");
    sb.resolution_m = get_double(c, s, p, "resolution_m", sb.resolution_m);
    if (!(sb.resolution_m > 0.0)) c.fail("seabed.resolution_m", "must be > 0");
    sb.far_extent_m = get_double(c, s, p, "far_extent_m", sb.far_extent_m);
    if (!(sb.far_extent_m >= 0.0)) c.fail("seabed.far_extent_m", "must be >= 0");
    if ((sb.size_m.x() / sb.resolution_m) * (sb.size_m.y() / sb.resolution_m) > 4.0e6)
      c.fail("seabed.resolution_m", "more than 4 million grid cells");
    if (const YAML::Node r = s["relief"]) {
      check_keys(c, r, "seabed.relief", {"amplitude_m", "wavelength_m", "seed"});
      sb.relief_amplitude_m = get_double(c, r, "seabed.relief", "amplitude_m", 0.0);
      sb.relief_wavelength_m = get_double(c, r, "seabed.relief", "wavelength_m", sb.relief_wavelength_m);
      sb.relief_seed = static_cast<std::uint32_t>(get_double(c, r, "seabed.relief", "seed", 1));
      if (!(sb.relief_amplitude_m >= 0.0) || !(sb.relief_wavelength_m > 0.0))
        c.fail("seabed.relief", "amplitude_m >= 0 and wavelength_m > 0 required");
    }
    if (const YAML::Node h = s["heightmap"]) {
      check_keys(c, h, "seabed.heightmap", {"file", "range_m"});
      sb.heightmap_file = resolve(w.dir, get_string(c, h, "seabed.heightmap", "file", ""));
      require_readable(c, "seabed.heightmap.file", sb.heightmap_file);
      sb.heightmap_range_m = get_double(c, h, "seabed.heightmap", "range_m", 1.0);
      cv::Mat img = cv::imread(sb.heightmap_file, cv::IMREAD_GRAYSCALE | cv::IMREAD_ANYDEPTH);
      if (img.empty() || img.cols < 2 || img.rows < 2)
        c.fail("seabed.heightmap.file", "cannot decode image: " + sb.heightmap_file);
      cv::Mat f;
      img.convertTo(f, CV_32F, img.depth() == CV_16U ? 1.0 / 65535.0 : 1.0 / 255.0);
      sb.hm_width = f.cols;
      sb.hm_height = f.rows;
      sb.hm_values.assign(f.begin<float>(), f.end<float>());
    }
    sb.material = parse_material(c, s["material"], "seabed.material", sb.material);
  }
}

// Pipelines.
void parse_pipelines(const YamlCtx& c, const YAML::Node& root, World& w) {
  if (const YAML::Node pl = root["pipelines"]) {
    if (!pl.IsSequence()) c.fail("pipelines", "expected a list");
    for (std::size_t i = 0; i < pl.size(); ++i) {
      const std::string p = "pipelines[" + std::to_string(i) + "]";
      const YAML::Node n = pl[i];
      check_keys(c, n, p,
                 {"name", "radius_m", "bend_radius_m", "burial_fraction", "points_ne", "points_ned", "material"});
      Pipeline pipe;
      pipe.name = get_string(c, n, p, "name", "pipeline" + std::to_string(i));
      pipe.radius_m = get_double(c, n, p, "radius_m", pipe.radius_m);
      if (!(pipe.radius_m > 0.0 && pipe.radius_m < 10.0)) c.fail(join_key(p, "radius_m"), "must be in (0, 10) m");
      pipe.bend_radius_m = get_double(c, n, p, "bend_radius_m", std::max(pipe.bend_radius_m, 2.0 * pipe.radius_m));
      if (!(pipe.bend_radius_m >= pipe.radius_m))
        c.fail(join_key(p, "bend_radius_m"), "must be >= radius_m (a tighter bend folds the tube)");
      const double burial = get_double(c, n, p, "burial_fraction", 0.2);
      if (!(burial >= 0.0 && burial < 1.0)) c.fail(join_key(p, "burial_fraction"), "must be in [0, 1)");
      if (n["points_ne"] && n["points_ned"]) c.fail(p, "give points_ne or points_ned, not both");
      pipe.points_W = parse_points(c, n, p, w.seabed, pipe.radius_m, burial);
      pipe.material = parse_material(c, n["material"], join_key(p, "material"), pipe.material);
      build_centerline(&pipe);
      w.pipelines.push_back(std::move(pipe));
    }
  }
}

// Rocks (explicit) and rock_field (seeded scatter).
void parse_rocks(const YamlCtx& c, const YAML::Node& root, World& w) {
  auto rock_on_seabed = [&](double n_m, double e_m, const Eigen::Vector3d& radii) {
    return Eigen::Vector3d(n_m, e_m, w.seabed.depth_at(n_m, e_m) - 0.45 * radii.z());
  };
  if (const YAML::Node rl = root["rocks"]) {
    if (!rl.IsSequence()) c.fail("rocks", "expected a list");
    for (std::size_t i = 0; i < rl.size(); ++i) {
      const std::string p = "rocks[" + std::to_string(i) + "]";
      const YAML::Node n = rl[i];
      check_keys(c, n, p, {"position_ne", "position_ned", "radii_m", "yaw_deg", "seed", "material"});
      Rock r;
      r.radii_m = get_vec<3>(c, n, p, "radii_m", r.radii_m, true);
      if (!(r.radii_m.minCoeff() > 0.0)) c.fail(join_key(p, "radii_m"), "must be > 0");
      if (n["position_ned"]) {
        r.p_W = get_vec<3>(c, n, p, "position_ned", r.p_W);
      } else if (n["position_ne"]) {
        const Eigen::Vector2d ne = get_vec<2>(c, n, p, "position_ne", Eigen::Vector2d::Zero());
        r.p_W = rock_on_seabed(ne.x(), ne.y(), r.radii_m);
      } else {
        c.fail(p, "needs position_ne or position_ned");
      }
      r.yaw_rad = get_double(c, n, p, "yaw_deg", 0.0) * M_PI / 180.0;
      r.seed = static_cast<std::uint32_t>(get_double(c, n, p, "seed", static_cast<double>(i + 1)));
      r.material = parse_material(c, n["material"], join_key(p, "material"), r.material);
      w.rocks.push_back(r);
    }
  }
  if (const YAML::Node rf = root["rock_field"]) {
    const std::string p = "rock_field";
    check_keys(c, rf, p, {"count", "seed", "region_ne", "radius_m", "clearance_from_pipe_m", "material"});
    const int count = static_cast<int>(get_double(c, rf, p, "count", 0));
    if (count < 0 || count > 5000) c.fail("rock_field.count", "must be in [0, 5000]");
    const auto seed = static_cast<std::uint32_t>(get_double(c, rf, p, "seed", 1));
    const YAML::Node reg = rf["region_ne"];
    if (!reg || !reg.IsSequence() || reg.size() != 2)
      c.fail("rock_field.region_ne", "expected [[n_min, e_min], [n_max, e_max]]");
    Eigen::Vector2d lo, hi;
    try {
      lo = {reg[0][0].as<double>(), reg[0][1].as<double>()};
      hi = {reg[1][0].as<double>(), reg[1][1].as<double>()};
    } catch (const YAML::Exception&) {
      c.fail("rock_field.region_ne", "expected [[n_min, e_min], [n_max, e_max]]");
    }
    const Eigen::Vector2d rr = get_vec<2>(c, rf, p, "radius_m", Eigen::Vector2d(0.1, 0.4));
    if (!(rr.x() > 0.0 && rr.y() >= rr.x())) c.fail("rock_field.radius_m", "need 0 < min <= max");
    const double clearance = get_double(c, rf, p, "clearance_from_pipe_m", 0.5);
    RockField field;
    field.count = count;
    field.seed = seed;
    field.region_lo_ne = lo;
    field.region_hi_ne = hi;
    field.radius_m = rr;
    field.clearance_from_pipe_m = clearance;
    field.material = parse_material(c, rf["material"], "rock_field.material", Rock{}.material);
    add_rock_field(&w, field);
  }
}

// Objects (mesh files or primitive shapes).
void parse_objects(const YamlCtx& c, const YAML::Node& root, World& w) {
  if (const YAML::Node ol = root["objects"]) {
    if (!ol.IsSequence()) c.fail("objects", "expected a list");
    for (std::size_t i = 0; i < ol.size(); ++i) {
      const std::string p = "objects[" + std::to_string(i) + "]";
      const YAML::Node n = ol[i];
      check_keys(c, n, p, {"name", "mesh", "shape", "size_m", "pose", "scale", "class", "material"});
      Object o;
      o.name = get_string(c, n, p, "name", "object" + std::to_string(i));
      if (n["mesh"] && n["shape"]) c.fail(p, "give mesh or shape, not both");
      if (n["mesh"]) {
        o.mesh_file = resolve(w.dir, get_string(c, n, p, "mesh", ""));
        require_readable(c, join_key(p, "mesh"), o.mesh_file);
      } else {
        o.shape = get_string(c, n, p, "shape", "");
        if (o.shape != "box" && o.shape != "sphere" && o.shape != "plane")
          c.fail(join_key(p, "shape"), "unknown shape '" + o.shape + "' (valid: box, sphere, plane; or give mesh)");
        o.size_m = get_vec<3>(c, n, p, "size_m", o.size_m, true);
        if (!(o.size_m.minCoeff() > 0.0)) c.fail(join_key(p, "size_m"), "must be > 0");
      }
      o.X_WO = parse_pose(c, n["pose"], join_key(p, "pose"));
      o.scale = get_vec<3>(c, n, p, "scale", o.scale, true);
      if (!(o.scale.minCoeff() > 0.0)) c.fail(join_key(p, "scale"), "must be > 0");
      o.seg_class = parse_class(c, join_key(p, "class"), get_string(c, n, p, "class", "other"));
      o.material = parse_material(c, n["material"], join_key(p, "material"), o.material);
      w.objects.push_back(o);
    }
  }
}

// Lights.
void parse_lights(const YamlCtx& c, const YAML::Node& root, World& w) {
  if (const YAML::Node l = root["lights"]) {
    check_keys(c, l, "lights", {"sun", "lamps"});
    if (const YAML::Node s = l["sun"]) {
      check_keys(c, s, "lights.sun", {"direction_ned", "surface_irradiance", "ambient_fraction"});
      const Eigen::Vector3d d = get_vec<3>(c, s, "lights.sun", "direction_ned", w.sun.direction_W);
      if (d.norm() < 1e-9) c.fail("lights.sun.direction_ned", "has zero length");
      if (d.z() <= 0.0) c.fail("lights.sun.direction_ned", "must point down (positive z in NED)");
      w.sun.direction_W = d.normalized();
      w.sun.surface_irradiance = get_vec<3>(c, s, "lights.sun", "surface_irradiance", w.sun.surface_irradiance, true);
      if (!(w.sun.surface_irradiance.minCoeff() >= 0.0)) c.fail("lights.sun.surface_irradiance", "must be >= 0");
      w.sun.ambient_fraction = get_double(c, s, "lights.sun", "ambient_fraction", w.sun.ambient_fraction);
      if (!(w.sun.ambient_fraction >= 0.0 && w.sun.ambient_fraction <= 1.0))
        c.fail("lights.sun.ambient_fraction", "must be in [0, 1]");
    }
    if (const YAML::Node ll = l["lamps"]) {
      if (!ll.IsSequence()) c.fail("lights.lamps", "expected a list");
      for (std::size_t i = 0; i < ll.size(); ++i) {
        const std::string p = "lights.lamps[" + std::to_string(i) + "]";
        const YAML::Node n = ll[i];
        check_keys(c, n, p, {"name", "mount", "half_angle_deg", "intensity"});
        Lamp lamp;
        lamp.name = get_string(c, n, p, "name", "lamp" + std::to_string(i));
        lamp.X_BL = parse_pose(c, n["mount"], join_key(p, "mount"));
        const double ha = get_double(c, n, p, "half_angle_deg", 35.0);
        if (!(ha > 0.0 && ha < 90.0)) c.fail(join_key(p, "half_angle_deg"), "must be in (0, 90)");
        lamp.cone_half_angle_rad = ha * M_PI / 180.0;
        lamp.intensity = get_vec<3>(c, n, p, "intensity", lamp.intensity, true);
        if (!(lamp.intensity.minCoeff() >= 0.0)) c.fail(join_key(p, "intensity"), "must be >= 0");
        w.lamps.push_back(lamp);
      }
      if (w.lamps.size() > 4) c.fail("lights.lamps", "at most 4 lamps are supported");
    }
  }
}

}  // namespace

void build_centerline(Pipeline* pipe, double step_m) {
  pipe->centerline_W = bent_centerline(pipe->points_W, pipe->bend_radius_m, step_m);
  pipe->arc_length_m.assign(pipe->centerline_W.size(), 0.0);
  for (std::size_t k = 1; k < pipe->centerline_W.size(); ++k)
    pipe->arc_length_m[k] = pipe->arc_length_m[k - 1] + (pipe->centerline_W[k] - pipe->centerline_W[k - 1]).norm();
}

void add_rock_field(World* world, const RockField& f) {
  World& w = *world;
  const Eigen::Vector2d &lo = f.region_lo_ne, &hi = f.region_hi_ne, &rr = f.radius_m;
  int placed = 0;
  for (int k = 0; placed < f.count && k < f.count * 20; ++k) {
    auto U = [&](int j) { return noise::lattice(k, j, 17, f.seed); };
    const double n_m = lo.x() + (hi.x() - lo.x()) * U(0), e_m = lo.y() + (hi.y() - lo.y()) * U(1);
    // Mostly small rocks, a few large ones.
    const double rad = rr.x() + (rr.y() - rr.x()) * std::pow(U(2), 2.0);
    Rock r;
    r.radii_m = rad * Eigen::Vector3d(0.8 + 0.4 * U(3), 0.8 + 0.4 * U(4), 0.45 + 0.3 * U(5));
    r.p_W = Eigen::Vector3d(n_m, e_m, w.seabed.depth_at(n_m, e_m) - 0.45 * r.radii_m.z());
    if (!w.pipelines.empty()) {
      const PipeQuery q = nearest_pipe_point(w, r.p_W, true);
      if (q.horizontal_distance_m < f.clearance_from_pipe_m + rad + w.pipelines[q.pipeline].radius_m) continue;
    }
    r.yaw_rad = 2.0 * M_PI * U(6);
    r.seed = f.seed * 1000U + static_cast<std::uint32_t>(k);
    r.material = f.material;
    w.rocks.push_back(r);
    ++placed;
  }
}

World load_world(const std::string& path) {
  YamlCtx c{path};
  const YAML::Node root = detail::load_yaml_file(path);
  check_keys(
      c, root, "",
      {"name", "description", "water", "seabed", "pipelines", "rocks", "rock_field", "objects", "lights", "current"});
  World w;
  w.file = path;
  w.dir = fs::path(path).parent_path().string();
  w.name = get_string(c, root, "", "name", fs::path(path).parent_path().filename().string());

  parse_water_section(c, root, w);
  parse_seabed(c, root, w);
  parse_pipelines(c, root, w);
  parse_rocks(c, root, w);
  parse_objects(c, root, w);
  parse_lights(c, root, w);
  if (const YAML::Node cur = root["current"]) {
    check_keys(c, cur, "current", {"file"});
    if (!cur["file"]) c.fail("current", "needs 'file' (a config/water/currents YAML)");
    w.current_file = resolve(w.dir, get_string(c, cur, "current", "file", ""));
    require_readable(c, "current.file", w.current_file);
  }
  return w;
}

PipeQuery nearest_pipe_point(const World& world, const Eigen::Vector3d& p_W, bool horizontal) {
  PipeQuery best;
  double best_d = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d mask = horizontal ? Eigen::Vector3d(1, 1, 0) : Eigen::Vector3d(1, 1, 1);
  for (std::size_t pi = 0; pi < world.pipelines.size(); ++pi) {
    const auto& pl = world.pipelines[pi];
    const auto& C = pl.centerline_W;
    for (std::size_t k = 0; k + 1 < C.size(); ++k) {
      const Eigen::Vector3d a = C[k].cwiseProduct(mask), b = C[k + 1].cwiseProduct(mask);
      const Eigen::Vector3d q = p_W.cwiseProduct(mask);
      const Eigen::Vector3d ab = b - a;
      const double L2 = ab.squaredNorm();
      const double t = L2 > 0 ? std::clamp((q - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
      const double d = (q - (a + t * ab)).norm();
      if (d < best_d) {
        best_d = d;
        best.valid = true;
        best.pipeline = pi;
        best.closest_W = C[k] + t * (C[k + 1] - C[k]);
        const Eigen::Vector3d dir = C[k + 1] - C[k];
        best.heading_rad = std::atan2(dir.y(), dir.x());
        best.arc_length_m = pl.arc_length_m[k] + t * (pl.arc_length_m[k + 1] - pl.arc_length_m[k]);
        const Eigen::Vector2d d2 = dir.head<2>().normalized();
        const Eigen::Vector2d o2 = (p_W - best.closest_W).head<2>();
        best.lateral_m = d2.x() * o2.y() - d2.y() * o2.x();
      }
    }
  }
  if (best.valid) {
    best.distance_m = (p_W - best.closest_W).norm();
    best.horizontal_distance_m = (p_W - best.closest_W).head<2>().norm();
  }
  return best;
}

double distance_to_pipe(const World& world, const Eigen::Vector3d& p_W) {
  const PipeQuery q = nearest_pipe_point(world, p_W, true);
  return q.valid ? q.horizontal_distance_m : std::numeric_limits<double>::infinity();
}

double pipe_heading(const World& world, const Eigen::Vector3d& p_W) {
  const PipeQuery q = nearest_pipe_point(world, p_W, true);
  return q.valid ? q.heading_rad : 0.0;
}

}  // namespace unav::scene
