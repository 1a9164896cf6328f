// The Foxglove WebSocket server (foxglove.websocket.v1) against a WebSocket client on loopback:
// serverInfo and advertise on connect (with each channel's ros2msg schema), channels added and
// removed while connected, subscribe -> the interest callback -> binary Message Data frames laid
// out as the spec says (opcode 1, uint32 subscription id, uint64 time, payload; little endian),
// unsubscribe, and a client without the subprotocol refused.
#define ASIO_STANDALONE
#include <websocketpp/client.hpp>
#include <websocketpp/config/asio_no_tls_client.hpp>

#include <nlohmann/json.hpp>

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>

#include <gtest/gtest.h>

#include "foxglove_server.hpp"

using unav::cli::FoxgloveServer;
using Json = nlohmann::json;
using namespace std::chrono_literals;

namespace {

using Client = websocketpp::client<websocketpp::config::asio_client>;

// A client that queues what it receives (text as JSON, binary as bytes).
class TestClient {
 public:
  explicit TestClient(std::uint16_t port, bool with_subprotocol = true) {
    c_.clear_access_channels(websocketpp::log::alevel::all);
    c_.clear_error_channels(websocketpp::log::elevel::all);
    c_.init_asio();
    c_.set_message_handler([this](const websocketpp::connection_hdl&, const Client::message_ptr& m) {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (m->get_opcode() == websocketpp::frame::opcode::text)
        text_.push_back(Json::parse(m->get_payload()));
      else
        binary_.push_back(m->get_payload());
      cv_.notify_all();
    });
    c_.set_open_handler([this](const websocketpp::connection_hdl&) { set_state(1); });
    c_.set_fail_handler([this](const websocketpp::connection_hdl& h) {
      http_status_ = c_.get_con_from_hdl(h)->get_response_code();
      set_state(2);
    });
    websocketpp::lib::error_code ec;
    auto con = c_.get_connection("ws://127.0.0.1:" + std::to_string(port), ec);
    if (with_subprotocol) con->add_subprotocol("foxglove.websocket.v1");
    hdl_ = con->get_handle();
    c_.connect(con);
    thread_ = std::thread([this] { c_.run(); });
  }
  ~TestClient() {
    websocketpp::lib::error_code ec;
    if (state_ == 1) c_.close(hdl_, websocketpp::close::status::normal, "", ec);
    c_.stop();
    thread_.join();
  }
  int wait_state() {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_for(lock, 10s, [this] { return state_ != 0; });
    return state_;
  }
  int http_status() const { return static_cast<int>(http_status_); }
  Json next_text() {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!cv_.wait_for(lock, 10s, [this] { return !text_.empty(); })) return Json();
    Json j = text_.front();
    text_.pop_front();
    return j;
  }
  std::string next_binary() {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!cv_.wait_for(lock, 10s, [this] { return !binary_.empty(); })) return {};
    std::string b = binary_.front();
    binary_.pop_front();
    return b;
  }
  void send(const Json& j) { c_.send(hdl_, j.dump(), websocketpp::frame::opcode::text); }
  void send_binary(const std::string& b) { c_.send(hdl_, b, websocketpp::frame::opcode::binary); }
  void close() {
    websocketpp::lib::error_code ec;
    c_.close(hdl_, websocketpp::close::status::normal, "", ec);
  }

 private:
  void set_state(int s) {
    const std::lock_guard<std::mutex> lock(mutex_);
    state_ = s;
    cv_.notify_all();
  }
  Client c_;
  websocketpp::connection_hdl hdl_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Json> text_;
  std::deque<std::string> binary_;
  int state_ = 0;
  websocketpp::http::status_code::value http_status_{};
};

}  // namespace

