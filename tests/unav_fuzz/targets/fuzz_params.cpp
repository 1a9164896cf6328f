// The params-file loader (`--ros-args --params-file F`, ROS 2 layout `node: {ros__parameters:
// {...}}`, `/**` wildcards, nested maps) on arbitrary YAML, then the overrides applied to a config
// schema as Node::declare_params() applies them: must give a ConfigError (ParameterError) naming
// the file, or apply values that the schema's rules accept.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fuzz_common.hpp"
#include "unav_common/config.hpp"
#include "unav_runtime/parameters.hpp"
#include "unav_runtime/ros_args.hpp"

namespace {

struct Gains {
  double kp = 1.0;
  std::vector<double> limits{1.0, 2.0};
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(unav::common::Field("kp", &kp).Min(0.0).Doc("gain"));
    a->Visit(unav::common::Field("limits", &limits).Range(-10.0, 10.0).Doc("limits"));
  }
};

// One field of each kind a node declares (types and rules of config.hpp).
struct Params {
  bool use_sim_time = false;
  int horizon_steps = 20;
  double dt = 0.05;
  std::string frame = "base_link_frd";
  std::string mode = "lockstep";
  std::vector<int> ids{1, 2};
  std::vector<std::string> names{"a"};
  Eigen::Vector3d weights{1, 2, 3};
  Gains gains;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(unav::common::Field("use_sim_time", &use_sim_time).Doc("sim time"));
    a->Visit(unav::common::Field("horizon_steps", &horizon_steps).Range(1, 500).Doc("steps"));
    a->Visit(unav::common::Field("dt", &dt).Above(0.0).Unit("s").Doc("step"));
    a->Visit(unav::common::Field("frame", &frame).Doc("frame"));
    a->Visit(unav::common::Field("mode", &mode).OneOf({"lockstep", "realtime"}).Doc("mode"));
    a->Visit(unav::common::Field("ids", &ids).Range(0, 100).Doc("ids"));
    a->Visit(unav::common::Field("names", &names).Doc("names"));
    a->Visit(unav::common::Field("weights", &weights).Min(0.0).Doc("weights"));
    a->Visit(unav::common::Field("gains", &gains).Doc("gains"));
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = unav::fuzz::write_input(data, size, ".params.yaml");
  unav::RosArgs args;
  args.params_files.push_back(path);
  try {
    unav::ParameterOverrides overrides(args, "/rov", "mpc_controller");
    Params p;
    for (const auto& f : unav::common::Describe(p)) {
      if (f.type == "mapping" || f.type == "mapping[]") continue;
      if (const unav::ParameterOverride* o = overrides.find(f.name)) {
        const std::string text = o->value.IsNull() && f.type == "string" ? "\"\"" : YAML::Dump(o->value);
        unav::common::ApplyOverride(&p, f.name, text, o->source);
      }
    }
    // What the schema let through obeys its rules.
    if (!(p.dt > 0.0) || !std::isfinite(p.dt) || p.horizon_steps < 1 || p.horizon_steps > 500 || !(p.gains.kp >= 0.0) ||
        (p.mode != "lockstep" && p.mode != "realtime"))
      __builtin_trap();
    (void)unav::common::ToYaml(p);
  } catch (const unav::ConfigError&) {  // ParameterError and the schema's errors
  }
  return 0;
}
