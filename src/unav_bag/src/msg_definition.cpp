// .msg text from parsed IDL: the inverse of rosidl's msg -> idl mapping for the subset ROS 2
// message IDL uses (primitives, strings, fixed arrays, bounded/unbounded sequences, nested
// messages, constants, defaults).
#include "unav_bag/msg_definition.hpp"

#include <set>
#include <sstream>

namespace unav::bag {
namespace {

namespace intro = unav::introspection;

std::string msg_primitive(intro::PrimitiveKind k) {
  switch (k) {
    case intro::PrimitiveKind::kBool:
      return "bool";
    case intro::PrimitiveKind::kOctet:
      return "byte";
    case intro::PrimitiveKind::kChar:
      return "char";
    case intro::PrimitiveKind::kFloat:
      return "float32";
    case intro::PrimitiveKind::kDouble:
      return "float64";
    default:
      return intro::primitive_name(k);  // int8 ... uint64
  }
}

// "std_msgs::msg::dds_::Header_" -> "std_msgs/Header" (how .msg files name other messages).
std::string msg_type_ref(const intro::StructType& s) {
  const std::string ros = intro::dds_to_ros_name(s.name);  // pkg/msg/Type
  return ros.substr(0, ros.find('/')) + ros.substr(ros.rfind('/'));
}

std::string element(const intro::ElementType& t) {
  switch (t.kind) {
    case intro::ElementType::Kind::kPrimitive:
      return msg_primitive(t.primitive);
    case intro::ElementType::Kind::kString:
      return t.string_bound ? "string<=" + std::to_string(t.string_bound) : "string";
    case intro::ElementType::Kind::kStruct:
      return msg_type_ref(*t.struct_type);
  }
  return "";
}

std::string scalar_text(const YAML::Node& n) {
  if (n.IsSequence()) {
    std::string s = "[";
    for (size_t i = 0; i < n.size(); ++i) s += (i ? ", " : "") + scalar_text(n[i]);
    return s + "]";
  }
  return n.as<std::string>();
}

std::string body(const intro::TypeRegistry& reg, const intro::StructType& s) {
  std::ostringstream out;
  for (const intro::Constant* c : reg.constants_of(s.name)) {
    const std::string name = c->name.substr(c->name.rfind("::") + 2);
    std::string type = c->type;
    if (type == "double") type = "float64";
    if (type == "float") type = "float32";
    if (type == "boolean") type = "bool";
    if (type == "octet") type = "byte";
    out << type << " " << name << "=" << c->value << "\n";
  }
  for (const auto& f : s.fields) {
    // rosidl gives an empty message one member, `uint8 structure_needs_at_least_one_member`;
    // the .msg has no field.
    if (f.name == "structure_needs_at_least_one_member") continue;
    std::string type = element(f.type);
    if (f.container == intro::Field::Container::kArray) type += "[" + std::to_string(f.array_size) + "]";
    if (f.container == intro::Field::Container::kSequence)
      type += f.sequence_bound ? "[<=" + std::to_string(f.sequence_bound) + "]" : "[]";
    out << type << " " << f.name;
    if (f.default_value && !f.default_value.IsNull()) out << " " << scalar_text(f.default_value);
    out << "\n";
  }
  return out.str();
}

void collect(const intro::StructType& s, std::vector<const intro::StructType*>& order,
             std::set<const intro::StructType*>& seen) {
  for (const auto& f : s.fields) {
    if (f.type.kind != intro::ElementType::Kind::kStruct) continue;
    const intro::StructType* d = f.type.struct_type;
    if (!seen.insert(d).second) continue;
    order.push_back(d);
    collect(*d, order, seen);
  }
}

}  // namespace

std::string ros2msg_definition(intro::TypeRegistry& registry, const std::string& type_name) {
  const intro::StructType& root = registry.load(type_name);
  std::string text = body(registry, root);
  std::vector<const intro::StructType*> deps;
  std::set<const intro::StructType*> seen{&root};
  collect(root, deps, seen);
  for (const auto* d : deps) {
    // rosbag2 names a dependency as its fields do ("MSG: std_msgs/Header", not std_msgs/msg/Header):
    // Foxglove's parser (@foxglove/rosmsg) resolves a field's type by exactly that name.
    text += std::string(80, '=') + "\nMSG: " + msg_type_ref(*d) + "\n" + body(registry, *d);
  }
  return text;
}

}  // namespace unav::bag
