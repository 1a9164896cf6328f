// Finds, parses and holds IDL struct types at run time.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "unav_introspection/type_description.hpp"

namespace unav::introspection {

/// An IDL file could not be read or parsed; what() is "file:line: message".
class IdlError : public std::runtime_error {
 public:
  IdlError(const std::string& file, int line, const std::string& message);
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

/// A type name is malformed or no IDL file under the registered roots declares it.
class UnknownTypeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An IDL `const` declaration (also those inside `module X_Constants { ... }`).
struct Constant {
  std::string name;   ///< fully scoped, e.g. "sensor_msgs::msg::Range_Constants::ULTRASOUND"
  std::string type;   ///< IDL type as written, e.g. "uint8", "string"
  std::string value;  ///< literal as written, string literals without quotes
};

/// Converts "sensor_msgs::msg::dds_::Image_" to "sensor_msgs/msg/Image" (also accepts names
/// without the `dds_` module). Throws UnknownTypeError on a malformed name.
std::string dds_to_ros_name(const std::string& dds_name);

/// Converts "sensor_msgs/msg/Image" or "sensor_msgs/Image" to "sensor_msgs::msg::dds_::Image_".
/// Throws UnknownTypeError on a malformed name.
std::string ros_to_dds_name(const std::string& ros_name);

/// The install root of the running executable: /proc/self/exe with `levels` trailing path parts
/// removed (3 for <install>/<pkg>/bin/tool, 4 for <install>/<pkg>/lib/<pkg>/tool); "" if unknown.
std::string executable_install_root(int levels);

/// Parsed IDL types, loaded lazily from IDL roots laid out as `<root>/<pkg>/msg/<Type>.idl`.
/// Type names may be given as DDS names ("std_msgs::msg::dds_::Header_"), ROS names
/// ("std_msgs/msg/Header") or short ROS names ("std_msgs/Header").
/// StructType pointers and references stay valid for the registry's lifetime. Not thread-safe.
class TypeRegistry {
 public:
  TypeRegistry();
  ~TypeRegistry();
  TypeRegistry(TypeRegistry&&) noexcept;
  TypeRegistry& operator=(TypeRegistry&&) noexcept;
  TypeRegistry(const TypeRegistry&) = delete;
  TypeRegistry& operator=(const TypeRegistry&) = delete;

  /// Adds an IDL root; roots are searched in the order added.
  void add_root(const std::string& path);

  /// Adds every `<prefix>/share/<package>/idl` folder of an install prefix; returns how many.
  size_t add_install_prefix(const std::string& prefix);

  /// The workspace's interface types as the tools find them: for every prefix in the environment
  /// (UNAV_IDL_PREFIXES, AMENT_PREFIX_PATH, CMAKE_PREFIX_PATH, COLCON_PREFIX_PATH) and for
  /// `install_root` (a tool's own install, so it works before sourcing setup.bash; "" = none),
  /// the prefix itself and its ros2_msgs and unav_msgs sub-prefixes (a colcon install root holds
  /// one prefix per package). Returns how many IDL roots were added.
  size_t add_workspace(const std::string& install_root);

  const std::vector<std::string>& roots() const;

  /// The struct named `type_name`, parsing its IDL file (and includes) on first use.
  /// Throws UnknownTypeError naming the type and the roots searched, or IdlError.
  const StructType& load(const std::string& type_name);

  /// Parses one IDL file (and its includes) and returns the structs it declares, in order.
  /// Throws IdlError.
  std::vector<const StructType*> load_file(const std::string& path);

  /// The already loaded struct named `type_name`, or nullptr.
  const StructType* find(const std::string& type_name) const;

  /// The already loaded constant with this fully scoped name, or nullptr.
  const Constant* find_constant(const std::string& scoped_name) const;

  /// The loaded constants declared with a message type, e.g. for "sensor_msgs/msg/Range" those of
  /// `sensor_msgs::msg::Range_Constants`, sorted by name. Empty when the type declares none.
  std::vector<const Constant*> constants_of(const std::string& type_name) const;

  /// ROS names ("std_msgs/msg/Header") of all `<pkg>/<kind>/<Type>.idl` files under the roots,
  /// sorted, without duplicates. Does not parse them.
  std::vector<std::string> list() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace unav::introspection
