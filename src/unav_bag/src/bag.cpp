// rosbag2 folders: metadata.yaml (format version 5, ROS 2 Humble), offered QoS strings, and the
// writer/reader that put a storage plugin behind them.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "storage.hpp"

namespace fs = std::filesystem;

namespace unav::bag {
namespace {

// rosbag2's "infinite" durations (rmw's RMW_DURATION_INFINITE as rosbag2 Humble prints it).
constexpr int64_t kInfSec = 2147483647;
constexpr int64_t kInfNsec = 4294967295;

void emit_duration(YAML::Emitter& e, const char* key) {
  e << YAML::Key << key << YAML::Value << YAML::BeginMap << YAML::Key << "sec" << YAML::Value << kInfSec << YAML::Key
    << "nsec" << YAML::Value << kInfNsec << YAML::EndMap;
}

std::string storage_extension(const std::string& id) { return id == "mcap" ? ".mcap" : ".db3"; }

template <typename T>
T required(const YAML::Node& node, const std::string& key, const std::string& file) {
  if (!node || !node[key]) throw BagError(file + ": key '" + key + "' is missing");
  try {
    return node[key].as<T>();
  } catch (const YAML::Exception& e) {
    throw BagError(file + ": key '" + key + "': " + e.msg);
  }
}

}  // namespace

void check_storage_id(const std::string& storage_id) {
  if (storage_id != "mcap" && storage_id != "sqlite3")
    throw BagError("storage '" + storage_id + "' is not supported (mcap, sqlite3)");
}

std::string offered_qos_yaml(const std::vector<QosProfile>& profiles) {
  YAML::Emitter e;
  e << YAML::BeginSeq;
  for (const auto& p : profiles) {
    // Enum values of rmw: history 3 = unknown (what a subscriber sees of a remote writer),
    // reliability 1 reliable / 2 best effort, durability 1 transient local / 2 volatile,
    // liveliness 1 automatic.
    e << YAML::BeginMap << YAML::Key << "history" << YAML::Value << 3 << YAML::Key << "depth" << YAML::Value << p.depth
      << YAML::Key << "reliability" << YAML::Value << (p.reliable ? 1 : 2) << YAML::Key << "durability" << YAML::Value
      << (p.transient_local ? 1 : 2);
    emit_duration(e, "deadline");
    emit_duration(e, "lifespan");
    e << YAML::Key << "liveliness" << YAML::Value << 1;
    emit_duration(e, "liveliness_lease_duration");
    e << YAML::Key << "avoid_ros_namespace_conventions" << YAML::Value << false << YAML::EndMap;
  }
  e << YAML::EndSeq;
  return e.c_str();
}

std::vector<QosProfile> parse_offered_qos_yaml(const std::string& yaml) {
  std::vector<QosProfile> out;
  if (yaml.empty()) return out;
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw BagError("offered_qos_profiles: malformed YAML: " + e.msg);
  }
  if (!root.IsSequence()) return out;
  for (const auto& item : root) {
    if (!item.IsMap()) {  // found by fuzz_mcap: a list of scalars threw YAML::BadSubscript
      throw BagError("offered_qos_profiles: each profile must be a map of policies, got '" +
                     (item.IsScalar() ? item.Scalar() : std::string("a list")) + "'");
    }
    QosProfile p;
    // Integers (Humble) or names (later distros: "reliable", "transient_local").
    auto is = [&](const char* key, int number, const char* name) {
      if (!item[key]) return false;
      if (!item[key].IsScalar()) return false;
      const std::string v = item[key].Scalar();
      return v == std::to_string(number) || v == name;
    };
    p.reliable = !is("reliability", 2, "best_effort");
    p.transient_local = is("durability", 1, "transient_local");
    if (item["depth"] && item["depth"].IsScalar()) p.depth = std::max(1, item["depth"].as<int32_t>(10));
    out.push_back(p);
  }
  return out;
}

