// Checks shared by the interface packages' tests: every generated type has its ROS 2 DDS name
// and survives a serialize -> deserialize -> serialize round trip with identical bytes.
#pragma once
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include <fastdds/rtps/common/SerializedPayload.h>

#include "generated_types.hpp"

namespace interface_checks {

inline std::vector<uint8_t> serialize(eprosima::fastdds::dds::TopicDataType& type, void* data) {
  const uint32_t size = type.getSerializedSizeProvider(data)();
  eprosima::fastrtps::rtps::SerializedPayload_t payload(size);
  EXPECT_TRUE(type.serialize(data, &payload));
  EXPECT_LE(payload.length, size) << "size provider under-estimates " << type.getName();
  return {payload.data, payload.data + payload.length};
}

inline void deserialize(eprosima::fastdds::dds::TopicDataType& type, const std::vector<uint8_t>& bytes, void* data) {
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<uint32_t>(bytes.size()));
  std::memcpy(payload.data, bytes.data(), bytes.size());
  payload.length = static_cast<uint32_t>(bytes.size());
  ASSERT_TRUE(type.deserialize(&payload, data));
}

inline void check_all_types_round_trip() {
  ASSERT_FALSE(generated_types().empty());
  for (const auto& entry : generated_types()) {
    auto type = entry.make();
    SCOPED_TRACE(entry.dds_name);
    // The DDS type name is what rmw_fastrtps registers, so ROS 2 tools match our topics.
    EXPECT_EQ(std::string(type->getName()), entry.dds_name);
    void* a = type->createData();
    void* b = type->createData();
    const auto bytes = serialize(*type, a);
    // XCDR1 little-endian encapsulation, as ROS 2 sends it.
    ASSERT_GE(bytes.size(), 4u);
    EXPECT_EQ(bytes[0], 0x00);
    EXPECT_EQ(bytes[1], 0x01);
    deserialize(*type, bytes, b);
    EXPECT_EQ(serialize(*type, b), bytes);
    type->deleteData(a);
    type->deleteData(b);
  }
}

}  // namespace interface_checks
