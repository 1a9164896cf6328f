// Typed publisher and subscription over Fast DDS.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "unav_runtime/context.hpp"
#include "unav_runtime/executor.hpp"

namespace unav {

/// The generated PubSubType of a message type, found by argument-dependent lookup of the
/// declaration in the ROS-style header (<pkg>/msg/<type>.hpp).
template <typename Msg>
using TypeSupportOf = decltype(unav_type_support_of(static_cast<const Msg*>(nullptr)));

/// CDR size of `msg` without the 4-byte encapsulation: a writer's QoS::max_sample_bytes is this
/// for its largest message (an image of the camera's size with its frame id and encoding).
template <typename Msg>
uint32_t serialized_bytes(const Msg& msg) {
  return static_cast<uint32_t>(Msg::getCdrSerializedSize(msg));
}

/// Lets the Context give a type a bound while it creates one endpoint: Fast DDS asks
/// is_bounded() and reads m_typeSize only when it creates a writer or reader, and data-sharing
/// needs a bounded type (a fixed payload size for the shared pool). One type object serves a
/// topic's writers and readers in a participant, so the bound is set per endpoint creation and
/// cleared after it; the wire format never changes.
class BoundSwitch {
 public:
  /// For a reader: bounded for Fast DDS's data-sharing check, the payload size left as generated.
  static constexpr uint32_t kReaderBound = UINT32_MAX;
  virtual ~BoundSwitch() = default;
  /// A writer's largest serialized sample, kReaderBound, or 0 to clear (unbounded again).
  virtual void set_bound(uint32_t serialized_bytes) = 0;
};

template <typename Base>
class SwitchableBoundType final : public Base, public BoundSwitch {
 public:
  bool is_bounded() const override { return bound_ != 0; }
  void set_bound(uint32_t serialized_bytes) override {
    bound_ = serialized_bytes;
    // + encapsulation, + up to 3 bytes of alignment as the generated constructor allows.
    this->m_typeSize = bound_ != 0 && bound_ != kReaderBound ? bound_ + 4 + 3 : unbounded_size_;
  }

 private:
  uint32_t unbounded_size_ = this->m_typeSize;
  uint32_t bound_ = 0;
};

/// Non-template part: owns the DataWriter.
class PublisherBase {
 public:
  PublisherBase(Context& ctx, const std::string& topic, eprosima::fastdds::dds::TopicDataType* type, const QoS& qos);
  virtual ~PublisherBase();
  PublisherBase(const PublisherBase&) = delete;
  PublisherBase& operator=(const PublisherBase&) = delete;
  const std::string& topic_name() const { return topic_; }
  /// Number of matched subscriptions (any process, any vendor).
  int subscription_count() const;
  /// The current DataWriter: a data-sharing writer stuck out of resources is replaced (see write()).
  eprosima::fastdds::dds::DataWriter* writer() const { return writer_; }
  /// How many times write() replaced a stuck data-sharing writer.
  int writer_recreations() const { return recreations_; }
  /// Tests only: the next n writes are refused out of resources without reaching the middleware
  /// (the Fast DDS stall write() answers cannot be produced on demand).
  void refuse_writes_for_test(int n) { refuse_for_test_ = n; }

 protected:
  bool write(const void* sample);

