#include "bag_command.hpp"

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>

#include "cli_common.hpp"
#include "graph.hpp"
#include "raw_type.hpp"
#include "unav_bag/async_recorder.hpp"
#include "unav_bag/bag.hpp"
#include "unav_bag/msg_definition.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace unav::cli {
namespace {

struct RecordOptions {
  std::vector<std::string> topics;
  bool all = false;
  std::string output;
  std::string storage = "mcap";
  std::string compression = "none";
  uint64_t max_cache_size = 512ull << 20;
  bool use_sim_time = false;
  double duration = 0.0;
};

struct PlayOptions {
  std::string bag;
  double rate = 1.0;
  bool loop = false;
  std::vector<std::string> topics;
  double clock_hz = 0.0;
  double delay = 0.0;
};

std::string default_bag_name() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  localtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof(buf), "rosbag2_%Y_%m_%d-%H_%M_%S", &tm);
  return buf;
}

// rosgraph_msgs/Clock in CDR: encapsulation, int32 sec, uint32 nanosec.
RawSample clock_sample(int64_t ns) {
  RawSample s;
  s.bytes = {0, 1, 0, 0};
  const auto sec = static_cast<int32_t>(ns / 1000000000);
  const auto nsec = static_cast<uint32_t>(ns % 1000000000);
  s.bytes.resize(12);
  std::memcpy(s.bytes.data() + 4, &sec, 4);
  std::memcpy(s.bytes.data() + 8, &nsec, 4);
  return s;
}

int64_t clock_from_sample(const RawSample& s) {
  if (s.bytes.size() < 12) return -1;
  int32_t sec = 0;
  uint32_t nsec = 0;
  std::memcpy(&sec, s.bytes.data() + 4, 4);
  std::memcpy(&nsec, s.bytes.data() + 8, 4);
  return static_cast<int64_t>(sec) * 1000000000 + nsec;
}

