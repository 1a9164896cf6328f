// The storage plugins behind BagWriter and BagReader (MCAP and sqlite3).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "unav_bag/bag.hpp"

namespace unav::bag {

class BagWriter::Storage {
 public:
  virtual ~Storage() = default;
  virtual void add_topic(size_t index, const TopicMetadata& topic) = 0;
  virtual void write(size_t topic, int64_t timestamp_ns, const uint8_t* data, size_t size) = 0;
  /// Finishes the file; `metadata_yaml` is what metadata.yaml will hold.
  virtual void close(const std::string& metadata_yaml) = 0;
};

class BagReader::Source {
 public:
  virtual ~Source() = default;
  /// Topics in index order (Message::topic indexes this).
  virtual const std::vector<TopicMetadata>& topics() const = 0;
  virtual bool next(Message& out) = 0;
  virtual void rewind() = 0;
  /// Statistics from the file itself (used when metadata.yaml is missing).
  virtual BagInfo scan_info() = 0;
};

std::unique_ptr<BagWriter::Storage> make_mcap_storage(const std::string& path, const BagWriter::Options& options);
std::unique_ptr<BagWriter::Storage> make_sqlite_storage(const std::string& path);
std::unique_ptr<BagReader::Source> open_mcap_source(const std::string& path);
std::unique_ptr<BagReader::Source> open_sqlite_source(const std::string& path);

/// Fills message_count/start/duration/topics of `info` by reading every message of `source`.
void scan_messages(BagReader::Source& source, BagInfo& info);

}  // namespace unav::bag
