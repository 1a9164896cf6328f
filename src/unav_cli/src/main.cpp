// unav: the command-line tool, modelled on ros2 (topic, node, launch).
#include <CLI/CLI.hpp>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <numeric>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include "bag_command.hpp"
#include "cli_common.hpp"
#include "foxglove_command.hpp"
#include "graph.hpp"
#include "raw_type.hpp"
#include "security_command.hpp"
#include "unav_introspection/cdr_codec.hpp"
#include "unav_introspection/type_registry.hpp"
#include "unav_launch/launch_description.hpp"
#include "unav_launch/package_index.hpp"
#include "unav_launch/supervisor.hpp"
#include "unav_runtime/shm_cleanup.hpp"

using namespace std::chrono_literals;
namespace intro = unav::introspection;

namespace unav::cli {

// IDL types of the workspace, found from the environment and from this executable's own install
// (<install>/unav_cli/bin/unav), so it works before sourcing setup.bash.
intro::TypeRegistry make_registry() {
  intro::TypeRegistry reg;
  reg.add_workspace(intro::executable_install_root(3));
  return reg;
}

std::string normalize_topic(const std::string& t) { return unav::resolve_topic_name(t, "/", "unav_cli"); }

namespace {

int topic_list(bool show_types) {
  Graph g;
  g.context().spin_until([] { return false; }, default_spin_time());
  for (const auto& [topic, types] : g.topics()) {
    std::cout << topic;
    if (show_types) {
      std::cout << " [";
      bool first = true;
      for (const auto& t : types) {
        std::cout << (first ? "" : ", ") << unav::ros_type_from_dds(t);
        first = false;
      }
      std::cout << "]";
    }
    std::cout << "\n";
  }
  return 0;
}

// Subscribes to `topic` with the publishers' type and QoS; waits (with ros2's warning) until
// one appears.
std::shared_ptr<RawSubscription> subscribe_any(Graph& g, const std::string& topic, std::string& dds_type,
                                               std::function<void(RawSample&)> cb) {
  dds_type = g.wait_for_type(topic, default_spin_time());
  if (dds_type.empty()) {
    std::cerr << "WARNING: topic [" << topic << "] does not appear to be published yet" << std::endl;
    while (dds_type.empty() && g.context().ok()) dds_type = g.wait_for_type(topic, 500ms);
    if (dds_type.empty()) return nullptr;
  }
  auto sub = std::make_shared<RawSubscription>(g.context(), unav::to_dds_topic(topic), dds_type, g.matching_qos(topic),
                                               std::move(cb));
  sub->start(g.matching_qos(topic));
  return sub;
}

int topic_echo(const std::string& topic_in, bool once, const intro::EchoOptions& opts) {
  const std::string topic = normalize_topic(topic_in);
  auto reg = make_registry();
  Graph g;
  std::string dds_type;
  const intro::StructType* type = nullptr;
  bool done = false;
  auto sub = subscribe_any(g, topic, dds_type, [&](const RawSample& s) {
    try {
      std::cout << intro::to_echo_yaml(*type, s.bytes.data(), s.bytes.size(), opts) << "---" << std::endl;
    } catch (const std::exception& e) {
      std::cerr << "cannot decode a sample of " << unav::ros_type_from_dds(dds_type) << ": " << e.what() << std::endl;
    }
    if (once) done = true;
  });
  if (!sub) return 0;
  try {
    type = &reg.load(dds_type);
  } catch (const std::exception& e) {
    throw UsageError("topic '" + topic + "' has type '" + unav::ros_type_from_dds(dds_type) +
                     "', which this installation has no IDL for: " + e.what());
  }
  while (!done && g.context().ok()) g.context().spin_until([&] { return done; }, 1s);
  return 0;
}

int topic_hz(const std::string& topic_in, size_t window) {
  const std::string topic = normalize_topic(topic_in);
  Graph g;
  std::string dds_type;
  std::deque<double> stamps;
  auto sub = subscribe_any(g, topic, dds_type, [&](const RawSample&) {
    stamps.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count());
    if (stamps.size() > window + 1) stamps.pop_front();
  });
  if (!sub) return 0;
  auto timer = std::make_shared<unav::Timer>(
      1s,
      [&] {
        if (stamps.size() < 2) {
          std::cout << "no new messages" << std::endl;
          return;
        }
        std::vector<double> d;
        for (size_t i = 1; i < stamps.size(); ++i) d.push_back(stamps[i] - stamps[i - 1]);
        const double mean = std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(d.size());
        double var = 0;
        for (double x : d) var += (x - mean) * (x - mean);
        const double sd = std::sqrt(var / static_cast<double>(d.size()));
        std::printf("average rate: %.3f\n\tmin: %.3fs max: %.3fs std dev: %.5fs window: %zu\n", 1.0 / mean,
                    *std::min_element(d.begin(), d.end()), *std::max_element(d.begin(), d.end()), sd, stamps.size());
        std::fflush(stdout);
      },
      false);
  g.context().executor().add_timer(timer);
  g.context().spin();
  return 0;
}

std::string human_bytes(double b, const char* suffix) {
  char buf[64];
  if (b >= 1e6)
    std::snprintf(buf, sizeof(buf), "%.2f M%s", b / 1e6, suffix);
  else if (b >= 1e3)
    std::snprintf(buf, sizeof(buf), "%.2f K%s", b / 1e3, suffix);
  else
    std::snprintf(buf, sizeof(buf), "%.0f %s", b, suffix);
  return buf;
}

int topic_bw(const std::string& topic_in, size_t window) {
  const std::string topic = normalize_topic(topic_in);
  Graph g;
  std::string dds_type;
  std::deque<std::pair<double, size_t>> samples;
  auto sub = subscribe_any(g, topic, dds_type, [&](const RawSample& s) {
    samples.emplace_back(std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(),
                         s.bytes.size());
    if (samples.size() > window) samples.pop_front();
  });
  if (!sub) return 0;
  std::cout << "Subscribed to [" << topic << "]" << std::endl;
  auto timer = std::make_shared<unav::Timer>(
      1s,
      [&] {
        if (samples.size() < 2) return;
        const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count() -
                          samples.front().first;
        size_t total = 0, mn = SIZE_MAX, mx = 0;
        for (const auto& s : samples) {
          total += s.second;
          mn = std::min(mn, s.second);
          mx = std::max(mx, s.second);
        }
        std::cout << human_bytes(static_cast<double>(total) / dt, "B/s") << " from " << samples.size() << " messages\n"
                  << "\tMessage size mean: " << human_bytes(static_cast<double>(total) / samples.size(), "B")
                  << " min: " << human_bytes(static_cast<double>(mn), "B")
                  << " max: " << human_bytes(static_cast<double>(mx), "B") << std::endl;
      },
      false);
  g.context().executor().add_timer(timer);
  g.context().spin();
  return 0;
}

int topic_pub(const std::string& topic_in, const std::string& type_name, const std::string& yaml_text, double rate,
              bool once, int times, int wait_matching) {
  const std::string topic = normalize_topic(topic_in);
  auto reg = make_registry();
  const intro::StructType* type = nullptr;
  try {
    type = &reg.load(type_name);
  } catch (const std::exception& e) {
    throw UsageError("unknown message type '" + type_name + "': " + e.what());
  }
  YAML::Node value;
  try {
    value = YAML::Load(yaml_text.empty() ? "{}" : yaml_text);
  } catch (const YAML::Exception& e) {
    throw UsageError("message values '" + yaml_text + "': malformed YAML: " + e.msg);
  }
  RawSample sample;
  try {
    sample.bytes = intro::encode(*type, value);
  } catch (const std::exception& e) {
    throw UsageError("message values for '" + type_name + "': " + e.what());
  }
  if (!(rate > 0.0) || !std::isfinite(rate)) throw UsageError("--rate " + std::to_string(rate) + ": must be > 0");
  Graph g;
  RawPublisher pub(g.context(), unav::to_dds_topic(topic), unav::dds_type_from_ros(type_name), unav::QoS::reliable());
  if (wait_matching > 0) {
    // -w N waits as long as it takes (ros2 topic pub does), saying every 10 s what it waits for.
    const int want = wait_matching;
    while (g.context().ok() &&
           !g.context().spin_until([&] { return pub.subscription_count() >= want; }, std::chrono::seconds(10)))
      std::cerr << "unav topic pub: waiting for " << want << " matching subscription(s) on " << topic << ", "
                << pub.subscription_count() << " so far" << std::endl;
  } else if (once || times > 0) {
    g.context().spin_until([&] { return pub.subscription_count() >= 1; }, default_spin_time());
  }
  std::cout << "publisher: beginning loop" << std::endl;
  YAML::Emitter flow;
  flow << YAML::Flow << intro::decode(*type, sample.bytes.data(), sample.bytes.size());
  int count = 0;
  const int limit = once ? 1 : times;
  while (g.context().ok()) {
    pub.publish(sample);
    std::cout << "publishing #" << ++count << ": " << unav::ros_type_from_dds(unav::dds_type_from_ros(type_name)) << "("
              << flow.c_str() << ")\n"
              << std::endl;
    if (limit > 0 && count >= limit) break;
    g.context().spin_until([] { return false; }, std::chrono::nanoseconds(static_cast<int64_t>(1e9 / rate)));
  }
  // Reliable delivery before exit, as `ros2 topic pub --once` keeps the publisher alive briefly.
  // On a loaded machine the reader may take seconds to match this writer and ask for the sample
  // (a soak lost 8 of 59 one-shot resets with a 2 s wait): wait up to 10 s, and say so if not all
  // readers acknowledged it.
  eprosima::fastrtps::Duration_t wait(10, 0);
  if (pub.writer()->wait_for_acknowledgments(wait) != eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK)
    std::cerr << "unav topic pub: not every reader of " << topic << " acknowledged the last message within 10 s"
              << std::endl;
  return 0;
}

int node_list() {
  Graph g;
  for (const auto& n : g.nodes()) std::cout << n << "\n";
  return 0;
}

int launch(const std::string& file, const std::vector<std::string>& args) {
  unav::launch::LaunchDescription desc;
  try {
    desc = unav::launch::load_launch_file(file, unav::launch::parse_launch_arguments(args));
  } catch (const std::exception& e) {
    throw UsageError(e.what());
  }
  return unav::launch::run(desc);
}

}  // namespace
}  // namespace unav::cli

