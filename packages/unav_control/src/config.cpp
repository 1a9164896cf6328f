// YAML loaders for the controller configs (see config.hpp).
#include "unav_control/config.hpp"

#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace unav::control {

namespace {

namespace fs = std::filesystem;
using physics::ConfigError;

std::string flow(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "null";
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

/// The parameter map of a file, plus typed accessors whose errors name file, key and value.
class Params {
 public:
  Params(const std::string& path, const char* node_name) : file_(path) {
    YAML::Node root;
    try {
      root = YAML::LoadFile(path);
    } catch (const YAML::BadFile&) {
      throw ConfigError(path + ": cannot open file");
    } catch (const YAML::Exception& e) {
      throw ConfigError(path + ": malformed YAML: " + e.what());
    }
    if (!root.IsMap()) throw ConfigError(path + ": <top level> must be a map (got " + flow(root) + ")");
    if (root[node_name] && root[node_name].IsMap() && root[node_name]["ros__parameters"]) {
      if (root.size() != 1) throw ConfigError(path + ": only '" + std::string(node_name) + "' expected at top level");
      map_ = root[node_name]["ros__parameters"];
      prefix_ = std::string(node_name) + ".ros__parameters.";
    } else {
      map_ = root;
    }
    if (!map_.IsMap()) throw ConfigError(path + ": " + prefix_ + " must be a map (got " + flow(map_) + ")");
  }
  [[noreturn]] void fail(const std::string& key, const std::string& rule, const std::string& value) const {
    throw ConfigError(file_ + ": " + prefix_ + key + " " + rule + " (got " + value + ")");
  }
  void only(const std::set<std::string>& allowed) const {
    for (const auto& kv : map_) {
      const std::string k = kv.first.as<std::string>();
      if (!allowed.count(k)) fail(k, "is not a known key", flow(kv.second));
    }
  }
  bool has(const std::string& k) const { return static_cast<bool>(map_[k]); }
  double num(const std::string& k, double def) const {
    const YAML::Node n = map_[k];
    if (!n) return def;
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(k, "must be a number", flow(n));
    }
    if (!std::isfinite(v)) fail(k, "must be finite", flow(n));
    return v;
  }
  int integer(const std::string& k, int def) const {
    const YAML::Node n = map_[k];
    if (!n) return def;
    try {
      return n.as<int>();
    } catch (const YAML::Exception&) {
      fail(k, "must be an integer", flow(n));
    }
  }
  std::string str(const std::string& k, const std::string& def) const {
    const YAML::Node n = map_[k];
    if (!n) return def;
    if (!n.IsScalar()) fail(k, "must be a string", flow(n));
    return n.as<std::string>();
  }
  std::vector<double> list(const std::string& k, int size) const {  // size < 0: any length
    const YAML::Node n = map_[k];
    std::vector<double> out;
    if (!n) return out;
    if (!n.IsSequence()) fail(k, "must be a list of numbers", flow(n));
    for (const auto& e : n) {
      double v = 0.0;
      try {
        v = e.as<double>();
      } catch (const YAML::Exception&) {
        fail(k, "must be a list of numbers", flow(n));
      }
      if (!std::isfinite(v)) fail(k, "must contain finite numbers", flow(n));
      out.push_back(v);
    }
    if (size >= 0 && static_cast<int>(out.size()) != size) {
      fail(k, "must have " + std::to_string(size) + " entries", flow(n));
    }
    return out;
  }
  std::vector<std::string> names(const std::string& k) const {
    const YAML::Node n = map_[k];
    std::vector<std::string> out;
    if (!n) return out;
    if (!n.IsSequence()) fail(k, "must be a list of thruster names", flow(n));
    for (const auto& e : n) {
      if (!e.IsScalar()) fail(k, "must be a list of thruster names", flow(n));
      out.push_back(e.as<std::string>());
    }
    return out;
  }
  const std::string& file() const { return file_; }

 private:
  std::string file_, prefix_;
  YAML::Node map_;
};

std::string resolve(const std::string& yaml_path, const std::string& config_root, const std::string& rel) {
  if (fs::path(rel).is_absolute()) return rel;
  const fs::path root = config_root.empty() ? fs::absolute(yaml_path).parent_path().parent_path() : fs::path(config_root);
  return (root / rel).lexically_normal().string();
}

physics::VehicleParams load_vehicle_for(const Params& p, const std::string& key, const std::string& path) {
  if (!fs::exists(path)) p.fail(key, "names a file that does not exist", path);
  return physics::load_vehicle(path);
}

}  // namespace

