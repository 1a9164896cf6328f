// CDR (XCDR1, as Fast DDS 2.x and rmw_fastrtps put it on the wire) <-> YAML for parsed IDL types.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "unav_introspection/type_description.hpp"

namespace unav::introspection {

/// A value does not fit its type (encode) or the bytes are not a valid sample (decode).
/// what() names the field path, e.g. "header.stamp.sec: ...".
class CodecError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Options of `ros2 topic echo`.
struct EchoOptions {
  /// Value of `--truncate-length`: longer strings and arrays are cut and marked with "...".
  static constexpr size_t kFullLength = std::numeric_limits<size_t>::max();  ///< `--full-length`
  size_t truncate_length = 128;
  bool no_arr = false;  ///< `--no-arr`: arrays and sequences become "<sequence type: T, length: N>"
  bool no_str = false;  ///< `--no-str`: strings become "<string length: <N>>"
};

/// Serializes `value` as little-endian CDR with its 4-byte encapsulation header.
/// Accepts YAML as `ros2 topic pub` does (`{linear: {x: 1}}`); missing fields take their
/// `@default` or zero/empty. Throws CodecError naming the field path, the value and the rule.
std::vector<uint8_t> encode(const StructType& type, const YAML::Node& value);

/// Deserializes one CDR sample (little or big endian, with encapsulation header) into a YAML map.
/// Integers, floats (Python repr) and booleans are scalars; octets are integers 0..255.
/// Throws CodecError on truncated or malformed data; never reads outside [data, data + size).
YAML::Node decode(const StructType& type, const uint8_t* data, size_t size);

/// The text `ros2 topic echo` (ROS 2 Humble) prints for one sample, without the "---" line.
/// Throws CodecError like decode().
std::string to_echo_yaml(const StructType& type, const uint8_t* data, size_t size,
                         const EchoOptions& options = EchoOptions{});

/// A double formatted like PyYAML dumps a Python float: "1.0", "0.1", "1.0e-05", ".nan", "-.inf".
std::string format_float_like_python(double value);

}  // namespace unav::introspection
