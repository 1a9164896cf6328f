// Typed publisher and subscription over Fast DDS.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "unav_runtime/context.hpp"
#include "unav_runtime/executor.hpp"

namespace unav {

/// The generated PubSubType of a message type, found by argument-dependent lookup of the
/// declaration in the ROS-style header (<pkg>/msg/<type>.hpp).
template <typename Msg>
using TypeSupportOf = decltype(unav_type_support_of(static_cast<const Msg*>(nullptr)));

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
  eprosima::fastdds::dds::DataWriter* writer() const { return writer_; }

 protected:
  bool write(const void* sample);

 private:
  Context& ctx_;
  std::string topic_;
  eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
};

template <typename Msg>
class Publisher : public PublisherBase {
 public:
  Publisher(Context& ctx, const std::string& topic, const QoS& qos)
      : PublisherBase(ctx, topic, new TypeSupportOf<Msg>(), qos) {}
  /// Serialises `msg` once into the transport; false if the middleware refused it.
  bool publish(const Msg& msg) { return write(&msg); }
};

/// Non-template part: owns the DataReader and is its listener.
class SubscriptionBase : public Waitable, public std::enable_shared_from_this<SubscriptionBase> {
 public:
  SubscriptionBase(Context& ctx, const std::string& topic, eprosima::fastdds::dds::TopicDataType* type,
                   const QoS& qos);
  ~SubscriptionBase() override;
  SubscriptionBase(const SubscriptionBase&) = delete;
  SubscriptionBase& operator=(const SubscriptionBase&) = delete;
  const std::string& topic_name() const { return topic_; }
  int publisher_count() const;
  eprosima::fastdds::dds::DataReader* reader() const { return reader_; }
  /// Creates the reader; called once by the node after construction (needs shared_from_this).
  void start(const QoS& qos);
  /// Listener thread entry: enqueue on the executor.
  void on_data();

 protected:
  /// Takes one sample into `sample`; true if a valid sample was taken.
  bool take(void* sample);

 private:
  Context& ctx_;
  std::string topic_;
  eprosima::fastdds::dds::Topic* dds_topic_ = nullptr;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
  std::unique_ptr<void, void (*)(void*)> listener_{nullptr, [](void*) {}};
};

template <typename Msg>
class Subscription : public SubscriptionBase {
 public:
  Subscription(Context& ctx, const std::string& topic, const QoS& qos, std::function<void(const Msg&)> callback)
      : SubscriptionBase(ctx, topic, new TypeSupportOf<Msg>(), qos), callback_(std::move(callback)) {}
  bool execute() override {
    // A bounded batch per turn keeps one busy topic from starving the others.
    for (int i = 0; i < 16; ++i) {
      if (!take(&sample_)) return false;
      callback_(sample_);
    }
    return true;
  }

 private:
  std::function<void(const Msg&)> callback_;
  Msg sample_;  // reused: an image's buffer is allocated once
};

}  // namespace unav