AllocatorConfig load_allocator_config(const std::string& yaml_path, const std::string& config_root) {
  const Params p(yaml_path, "control_allocator");
  p.only({"vehicle_config", "mode", "thruster_weights", "failed_thrusters", "max_redistribution_iterations"});
  AllocatorConfig c;
  if (!p.has("vehicle_config")) p.fail("vehicle_config", "is required", "nothing");
  c.vehicle_path = resolve(yaml_path, config_root, p.str("vehicle_config", ""));
  c.vehicle = load_vehicle_for(p, "vehicle_config", c.vehicle_path);
  const std::string mode = p.str("mode", to_string(c.options.mode));
  if (!parse_allocation_mode(mode, &c.options.mode)) p.fail("mode", "must be pseudo_inverse or redistributed", mode);
  c.options.thruster_weights = p.list("thruster_weights", -1);
  const std::size_t n = c.vehicle.thrusters.size();
  if (!c.options.thruster_weights.empty() && c.options.thruster_weights.size() != n) {
    p.fail("thruster_weights", "must be empty or have one entry per thruster (" + std::to_string(n) + ")",
           std::to_string(c.options.thruster_weights.size()) + " entries");
  }
  for (double w : c.options.thruster_weights) {
    if (!(w > 0.0)) p.fail("thruster_weights", "must all be > 0", std::to_string(w));
  }
  c.options.max_redistribution_iterations = p.integer("max_redistribution_iterations", 8);
  if (c.options.max_redistribution_iterations < 1) {
    p.fail("max_redistribution_iterations", "must be >= 1", std::to_string(c.options.max_redistribution_iterations));
  }
  for (const std::string& name : p.names("failed_thrusters")) {
    int found = -1;
    for (std::size_t i = 0; i < n; ++i) {
      if (c.vehicle.thrusters[i].name == name) found = static_cast<int>(i);
    }
    if (found < 0) p.fail("failed_thrusters", "names a thruster the vehicle does not have", name);
    c.failed_thrusters.push_back(found);
  }
  std::string msg;
  if (!c.options.IsValid(&msg)) throw ConfigError(yaml_path + ": " + msg);
  return c;
}

Allocator make_allocator(const AllocatorConfig& config) {
  Allocator a(config.vehicle.thrusters, config.options);
  for (int i : config.failed_thrusters) a.SetThrusterFailed(i, true);
  return a;
}

MpcConfig load_mpc_config(const std::string& yaml_path, const std::string& config_root) {
  const Params p(yaml_path, "mpc_controller");
  p.only({"model_vehicle_config", "horizon_steps", "dt", "control_blocks", "position_weights", "attitude_weights",
          "linear_velocity_weights", "angular_velocity_weights", "terminal_weight_scale", "force_weights",
          "moment_weights", "force_rate_weights", "moment_rate_weights", "bounds_margin", "actuator_time_constant",
          "disturbance_gain", "disturbance_limit_fraction", "max_iterations", "max_solve_time_ms",
          "function_tolerance", "acceptance_radius"});
  MpcConfig c;
  MpcOptions& o = c.options;
  if (!p.has("model_vehicle_config")) p.fail("model_vehicle_config", "is required", "nothing");
  c.model_vehicle_path = resolve(yaml_path, config_root, p.str("model_vehicle_config", ""));
  c.model = load_vehicle_for(p, "model_vehicle_config", c.model_vehicle_path);
  o.horizon_steps = p.integer("horizon_steps", o.horizon_steps);
  if (o.horizon_steps < 1) p.fail("horizon_steps", "must be >= 1", std::to_string(o.horizon_steps));
  o.dt = p.num("dt", o.dt);
  if (!(o.dt > 0.0)) p.fail("dt", "must be > 0 s", std::to_string(o.dt));
  o.control_blocks = p.integer("control_blocks", o.control_blocks);
  if (o.control_blocks < 1 || o.control_blocks > o.horizon_steps) {
    p.fail("control_blocks", "must be in [1, horizon_steps]", std::to_string(o.control_blocks));
  }
  auto read3 = [&](const std::string& key, auto segment) {
    const std::vector<double> v = p.list(key, 3);
    for (double x : v) {
      if (x < 0.0) p.fail(key, "must be >= 0 (diagonal of a positive semi-definite weight)", std::to_string(x));
    }
    if (!v.empty()) segment = Eigen::Vector3d(v[0], v[1], v[2]);
  };
  read3("position_weights", o.state_weights.segment<3>(0));
  read3("attitude_weights", o.state_weights.segment<3>(3));
  read3("linear_velocity_weights", o.state_weights.segment<3>(6));
  read3("angular_velocity_weights", o.state_weights.segment<3>(9));
  read3("force_weights", o.input_weights.head<3>());
  read3("moment_weights", o.input_weights.tail<3>());
  read3("force_rate_weights", o.input_rate_weights.head<3>());
  read3("moment_rate_weights", o.input_rate_weights.tail<3>());
  o.terminal_weight_scale = p.num("terminal_weight_scale", o.terminal_weight_scale);
  c.bounds_margin = p.num("bounds_margin", c.bounds_margin);
  if (!(c.bounds_margin > 0.0 && c.bounds_margin <= 1.0)) {
    p.fail("bounds_margin", "must be in (0, 1]", std::to_string(c.bounds_margin));
  }
  o.actuator_time_constant = p.num("actuator_time_constant", o.actuator_time_constant);
  o.disturbance_gain = p.num("disturbance_gain", o.disturbance_gain);
  o.disturbance_limit_fraction = p.num("disturbance_limit_fraction", o.disturbance_limit_fraction);
  o.max_iterations = p.integer("max_iterations", o.max_iterations);
  o.max_solve_time_ms = p.num("max_solve_time_ms", o.max_solve_time_ms);
  o.function_tolerance = p.num("function_tolerance", o.function_tolerance);
  c.waypoints.acceptance_radius = p.num("acceptance_radius", c.waypoints.acceptance_radius);
  // Bounds: what the model vehicle's thrusters reach per axis (pseudo-inverse), with a margin.
  o.input_bounds = Allocator(c.model.thrusters).achievable_wrench_box().Scaled(c.bounds_margin);
  std::string msg;
  if (!o.IsValid(&msg)) throw ConfigError(yaml_path + ": " + msg);
  if (!c.waypoints.IsValid(&msg)) throw ConfigError(yaml_path + ": " + msg);
  return c;
}

}  // namespace unav::control
