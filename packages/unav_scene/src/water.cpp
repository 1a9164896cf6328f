#include "unav_scene/water.hpp"

#include <cmath>
#include <stdexcept>

#include "unav_scene/errors.hpp"
#include "yaml_util.hpp"

namespace unav::scene {
namespace {

struct PresetRow {
  const char* name;
  double beta[3];       // REFERENCE.md section 3 (UWCNN, -ln N), 1/m
  double b_inf[3];      // veiling light at the surface for E0 = 1: ESTIMATE (see config/water)
  double scatter_frac;  // b / beta: ESTIMATE (clear ocean ~0.3, coastal ~0.6)
  double fwd_per_m;     // forward-scatter fraction per metre: ESTIMATE
  double blur_rad_per_m;
};

// B_inf: plausible veiling-light colours (blue in oceanic I-III, turning green then
// yellow-green in coastal 1C-9C), chosen so that water seen at 10 m depth looks like
// typical footage; they are estimates, not measurements.
constexpr PresetRow kPresets[] = {
    {"I", {0.217, 0.040, 0.018}, {0.020, 0.150, 0.260}, 0.30, 0.010, 0.0010},
    {"IA", {0.218, 0.046, 0.025}, {0.020, 0.150, 0.250}, 0.30, 0.012, 0.0010},
    {"IB", {0.186, 0.051, 0.033}, {0.022, 0.160, 0.240}, 0.32, 0.014, 0.0012},
    {"II", {0.223, 0.078, 0.062}, {0.025, 0.170, 0.230}, 0.35, 0.020, 0.0015},
    {"III", {0.288, 0.122, 0.117}, {0.030, 0.180, 0.210}, 0.40, 0.030, 0.0020},
    {"1C", {0.288, 0.122, 0.134}, {0.035, 0.190, 0.200}, 0.45, 0.035, 0.0020},
    {"3C", {0.342, 0.198, 0.223}, {0.045, 0.200, 0.180}, 0.55, 0.050, 0.0025},
    {"5C", {0.400, 0.315, 0.400}, {0.060, 0.210, 0.160}, 0.60, 0.070, 0.0030},
    {"7C", {0.478, 0.494, 0.693}, {0.080, 0.200, 0.120}, 0.65, 0.090, 0.0035},
    {"9C", {0.598, 0.777, 1.238}, {0.100, 0.180, 0.080}, 0.70, 0.110, 0.0040},
};

std::string strip_prefix(const std::string& n) {
  const std::string p = "jerlov_";
  return n.rfind(p, 0) == 0 ? n.substr(p.size()) : n;
}

}  // namespace

Eigen::Vector3d WaterModel::veiling_light_at(double depth_m, const Eigen::Vector3d& E0) const {
  const double d = std::max(0.0, depth_m);
  return (B_inf.array() * E0.array() * (-K_d.array() * d).exp()).matrix();
}

void WaterModel::validate(const std::string& where) const {
  auto check = [&](const Eigen::Vector3d& v, const char* field) {
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(v[i]) || v[i] < 0.0)
        throw ConfigError(where + ": water." + field + " must be finite and >= 0 (got " + std::to_string(v[i]) + ")");
  };
  check(beta_D, "beta_D");
  check(beta_B, "beta_B");
  check(K_d, "K_d");
  check(B_inf, "B_inf");
  check(b_scatter, "b_scatter");
  if (!(phase_g > -1.0 && phase_g < 1.0)) throw ConfigError(where + ": water.phase_g must be in (-1, 1)");
  if (!(refractive_index >= 1.0 && refractive_index <= 1.6))
    throw ConfigError(where + ": water.refractive_index must be in [1, 1.6] (got " + std::to_string(refractive_index) +
                      ")");
  if (!(phase_backscatter_fraction >= 0.0 && phase_backscatter_fraction <= 1.0))
    throw ConfigError(where + ": water.phase_backscatter_fraction must be in [0, 1]");
  if (!(veiling_light_gradient >= 0.0 && veiling_light_gradient < 1.0))
    throw ConfigError(where + ": water.veiling_light_gradient must be in [0, 1)");
  if (!(forward_scatter_per_m >= 0.0) || !(forward_blur_rad_per_m >= 0.0))
    throw ConfigError(where + ": water.forward_scatter must be >= 0");
}

std::vector<std::string> jerlov_preset_names() {
  std::vector<std::string> out;
  for (const auto& r : kPresets) out.push_back(std::string("jerlov_") + r.name);
  return out;
}

