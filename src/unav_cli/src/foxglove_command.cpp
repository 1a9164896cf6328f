#include "foxglove_command.hpp"

#include <atomic>
#include <chrono>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "foxglove_server.hpp"
#include "graph.hpp"
#include "raw_type.hpp"
#include "unav_bag/msg_definition.hpp"

using namespace std::chrono_literals;

namespace unav::cli {
namespace {

struct FoxgloveOptions {
  std::string address = "127.0.0.1";
  int port = 8765;
  std::vector<std::string> topics;  // empty: every topic with a publisher
};

int run(const FoxgloveOptions& o) {
  if (o.port < 0 || o.port > 65535) throw UsageError("--port " + std::to_string(o.port) + ": must be in [0, 65535]");
  std::set<std::string> only;
  for (const auto& t : o.topics) only.insert(normalize_topic(t));
  auto reg = make_registry();
  Graph g;
  struct Topic {
    std::string name, dds_type;
    std::shared_ptr<RawSubscription> sub;
  };
  std::map<std::uint32_t, Topic> channels;  // touched on this thread only
  std::map<std::string, std::uint32_t> channel_of_topic;
  std::mutex wanted_mutex;  // the server's thread says which channels clients want
  std::map<std::uint32_t, bool> wanted;
  FoxgloveServer::Options so;
  so.address = o.address;
  so.port = static_cast<std::uint16_t>(o.port);
  std::unique_ptr<FoxgloveServer> server;
  try {
    server = std::make_unique<FoxgloveServer>(so, [&](std::uint32_t channel, bool want) {
      const std::lock_guard<std::mutex> lock(wanted_mutex);
      wanted[channel] = want;
    });
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }
  // Every 100 ms: advertise topics whose publisher appeared, and hold a DDS subscription exactly
  // for the channels some client subscribed to.
  auto tick = [&] {
    for (const auto& [topic, types] : g.topics()) {
      if (channel_of_topic.count(topic) || types.empty() || (!only.empty() && !only.count(topic))) continue;
      const std::string dds_type = g.writer_type(topic);  // a reader alone does not make a channel
      if (dds_type.empty()) continue;
      FoxgloveServer::Channel c;
      c.topic = topic;
      c.schema_name = unav::ros_type_from_dds(dds_type);
      try {
        c.schema = unav::bag::ros2msg_definition(reg, dds_type);
      } catch (const std::exception& e) {
        std::cerr << "[WARN] [unav_foxglove]: no IDL for " << c.schema_name << " (" << e.what() << "): '" << topic
                  << "' not advertised" << std::endl;
        channel_of_topic[topic] = 0;
        continue;
      }
      const std::uint32_t id = server->add_channel(c);
      channel_of_topic[topic] = id;
      channels[id] = Topic{topic, dds_type, nullptr};
    }
    std::map<std::uint32_t, bool> now;
    {
      const std::lock_guard<std::mutex> lock(wanted_mutex);
      now = wanted;
    }
    for (auto& [id, t] : channels) {
      const bool want = now.count(id) && now.at(id);
      if (want && !t.sub) {
        const unav::QoS qos = g.matching_qos(t.name);
        const std::uint32_t channel = id;
        t.sub = std::make_shared<RawSubscription>(
            g.context(), unav::to_dds_topic(t.name), t.dds_type, qos, [&server, channel](RawSample& s) {
              server->publish(channel, static_cast<std::uint64_t>(wall_ns()), s.bytes.data(), s.bytes.size());
            });
        t.sub->start(qos);
        std::cout << "[INFO] [unav_foxglove]: forwarding '" << t.name << "'" << std::endl;
      } else if (!want && t.sub) {
        t.sub.reset();
        std::cout << "[INFO] [unav_foxglove]: '" << t.name << "' unsubscribed" << std::endl;
      }
    }
  };
  auto timer = std::make_shared<unav::Timer>(100ms, tick, false);
  g.context().executor().add_timer(timer);
  std::cout << "[INFO] [unav_foxglove]: Foxglove WebSocket server on ws://" << o.address << ":" << server->port()
            << " (open it in Foxglove: Open connection > Foxglove WebSocket)" << std::endl;
  while (g.context().ok()) g.context().spin_until([] { return false; }, 200ms);
  timer->cancel();
  for (auto& [id, t] : channels) t.sub.reset();
  std::cout << "[INFO] [unav_foxglove]: " << channels.size() << " topics advertised, " << server->sent()
            << " messages sent, " << server->dropped() << " dropped (a client's queue was full)" << std::endl;
  server.reset();
  return 0;
}

}  // namespace

std::function<int()> add_foxglove_command(CLI::App& app) {
  auto o = std::make_shared<FoxgloveOptions>();
  auto* cmd = app.add_subcommand(
      "foxglove",
      "live view in Foxglove: a Foxglove WebSocket server forwarding the ROS 2 topics (like foxglove_bridge)");
  cmd->add_option("topics", o->topics, "topics to offer (default: every topic with a publisher)");
  cmd->add_option("--address", o->address, "address to listen on (0.0.0.0: every interface)");
  cmd->add_option("-p,--port", o->port, "port (default 8765, as foxglove_bridge; 0: any free port)");
  return [o] { return run(*o); };
}

}  // namespace unav::cli
