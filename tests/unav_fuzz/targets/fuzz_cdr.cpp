// The CDR decoder (`unav topic echo` of whatever arrives on the wire) for every registered type:
// the first two bytes pick the type, the rest is the sample. Malformed samples must give
// CodecError, never a crash, a hang or an out-of-bounds read.
#include <cstdint>
#include <vector>

#include "unav_introspection/cdr_codec.hpp"
#include "unav_introspection/type_registry.hpp"

namespace intro = unav::introspection;

namespace {
struct Types {
  intro::TypeRegistry reg;
  std::vector<const intro::StructType*> all;
  Types() {
    reg.add_root(UNAV_WS "/interfaces/ros2_msgs/idl");
    reg.add_root(UNAV_WS "/interfaces/unav_msgs/idl");
    for (const auto& name : reg.list()) all.push_back(&reg.load(name));
  }
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Types types;
  if (size < 2 || types.all.empty()) return 0;
  const intro::StructType& t = *types.all[(data[0] | (data[1] << 8)) % types.all.size()];
  try {
    const YAML::Node n = intro::decode(t, data + 2, size - 2);
    // What decodes must encode again (the same value, as `unav topic pub` would send it).
    (void)intro::encode(t, n);
  } catch (const intro::CodecError&) {
  }
  try {
    intro::EchoOptions o;
    o.truncate_length = 16;
    (void)intro::to_echo_yaml(t, data + 2, size - 2, o);
  } catch (const intro::CodecError&) {
  }
  return 0;
}