std::string to_metadata_yaml(const BagInfo& info) {
  YAML::Emitter e;
  e << YAML::BeginMap << YAML::Key << "rosbag2_bagfile_information" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "version" << YAML::Value << info.version;
  e << YAML::Key << "storage_identifier" << YAML::Value << info.storage_identifier;
  e << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds" << YAML::Value
    << info.duration_ns << YAML::EndMap;
  e << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds_since_epoch"
    << YAML::Value << info.starting_time_ns << YAML::EndMap;
  e << YAML::Key << "message_count" << YAML::Value << info.message_count;
  e << YAML::Key << "topics_with_message_count" << YAML::Value << YAML::BeginSeq;
  for (const auto& t : info.topics) {
    e << YAML::BeginMap << YAML::Key << "topic_metadata" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "name" << YAML::Value << t.topic.name;
    e << YAML::Key << "type" << YAML::Value << t.topic.type;
    e << YAML::Key << "serialization_format" << YAML::Value << t.topic.serialization_format;
    e << YAML::Key << "offered_qos_profiles" << YAML::Value << YAML::DoubleQuoted << t.topic.offered_qos_profiles;
    e << YAML::EndMap << YAML::Key << "message_count" << YAML::Value << t.message_count << YAML::EndMap;
  }
  e << YAML::EndSeq;
  e << YAML::Key << "compression_format" << YAML::Value << YAML::DoubleQuoted << "";
  e << YAML::Key << "compression_mode" << YAML::Value << YAML::DoubleQuoted << "";
  e << YAML::Key << "relative_file_paths" << YAML::Value << YAML::BeginSeq;
  for (const auto& f : info.files) e << f.path;
  e << YAML::EndSeq;
  e << YAML::Key << "files" << YAML::Value << YAML::BeginSeq;
  for (const auto& f : info.files) {
    e << YAML::BeginMap << YAML::Key << "path" << YAML::Value << f.path;
    e << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds_since_epoch"
      << YAML::Value << f.starting_time_ns << YAML::EndMap;
    e << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds" << YAML::Value
      << f.duration_ns << YAML::EndMap;
    e << YAML::Key << "message_count" << YAML::Value << f.message_count << YAML::EndMap;
  }
  e << YAML::EndSeq;
  e << YAML::EndMap << YAML::EndMap;
  return std::string(e.c_str()) + "\n";
}

BagInfo read_metadata(const std::string& bag_dir) {
  const std::string file = (fs::path(bag_dir) / "metadata.yaml").string();
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::BadFile&) {
    throw BagError(file + ": cannot read");
  } catch (const YAML::Exception& e) {
    throw BagError(file + ": malformed YAML: " + e.msg);
  }
  const YAML::Node b = root["rosbag2_bagfile_information"];
  if (!b) throw BagError(file + ": key 'rosbag2_bagfile_information' is missing");
  BagInfo info;
  info.version = required<int>(b, "version", file);
  info.storage_identifier = required<std::string>(b, "storage_identifier", file);
  info.duration_ns = required<int64_t>(b["duration"], "nanoseconds", file);
  info.starting_time_ns = required<int64_t>(b["starting_time"], "nanoseconds_since_epoch", file);
  info.message_count = required<uint64_t>(b, "message_count", file);
  for (const auto& t : b["topics_with_message_count"]) {
    TopicInformation ti;
    const YAML::Node m = t["topic_metadata"];
    ti.topic.name = required<std::string>(m, "name", file);
    ti.topic.type = required<std::string>(m, "type", file);
    ti.topic.serialization_format = required<std::string>(m, "serialization_format", file);
    if (m["offered_qos_profiles"]) {
      // A string (Humble) or, in later formats, a list of maps.
      if (m["offered_qos_profiles"].IsScalar()) {
        ti.topic.offered_qos_profiles = m["offered_qos_profiles"].as<std::string>();
      } else {
        YAML::Emitter q;
        q << m["offered_qos_profiles"];
        ti.topic.offered_qos_profiles = q.c_str();
      }
    }
    ti.message_count = required<uint64_t>(t, "message_count", file);
    info.topics.push_back(ti);
  }
  if (b["files"]) {
    for (const auto& f : b["files"]) {
      FileInformation fi;
      fi.path = required<std::string>(f, "path", file);
      fi.starting_time_ns = required<int64_t>(f["starting_time"], "nanoseconds_since_epoch", file);
      fi.duration_ns = required<int64_t>(f["duration"], "nanoseconds", file);
      fi.message_count = required<uint64_t>(f, "message_count", file);
      info.files.push_back(fi);
    }
  } else {
    for (const auto& p : b["relative_file_paths"]) info.files.push_back({p.as<std::string>(), 0, 0, 0});
  }
  return info;
}

