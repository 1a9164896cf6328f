// rosbag2 folders (metadata.yaml + one storage file) in the two storage formats ROS 2 Humble
// writes: MCAP (ROS 2 profile, cdr messages, ros2msg schemas) and sqlite3 (.db3). DDS-free: the
// caller hands serialized CDR samples; `unav bag record|play|info` adapts this to the wire.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace unav::bag {

/// A bag cannot be written or read; what() names the file and the rule broken.
class BagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One offered QoS profile of a recorded topic (the policies rosbag2 replays with).
struct QosProfile {
  bool reliable = true;
  bool transient_local = false;
  int32_t depth = 10;
};

/// The `offered_qos_profiles` YAML string rosbag2 (Humble) stores per topic.
std::string offered_qos_yaml(const std::vector<QosProfile>& profiles);
/// Parses an `offered_qos_profiles` string; throws BagError on malformed YAML.
std::vector<QosProfile> parse_offered_qos_yaml(const std::string& yaml);

/// A recorded topic.
struct TopicMetadata {
  std::string name;                          ///< "/rov/imu"
  std::string type;                          ///< "sensor_msgs/msg/Imu"
  std::string serialization_format = "cdr";  ///< always "cdr" here
  std::string offered_qos_profiles;          ///< YAML, see offered_qos_yaml()
  std::string message_definition;            ///< ros2msg text with dependencies (MCAP schema)
};

struct TopicInformation {
  TopicMetadata topic;
  uint64_t message_count = 0;
};

struct FileInformation {
  std::string path;  ///< relative to the bag folder
  int64_t starting_time_ns = 0;
  int64_t duration_ns = 0;
  uint64_t message_count = 0;
};

/// The content of metadata.yaml (rosbag2 format version 5, as ROS 2 Humble writes it).
struct BagInfo {
  int version = 5;
  std::string storage_identifier;  ///< "mcap" or "sqlite3"
  int64_t starting_time_ns = 0;    ///< first message's timestamp (ns since epoch)
  int64_t duration_ns = 0;         ///< last - first
  uint64_t message_count = 0;
  std::vector<TopicInformation> topics;
  std::vector<FileInformation> files;
};

std::string to_metadata_yaml(const BagInfo& info);
/// Reads `<dir>/metadata.yaml`; throws BagError naming the file and the key.
BagInfo read_metadata(const std::string& bag_dir);

/// Storage formats: "mcap" or "sqlite3". Throws BagError naming the value otherwise.
void check_storage_id(const std::string& storage_id);

/// Writes one rosbag2 folder. Not thread-safe (AsyncRecorder puts it behind a queue).
class BagWriter {
 public:
  struct Options {
    std::string storage_id = "mcap";   ///< "mcap" or "sqlite3"
    std::string compression = "none";  ///< MCAP chunk compression: "none" or "zstd"
    size_t chunk_size = 1u << 20;      ///< MCAP: a chunk is closed once its records exceed this [bytes]
  };
  /// Creates `dir` (which must not exist yet, as `ros2 bag record -o` requires) and its storage
  /// file `<basename(dir)>_0.mcap|.db3`. Throws BagError.
  BagWriter(const std::string& dir, const Options& options);
  ~BagWriter();
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  /// Registers a topic; returns its index for write(). Throws BagError on a duplicate name.
  size_t add_topic(const TopicMetadata& topic);
  /// Appends one serialized message (CDR with its encapsulation header). Throws BagError when
  /// the storage fails (disk full): what was written before stays readable after close().
  void write(size_t topic, int64_t timestamp_ns, const uint8_t* data, size_t size);
  /// Finishes the storage file (MCAP summary and footer; sqlite commit) and writes metadata.yaml
  /// last, atomically. Idempotent. Throws BagError.
  void close();

  const std::string& dir() const { return dir_; }
  const std::string& storage_file() const { return file_; }
  /// Bytes of message payload written so far.
  uint64_t payload_bytes() const { return payload_bytes_; }
  const std::vector<TopicInformation>& topics() const { return topics_; }

  class Storage;

 private:
  std::string dir_, file_;
  Options options_;
  std::unique_ptr<Storage> storage_;
  std::vector<TopicInformation> topics_;
  int64_t first_ns_ = 0, last_ns_ = 0;
  uint64_t count_ = 0, payload_bytes_ = 0;
  bool closed_ = false;
};

/// One message read back.
struct Message {
  size_t topic = 0;  ///< index into BagReader::topics()
  int64_t timestamp_ns = 0;
  std::vector<uint8_t> data;
};

/// Reads a rosbag2 folder written by us or by ROS 2 (MCAP with uncompressed or zstd chunks,
/// sqlite3 with schema version 1-4; a bag split over several files is read file after file in
/// metadata.yaml's order, its topics merged by name), or a single .mcap/.db3 file. Messages come in timestamp
/// order for sqlite3 and in file order for MCAP (which rosbag2 writes in arrival order).
class BagReader {
 public:
  /// Throws BagError naming the path when it is not a readable bag.
  explicit BagReader(const std::string& path);
  ~BagReader();
  BagReader(const BagReader&) = delete;
  BagReader& operator=(const BagReader&) = delete;

  /// The bag's metadata: from metadata.yaml when present, else from scanning the storage file.
  const BagInfo& info() const { return info_; }
  const std::vector<TopicMetadata>& topics() const { return topics_; }
  /// The next message, or false at the end. Throws BagError on a corrupt file.
  bool next(Message& out);
  /// Starts again from the first message.
  void rewind();

  class Source;

 private:
  std::string path_;
  BagInfo info_;
  std::vector<TopicMetadata> topics_;
  std::unique_ptr<Source> source_;
};

}  // namespace unav::bag
