#include "foxglove_server.hpp"

#define ASIO_STANDALONE
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <cstring>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <utility>

namespace unav::cli {
namespace {

using Server = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;
using Json = nlohmann::json;
constexpr const char* kSubprotocol = "foxglove.websocket.v1";
constexpr std::uint8_t kMessageData = 0x01;
constexpr std::uint8_t kTime = 0x02;

Json channel_json(std::uint32_t id, const FoxgloveServer::Channel& c) {
  return {{"id", id},           {"topic", c.topic},           {"encoding", "cdr"}, {"schemaName", c.schema_name},
          {"schema", c.schema}, {"schemaEncoding", "ros2msg"}};
}

}  // namespace

struct FoxgloveServer::Impl {
  Options options;
  Handlers handlers;
  Server server;
  std::thread thread;
  std::uint16_t port = 0;

  // Everything below is touched on the server's thread only (handlers and posted work).
  struct Client {
    std::uint64_t key = 0;
    std::map<std::uint32_t, std::uint32_t> subscription_of_channel;  // channel -> client's subscription id
    std::map<std::uint32_t, std::uint32_t> channel_of_subscription;
    std::map<std::uint32_t, ClientChannel> advertised;  // the client's own channels, by its id
  };
  std::map<Handle, Client, std::owner_less<Handle>> clients;
  std::map<std::uint32_t, Channel> channels;
  std::map<std::uint32_t, int> interest;  // channel -> subscribed clients
  std::uint32_t next_channel = 1;
  std::uint64_t next_client = 1;
  std::mutex id_mutex;  // next_channel is handed out on the caller's thread

  std::atomic<std::size_t> client_count{0};
  std::atomic<std::uint64_t> sent{0}, dropped{0}, received{0};

  void send_text(const Handle& h, const Json& j) {
    websocketpp::lib::error_code ec;
    server.send(h, j.dump(), websocketpp::frame::opcode::text, ec);
  }
  void status(const Handle& h, int level, const std::string& message) {
    send_text(h, {{"op", "status"}, {"level", level}, {"message", message}});
  }
  void change_interest(std::uint32_t channel, int delta) {
    const int before = interest[channel];
    const int after = before + delta;
    interest[channel] = after;
    if (handlers.on_interest && (before == 0) != (after == 0)) handlers.on_interest(channel, after > 0);
  }

  void on_open(const Handle& h) {
    Client client;
    client.key = next_client++;
    clients[h] = client;
    client_count = clients.size();
    Json capabilities = Json::array();
    if (options.client_publish) capabilities.push_back("clientPublish");
    if (options.time) capabilities.push_back("time");
    send_text(h, {{"op", "serverInfo"},
                  {"name", options.name},
                  {"capabilities", capabilities},
                  {"supportedEncodings", options.client_publish ? Json::array({"cdr"}) : Json::array()},
                  {"metadata", Json::object()},
                  {"sessionId", std::to_string(std::chrono::system_clock::now().time_since_epoch().count())}});
    Json list = Json::array();
    for (const auto& [id, c] : channels) list.push_back(channel_json(id, c));
    send_text(h, {{"op", "advertise"}, {"channels", list}});
  }

  void on_close(const Handle& h) {
    const auto it = clients.find(h);
    if (it == clients.end()) return;
    for (const auto& [channel, sub] : it->second.subscription_of_channel) change_interest(channel, -1);
    for (const auto& [id, ch] : it->second.advertised)
      if (handlers.on_client_unadvertise) handlers.on_client_unadvertise(ch);
    clients.erase(it);
    client_count = clients.size();
  }