WaterModel jerlov_preset(const std::string& name) {
  const std::string n = strip_prefix(name);
  for (const auto& r : kPresets) {
    if (n != r.name) continue;
    WaterModel w;
    w.name = std::string("jerlov_") + r.name;
    w.beta_D = {r.beta[0], r.beta[1], r.beta[2]};
    w.beta_B = w.beta_D;
    w.K_d = w.beta_D;
    w.B_inf = {r.b_inf[0], r.b_inf[1], r.b_inf[2]};
    w.b_scatter = r.scatter_frac * w.beta_D;
    w.forward_scatter_per_m = r.fwd_per_m;
    w.forward_blur_rad_per_m = r.blur_rad_per_m;
    return w;
  }
  std::string list;
  for (const auto& s : jerlov_preset_names()) list += (list.empty() ? "" : ", ") + s;
  throw ConfigError("unknown Jerlov water preset '" + name + "' (valid: " + list + ")");
}

namespace detail {
// Shared by load_water_file and the world loader: `node` is a water mapping.
WaterModel parse_water(const YamlCtx& c, const YAML::Node& node, const std::string& path, bool in_world) {
  if (in_world)
    check_keys(
        c, node, path,
        {"preset", "name", "beta_D", "beta_B", "K_d", "B_inf", "b_scatter", "phase_g", "phase_backscatter_fraction",
         "forward_scatter_per_m", "forward_blur_rad_per_m", "veiling_light_gradient", "temperature_c", "salinity_psu",
         "ph", "refractive_index", "file", "marine_snow", "description"});
  else
    check_keys(c, node, path,
               {"preset", "name", "beta_D", "beta_B", "K_d", "B_inf", "b_scatter", "phase_g",
                "phase_backscatter_fraction", "forward_scatter_per_m", "forward_blur_rad_per_m",
                "veiling_light_gradient", "temperature_c", "salinity_psu", "ph", "refractive_index", "description"});
  WaterModel w;
  if (node["preset"]) {
    try {
      w = jerlov_preset(get_string(c, node, path, "preset", ""));
    } catch (const ConfigError& e) {
      c.fail(join_key(path, "preset"), e.what());
    }
  } else if (!node["beta_D"]) {
    c.fail(path, "needs either 'preset' or explicit coefficients (beta_D, ...)");
  }
  w.name = get_string(c, node, path, "name", w.name);
  w.beta_D = get_vec<3>(c, node, path, "beta_D", w.beta_D, true);
  // Without explicit values the backscatter and diffuse coefficients follow beta_D.
  const bool explicit_only = !node["preset"];
  w.beta_B = get_vec<3>(c, node, path, "beta_B", explicit_only ? w.beta_D : w.beta_B, true);
  w.K_d = get_vec<3>(c, node, path, "K_d", explicit_only ? w.beta_D : w.K_d, true);
  w.B_inf = get_vec<3>(c, node, path, "B_inf", w.B_inf, true);
  w.b_scatter =
      get_vec<3>(c, node, path, "b_scatter", explicit_only ? Eigen::Vector3d(0.4 * w.beta_D) : w.b_scatter, true);
  w.phase_g = get_double(c, node, path, "phase_g", w.phase_g);
  w.phase_backscatter_fraction = get_double(c, node, path, "phase_backscatter_fraction", w.phase_backscatter_fraction);
  w.veiling_light_gradient = get_double(c, node, path, "veiling_light_gradient", w.veiling_light_gradient);
  w.forward_scatter_per_m = get_double(c, node, path, "forward_scatter_per_m", w.forward_scatter_per_m);
  w.forward_blur_rad_per_m = get_double(c, node, path, "forward_blur_rad_per_m", w.forward_blur_rad_per_m);
  w.temperature_c = get_double(c, node, path, "temperature_c", w.temperature_c);
  w.salinity_psu = get_double(c, node, path, "salinity_psu", w.salinity_psu);
  w.ph = get_double(c, node, path, "ph", w.ph);
  w.refractive_index = get_double(c, node, path, "refractive_index", w.refractive_index);
  if (!(w.refractive_index >= 1.0 && w.refractive_index <= 1.6))
    c.fail(join_key(path, "refractive_index"), "must be in [1, 1.6]");
  if (!(w.temperature_c >= -2.0 && w.temperature_c <= 40.0))
    c.fail(join_key(path, "temperature_c"), "must be in [-2, 40] deg C");
  if (!(w.salinity_psu >= 0.0 && w.salinity_psu <= 45.0)) c.fail(join_key(path, "salinity_psu"), "must be in [0, 45]");
  if (!(w.ph >= 7.0 && w.ph <= 9.0)) c.fail(join_key(path, "ph"), "must be in [7, 9]");
  w.validate(c.file);
  return w;
}
}  // namespace detail

WaterModel load_water_file(const std::string& path) {
  detail::YamlCtx c{path};
  const YAML::Node root = detail::load_yaml_file(path);
  const YAML::Node node = root["water"] ? root["water"] : root;
  if (root["water"]) detail::check_keys(c, root, "", {"water"});
  return detail::parse_water(c, node, root["water"] ? "water" : "", false);
}

WaterModel load_water_spec(const std::string& spec) {
  const bool file = spec.find('/') != std::string::npos || spec.find(".yaml") != std::string::npos;
  return file ? load_water_file(spec) : jerlov_preset(spec);
}

}  // namespace unav::scene
