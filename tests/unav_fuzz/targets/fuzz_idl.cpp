// The IDL parser (types of any installed interface package): arbitrary text as
// fuzz_msgs/msg/Fuzz.idl under a root that also holds the real ROS 2 types (includes resolve).
// Malformed IDL must give IdlError / UnknownTypeError naming file and line.
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "fuzz_common.hpp"
#include "unav_introspection/type_registry.hpp"

namespace intro = unav::introspection;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string root = [] {
    std::string r = "/tmp/unav_fuzz_idl_" + std::to_string(getpid());
    std::filesystem::create_directories(r + "/fuzz_msgs/msg");
    return r;
  }();
  const std::string path = root + "/fuzz_msgs/msg/Fuzz.idl";
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  intro::TypeRegistry reg;
  reg.add_root(root);
  reg.add_root(UNAV_WS "/interfaces/ros2_msgs/idl");
  try {
    for (const intro::StructType* t : reg.load_file(path))
      (void)intro::field_type_string(t->fields.empty() ? intro::Field{} : t->fields[0]);
    (void)reg.load("fuzz_msgs/msg/Fuzz");
  } catch (const intro::IdlError&) {
  } catch (const intro::UnknownTypeError&) {
  }
  return 0;
}
