#include "unav_introspection/type_description.hpp"

#include "unav_introspection/type_registry.hpp"

namespace unav::introspection {

size_t primitive_size(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kBool:
    case PrimitiveKind::kOctet:
    case PrimitiveKind::kChar:
    case PrimitiveKind::kInt8:
    case PrimitiveKind::kUint8:
      return 1;
    case PrimitiveKind::kInt16:
    case PrimitiveKind::kUint16:
      return 2;
    case PrimitiveKind::kInt32:
    case PrimitiveKind::kUint32:
    case PrimitiveKind::kFloat:
      return 4;
    case PrimitiveKind::kInt64:
    case PrimitiveKind::kUint64:
    case PrimitiveKind::kDouble:
      return 8;
  }
  return 1;
}

const char* primitive_name(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kBool:
      return "boolean";
    case PrimitiveKind::kOctet:
      return "octet";
    case PrimitiveKind::kChar:
      return "char";
    case PrimitiveKind::kInt8:
      return "int8";
    case PrimitiveKind::kUint8:
      return "uint8";
    case PrimitiveKind::kInt16:
      return "int16";
    case PrimitiveKind::kUint16:
      return "uint16";
    case PrimitiveKind::kInt32:
      return "int32";
    case PrimitiveKind::kUint32:
      return "uint32";
    case PrimitiveKind::kInt64:
      return "int64";
    case PrimitiveKind::kUint64:
      return "uint64";
    case PrimitiveKind::kFloat:
      return "float";
    case PrimitiveKind::kDouble:
      return "double";
  }
  return "?";
}

std::string element_type_string(const ElementType& type) {
  switch (type.kind) {
    case ElementType::Kind::kPrimitive:
      return primitive_name(type.primitive);
    case ElementType::Kind::kString:
      return type.string_bound ? "string<" + std::to_string(type.string_bound) + ">" : "string";
    case ElementType::Kind::kStruct:
      try {
        return dds_to_ros_name(type.struct_type->name);
      } catch (const UnknownTypeError&) {
        return type.struct_type->name;
      }
  }
  return "?";
}

std::string field_type_string(const Field& field) {
  std::string element = element_type_string(field.type);
  switch (field.container) {
    case Field::Container::kSingle:
      return element;
    case Field::Container::kArray:
      return element + "[" + std::to_string(field.array_size) + "]";
    case Field::Container::kSequence:
      return field.sequence_bound ? "sequence<" + element + ", " + std::to_string(field.sequence_bound) + ">"
                                  : "sequence<" + element + ">";
  }
  return element;
}

}  // namespace unav::introspection