// `unav localize ...` and `unav eval ...` run a capability package's tool with the same
// arguments (as `ros2 <verb>` extensions do), so the framework links no capability.
int run_package_tool(const char* package, const char* executable, int argc, char** argv) {
  std::vector<std::string> searched;
  const auto exe = unav::launch::find_executable(package, executable, &searched);
  if (!exe) {
    std::string dirs;
    for (const auto& d : searched) dirs += " " + d;
    std::cerr << "unav: error: " << executable << " not found (package " << package << "; searched:" << dirs << ")"
              << std::endl;
    return 2;
  }
  std::vector<char*> args{const_cast<char*>(exe->c_str())};
  for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  ::execv(exe->c_str(), args.data());
  std::cerr << "unav: error: cannot run " << *exe << std::endl;
  return 1;
}

// `unav doctor [--clean]`: Fast DDS data-sharing pools in /dev/shm, live and dead (their writer
// died without closing: unav_runtime/shm_cleanup.hpp). Exit 1 when dead ones remain.
int shm_doctor(bool clean) {
  const unav::shm::CleanReport r = unav::shm::clean_data_sharing("/dev/shm", !clean);
  std::uint64_t live_bytes = 0, dead_bytes = 0;
  int dead = 0;
  for (const auto& s : r.segments) {
    if (s.dead) {
      ++dead;
      dead_bytes += s.bytes;
    } else {
      live_bytes += s.bytes;
    }
  }
  const std::string tail = clean ? ", removed " + std::to_string(r.removed)
                                 : (dead > 0 ? std::string("; unav doctor --clean removes them") : std::string());
  std::printf("/dev/shm: %zu data-sharing segments: %zu of live processes (%.1f MB), %d of dead ones (%.1f MB)%s\n",
              r.segments.size(), r.segments.size() - static_cast<std::size_t>(dead),
              static_cast<double>(live_bytes) / 1e6, dead, static_cast<double>(dead_bytes) / 1e6, tail.c_str());
  for (const auto& e : r.errors) std::printf("  not removed: %s\n", e.c_str());
  return (clean ? dead - r.removed : dead) > 0 ? 1 : 0;
}