int record(const RecordOptions& o) {
  if (!o.all && o.topics.empty()) throw UsageError("bag record: give topics or -a/--all");
  try {
    unav::bag::check_storage_id(o.storage);
  } catch (const unav::bag::BagError& e) {
    throw UsageError(std::string("-s/--storage: ") + e.what());
  }
  if (!(o.duration >= 0.0) || !std::isfinite(o.duration))
    throw UsageError("--duration " + std::to_string(o.duration) + ": must be >= 0 (0: until Ctrl-C)");
  if (o.max_cache_size == 0) throw UsageError("--max-cache-size 0: must be >= 1 byte");
  std::set<std::string> wanted;
  for (const auto& t : o.topics) wanted.insert(normalize_topic(t));
  const std::string out = o.output.empty() ? default_bag_name() : o.output;
  unav::bag::BagWriter::Options wo;
  wo.storage_id = o.storage;
  wo.compression = o.compression;
  std::unique_ptr<unav::bag::AsyncRecorder> rec;
  try {
    rec = std::make_unique<unav::bag::AsyncRecorder>(std::make_unique<unav::bag::BagWriter>(out, wo),
                                                     static_cast<size_t>(o.max_cache_size));
  } catch (const unav::bag::BagError& e) {
    throw UsageError(e.what());
  }
  auto reg = make_registry();
  Graph g;
  std::atomic<int64_t> sim_now{-1};
  std::vector<std::shared_ptr<RawSubscription>> subs;
  std::map<std::string, size_t> recording;  // topic -> bag topic index
  std::shared_ptr<RawSubscription> clock_sub;
  if (o.use_sim_time) {
    clock_sub = std::make_shared<RawSubscription>(g.context(), "rt/clock", "rosgraph_msgs::msg::dds_::Clock_",
                                                  unav::QoS::reliable(10),
                                                  [&](RawSample& s) { sim_now = clock_from_sample(s); });
    clock_sub->start(unav::QoS::reliable(10));
  }
  // Topics appear as their publishers are discovered: look every 100 ms (also for `-a`).
  auto discover = [&] {
    for (const auto& [topic, types] : g.topics()) {
      if (recording.count(topic) || types.empty()) continue;
      if (!o.all && !wanted.count(topic)) continue;
      // Only once a publisher is known: a topic seen through another subscriber alone would get
      // a reliable reader that a best-effort publisher (IMU, cameras) never matches.
      std::vector<unav::bag::QosProfile> offered;
      std::string dds_type;
      for (const auto& e : g.endpoints())
        if (e.is_writer && e.dds_topic == unav::to_dds_topic(topic)) {
          offered.push_back({e.reliable, e.transient_local, 0});
          dds_type = e.dds_type;
        }
      if (offered.empty()) continue;
      unav::bag::TopicMetadata meta;
      meta.name = topic;
      meta.type = unav::ros_type_from_dds(dds_type);
      meta.offered_qos_profiles = unav::bag::offered_qos_yaml(offered);
      try {
        meta.message_definition = unav::bag::ros2msg_definition(reg, dds_type);
      } catch (const std::exception& e) {
        std::cerr << "[WARN] [unav_bag]: no IDL for " << meta.type << " (" << e.what()
                  << "): recorded without a message definition" << std::endl;
      }
      const size_t index = rec->add_topic(meta);
      recording[topic] = index;
      const unav::QoS qos = g.matching_qos(topic);
      auto sub = std::make_shared<RawSubscription>(g.context(), unav::to_dds_topic(topic), dds_type, qos,
                                                   [&, index](RawSample& s) {
                                                     const int64_t ts = o.use_sim_time ? sim_now.load() : wall_ns();
                                                     if (ts < 0) return;  // no /clock yet
                                                     rec->enqueue(index, ts, std::move(s.bytes));
                                                   });
      sub->start(qos);
      subs.push_back(sub);
      std::cout << "[INFO] [unav_bag]: Subscribed to topic '" << topic << "'" << std::endl;
    }
  };
  auto discovery_timer = std::make_shared<unav::Timer>(100ms, discover, false);
  g.context().executor().add_timer(discovery_timer);
  std::cout << "[INFO] [unav_bag]: Recording to '" << out << "' (" << o.storage << ")..." << std::endl;
  auto last_report = std::chrono::steady_clock::now();
  uint64_t reported_drops = 0;
  const auto start = std::chrono::steady_clock::now();
  while (g.context().ok()) {
    g.context().spin_until([] { return false; }, 200ms);
    const auto now = std::chrono::steady_clock::now();
    if (o.duration > 0.0 && now - start >= std::chrono::duration<double>(o.duration)) break;
    if (now - last_report >= 1s) {  // drops are reported as they happen, not only at the end
      last_report = now;
      const uint64_t d = rec->dropped();
      const std::string error = rec->error();
      if (d > reported_drops && error.empty()) {
        std::cerr << "[WARN] [unav_bag]: " << d - reported_drops
                  << " messages dropped: the disk is slower than the data (queue "
                  << rec->peak_queued_bytes() / (1 << 20) << " MiB of " << o.max_cache_size / (1 << 20)
                  << "; raise --max-cache-size)" << std::endl;
        reported_drops = d;
      }
      if (!error.empty()) break;  // a write failed (disk full...): close() reports what the bag holds
    }
  }
  discovery_timer->cancel();
  subs.clear();
  int rc = 0;
  try {
    rec->close();
  } catch (const unav::bag::BagError& e) {
    std::cerr << "[ERROR] [unav_bag]: " << e.what() << std::endl;
    rc = 1;
  }
  uint64_t written = 0, dropped = 0;
  for (const auto& c : rec->counts()) {
    written += c.written;
    dropped += c.dropped;
    std::cout << "[INFO] [unav_bag]: " << c.name << ": " << c.written << " recorded, " << c.dropped << " dropped"
              << std::endl;
  }
  std::cout << "[INFO] [unav_bag]: Recorded " << written << " messages (" << rec->writer().payload_bytes()
            << " bytes) to '" << out << "'; dropped " << dropped << "; queue peak " << rec->peak_queued_bytes()
            << " bytes" << std::endl;
  return rc;
}

std::string format_size(double b) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int u = 0;
  while (b >= 1024.0 && u < 4) {
    b /= 1024.0;
    ++u;
  }
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f %s", b, units[u]);
  return buf;
}

std::string format_time(int64_t ns) {
  const std::time_t t = static_cast<std::time_t>(ns / 1000000000);
  std::tm tm{};
  localtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof(buf), "%b %e %Y %H:%M:%S", &tm);
  char out[128];
  std::snprintf(out, sizeof(out), "%s.%03lld (%lld.%03lld)", buf, static_cast<long long>(ns / 1000000 % 1000),
                static_cast<long long>(ns / 1000000000), static_cast<long long>(ns / 1000000 % 1000));
  return out;
}

