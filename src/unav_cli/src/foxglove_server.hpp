// The Foxglove WebSocket protocol (foxglove.websocket.v1, what foxglove_bridge speaks and Foxglove
// Studio / Lichtblick connect to), server side, with no DDS in it: channels are advertised with
// their ros2msg schema, clients subscribe, and each message goes out as a binary frame
//   opcode 0x01 | uint32 subscription id | uint64 receive time [ns] | CDR payload   (little endian)
// to every client subscribed to its channel. The server runs its own thread (asio); add/remove and
// publish may be called from any thread. A client that cannot keep up (more than
// max_buffered_bytes queued) loses messages instead of holding the publisher: drops are counted.
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
  };
  struct Channel {
    std::string topic;
    std::string schema_name;  ///< ROS 2 type, e.g. nav_msgs/msg/Odometry
    std::string schema;       ///< ros2msg text (MSG: dependencies), as MCAP stores it
  };
  /// Called on the server's thread when a channel's subscriber count goes 0 -> 1 or 1 -> 0.
  using InterestCallback = std::function<void(std::uint32_t channel, bool wanted)>;

  /// Listens on address:port; throws std::runtime_error (with the address) when it cannot.
  explicit FoxgloveServer(const Options& options, InterestCallback on_interest = nullptr);
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

  std::size_t clients() const;
  std::uint64_t sent() const;     ///< binary message frames sent
  std::uint64_t dropped() const;  ///< not sent: the client's queue was full

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace unav::cli
