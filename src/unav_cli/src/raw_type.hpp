// A DDS type known only by name: samples are the raw CDR bytes (with encapsulation), so the CLI
// can subscribe to and publish any type and decode it with run-time introspection.
#pragma once

#include <cstring>
#include <string>
#include <vector>

#include <fastdds/rtps/common/SerializedPayload.h>
#include <fastdds/dds/topic/TopicDataType.hpp>

#include "unav_runtime/runtime.hpp"

namespace unav::cli {

struct RawSample {
  std::vector<uint8_t> bytes;
};

class RawType : public eprosima::fastdds::dds::TopicDataType {
 public:
  explicit RawType(const std::string& dds_type_name) {
    setName(dds_type_name.c_str());
    m_typeSize = 64 * 1024;  // initial payload size; larger samples reallocate
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override {
    const auto& b = static_cast<RawSample*>(data)->bytes;
    if (payload->max_size < b.size()) payload->reserve(static_cast<uint32_t>(b.size()));
    std::memcpy(payload->data, b.data(), b.size());
    payload->length = static_cast<uint32_t>(b.size());
    payload->encapsulation = b.size() > 1 && b[1] == 0 ? 0 /*BE*/ : 1 /*LE*/;
    return true;
  }
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    static_cast<RawSample*>(data)->bytes.assign(payload->data, payload->data + payload->length);
    return true;
  }
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] { return static_cast<uint32_t>(static_cast<RawSample*>(data)->bytes.size()); };
  }
  void* createData() override { return new RawSample(); }
  void deleteData(void* data) override { delete static_cast<RawSample*>(data); }
  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
};

/// Subscription to any type, delivering raw CDR samples.
class RawSubscription : public unav::SubscriptionBase {
 public:
  RawSubscription(unav::Context& ctx, const std::string& dds_topic, const std::string& dds_type, const unav::QoS& qos,
                  std::function<void(RawSample&)> cb)
      : SubscriptionBase(ctx, dds_topic, new RawType(dds_type), qos), cb_(std::move(cb)) {}
  bool execute() override {
    for (int i = 0; i < 64; ++i) {
      if (!take(&sample_)) return false;
      cb_(sample_);  // may move the bytes out
    }
    return true;
  }

 private:
  std::function<void(RawSample&)> cb_;
  RawSample sample_;
};

/// Publisher of any type from raw CDR samples.
class RawPublisher : public unav::PublisherBase {
 public:
  RawPublisher(unav::Context& ctx, const std::string& dds_topic, const std::string& dds_type, const unav::QoS& qos)
      : PublisherBase(ctx, dds_topic, new RawType(dds_type), qos) {}
  bool publish(const RawSample& s) { return write(&s); }
};

}  // namespace unav::cli
