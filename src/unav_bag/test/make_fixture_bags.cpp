// Writes bags of known content for test_external_readers.py and test_foxglove_readers: OUT/mcap,
// OUT/mcap_zstd and OUT/sqlite3, each with /tf, /rov/odom, /rov/dvl (a unav_msgs type), /rov/range
// (constants in its schema) and /rov/camera/image (640x480 rgb8). Message i of every topic is
// stamped kStart + i * 100 ms and carries i in a field the test checks. OUT/all_types (MCAP, zstd):
// two messages (every field at its default) of every message type of interfaces/, one topic each
// (/all/<pkg>/<Type>): every schema we can write, for every reader.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "unav_bag/bag.hpp"
#include "unav_bag/msg_definition.hpp"
#include "unav_introspection/cdr_codec.hpp"

namespace {

constexpr int64_t kStart = 1764000000000000000;  // ns since epoch
constexpr int kCount = 10;

// CDR of sensor_msgs/Image built directly (a 921600-element YAML list would only be slow).
std::vector<uint8_t> image_cdr(int i, uint32_t w, uint32_t h) {
  std::vector<uint8_t> b = {0, 1, 0, 0};  // little-endian CDR encapsulation
  auto align = [&](size_t n) {
    while ((b.size() - 4) % n) b.push_back(0);
  };
  auto u32 = [&](uint32_t v) {
    align(4);
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    b.insert(b.end(), p, p + 4);
  };
  auto str = [&](const std::string& s) {
    u32(static_cast<uint32_t>(s.size() + 1));
    b.insert(b.end(), s.begin(), s.end());
    b.push_back(0);
  };
  const int64_t t = kStart + i * 100000000LL;
  u32(static_cast<uint32_t>(t / 1000000000));
  u32(static_cast<uint32_t>(t % 1000000000));
  str("camera_front_optical");
  u32(h);
  u32(w);
  str("rgb8");
  b.push_back(0);  // is_bigendian
  u32(w * 3);
  u32(w * h * 3);
  for (uint32_t k = 0; k < w * h * 3; ++k) b.push_back(static_cast<uint8_t>((k + static_cast<uint32_t>(i)) % 251));
  return b;
}

YAML::Node stamp(int i) {
  const int64_t t = kStart + i * 100000000LL;
  YAML::Node s;
  s["sec"] = t / 1000000000;
  s["nanosec"] = t % 1000000000;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_fixture_bags OUT_DIR\n");
    return 2;
  }
  namespace intro = unav::introspection;
  intro::TypeRegistry reg;
  reg.add_root(ROS2_MSGS_IDL);
  reg.add_root(UNAV_MSGS_IDL);
  const std::string out = argv[1];
  struct Topic {
    const char* name;
    const char* type;
    bool latched;
  };
  const Topic topics[] = {{"/tf", "tf2_msgs/msg/TFMessage", false},
                          {"/rov/odom", "nav_msgs/msg/Odometry", false},
                          {"/rov/dvl", "unav_msgs/msg/Dvl", false},
                          {"/rov/range", "sensor_msgs/msg/Range", true},
                          {"/rov/camera/image", "sensor_msgs/msg/Image", false}};
  for (const auto& [dir, storage, compression] :
       {std::tuple{"mcap", "mcap", "none"}, std::tuple{"mcap_zstd", "mcap", "zstd"},
        std::tuple{"sqlite3", "sqlite3", "none"}}) {
    unav::bag::BagWriter::Options opt;
    opt.storage_id = storage;
    opt.compression = compression;
    opt.chunk_size = size_t{256} * 1024;  // several chunks, some with many small messages
    unav::bag::BagWriter w(out + "/" + dir, opt);
    for (const auto& t : topics) {
      unav::bag::TopicMetadata m;
      m.name = t.name;
      m.type = t.type;
      m.offered_qos_profiles = unav::bag::offered_qos_yaml({{true, t.latched, t.latched ? 1 : 10}});
      m.message_definition = unav::bag::ros2msg_definition(reg, t.type);
      w.add_topic(m);
    }
    for (int i = 0; i < kCount; ++i) {
      const int64_t t = kStart + i * 100000000LL;
      YAML::Node tf;
      YAML::Node tr;
      tr["header"]["stamp"] = stamp(i);
      tr["header"]["frame_id"] = "map";
      tr["child_frame_id"] = "base_link";
      tr["transform"]["translation"]["x"] = static_cast<double>(i);
      tr["transform"]["translation"]["y"] = 2.0;
      tr["transform"]["translation"]["z"] = -3.0;
      tr["transform"]["rotation"]["w"] = 1.0;
      tf["transforms"].push_back(tr);
      YAML::Node odom;
      odom["header"]["stamp"] = stamp(i);
      odom["header"]["frame_id"] = "map";
      odom["child_frame_id"] = "base_link";
      odom["pose"]["pose"]["position"]["x"] = 0.5 * i;
      odom["pose"]["pose"]["orientation"]["w"] = 1.0;
      odom["twist"]["twist"]["linear"]["x"] = 0.25;
      YAML::Node dvl;
      dvl["header"]["stamp"] = stamp(i);
      dvl["header"]["frame_id"] = "dvl";
      dvl["velocity"]["x"] = 0.1 * i;
      dvl["altitude"] = 2.5;
      dvl["valid"] = true;
      YAML::Node range;
      range["header"]["stamp"] = stamp(i);
      range["radiation_type"] = 1;
      range["range"] = 1.5F;
      range["max_range"] = 10.0F;
      const std::vector<uint8_t> samples[] = {intro::encode(reg.load(topics[0].type), tf),
                                              intro::encode(reg.load(topics[1].type), odom),
                                              intro::encode(reg.load(topics[2].type), dvl),
                                              intro::encode(reg.load(topics[3].type), range), image_cdr(i, 640, 480)};
      for (size_t k = 0; k < 5; ++k) w.write(k, t + static_cast<int64_t>(k), samples[k].data(), samples[k].size());
    }
    w.close();
  }
  // Every message type of interfaces/ (services' request/response types are not published alone).
  unav::bag::BagWriter::Options opt;
  opt.storage_id = "mcap";
  opt.compression = "zstd";
  unav::bag::BagWriter all(out + "/all_types", opt);
  std::vector<std::vector<uint8_t>> samples;
  for (const std::string& type : reg.list()) {
    if (type.find("/msg/") == std::string::npos) continue;
    unav::bag::TopicMetadata m;
    m.name = "/all/" + type.substr(0, type.find('/')) + type.substr(type.rfind('/'));
    m.type = type;
    m.offered_qos_profiles = unav::bag::offered_qos_yaml({{true, false, 10}});
    m.message_definition = unav::bag::ros2msg_definition(reg, type);
    all.add_topic(m);
    samples.push_back(intro::encode(reg.load(type), YAML::Node(YAML::NodeType::Map)));
  }
  for (int i = 0; i < 2; ++i)
    for (size_t k = 0; k < samples.size(); ++k)
      all.write(k, kStart + i * 100000000LL + static_cast<int64_t>(k), samples[k].data(), samples[k].size());
  all.close();
  std::printf("make_fixture_bags: %s/{mcap,mcap_zstd,sqlite3,all_types} (%zu types)\n", out.c_str(), samples.size());
  return 0;
}
