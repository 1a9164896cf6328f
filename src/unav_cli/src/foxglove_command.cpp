#include "foxglove_command.hpp"

#include <algorithm>
#include <chrono>
#include <deque>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <fastdds/rtps/common/SerializedPayload.h>

#include "cli_common.hpp"
#include "foxglove_server.hpp"
#include "graph.hpp"
#include "image_compression.hpp"
#include "raw_type.hpp"
#include "rosgraph_msgs/msg/clock.hpp"
#include "sensor_msgs/msg/compressed_image.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "unav_bag/msg_definition.hpp"

using namespace std::chrono_literals;

namespace unav::cli {
namespace {

constexpr const char* kImageType = "sensor_msgs::msg::dds_::Image_";
constexpr const char* kCompressedImageType = "sensor_msgs/msg/CompressedImage";
constexpr std::size_t kMaxPendingClientMessages = 256;  // per client channel, until its writer exists

struct FoxgloveOptions {
  std::string address = "127.0.0.1";
  int port = 8765;
  std::vector<std::string> topics;  // empty: every topic with a publisher
  bool no_publish = false;
  bool allow_secured = false;
  int jpeg_quality = 90;
};

// A channel we offer: a DDS topic as it is, or the compressed twin of an image topic.
struct Offered {
  std::string topic;     // the DDS topic read (the image topic for a compressed twin)
  std::string dds_type;  // its type
  bool compressed = false;
  std::shared_ptr<unav::SubscriptionBase> sub;  // while some client wants the channel
};

// A channel a client advertised: a DDS writer made on the DDS thread, samples queued until then.
struct ClientWriter {
  std::string topic, dds_type;
  std::shared_ptr<RawPublisher> writer;
  std::deque<RawSample> pending;
  bool closed = false;
};

template <typename Msg>
void publish_typed(FoxgloveServer& server, std::uint32_t channel, std::uint64_t receive_ns, Msg& msg) {
  unav::TypeSupportOf<Msg> type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&msg)());
  if (type.serialize(&msg, &payload)) server.publish(channel, receive_ns, payload.data, payload.length);
}

template <typename Msg>
bool decode_typed(const std::vector<std::uint8_t>& cdr, Msg& msg) {
  unav::TypeSupportOf<Msg> type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(cdr.size()));
  std::copy(cdr.begin(), cdr.end(), payload.data);
  payload.length = static_cast<std::uint32_t>(cdr.size());
  try {
    return type.deserialize(&payload, &msg);
  } catch (const std::exception&) {  // Fast CDR throws on truncated data
    return false;
  }
}

