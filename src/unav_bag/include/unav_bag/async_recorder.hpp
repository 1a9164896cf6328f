// Records into a BagWriter from a thread of its own, so that the thread that receives messages
// (a DDS executor, the simulation loop) never waits for the disk. The queue is bounded in bytes;
// a message that does not fit is dropped and counted per topic, never silently.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "unav_bag/bag.hpp"

namespace unav::bag {

class AsyncRecorder {
 public:
  struct TopicCounts {
    std::string name;
    uint64_t received = 0;  ///< handed to enqueue()
    uint64_t written = 0;   ///< in the bag
    uint64_t dropped = 0;   ///< refused: the queue was full, or the writer had failed
  };

  /// Takes the writer; `max_queue_bytes` bounds the payload waiting for the disk (>= 1).
  AsyncRecorder(std::unique_ptr<BagWriter> writer, size_t max_queue_bytes);
  /// Closes (drains the queue) if close() was not called.
  ~AsyncRecorder();
  AsyncRecorder(const AsyncRecorder&) = delete;
  AsyncRecorder& operator=(const AsyncRecorder&) = delete;

  /// Registers a topic (thread-safe; may be called while recording). Returns its index.
  size_t add_topic(const TopicMetadata& topic);
  /// Queues one message; false when it was dropped (queue full or writer failed). Never blocks
  /// on the disk. Thread-safe.
  bool enqueue(size_t topic, int64_t timestamp_ns, std::vector<uint8_t> data);
  /// Writes everything queued, closes the bag (metadata.yaml last) and stops the thread.
  /// Throws BagError if the writer failed (the bag then holds what was written before).
  void close();

  std::vector<TopicCounts> counts() const;
  uint64_t dropped() const;
  /// Bytes waiting now, and the most that ever waited.
  size_t queued_bytes() const;
  size_t peak_queued_bytes() const;
  /// The writer's error ("" while healthy): the first failure stops writing.
  std::string error() const;
  const BagWriter& writer() const { return *writer_; }

 private:
  struct Item {
    bool is_topic = false;
    size_t topic = 0;
    int64_t timestamp_ns = 0;
    std::vector<uint8_t> data;
    TopicMetadata metadata;
  };
  void run();

  std::unique_ptr<BagWriter> writer_;
  const size_t max_queue_bytes_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Item> queue_;
  std::vector<TopicCounts> counts_;
  size_t queued_bytes_ = 0, peak_bytes_ = 0;
  bool stop_ = false, closed_ = false;
  std::string error_;
  std::thread thread_;
};

}  // namespace unav::bag