int main(int argc, char** argv) {
  using namespace unav::cli;
  if (argc >= 2 && std::string(argv[1]) == "localize")
    return run_package_tool("unav_localization", "unav_localize", argc, argv);
  if (argc >= 2 && std::string(argv[1]) == "eval") return run_package_tool("unav_evaluation", "unav_eval", argc, argv);
  if (argc >= 2 && std::string(argv[1]) == "datagen") return run_package_tool("unav_sim", "unav_datagen", argc, argv);
  if (argc >= 2 && std::string(argv[1]) == "run") return run_package_tool("unav_sim", "unav_run", argc, argv);
  CLI::App app{"unav: command-line tool of UNav-Sim (like ros2)", "unav"};
  app.require_subcommand(1);

  auto* topic = app.add_subcommand("topic", "inspect and publish topics");
  topic->require_subcommand(1);
  bool show_types = false;
  auto* list = topic->add_subcommand("list", "list topics seen through DDS discovery");
  list->add_flag("-t,--show-types", show_types, "show the ROS 2 type of each topic");

  std::string topic_name, type_name, values;
  bool once = false;
  intro::EchoOptions echo_opts;
  bool full_length = false;
  auto* echo = topic->add_subcommand("echo", "print messages of a topic as YAML");
  echo->add_option("topic", topic_name, "topic name, e.g. /rov/imu")->required();
  echo->add_flag("--once", once, "print one message and exit");
  echo->add_flag("--no-arr", echo_opts.no_arr, "do not print arrays and sequences");
  echo->add_flag("--no-str", echo_opts.no_str, "do not print strings");
  echo->add_flag("-f,--full-length", full_length, "do not truncate long arrays and strings");
  echo->add_option("-l,--truncate-length", echo_opts.truncate_length, "truncate arrays/strings longer than this");

  size_t window = 10000;
  auto* hz = topic->add_subcommand("hz", "print the average publishing rate");
  hz->add_option("topic", topic_name)->required();
  hz->add_option("-w,--window", window, "number of messages in the window");
  auto* bw = topic->add_subcommand("bw", "print the bandwidth used by a topic");
  bw->add_option("topic", topic_name)->required();
  size_t bw_window = 100;
  bw->add_option("-w,--window", bw_window, "number of messages in the window");

  double rate = 1.0;
  int times = 0, wait_matching = 0;
  auto* pub = topic->add_subcommand("pub", "publish a message (values as YAML)");
  pub->add_option("topic", topic_name)->required();
  pub->add_option("type", type_name, "e.g. geometry_msgs/msg/Twist")->required();
  pub->add_option("values", values, "YAML, e.g. '{linear: {x: 1.0}}'");
  pub->add_option("-r,--rate", rate, "publishing rate [Hz] (default 1)");
  pub->add_flag("-1,--once", once, "publish one message and exit");
  pub->add_option("-t,--times", times, "publish this many messages and exit");
  pub->add_option("-w,--wait-matching-subscriptions", wait_matching, "wait for this many subscriptions first");

  auto* node = app.add_subcommand("node", "inspect nodes");
  node->require_subcommand(1);
  auto* node_list_cmd = node->add_subcommand("list", "list nodes (from ros_discovery_info)");

  std::string launch_file;
  std::vector<std::string> launch_args;
  auto* launch_cmd = app.add_subcommand("launch", "start the nodes of a *.launch.yaml file, one process each");
  launch_cmd->add_option("file", launch_file, "launch file")->required();
  launch_cmd->add_option("args", launch_args, "launch arguments name:=value");

  app.add_subcommand("localize", "run a visual localization estimator on an image folder (unav localize --help)");

  app.add_subcommand("eval", "trajectory metrics on TUM files, as evo computes them (unav eval --help)");

  app.add_subcommand("datagen", "randomized synthetic datasets, locally or on Slurm (unav datagen --help)");

  app.add_subcommand("run", "one scenario file over DDS or --in-process: ground truth and images (unav run --help)");

  bool doctor_clean = false;
  auto* doctor = app.add_subcommand(
      "doctor", "report (and with --clean remove) data-sharing segments left in /dev/shm by processes that died");
  doctor->add_flag("--clean", doctor_clean, "remove the dead ones (every participant also does at start)");

  const auto run_bag = add_bag_command(app);
  const auto run_foxglove = add_foxglove_command(app);
  const auto run_security = add_security_command(app);

  CLI11_PARSE(app, argc, argv);
  if (full_length) echo_opts.truncate_length = intro::EchoOptions::kFullLength;
  try {
    if (list->parsed()) return topic_list(show_types);
    if (echo->parsed()) return topic_echo(topic_name, once, echo_opts);
    if (hz->parsed()) return topic_hz(topic_name, window);
    if (bw->parsed()) return topic_bw(topic_name, bw_window);
    if (pub->parsed()) return topic_pub(topic_name, type_name, values, rate, once, times, wait_matching);
    if (node_list_cmd->parsed()) return node_list();
    if (launch_cmd->parsed()) return launch(launch_file, launch_args);
    if (app.got_subcommand("bag")) return run_bag();
    if (app.got_subcommand("foxglove")) return run_foxglove();
    if (app.got_subcommand("security")) return run_security();
    if (doctor->parsed()) return shm_doctor(doctor_clean);
  } catch (const UsageError& e) {
    std::cerr << "unav: error: " << e.what() << std::endl;
    return 2;
  } catch (const unav::ConfigError& e) {
    std::cerr << "unav: error: " << e.what() << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "unav: fatal: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
