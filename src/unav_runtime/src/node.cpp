#include "unav_runtime/node.hpp"

#include <cstring>
#include <iostream>
#include <sstream>

#include "unav_common/crash_report.hpp"
#include "unav_runtime/names.hpp"

namespace unav {
namespace {

// Parameters every node has (rclcpp declares use_sim_time on every node too).
struct NodeCommonParams {
  bool use_sim_time = false;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(common::Field("use_sim_time", &use_sim_time).Doc("follow /clock instead of the system clock"));
  }
};

Context& require_context(const NodeOptions& o) {
  if (!o.context) throw ConfigError("NodeOptions.context is null: create a unav::Context first");
  return *o.context;
}

// Flattens nested maps into dotted names (as params files are flattened).
void flatten(const YAML::Node& n, const std::string& prefix, std::map<std::string, YAML::Node>* out) {
  if (n.IsMap()) {
    for (const auto& kv : n)
      flatten(kv.second, prefix.empty() ? kv.first.as<std::string>() : prefix + "." + kv.first.as<std::string>(), out);
  } else {
    (*out)[prefix] = n;
  }
}

bool wants_help(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--ros-args") == 0) return false;
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) return true;
  }
  return false;
}

}  // namespace

void Node::record_params(const std::vector<common::FieldInfo>& fields, const YAML::Node& effective) {
  for (const auto& f : fields) {
    if (f.type == "mapping" || f.type == "mapping[]") continue;
    if (values_.count(f.name)) throw ParameterError("node '" + name_ + "': parameter '" + f.name + "' declared twice");
    table_.push_back(f);
  }
  std::map<std::string, YAML::Node> flat;
  flatten(effective, "", &flat);
  for (auto& [k, v] : flat) values_[k] = v;
}

Node::Node(const std::string& default_name, const NodeOptions& options, const std::string& default_namespace)
    : ctx_(require_context(options)) {
  const RosArgs& args = ctx_.args();
  name_ = args.node_name.empty() ? default_name : args.node_name;
  validate_node_name(name_);
  namespace_ = normalize_namespace(args.node_namespace.empty() ? default_namespace : args.node_namespace);
  logger_ = make_logger(fully_qualified_name());
  overrides_ = ParameterOverrides(args, namespace_, name_);
  NodeCommonParams common;
  declare_params(&common);
  if (common.use_sim_time) ctx_.enable_sim_time();
  ctx_.add_node(this);
}

Node::~Node() {
  ctx_.remove_node(this);
  subscriptions_.clear();
  publishers_.clear();
}

std::string Node::fully_qualified_name() const { return (namespace_ == "/" ? "" : namespace_) + "/" + name_; }

std::string Node::resolve_topic(const std::string& name) const {
  return apply_remaps(resolve_topic_name(name, namespace_, name_), ctx_.args().remaps, namespace_, name_);
}

std::shared_ptr<Timer> Node::create_wall_timer(std::chrono::nanoseconds period, std::function<void()> callback) {
  if (period.count() <= 0) throw ConfigError("node '" + name_ + "': timer period must be > 0");
  auto t = std::make_shared<Timer>(period, std::move(callback), false);
  ctx_.executor().add_timer(t);
  return t;
}

std::shared_ptr<Timer> Node::create_timer(std::chrono::nanoseconds period, std::function<void()> callback) {
  if (period.count() <= 0) throw ConfigError("node '" + name_ + "': timer period must be > 0");
  auto t = std::make_shared<Timer>(period, std::move(callback), true);
  ctx_.executor().add_timer(t);
  return t;
}

void Node::check_undeclared_parameters() const {
  const auto unused = overrides_.unused();
  if (unused.empty()) return;
  std::string declared;
  for (const auto& kv : values_) declared += (declared.empty() ? "" : ", ") + kv.first;
  const auto* o = overrides_.find(unused.front());
  throw ParameterError(o->source + ": node '" + name_ + "' has no parameter '" + unused.front() +
                       "' (declared: " + declared + ")");
}

std::vector<const PublisherBase*> Node::publishers() const {
  std::vector<const PublisherBase*> out;
  for (const auto& p : publishers_) out.push_back(p.get());
  return out;
}

std::vector<const SubscriptionBase*> Node::subscriptions() const {
  std::vector<const SubscriptionBase*> out;
  for (const auto& s : subscriptions_) out.push_back(s.get());
  return out;
}

int run_node_impl(int argc, char** argv, const std::function<std::unique_ptr<Node>(const NodeOptions&)>& make) {
  std::string exe = argc > 0 ? argv[0] : "node";
  exe = exe.substr(exe.find_last_of('/') + 1);
  common::InstallCrashReport(exe.c_str());
  if (wants_help(argc, argv)) {
    // Construct the node on a private, local-only domain (nothing reaches a running system)
    // and print every parameter it declares: name, type, default, range, unit, description.
    try {
      ContextOptions o;
      o.domain_id = 232;
      o.handle_signals = false;
      Context ctx(o);
      std::unique_ptr<Node> node = make(NodeOptions{&ctx});
      std::cout << "usage: " << exe << " [--ros-args [--params-file FILE] [-p NAME:=VALUE] [-r FROM:=TO] ...]\n\n"
                << "parameters of node '" << node->name() << "':\n"
                << common::FormatHelp(node->parameter_table());
      return 0;
    } catch (const std::exception& e) {
      std::cerr << exe << ": --help: the node could not be constructed with its defaults: " << e.what() << std::endl;
      return 2;
    }
  }
  try {
    Context ctx(argc, argv);
    std::unique_ptr<Node> node;
    try {
      node = make(NodeOptions{&ctx});
      node->check_undeclared_parameters();
    } catch (const ConfigError& e) {
      std::cerr << exe << ": error: " << e.what() << std::endl;
      return 2;
    }
    ctx.spin();
    node->logger()->debug("shutting down");
    node.reset();  // destructors flush outputs before the participant goes away
    return 0;
  } catch (const ConfigError& e) {
    std::cerr << exe << ": error: " << e.what() << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << exe << ": fatal: " << e.what() << std::endl;
    return 1;
  }
}

}  // namespace unav