int info(const std::string& path) {
  std::unique_ptr<unav::bag::BagReader> r;
  try {
    r = std::make_unique<unav::bag::BagReader>(path);
  } catch (const unav::bag::BagError& e) {
    throw UsageError(e.what());
  }
  const auto& in = r->info();
  uint64_t size = 0;
  std::string files;
  for (const auto& f : in.files) {
    const fs::path p = fs::is_directory(path) ? fs::path(path) / f.path : fs::path(path);
    std::error_code ec;
    size += fs::file_size(p, ec);
    files += (files.empty() ? "" : "\n                   ") + f.path;
  }
  char dur[64];
  std::snprintf(dur, sizeof(dur), "%.3fs", static_cast<double>(in.duration_ns) * 1e-9);
  std::cout << "\nFiles:             " << files << "\n"
            << "Bag size:          " << format_size(static_cast<double>(size)) << "\n"
            << "Storage id:        " << in.storage_identifier << "\n"
            << "Duration:          " << dur << "\n"
            << "Start:             " << format_time(in.starting_time_ns) << "\n"
            << "End:               " << format_time(in.starting_time_ns + in.duration_ns) << "\n"
            << "Messages:          " << in.message_count << "\n"
            << "Topic information: ";
  bool first = true;
  for (const auto& t : in.topics) {
    std::cout << (first ? "" : "                   ") << "Topic: " << t.topic.name << " | Type: " << t.topic.type
              << " | Count: " << t.message_count << " | Serialization Format: " << t.topic.serialization_format << "\n";
    first = false;
  }
  std::cout << std::endl;
  return 0;
}

int play(const PlayOptions& o) {
  if (!(o.rate > 0.0) || !std::isfinite(o.rate))
    throw UsageError("-r/--rate " + std::to_string(o.rate) + ": must be > 0");
  if (!(o.clock_hz >= 0.0) || !std::isfinite(o.clock_hz))
    throw UsageError("--clock " + std::to_string(o.clock_hz) + ": must be >= 0 Hz");
  if (!(o.delay >= 0.0) || !std::isfinite(o.delay)) throw UsageError("--delay: must be >= 0 s");
  std::unique_ptr<unav::bag::BagReader> r;
  try {
    r = std::make_unique<unav::bag::BagReader>(o.bag);
  } catch (const unav::bag::BagError& e) {
    throw UsageError(e.what());
  }
  std::set<std::string> filter;
  for (const auto& t : o.topics) filter.insert(normalize_topic(t));
  for (const auto& t : filter) {
    const bool known = std::any_of(r->topics().begin(), r->topics().end(), [&](const auto& m) { return m.name == t; });
    if (!known) throw UsageError("--topics: '" + t + "' is not in the bag (see unav bag info " + o.bag + ")");
  }
  Graph g;
  std::vector<std::unique_ptr<RawPublisher>> pubs(r->topics().size());
  for (size_t i = 0; i < r->topics().size(); ++i) {
    const auto& t = r->topics()[i];
    if (!filter.empty() && !filter.count(t.name)) continue;
    // Replay with the QoS the recorded publishers offered (rosbag2's adaptive choice): reliable
    // and transient local only if every one of them was.
    unav::QoS qos = unav::QoS::reliable(10);
    const auto offered = unav::bag::parse_offered_qos_yaml(t.offered_qos_profiles);
    if (!offered.empty()) {
      const bool reliable = std::all_of(offered.begin(), offered.end(), [](const auto& q) { return q.reliable; });
      const bool latched = std::all_of(offered.begin(), offered.end(), [](const auto& q) { return q.transient_local; });
      if (!reliable) qos.reliability = unav::QoS::Reliability::kBestEffort;
      if (latched) qos.durability = unav::QoS::Durability::kTransientLocal;
    }
    try {
      pubs[i] =
          std::make_unique<RawPublisher>(g.context(), unav::to_dds_topic(t.name), unav::dds_type_from_ros(t.type), qos);
    } catch (const unav::ConfigError& e) {  // e.g. rmw_dds_common's types: this process's graph uses them
      std::cerr << "[WARN] [unav_bag]: '" << t.name << "' not played: " << e.what() << std::endl;
    }
  }
  std::unique_ptr<RawPublisher> clock_pub;
  if (o.clock_hz > 0.0)
    clock_pub = std::make_unique<RawPublisher>(g.context(), "rt/clock", "rosgraph_msgs::msg::dds_::Clock_",
                                               unav::QoS::reliable(10));
  if (o.delay > 0.0)
    g.context().spin_until([] { return false; }, std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                     std::chrono::duration<double>(o.delay)));
  const int64_t bag_start = r->info().starting_time_ns;
  std::atomic<int64_t> bag_now{bag_start};
  std::shared_ptr<unav::Timer> clock_timer;
  if (clock_pub) {
    clock_timer = std::make_shared<unav::Timer>(
        std::chrono::nanoseconds(static_cast<int64_t>(1e9 / o.clock_hz)),
        [&] { clock_pub->publish(clock_sample(bag_now.load())); }, false);
    g.context().executor().add_timer(clock_timer);
  }
  uint64_t published = 0;
  do {
    std::cout << "[INFO] [unav_bag]: Playing '" << o.bag << "' at rate " << o.rate << std::endl;
    const auto wall_start = std::chrono::steady_clock::now();
    unav::bag::Message m;
    while (g.context().ok() && r->next(m)) {
      if (!pubs[m.topic]) continue;
      const double offset = static_cast<double>(m.timestamp_ns - bag_start) / o.rate;
      const auto due = wall_start + std::chrono::nanoseconds(static_cast<int64_t>(std::max(0.0, offset)));
      g.context().spin_until([&] { return std::chrono::steady_clock::now() >= due; },
                             std::max(std::chrono::nanoseconds(0), std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                                       due - std::chrono::steady_clock::now())));
      if (!g.context().ok()) break;
      bag_now = m.timestamp_ns;
      RawSample s;
      s.bytes = std::move(m.data);
      pubs[m.topic]->publish(s);
      ++published;
    }
    r->rewind();
  } while (o.loop && g.context().ok());
  if (clock_timer) clock_timer->cancel();
  // Let reliable subscribers acknowledge the last samples before the writers go away.
  for (const auto& p : pubs)
    if (p) {
      eprosima::fastrtps::Duration_t wait(2, 0);
      p->writer()->wait_for_acknowledgments(wait);
    }
  std::cout << "[INFO] [unav_bag]: Published " << published << " messages" << std::endl;
  return 0;
}

}  // namespace

