// Run-time description of IDL struct types, as parsed by TypeRegistry.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace unav::introspection {

/// IDL primitive types, normalized (`long` is kInt32, `unsigned short` is kUint16, ...).
enum class PrimitiveKind : uint8_t {
  kBool,
  kOctet,
  kChar,
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kInt64,
  kUint64,
  kFloat,
  kDouble,
};

/// Size of the primitive on the wire [bytes]; in CDR it is also its alignment.
size_t primitive_size(PrimitiveKind kind);

/// Canonical IDL name as ROS 2 prints it: "boolean", "octet", "char", "uint8", "float", "double".
const char* primitive_name(PrimitiveKind kind);

struct StructType;

/// The type of one value: a primitive, a (possibly bounded) string or a struct.
struct ElementType {
  enum class Kind : uint8_t { kPrimitive, kString, kStruct };
  Kind kind = Kind::kPrimitive;
  PrimitiveKind primitive = PrimitiveKind::kBool;  ///< valid for kPrimitive
  size_t string_bound = 0;                         ///< kString: maximum length [bytes], 0 = unbounded
  const StructType* struct_type = nullptr;         ///< kStruct: owned by the TypeRegistry
};

/// A struct member: a single value, a fixed array or a (bounded) sequence of `type`.
struct Field {
  enum class Container : uint8_t { kSingle, kArray, kSequence };
  std::string name;
  ElementType type;
  Container container = Container::kSingle;
  size_t array_size = 0;      ///< kArray: number of elements
  size_t sequence_bound = 0;  ///< kSequence: maximum number of elements, 0 = unbounded
  YAML::Node default_value;   ///< from `@default (value=...)`; a null node when absent
};

/// A parsed IDL struct.
struct StructType {
  std::string name;  ///< fully scoped DDS name, e.g. "std_msgs::msg::dds_::Header_"
  std::vector<Field> fields;
  std::string file;  ///< IDL file that declares it
  int line = 0;      ///< line of the `struct` keyword in `file`
};

/// Human-readable type of a field for messages, e.g. "sequence<double, 3>", "string<10>", "int32[4]".
std::string field_type_string(const Field& field);

/// Human-readable element type: "double", "string", "std_msgs/msg/Header".
std::string element_type_string(const ElementType& type);

}  // namespace unav::introspection