 private:
  Context& ctx_;
  std::string topic_;
  eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
  uint32_t max_sample_bytes_ = 0;  // data-sharing bound, for the error when a sample exceeds it
  // Refused writes: the 1st, 2nd, 4th, 8th ... are logged with the middleware's reason, and the
  // first success after them (a camera at 30 Hz would flood the log; a writer that refuses for
  // good must still show in a log's tail).
  std::uint64_t write_failures_ = 0, failures_since_ok_ = 0;
  // A data-sharing writer whose payload pool stays full (Fast DDS 2.9 with several data-sharing
  // readers: seen in lockstep runs, every write refused out of resources for good while its readers
  // stay matched) is deleted and created again: readers match the new one, the pool starts empty.
  eprosima::fastdds::dds::Topic* dds_topic_ = nullptr;
  QoS qos_;
  std::chrono::steady_clock::time_point first_refusal_{}, last_recreation_{};
  int recreations_ = 0;
  int refuse_for_test_ = 0;
};

template <typename Msg>
class Publisher : public PublisherBase {
 public:
  Publisher(Context& ctx, const std::string& topic, const QoS& qos)
      : PublisherBase(ctx, topic, new SwitchableBoundType<TypeSupportOf<Msg>>(), qos) {}
  /// Serialises `msg` once into the transport; false if the middleware refused it.
  bool publish(const Msg& msg) { return write(&msg); }
};

/// Non-template part: owns the DataReader and is its listener.
class SubscriptionBase : public Waitable, public std::enable_shared_from_this<SubscriptionBase> {
 public:
  SubscriptionBase(Context& ctx, const std::string& topic, eprosima::fastdds::dds::TopicDataType* type, const QoS& qos);
  ~SubscriptionBase() override;
  SubscriptionBase(const SubscriptionBase&) = delete;
  SubscriptionBase& operator=(const SubscriptionBase&) = delete;
  const std::string& topic_name() const { return topic_; }
  int publisher_count() const;
  eprosima::fastdds::dds::DataReader* reader() const { return reader_.load(std::memory_order_acquire); }
  /// Creates the reader; called once by the node after construction (needs shared_from_this).
  void start(const QoS& qos);
  /// Listener thread entry: wakes the executor, then takes one sample ahead while it wakes up
  /// (prefetch), so a large message's deserialisation overlaps the thread switch.
  void on_data();

 protected:
  /// Takes one sample into `sample`; true if a valid sample was taken.
  bool take(void* sample);
  /// Listener thread: takes one sample into the spare slot if it is free and no take is under
  /// way; true if it did. Default: no prefetch (the executor takes everything).
  virtual bool prefetch() { return false; }
  /// Every take, the listener's prefetch and the executor's, holds it: samples reach the
  /// callback in the order they were taken (the prefetched one first).
  std::mutex take_mutex_;

 private:
  Context& ctx_;
  std::string topic_;
  eprosima::fastdds::dds::Topic* dds_topic_ = nullptr;
  // Set by start() once create_reader() returns; the listener (prefetch) may run before that,
  // for a transient-local sample that arrives during the creation, and must then see null.
  std::atomic<eprosima::fastdds::dds::DataReader*> reader_{nullptr};
  std::unique_ptr<void, void (*)(void*)> listener_{nullptr, [](void*) {}};
};

template <typename Msg>
class Subscription : public SubscriptionBase {
 public:
  Subscription(Context& ctx, const std::string& topic, const QoS& qos, std::function<void(const Msg&)> callback)
      : SubscriptionBase(ctx, topic, new SwitchableBoundType<TypeSupportOf<Msg>>(), qos),
        callback_(std::move(callback)) {}
  bool execute() override {
    // A bounded batch per turn keeps one busy topic from starving the others.
    for (int i = 0; i < 16; ++i) {
      {
        std::lock_guard<std::mutex> lock(take_mutex_);
        if (prefetched_) {
          std::swap(sample_, spare_);  // buffers trade places: nothing is copied or allocated
          prefetched_ = false;
        } else if (!take(&sample_)) {
          return false;
        }
      }
      callback_(sample_);
    }
    return true;
  }

 protected:
  bool prefetch() override {
    std::unique_lock<std::mutex> lock(take_mutex_, std::try_to_lock);
    if (!lock.owns_lock() || prefetched_) return false;
    prefetched_ = take(&spare_);
    return prefetched_;
  }

 private:
  std::function<void(const Msg&)> callback_;
  Msg sample_;  // reused: an image's buffer is allocated once
  Msg spare_;   // the prefetched sample (take_mutex_)
  bool prefetched_ = false;
};

}  // namespace unav