std::function<int()> add_bag_command(CLI::App& app) {
  auto* bag = app.add_subcommand("bag", "record, play and inspect rosbag2 bags (MCAP, sqlite3)");
  bag->require_subcommand(1);
  auto ro = std::make_shared<RecordOptions>();
  auto* rec = bag->add_subcommand("record", "record topics to a rosbag2 folder");
  rec->add_option("topics", ro->topics, "topics to record");
  rec->add_flag("-a,--all", ro->all, "record every topic, also those that appear later");
  rec->add_option("-o,--output", ro->output, "bag folder (must not exist); default rosbag2_<date>-<time>");
  rec->add_option("-s,--storage", ro->storage, "storage: mcap (default) or sqlite3");
  rec->add_option("--compression", ro->compression, "MCAP chunk compression: none (default) or zstd");
  rec->add_option("--max-cache-size", ro->max_cache_size,
                  "bytes waiting for the disk before messages are dropped (counted); default 512 MiB");
  rec->add_flag("--use-sim-time", ro->use_sim_time, "stamp messages with /clock instead of the system clock");
  rec->add_option("-d,--duration", ro->duration, "stop after this many seconds (default: at Ctrl-C)");
  auto po = std::make_shared<PlayOptions>();
  auto* pl = bag->add_subcommand("play", "publish the messages of a bag");
  pl->add_option("bag", po->bag, "bag folder or .mcap/.db3 file")->required();
  pl->add_option("-r,--rate", po->rate, "rate factor (default 1.0)");
  pl->add_flag("-l,--loop", po->loop, "play again from the start at the end");
  pl->add_option("--topics", po->topics, "play only these topics");
  pl->add_option("--clock", po->clock_hz, "publish /clock at this rate [Hz] with the bag's time")
      ->expected(0, 1)
      ->default_str("40");
  pl->add_option("-d,--delay", po->delay, "wait this many seconds after creating the publishers");
  auto info_path = std::make_shared<std::string>();
  auto* in = bag->add_subcommand("info", "print a bag's topics, types, counts and duration");
  in->add_option("bag", *info_path, "bag folder or .mcap/.db3 file")->required();
  return [rec, pl, in, ro, po, info_path] {
    if (rec->parsed()) return record(*ro);
    if (pl->parsed()) return play(*po);
    if (in->parsed()) return info(*info_path);
    return 0;
  };
}

}  // namespace unav::cli