void scan_messages(BagReader::Source& source, BagInfo& info) {
  info.topics.clear();
  for (const auto& t : source.topics()) info.topics.push_back({t, 0});
  info.message_count = 0;
  int64_t first = 0, last = 0;
  Message m;
  source.rewind();
  while (source.next(m)) {
    if (info.message_count++ == 0) first = last = m.timestamp_ns;
    first = std::min(first, m.timestamp_ns);
    last = std::max(last, m.timestamp_ns);
    ++info.topics[m.topic].message_count;
  }
  source.rewind();
  info.starting_time_ns = first;
  // Found by fuzz_mcap: forged stamps far apart overflowed the subtraction.
  if (__builtin_sub_overflow(last, first, &info.duration_ns))
    throw BagError("message timestamps " + std::to_string(first) + " .. " + std::to_string(last) +
                   " ns span more than 292 years: corrupt bag");
}

// ---------------------------------------------------------------------------------------------

BagWriter::BagWriter(const std::string& dir, const Options& options) : dir_(dir), options_(options) {
  check_storage_id(options.storage_id);
  if (options.compression != "none" && options.compression != "zstd")
    throw BagError("compression '" + options.compression + "' is not supported (none, zstd)");
  if (options.compression != "none" && options.storage_id != "mcap")
    throw BagError("compression '" + options.compression + "' needs storage mcap (it compresses MCAP chunks)");
  std::error_code ec;
  if (fs::exists(dir, ec)) throw BagError(dir + ": output folder exists already (choose another with -o)");
  fs::create_directories(dir, ec);
  if (ec) throw BagError(dir + ": cannot create folder: " + ec.message());
  std::string base = fs::path(dir).lexically_normal().filename().string();
  if (base.empty()) base = fs::path(dir).lexically_normal().parent_path().filename().string();
  file_ = base + "_0" + storage_extension(options.storage_id);
  const std::string path = (fs::path(dir) / file_).string();
  storage_ = options.storage_id == "mcap" ? make_mcap_storage(path, options) : make_sqlite_storage(path);
}

BagWriter::~BagWriter() {
  try {
    close();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "unav_bag: %s\n", e.what());
  }
}

size_t BagWriter::add_topic(const TopicMetadata& topic) {
  if (closed_) throw BagError(dir_ + ": add_topic after close");
  for (const auto& t : topics_)
    if (t.topic.name == topic.name) throw BagError(dir_ + ": topic '" + topic.name + "' added twice");
  storage_->add_topic(topics_.size(), topic);
  topics_.push_back({topic, 0});
  return topics_.size() - 1;
}

void BagWriter::write(size_t topic, int64_t timestamp_ns, const uint8_t* data, size_t size) {
  if (closed_) throw BagError(dir_ + ": write after close");
  if (topic >= topics_.size()) throw BagError(dir_ + ": write to unknown topic index " + std::to_string(topic));
  storage_->write(topic, timestamp_ns, data, size);
  if (count_++ == 0) first_ns_ = last_ns_ = timestamp_ns;
  first_ns_ = std::min(first_ns_, timestamp_ns);
  last_ns_ = std::max(last_ns_, timestamp_ns);
  ++topics_[topic].message_count;
  payload_bytes_ += size;
}

void BagWriter::close() {
  if (closed_) return;
  closed_ = true;
  BagInfo info;
  info.storage_identifier = options_.storage_id;
  info.starting_time_ns = count_ ? first_ns_ : 0;
  info.duration_ns = count_ ? last_ns_ - first_ns_ : 0;
  info.message_count = count_;
  info.topics = topics_;
  info.files.push_back({file_, info.starting_time_ns, info.duration_ns, count_});
  const std::string yaml = to_metadata_yaml(info);
  storage_->close(yaml);
  storage_.reset();
  // metadata.yaml last and atomically: a bag with metadata.yaml is a complete bag.
  const fs::path tmp = fs::path(dir_) / ".metadata.yaml.tmp";
  {
    std::ofstream out(tmp);
    out << yaml;
    out.flush();
    if (!out) throw BagError((fs::path(dir_) / "metadata.yaml").string() + ": cannot write");
  }
  std::error_code ec;
  fs::rename(tmp, fs::path(dir_) / "metadata.yaml", ec);
  if (ec) throw BagError((fs::path(dir_) / "metadata.yaml").string() + ": cannot write: " + ec.message());
}