int run(const FoxgloveOptions& o) {
  if (o.port < 0 || o.port > 65535) throw UsageError("--port " + std::to_string(o.port) + ": must be in [0, 65535]");
  if (o.jpeg_quality < 1 || o.jpeg_quality > 100)
    throw UsageError("--jpeg-quality " + std::to_string(o.jpeg_quality) + ": must be in [1, 100]");
  std::set<std::string> only;
  for (const auto& t : o.topics) only.insert(normalize_topic(t));
  auto reg = make_registry();
  std::mutex reg_mutex;  // the registry is used on the DDS thread and by the server's advertise handler
  Graph g;
  if (!g.context().secured_enclave().empty()) {
    if (!o.allow_secured)
      throw UsageError("this participant is secured (enclave '" + g.context().secured_enclave() +
                       "'): the topics it can read are protected by DDS Security and would leave it unencrypted "
                       "over the WebSocket; pass --allow-secured to bridge them anyway");
    std::cerr << "[WARN] [unav_foxglove]: --allow-secured: secured topics are forwarded in clear over the WebSocket"
              << std::endl;
  }
  std::map<std::uint32_t, Offered> channels;  // touched on this thread only
  std::map<std::string, std::uint32_t> channel_of_topic;
  std::mutex wanted_mutex;  // the server's thread says which channels clients want
  std::map<std::uint32_t, bool> wanted;
  std::mutex writers_mutex;  // client channels: the server's thread adds and feeds, this thread makes writers
  std::map<std::pair<std::uint64_t, std::uint32_t>, ClientWriter> writers;

  FoxgloveServer::Options so;
  so.address = o.address;
  so.port = static_cast<std::uint16_t>(o.port);
  so.client_publish = !o.no_publish;
  so.time = true;
  FoxgloveServer::Handlers handlers;
  handlers.on_interest = [&](std::uint32_t channel, bool want) {
    const std::lock_guard<std::mutex> lock(wanted_mutex);
    wanted[channel] = want;
  };
  handlers.on_client_advertise = [&](const FoxgloveServer::ClientChannel& c) -> std::string {
    // Foxglove names ROS 2 types either way (geometry_msgs/msg/Twist, geometry_msgs/Twist): the
    // DDS name is the same for both.
    const std::string dds_type = unav::dds_type_from_ros(c.schema_name);
    try {
      const std::lock_guard<std::mutex> lock(reg_mutex);
      reg.load(dds_type);
    } catch (const std::exception& e) {
      return std::string("no IDL for this type here: ") + e.what();
    }
    ClientWriter w;
    w.topic = normalize_topic(c.topic);
    w.dds_type = dds_type;
    const std::lock_guard<std::mutex> lock(writers_mutex);
    writers[{c.client, c.id}] = std::move(w);
    std::cout << "[INFO] [unav_foxglove]: a client publishes '" << c.topic << "' [" << c.schema_name << "]"
              << std::endl;
    return "";
  };
  handlers.on_client_message = [&](const FoxgloveServer::ClientChannel& c, const std::uint8_t* cdr, std::size_t n) {
    RawSample s;
    s.bytes.assign(cdr, cdr + n);
    std::shared_ptr<RawPublisher> writer;
    {
      const std::lock_guard<std::mutex> lock(writers_mutex);
      const auto it = writers.find({c.client, c.id});
      if (it == writers.end()) return;
      if (!it->second.writer) {
        if (it->second.pending.size() < kMaxPendingClientMessages) it->second.pending.push_back(std::move(s));
        return;
      }
      writer = it->second.writer;
    }
    writer->publish(s);  // DataWriter::write is thread-safe
  };
  handlers.on_client_unadvertise = [&](const FoxgloveServer::ClientChannel& c) {
    const std::lock_guard<std::mutex> lock(writers_mutex);
    const auto it = writers.find({c.client, c.id});
    if (it != writers.end()) it->second.closed = true;  // the writer is deleted on the DDS thread
  };
  std::unique_ptr<FoxgloveServer> server;
  try {
    server = std::make_unique<FoxgloveServer>(so, handlers);
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }

  auto advertise = [&](const std::string& name, const std::string& topic, const std::string& dds_type,
                       const std::string& schema_type, bool compressed) {
    FoxgloveServer::Channel c;
    c.topic = name;
    c.schema_name = unav::ros_type_from_dds(unav::dds_type_from_ros(schema_type));
    try {
      const std::lock_guard<std::mutex> lock(reg_mutex);
      c.schema = unav::bag::ros2msg_definition(reg, schema_type);
    } catch (const std::exception& e) {
      std::cerr << "[WARN] [unav_foxglove]: no IDL for " << c.schema_name << " (" << e.what() << "): '" << name
                << "' not advertised" << std::endl;
      channel_of_topic[name] = 0;
      return;
    }
    const std::uint32_t id = server->add_channel(c);
    channel_of_topic[name] = id;
    channels[id] = Offered{topic, dds_type, compressed, nullptr};
  };
  auto subscribe = [&](std::uint32_t id, Offered& t) {
    const unav::QoS qos = g.matching_qos(t.topic);
    FoxgloveServer& s = *server;
    if (!t.compressed) {
      auto sub = std::make_shared<RawSubscription>(
          g.context(), unav::to_dds_topic(t.topic), t.dds_type, qos, [&s, id](RawSample& m) {
            s.publish(id, static_cast<std::uint64_t>(wall_ns()), m.bytes.data(), m.bytes.size());
          });
      sub->start(qos);
      t.sub = sub;
      return;
    }
    // The same raw reader as above (one type per DDS topic in this participant, whichever
    // channels are wanted), each sample decoded into a sensor_msgs/Image to compress it.
    const int quality = o.jpeg_quality;
    const std::string topic = t.topic;
    auto sub = std::make_shared<RawSubscription>(
        g.context(), unav::to_dds_topic(t.topic), t.dds_type, qos,
        [&s, id, quality, topic, warned = false](RawSample& raw) mutable {
          const auto received = static_cast<std::uint64_t>(wall_ns());
          sensor_msgs::msg::Image m;
          sensor_msgs::msg::CompressedImage out;
          try {
            if (!decode_typed(raw.bytes, m)) throw std::invalid_argument("a sample that does not decode as an Image");
            CompressedImageData c = compress_image(ImageView{m.encoding(), m.width(), m.height(), m.step(),
                                                             m.is_bigendian() != 0, m.data().data(), m.data().size()},
                                                   quality);
            out.format(std::move(c.format));
            out.data(std::move(c.data));
          } catch (const std::invalid_argument& e) {
            // E.g. a 32FC1 depth image: its /compressed channel is withdrawn (the raw one stays).
            if (!warned)
              std::cerr << "[WARN] [unav_foxglove]: '" << topic << "': " << e.what() << "; '" << topic
                        << "/compressed' withdrawn" << std::endl;
            if (!warned) s.remove_channel(id);
            warned = true;
            return;
          }
          out.header(m.header());
          publish_typed(s, id, received, out);
        });
    sub->start(qos);
    t.sub = sub;
  };
  std::shared_ptr<RawSubscription> clock;  // the sim clock, for the time capability

  // Every 100 ms: advertise topics whose publisher appeared (and the compressed twin of each
  // image topic), hold a DDS subscription exactly for the channels some client subscribed to,
  // and make or delete the DDS writers of the clients' channels.
  auto tick = [&] {
    const auto topics = g.topics();
    for (const auto& [topic, types] : topics) {
      if (channel_of_topic.count(topic) || types.empty() || (!only.empty() && !only.count(topic))) continue;
      const std::string dds_type = g.writer_type(topic);  // a reader alone does not make a channel
      if (dds_type.empty()) continue;
      advertise(topic, topic, dds_type, dds_type, false);
      const std::string twin = topic + "/compressed";  // image_transport's name
      if (dds_type == kImageType && !channel_of_topic.count(twin) && !topics.count(twin))
        advertise(twin, topic, dds_type, kCompressedImageType, true);
    }
    const std::string clock_type = g.writer_type("/clock");
    if (!clock && !clock_type.empty()) {
      FoxgloveServer& s = *server;
      const unav::QoS qos = g.matching_qos("/clock");
      clock = std::make_shared<RawSubscription>(
          g.context(), unav::to_dds_topic("/clock"), clock_type, qos, [&s](RawSample& raw) {
            rosgraph_msgs::msg::Clock c;
            if (!decode_typed(raw.bytes, c)) return;
            s.publish_time(static_cast<std::uint64_t>(c.clock().sec()) * 1000000000ull + c.clock().nanosec());
          });
      clock->start(qos);
    }
    std::map<std::uint32_t, bool> now;
    {
      const std::lock_guard<std::mutex> lock(wanted_mutex);
      now = wanted;
    }
    for (auto& [id, t] : channels) {
      const bool want = now.count(id) && now.at(id);
      if (want && !t.sub) {
        try {
          subscribe(id, t);
        } catch (const unav::ConfigError& e) {  // e.g. rmw_dds_common's types: the graph's own
          std::cerr << "[WARN] [unav_foxglove]: '" << t.topic << "' withdrawn: " << e.what() << std::endl;
          server->remove_channel(id);
          continue;
        }
        std::cout << "[INFO] [unav_foxglove]: forwarding '" << t.topic << "'" << (t.compressed ? " compressed" : "")
                  << std::endl;
      } else if (!want && t.sub) {
        t.sub.reset();
        std::cout << "[INFO] [unav_foxglove]: '" << t.topic << "'" << (t.compressed ? " compressed" : "")
                  << " unsubscribed" << std::endl;
      }
    }
    std::vector<std::shared_ptr<RawPublisher>> to_delete;  // deleted outside the lock
    const std::lock_guard<std::mutex> lock(writers_mutex);
    for (auto it = writers.begin(); it != writers.end();) {
      ClientWriter& w = it->second;
      if (w.closed) {
        to_delete.push_back(std::move(w.writer));
        it = writers.erase(it);
        continue;
      }
      if (!w.writer) {
        try {
          w.writer = std::make_shared<RawPublisher>(g.context(), unav::to_dds_topic(w.topic), w.dds_type,
                                                    unav::QoS::reliable());
        } catch (const unav::ConfigError& e) {
          std::cerr << "[WARN] [unav_foxglove]: a client's '" << w.topic << "' not published: " << e.what()
                    << std::endl;
          it = writers.erase(it);
          continue;
        }
        for (const auto& s : w.pending) w.writer->publish(s);
        w.pending.clear();
      }
      ++it;
    }
  };
  auto timer = std::make_shared<unav::Timer>(100ms, tick, false);
  g.context().executor().add_timer(timer);
  std::cout << "[INFO] [unav_foxglove]: Foxglove WebSocket server on ws://" << o.address << ":" << server->port()
            << " (open it in Foxglove: Open connection > Foxglove WebSocket)" << std::endl;
  while (g.context().ok()) g.context().spin_until([] { return false; }, 200ms);
  timer->cancel();
  for (auto& [id, t] : channels) t.sub.reset();
  clock.reset();
  std::cout << "[INFO] [unav_foxglove]: " << channels.size() << " channels advertised, " << server->sent()
            << " messages sent, " << server->dropped() << " dropped (a client's queue was full), " << server->received()
            << " received from clients" << std::endl;
  server.reset();  // its thread stops: no handler runs after this
  const std::lock_guard<std::mutex> lock(writers_mutex);
  writers.clear();
  return 0;
}

}  // namespace

std::function<int()> add_foxglove_command(CLI::App& app) {
  auto o = std::make_shared<FoxgloveOptions>();
  auto* cmd = app.add_subcommand(
      "foxglove",
      "live view in Foxglove: a Foxglove WebSocket server forwarding the ROS 2 topics (like foxglove_bridge)");
  cmd->add_flag("--no-publish", o->no_publish, "do not let clients publish (teleop, Publish panel, 3-D goal poses)");
  cmd->add_flag("--allow-secured", o->allow_secured,
                "bridge even when this participant is secured (the WebSocket is not encrypted)");
  cmd->add_option("topics", o->topics, "topics to offer (default: every topic with a publisher)");
  cmd->add_option("--address", o->address, "address to listen on (0.0.0.0: every interface)");
  cmd->add_option("-p,--port", o->port, "port (default 8765, as foxglove_bridge; 0: any free port)");
  cmd->add_option("--jpeg-quality", o->jpeg_quality,
                  "JPEG quality of the <image topic>/compressed channels (1-100, default 90)");
  return [o] { return run(*o); };
}

}  // namespace unav::cli