  void on_message(const Handle& h, const Server::message_ptr& msg) {
    const auto it = clients.find(h);
    if (it == clients.end()) return;
    Client& c = it->second;
    if (msg->get_opcode() != websocketpp::frame::opcode::text) return on_binary(h, c, msg->get_payload());
    Json j;
    try {
      j = Json::parse(msg->get_payload());
    } catch (const Json::exception& e) {
      return status(h, 2, std::string("malformed JSON: ") + e.what());
    }
    const std::string op = j.value("op", "");
    try {
      if (op == "subscribe") {
        for (const auto& s : j.at("subscriptions")) {
          const auto sub = s.at("id").get<std::uint32_t>();
          const auto channel = s.at("channelId").get<std::uint32_t>();
          if (!channels.count(channel)) {
            status(h, 1, "subscribe: no channel " + std::to_string(channel));
          } else if (c.channel_of_subscription.count(sub) || c.subscription_of_channel.count(channel)) {
            status(h, 1,
                   "subscribe: subscription " + std::to_string(sub) + " or channel " + std::to_string(channel) +
                       " is already in use");
          } else {
            c.channel_of_subscription[sub] = channel;
            c.subscription_of_channel[channel] = sub;
            change_interest(channel, +1);
          }
        }
      } else if (op == "unsubscribe") {
        for (const auto& s : j.at("subscriptionIds")) {
          const auto sub = s.get<std::uint32_t>();
          const auto found = c.channel_of_subscription.find(sub);
          if (found == c.channel_of_subscription.end()) continue;
          c.subscription_of_channel.erase(found->second);
          change_interest(found->second, -1);
          c.channel_of_subscription.erase(found);
        }
      } else if (op == "advertise" && options.client_publish) {
        for (const auto& a : j.at("channels")) client_advertise(h, c, a);
      } else if (op == "unadvertise" && options.client_publish) {
        for (const auto& id : j.at("channelIds")) {
          const auto found = c.advertised.find(id.get<std::uint32_t>());
          if (found == c.advertised.end()) continue;
          if (handlers.on_client_unadvertise) handlers.on_client_unadvertise(found->second);
          c.advertised.erase(found);
        }
      } else {
        status(h, 1, "unsupported op '" + op + "'");
      }
    } catch (const Json::exception& e) {
      status(h, 2, op + ": " + e.what());
    }
  }

  void client_advertise(const Handle& h, Client& c, const Json& a) {
    ClientChannel ch;
    ch.client = c.key;
    ch.id = a.at("id").get<std::uint32_t>();
    ch.topic = a.at("topic").get<std::string>();
    ch.schema_name = a.at("schemaName").get<std::string>();
    const std::string encoding = a.at("encoding").get<std::string>();
    const std::string what = "advertise of '" + ch.topic + "' [" + ch.schema_name + "]: ";
    if (c.advertised.count(ch.id)) return status(h, 2, what + "channel id " + std::to_string(ch.id) + " is in use");
    if (encoding != "cdr") return status(h, 2, what + "encoding '" + encoding + "' is not supported (only cdr)");
    const std::string refused = handlers.on_client_advertise ? handlers.on_client_advertise(ch) : "";
    if (!refused.empty()) return status(h, 2, what + refused);
    c.advertised[ch.id] = ch;
  }

  void on_binary(const Handle& h, Client& c, const std::string& frame) {
    if (!options.client_publish) return status(h, 2, "client publishing is not enabled on this server");
    if (frame.size() < 5 || static_cast<std::uint8_t>(frame[0]) != kMessageData)
      return status(h, 2, "binary client message: only Message Data (opcode 1, uint32 channel id, payload)");
    std::uint32_t id = 0;
    std::memcpy(&id, frame.data() + 1, 4);
    const auto found = c.advertised.find(id);
    if (found == c.advertised.end())
      return status(h, 1, "message on channel " + std::to_string(id) + ", never advertised");
    if (handlers.on_client_message)
      handlers.on_client_message(found->second, reinterpret_cast<const std::uint8_t*>(frame.data()) + 5,
                                 frame.size() - 5);
    ++received;
  }

  // Sends a message to every subscriber of `channel`, each in a frame of its own (the header
  // carries that client's subscription id).
  void deliver(std::uint32_t channel, std::uint64_t receive_ns, const std::shared_ptr<std::string>& payload) {
    for (auto& [h, c] : clients) {
      const auto sub = c.subscription_of_channel.find(channel);
      if (sub == c.subscription_of_channel.end()) continue;
      websocketpp::lib::error_code ec;
      const auto con = server.get_con_from_hdl(h, ec);
      if (ec || con->get_buffered_amount() > options.max_buffered_bytes) {
        ++dropped;
        continue;
      }
      std::string frame(1 + 4 + 8 + payload->size(), '\0');
      frame[0] = static_cast<char>(kMessageData);
      const std::uint32_t id = sub->second;  // little endian on the machines we build for (x86-64, arm64)
      std::memcpy(frame.data() + 1, &id, 4);
      std::memcpy(frame.data() + 5, &receive_ns, 8);
      std::memcpy(frame.data() + 13, payload->data(), payload->size());
      con->send(frame, websocketpp::frame::opcode::binary);
      ++sent;
    }
  }
};

FoxgloveServer::FoxgloveServer(const Options& options, Handlers handlers) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.options = options;
  m.handlers = std::move(handlers);
  m.server.clear_access_channels(websocketpp::log::alevel::all);
  m.server.clear_error_channels(websocketpp::log::elevel::all);
  m.server.init_asio();
  m.server.set_reuse_addr(true);
  m.server.set_validate_handler([&m](const Handle& h) {
    websocketpp::lib::error_code ec;
    const auto con = m.server.get_con_from_hdl(h, ec);
    if (ec) return false;
    for (const auto& p : con->get_requested_subprotocols())
      if (p == kSubprotocol) {
        con->select_subprotocol(kSubprotocol);
        return true;
      }
    con->set_status(websocketpp::http::status_code::bad_request);
    con->set_body(std::string("this is a Foxglove WebSocket server: connect with subprotocol ") + kSubprotocol);
    return false;
  });
  m.server.set_open_handler([&m](const Handle& h) { m.on_open(h); });
  m.server.set_close_handler([&m](const Handle& h) { m.on_close(h); });
  m.server.set_fail_handler([&m](const Handle& h) { m.on_close(h); });
  m.server.set_message_handler([&m](const Handle& h, const Server::message_ptr& msg) { m.on_message(h, msg); });
  websocketpp::lib::error_code ec;
  asio::ip::tcp::endpoint endpoint(asio::ip::make_address(options.address, ec), options.port);
  if (!ec) m.server.listen(endpoint, ec);
  if (ec)
    throw std::runtime_error("foxglove server: cannot listen on " + options.address + ":" +
                             std::to_string(options.port) + ": " + ec.message());
  m.server.start_accept(ec);
  if (ec) throw std::runtime_error("foxglove server: cannot accept: " + ec.message());
  asio::error_code aec;
  m.port = m.server.get_local_endpoint(aec).port();
  m.thread = std::thread([&m] { m.server.run(); });
}

