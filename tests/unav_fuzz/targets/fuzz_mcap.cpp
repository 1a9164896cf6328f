// The bag reader (`unav bag info|play`, `unav eval --format bag`) on arbitrary .mcap bytes: must
// give BagError, never a crash, a hang or an allocation driven by a forged size.
#include "fuzz_common.hpp"
#include "unav_bag/bag.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = unav::fuzz::write_input(data, size, ".mcap");
  try {
    unav::bag::BagReader r(path);
    unav::bag::Message m;
    size_t n = 0;
    while (r.next(m) && n < 100000) ++n;
    (void)unav::bag::to_metadata_yaml(r.info());
    for (const auto& t : r.topics()) (void)unav::bag::parse_offered_qos_yaml(t.offered_qos_profiles);
  } catch (const unav::bag::BagError&) {
  }
  return 0;
}