TEST(FoxgloveServer, AdvertisesSubscribesAndFramesMessagesAsTheSpecSays) {
  std::mutex m;
  std::vector<std::pair<std::uint32_t, bool>> interest;
  FoxgloveServer::Handlers handlers;
  handlers.on_interest = [&](std::uint32_t c, bool w) {
    const std::lock_guard<std::mutex> lock(m);
    interest.emplace_back(c, w);
  };
  FoxgloveServer s({"127.0.0.1", 0, "test", 1u << 20}, handlers);
  ASSERT_GT(s.port(), 0);
  const std::uint32_t odom = s.add_channel({"/rov/odom", "nav_msgs/msg/Odometry", "std_msgs/Header header\n"});

  TestClient client(s.port());
  ASSERT_EQ(client.wait_state(), 1);
  const Json info = client.next_text();
  EXPECT_EQ(info["op"], "serverInfo") << info;
  EXPECT_EQ(info["name"], "test");
  EXPECT_EQ(info["capabilities"], Json::array());  // publishing and time are opt-in
  const Json adv = client.next_text();
  ASSERT_EQ(adv["op"], "advertise") << adv;
  ASSERT_EQ(adv["channels"].size(), 1u);
  const Json& ch = adv["channels"][0];
  EXPECT_EQ(ch["id"], odom);
  EXPECT_EQ(ch["topic"], "/rov/odom");
  EXPECT_EQ(ch["encoding"], "cdr");
  EXPECT_EQ(ch["schemaName"], "nav_msgs/msg/Odometry");
  EXPECT_EQ(ch["schemaEncoding"], "ros2msg");
  EXPECT_EQ(ch["schema"], "std_msgs/Header header\n");

  // A channel added while connected is advertised to the client at once.
  const std::uint32_t imu = s.add_channel({"/rov/imu", "sensor_msgs/msg/Imu", "float64 x\n"});
  const Json adv2 = client.next_text();
  EXPECT_EQ(adv2["op"], "advertise");
  EXPECT_EQ(adv2["channels"][0]["id"], imu);
  EXPECT_EQ(s.clients(), 1u);

  client.send({{"op", "subscribe"}, {"subscriptions", {{{"id", 7}, {"channelId", odom}}}}});
  for (int i = 0; i < 100; ++i) {  // the callback comes on the server's thread
    {
      const std::lock_guard<std::mutex> lock(m);
      if (!interest.empty()) break;
    }
    std::this_thread::sleep_for(20ms);
  }
  {
    const std::lock_guard<std::mutex> lock(m);
    ASSERT_EQ(interest.size(), 1u);
    EXPECT_EQ(interest[0], std::make_pair(odom, true));
  }
  const std::vector<std::uint8_t> cdr{0x00, 0x01, 0x00, 0x00, 0x2a, 0x00, 0x00, 0x00};
  s.publish(imu, 5, cdr.data(), cdr.size());  // nobody subscribed: not sent
  s.publish(odom, 0x0102030405060708ull, cdr.data(), cdr.size());
  const std::string frame = client.next_binary();
  ASSERT_EQ(frame.size(), 1u + 4u + 8u + cdr.size());
  EXPECT_EQ(static_cast<std::uint8_t>(frame[0]), 0x01);
  std::uint32_t sub = 0;
  std::uint64_t t = 0;
  std::memcpy(&sub, frame.data() + 1, 4);
  std::memcpy(&t, frame.data() + 5, 8);
  EXPECT_EQ(sub, 7u);
  EXPECT_EQ(t, 0x0102030405060708ull);
  EXPECT_EQ(std::memcmp(frame.data() + 13, cdr.data(), cdr.size()), 0);
  EXPECT_EQ(s.sent(), 1u);

  // A second subscription to the same channel by the same client is refused with a status.
  client.send({{"op", "subscribe"}, {"subscriptions", {{{"id", 8}, {"channelId", odom}}}}});
  const Json st = client.next_text();
  EXPECT_EQ(st["op"], "status") << st;
  EXPECT_EQ(st["level"], 1);

  client.send({{"op", "unsubscribe"}, {"subscriptionIds", {7}}});
  s.remove_channel(imu);
  const Json unadv = client.next_text();
  EXPECT_EQ(unadv["op"], "unadvertise") << unadv;
  EXPECT_EQ(unadv["channelIds"][0], imu);
  {
    const std::lock_guard<std::mutex> lock(m);
    ASSERT_EQ(interest.size(), 2u);
    EXPECT_EQ(interest[1], std::make_pair(odom, false));
  }
  s.publish(odom, 9, cdr.data(), cdr.size());
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(s.sent(), 1u);  // unsubscribed: nothing more
}