FoxgloveServer::~FoxgloveServer() {
  Impl& m = *impl_;
  asio::post(m.server.get_io_service(), [&m] {
    websocketpp::lib::error_code ec;
    m.server.stop_listening(ec);
    for (const auto& [h, c] : m.clients) m.server.close(h, websocketpp::close::status::going_away, "server stops", ec);
  });
  // Closing handshakes get a moment; then the loop is stopped whatever the clients do.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  m.server.stop();
  if (m.thread.joinable()) m.thread.join();
}

std::uint16_t FoxgloveServer::port() const { return impl_->port; }

std::uint32_t FoxgloveServer::add_channel(const Channel& channel) {
  Impl& m = *impl_;
  std::uint32_t id = 0;
  {
    const std::lock_guard<std::mutex> lock(m.id_mutex);
    id = m.next_channel++;
  }
  asio::post(m.server.get_io_service(), [&m, id, channel] {
    m.channels[id] = channel;
    for (const auto& [h, c] : m.clients)
      m.send_text(h, {{"op", "advertise"}, {"channels", {channel_json(id, channel)}}});
  });
  return id;
}

void FoxgloveServer::remove_channel(std::uint32_t channel) {
  Impl& m = *impl_;
  asio::post(m.server.get_io_service(), [&m, channel] {
    if (!m.channels.erase(channel)) return;
    for (auto& [h, c] : m.clients) {
      const auto sub = c.subscription_of_channel.find(channel);
      if (sub != c.subscription_of_channel.end()) {
        c.channel_of_subscription.erase(sub->second);
        c.subscription_of_channel.erase(sub);
      }
      m.send_text(h, {{"op", "unadvertise"}, {"channelIds", {channel}}});
    }
    if (m.interest[channel] > 0 && m.handlers.on_interest) m.handlers.on_interest(channel, false);
    m.interest.erase(channel);
  });
}

void FoxgloveServer::publish(std::uint32_t channel, std::uint64_t receive_ns, const std::uint8_t* cdr,
                             std::size_t size) {
  Impl& m = *impl_;
  auto payload = std::make_shared<std::string>(reinterpret_cast<const char*>(cdr), size);
  asio::post(m.server.get_io_service(),
             [&m, channel, receive_ns, payload] { m.deliver(channel, receive_ns, payload); });
}

void FoxgloveServer::publish_time(std::uint64_t time_ns) {
  Impl& m = *impl_;
  if (!m.options.time) return;
  asio::post(m.server.get_io_service(), [&m, time_ns] {
    std::string frame(1 + 8, '\0');
    frame[0] = static_cast<char>(kTime);
    std::memcpy(frame.data() + 1, &time_ns, 8);
    for (const auto& [h, c] : m.clients) {
      websocketpp::lib::error_code ec;
      m.server.send(h, frame, websocketpp::frame::opcode::binary, ec);
    }
  });
}

std::size_t FoxgloveServer::clients() const { return impl_->client_count; }
std::uint64_t FoxgloveServer::sent() const { return impl_->sent; }
std::uint64_t FoxgloveServer::dropped() const { return impl_->dropped; }
std::uint64_t FoxgloveServer::received() const { return impl_->received; }

}  // namespace unav::cli
