// The Foxglove WebSocket protocol (foxglove.websocket.v1, what foxglove_bridge speaks and Foxglove
// Studio / Lichtblick connect to), server side, with no DDS in it: channels are advertised with
// their ros2msg schema, clients subscribe, and each message goes out as a binary frame
//   opcode 0x01 | uint32 subscription id | uint64 receive time [ns] | CDR payload   (little endian)
// to every client subscribed to its channel. Clients may publish (capability clientPublish,
// encoding cdr): they advertise channels of their own and send
//   opcode 0x01 | uint32 client channel id | CDR payload
// which the handlers receive. With the time capability, the server sends
//   opcode 0x02 | uint64 time [ns]
// (the simulation clock) to every client. The server runs its own thread (asio); add/remove,
// publish and publish_time may be called from any thread; the handlers are called on the server's
// thread. A client that cannot keep up (more than max_buffered_bytes queued) loses messages
// instead of holding the publisher: drops are counted.
//
//   FoxgloveServer s({"127.0.0.1", 8765, "unav"});
//   const auto id = s.add_channel({"/rov/ground_truth/odom", "nav_msgs/msg/Odometry", schema_text});
//   s.publish(id, stamp_ns, cdr_bytes.data(), cdr_bytes.size());
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace unav::cli {

class FoxgloveServer {
 public:
  struct Options {
    std::string address = "127.0.0.1";
    std::uint16_t port = 8765;  ///< 0: any free port (port() tells which)
    std::string name = "unav";
    std::size_t max_buffered_bytes = 32u << 20;  ///< per client; beyond it messages are dropped
    bool client_publish = false;                 ///< offer clientPublish (clients' advertise and message data)
    bool time = false;                           ///< offer time (publish_time sends the clock to every client)
  };
  struct Channel {
    std::string topic;
    std::string schema_name;  ///< ROS 2 type, e.g. nav_msgs/msg/Odometry
    std::string schema;       ///< ros2msg text (MSG: dependencies), as MCAP stores it
  };
  /// A channel a client advertised (its id is the client's own; `client` tells clients apart).
  struct ClientChannel {
    std::uint64_t client = 0;
    std::uint32_t id = 0;
    std::string topic;
    std::string schema_name;  ///< ROS 2 type, e.g. geometry_msgs/msg/PoseStamped
  };
  /// Everything is called on the server's thread; any may be empty.
  struct Handlers {
    /// A channel's subscriber count went 0 -> 1 (wanted) or 1 -> 0.
    std::function<void(std::uint32_t channel, bool wanted)> on_interest;
    /// A client advertised a channel (encoding cdr, checked here): return "" to accept it, else
    /// the reason it is refused (sent to the client as an error status).
    std::function<std::string(const ClientChannel&)> on_client_advertise;
    /// One CDR sample (with its encapsulation header) on an accepted client channel.
    std::function<void(const ClientChannel&, const std::uint8_t* cdr, std::size_t size)> on_client_message;
    /// The client unadvertised the channel or went away.
    std::function<void(const ClientChannel&)> on_client_unadvertise;
  };

  /// Listens on address:port; throws std::runtime_error (with the address) when it cannot.
  explicit FoxgloveServer(const Options& options, Handlers handlers = {});
  ~FoxgloveServer();
  FoxgloveServer(const FoxgloveServer&) = delete;
  FoxgloveServer& operator=(const FoxgloveServer&) = delete;

  std::uint16_t port() const;
  /// Advertises a channel to every client (and to those that connect later); returns its id.
  std::uint32_t add_channel(const Channel& channel);
  /// Unadvertises it; clients' subscriptions to it end.
  void remove_channel(std::uint32_t channel);
  /// Sends one CDR sample (with its encapsulation header) to the channel's subscribers.
  void publish(std::uint32_t channel, std::uint64_t receive_ns, const std::uint8_t* cdr, std::size_t size);

  /// Sends the clock to every client (only with Options::time).
  void publish_time(std::uint64_t time_ns);

  std::size_t clients() const;
  std::uint64_t sent() const;      ///< binary message frames sent
  std::uint64_t dropped() const;   ///< not sent: the client's queue was full
  std::uint64_t received() const;  ///< client message frames handed to on_client_message

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace unav::cli