// ---------------------------------------------------------------------------------------------

namespace {

std::unique_ptr<BagReader::Source> open_source(const std::string& file) {
  const std::string ext = fs::path(file).extension().string();
  if (ext == ".mcap") return open_mcap_source(file);
  if (ext == ".db3") return open_sqlite_source(file);
  throw BagError(file + ": unknown storage (expected .mcap or .db3)");
}

// A bag rosbag2 split over several files (max_bag_size / max_bag_duration): the files one after
// the other in metadata.yaml's order, their topics merged by name (each file lists its own).
class SplitSource final : public BagReader::Source {
 public:
  explicit SplitSource(const std::vector<std::string>& files) {
    for (const auto& f : files) {
      parts_.push_back(open_source(f));
      std::vector<size_t> map;
      for (const auto& t : parts_.back()->topics()) {
        const auto it =
            std::find_if(topics_.begin(), topics_.end(), [&](const TopicMetadata& u) { return u.name == t.name; });
        if (it != topics_.end() && it->type != t.type)
          throw BagError(f + ": topic '" + t.name + "' has type " + t.type + " here and " + it->type +
                         " in an earlier file of the bag");
        map.push_back(it != topics_.end() ? static_cast<size_t>(it - topics_.begin()) : topics_.size());
        if (it == topics_.end()) topics_.push_back(t);
      }
      index_.push_back(std::move(map));
    }
  }
  const std::vector<TopicMetadata>& topics() const override { return topics_; }
  bool next(Message& out) override {
    for (; current_ < parts_.size(); ++current_) {
      if (parts_[current_]->next(out)) {
        out.topic = index_[current_].at(out.topic);
        return true;
      }
    }
    return false;
  }
  void rewind() override {
    for (auto& p : parts_) p->rewind();
    current_ = 0;
  }
  BagInfo scan_info() override {
    BagInfo info;
    scan_messages(*this, info);
    return info;
  }

 private:
  std::vector<std::unique_ptr<BagReader::Source>> parts_;
  std::vector<std::vector<size_t>> index_;  // per file: its topic index -> ours
  std::vector<TopicMetadata> topics_;
  size_t current_ = 0;
};

}  // namespace

BagReader::BagReader(const std::string& path) : path_(path) {
  std::error_code ec;
  std::string file;
  bool have_metadata = false;
  if (fs::is_directory(path, ec)) {
    if (fs::exists(fs::path(path) / "metadata.yaml")) {
      info_ = read_metadata(path);
      have_metadata = true;
      if (info_.files.empty()) throw BagError(path + "/metadata.yaml: no storage file listed");
      if (info_.files.size() > 1) {
        std::vector<std::string> files;
        for (const auto& f : info_.files) files.push_back((fs::path(path) / f.path).string());
        source_ = std::make_unique<SplitSource>(files);
      }
      file = (fs::path(path) / info_.files.front().path).string();
    } else {
      for (const auto& entry : fs::directory_iterator(path)) {
        const auto ext = entry.path().extension();
        if (ext == ".mcap" || ext == ".db3") {
          if (!file.empty()) throw BagError(path + ": no metadata.yaml and more than one storage file");
          file = entry.path().string();
        }
      }
      if (file.empty()) throw BagError(path + ": not a bag (no metadata.yaml, no .mcap or .db3 file)");
    }
  } else if (fs::exists(path, ec)) {
    file = path;
  } else {
    throw BagError(path + ": no such bag");
  }
  if (!source_) source_ = open_source(file);
  topics_ = source_->topics();
  if (!have_metadata) {
    info_ = source_->scan_info();
    info_.files = {
        {fs::path(file).filename().string(), info_.starting_time_ns, info_.duration_ns, info_.message_count}};
  } else {
    // sqlite3 keeps no message definitions: take types and QoS from the storage, counts from
    // metadata.yaml.
    for (auto& t : topics_)
      for (const auto& ti : info_.topics)
        if (ti.topic.name == t.name && t.offered_qos_profiles.empty())
          t.offered_qos_profiles = ti.topic.offered_qos_profiles;
  }
}

BagReader::~BagReader() = default;

bool BagReader::next(Message& out) { return source_->next(out); }

void BagReader::rewind() { source_->rewind(); }

}  // namespace unav::bag