TEST(FoxgloveServer, RefusesClientsWithoutTheSubprotocolAndBusyPorts) {
  FoxgloveServer s({"127.0.0.1", 0, "test", 1u << 20});
  TestClient plain(s.port(), false);
  EXPECT_EQ(plain.wait_state(), 2);
  EXPECT_EQ(plain.http_status(), 400);
  EXPECT_EQ(s.clients(), 0u);
  try {
    FoxgloveServer again({"127.0.0.1", s.port(), "test", 1u << 20});
    ADD_FAILURE() << "a second server on a busy port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot listen on 127.0.0.1:" + std::to_string(s.port())), std::string::npos)
        << e.what();
  }
}

// Client publishing (capability clientPublish): a client advertises a channel of its own, the
// handler accepts or refuses it (the refusal reaches the client as an error status), Message Data
// frames (opcode 1, uint32 client channel id, payload) reach the handler byte for byte, and the
// channel is unadvertised when the client says so or goes away. The time capability sends
// opcode 2 | uint64 ns to every client.
TEST(FoxgloveServer, ClientsPublishOnChannelsTheyAdvertiseAndReceiveTheClock) {
  std::mutex m;
  std::vector<FoxgloveServer::ClientChannel> advertised, unadvertised;
  std::vector<std::string> payloads;
  FoxgloveServer::Handlers handlers;
  handlers.on_client_advertise = [&](const FoxgloveServer::ClientChannel& c) -> std::string {
    const std::lock_guard<std::mutex> lock(m);
    if (c.schema_name == "no_such/msg/Type") return "unknown type";
    advertised.push_back(c);
    return "";
  };
  handlers.on_client_message = [&](const FoxgloveServer::ClientChannel& c, const std::uint8_t* d, std::size_t n) {
    const std::lock_guard<std::mutex> lock(m);
    payloads.push_back(c.topic + ":" + std::string(reinterpret_cast<const char*>(d), n));
  };
  handlers.on_client_unadvertise = [&](const FoxgloveServer::ClientChannel& c) {
    const std::lock_guard<std::mutex> lock(m);
    unadvertised.push_back(c);
  };
  FoxgloveServer::Options o{"127.0.0.1", 0, "test", 1u << 20};
  o.client_publish = true;
  o.time = true;
  FoxgloveServer s(o, handlers);
  auto wait_for = [&](const std::function<bool()>& done) {
    for (int i = 0; i < 250; ++i) {  // the handlers run on the server's thread
      {
        const std::lock_guard<std::mutex> lock(m);
        if (done()) return true;
      }
      std::this_thread::sleep_for(20ms);
    }
    return false;
  };

  TestClient client(s.port());
  ASSERT_EQ(client.wait_state(), 1);
  const Json info = client.next_text();
  EXPECT_EQ(info["capabilities"], Json::array({"clientPublish", "time"})) << info;
  EXPECT_EQ(info["supportedEncodings"], Json::array({"cdr"}));
  EXPECT_EQ(client.next_text()["op"], "advertise");  // the server's (empty) channel list

  client.send({{"op", "advertise"},
               {"channels",
                {{{"id", 3},
                  {"topic", "/rov/control/pose_setpoint"},
                  {"encoding", "cdr"},
                  {"schemaName", "geometry_msgs/msg/PoseStamped"}},
                 {{"id", 4}, {"topic", "/x"}, {"encoding", "json"}, {"schemaName", "std_msgs/msg/String"}},
                 {{"id", 5}, {"topic", "/y"}, {"encoding", "cdr"}, {"schemaName", "no_such/msg/Type"}}}}});
  const Json json_refused = client.next_text();
  EXPECT_EQ(json_refused["level"], 2) << json_refused;
  EXPECT_NE(json_refused["message"].get<std::string>().find("encoding 'json' is not supported"), std::string::npos);
  const Json type_refused = client.next_text();
  EXPECT_NE(type_refused["message"].get<std::string>().find("'/y' [no_such/msg/Type]: unknown type"), std::string::npos)
      << type_refused;
  ASSERT_TRUE(wait_for([&] { return advertised.size() == 1; }));
  EXPECT_EQ(advertised[0].id, 3u);
  EXPECT_EQ(advertised[0].topic, "/rov/control/pose_setpoint");

  std::string frame("\x01\x03\x00\x00\x00", 5);
  frame += std::string("\x00\x01\x00\x00\xff\x7f", 6);  // any bytes: the server does not look inside
  client.send_binary(frame);
  client.send_binary(std::string("\x01\x09\x00\x00\x00zz", 7));  // channel 9 was never advertised
  const Json unknown = client.next_text();
  EXPECT_EQ(unknown["level"], 1) << unknown;
  ASSERT_TRUE(wait_for([&] { return payloads.size() == 1; }));
  EXPECT_EQ(payloads[0], "/rov/control/pose_setpoint:" + std::string("\x00\x01\x00\x00\xff\x7f", 6));
  EXPECT_EQ(s.received(), 1u);

  s.publish_time(1234567890123ull);
  const std::string t = client.next_binary();
  ASSERT_EQ(t.size(), 9u);
  EXPECT_EQ(static_cast<std::uint8_t>(t[0]), 0x02);
  std::uint64_t ns = 0;
  std::memcpy(&ns, t.data() + 1, 8);
  EXPECT_EQ(ns, 1234567890123ull);

  client.send({{"op", "unadvertise"}, {"channelIds", {3}}});
  ASSERT_TRUE(wait_for([&] { return unadvertised.size() == 1; }));
  EXPECT_EQ(unadvertised[0].id, 3u);

  // A client that goes away unadvertises what it still had.
  client.send({{"op", "advertise"},
               {"channels",
                {{{"id", 6},
                  {"topic", "/rov/thrusters/command"},
                  {"encoding", "cdr"},
                  {"schemaName", "unav_msgs/msg/ThrusterCommand"}}}}});
  ASSERT_TRUE(wait_for([&] { return advertised.size() == 2; }));
  client.close();
  ASSERT_TRUE(wait_for([&] { return unadvertised.size() == 2; }));
  EXPECT_EQ(unadvertised[1].topic, "/rov/thrusters/command");
}

TEST(FoxgloveServer, RefusesPublishingWhenNotOffered) {
  FoxgloveServer s({"127.0.0.1", 0, "test", 1u << 20});
  TestClient client(s.port());
  ASSERT_EQ(client.wait_state(), 1);
  client.next_text();
  client.next_text();
  client.send(
      {{"op", "advertise"},
       {"channels", {{{"id", 1}, {"topic", "/x"}, {"encoding", "cdr"}, {"schemaName", "std_msgs/msg/String"}}}}});
  const Json st = client.next_text();
  EXPECT_EQ(st["op"], "status") << st;
  EXPECT_NE(st["message"].get<std::string>().find("unsupported op 'advertise'"), std::string::npos) << st;
  client.send_binary(std::string("\x01\x01\x00\x00\x00", 5));
  const Json st2 = client.next_text();
  EXPECT_EQ(st2["level"], 2) << st2;
  EXPECT_EQ(s.received(), 0u);
}
