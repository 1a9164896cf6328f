#include "unav_bag/async_recorder.hpp"

#include <pthread.h>
#include <signal.h>

#include <cstdio>

namespace unav::bag {

AsyncRecorder::AsyncRecorder(std::unique_ptr<BagWriter> writer, size_t max_queue_bytes)
    : writer_(std::move(writer)), max_queue_bytes_(max_queue_bytes) {
  if (!writer_) throw BagError("AsyncRecorder: no writer");
  if (max_queue_bytes_ == 0) throw BagError("AsyncRecorder: max_queue_bytes 0: must be >= 1");
  thread_ = std::thread([this] { run(); });
}

AsyncRecorder::~AsyncRecorder() {
  try {
    close();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "unav_bag: %s\n", e.what());
  }
}

size_t AsyncRecorder::add_topic(const TopicMetadata& topic) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (closed_) throw BagError(writer_->dir() + ": add_topic after close");
  for (const auto& c : counts_)
    if (c.name == topic.name) throw BagError(writer_->dir() + ": topic '" + topic.name + "' added twice");
  Item item;
  item.is_topic = true;
  item.topic = counts_.size();
  item.metadata = topic;
  counts_.push_back({topic.name, 0, 0, 0});
  queue_.push_back(std::move(item));
  cv_.notify_one();
  return counts_.size() - 1;
}

bool AsyncRecorder::enqueue(size_t topic, int64_t timestamp_ns, std::vector<uint8_t> data) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (topic >= counts_.size()) throw BagError(writer_->dir() + ": enqueue to unknown topic " + std::to_string(topic));
  TopicCounts& c = counts_[topic];
  ++c.received;
  // One message larger than the whole queue is still taken when the queue is empty, so a bound
  // smaller than one image does not drop every image.
  const bool fits = queued_bytes_ + data.size() <= max_queue_bytes_ || queued_bytes_ == 0;
  if (closed_ || !error_.empty() || !fits) {
    ++c.dropped;
    return false;
  }
  queued_bytes_ += data.size();
  peak_bytes_ = std::max(peak_bytes_, queued_bytes_);
  Item item;
  item.topic = topic;
  item.timestamp_ns = timestamp_ns;
  item.data = std::move(data);
  queue_.push_back(std::move(item));
  cv_.notify_one();
  return true;
}

void AsyncRecorder::run() {
  // A library thread takes no process signals: Ctrl-C belongs to the thread that handles it (a
  // node's signal thread), whatever order the threads were started in.
  sigset_t all;
  sigfillset(&all);
  pthread_sigmask(SIG_BLOCK, &all, nullptr);
  for (;;) {
    Item item;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stop_ and drained
      item = std::move(queue_.front());
      queue_.pop_front();
    }
    std::string failure;
    try {
      if (item.is_topic) {
        writer_->add_topic(item.metadata);
      } else if (error_.empty()) {
        writer_->write(item.topic, item.timestamp_ns, item.data.data(), item.data.size());
      }
    } catch (const std::exception& e) {
      failure = e.what();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (!item.is_topic) {
      queued_bytes_ -= item.data.size();
      if (failure.empty() && error_.empty()) {
        ++counts_[item.topic].written;
      } else {
        ++counts_[item.topic].dropped;
      }
    }
    if (!failure.empty() && error_.empty()) error_ = failure;
  }
}

void AsyncRecorder::close() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (closed_) return;
    closed_ = true;
    stop_ = true;
  }
  cv_.notify_one();
  if (thread_.joinable()) thread_.join();
  std::string err = error();
  try {
    writer_->close();  // the bag holds what was written before a write error
  } catch (const std::exception& e) {
    err += (err.empty() ? "" : "; then ") + std::string(e.what());
  }
  if (!err.empty()) throw BagError(err);
}

std::vector<AsyncRecorder::TopicCounts> AsyncRecorder::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_;
}

uint64_t AsyncRecorder::dropped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  uint64_t n = 0;
  for (const auto& c : counts_) n += c.dropped;
  return n;
}

size_t AsyncRecorder::queued_bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queued_bytes_;
}

size_t AsyncRecorder::peak_queued_bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return peak_bytes_;
}

std::string AsyncRecorder::error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

}  // namespace unav::bag
