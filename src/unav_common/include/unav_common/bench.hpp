// The benchmarks' machine-readable line, one figure each: `BENCH <id> <value> <unit>`, printed
// besides their human-readable output and collected by scripts/bench_compare.sh (docs/testing.md,
// "Benchmark history"). id: "<area>/<figure>", no spaces (physics/server_lockstep_x_real_time);
// value: a plain decimal number; unit: a short token (ns, us, ms, fps, steps_per_s, x_real_time).
#pragma once

#include <cstdio>
#include <string>

namespace unav::common {

inline void print_bench(const std::string& id, double value, const char* unit) {
  std::printf("BENCH %s %.4f %s\n", id.c_str(), value, unit);
}

}  // namespace unav::common
