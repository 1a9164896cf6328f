// The message of what a callable throws, for tests that check that an error names its file, key,
// value and rule.
#pragma once

#include <exception>
#include <string>
#include <utility>

namespace unav::common {

/// what() of the E that f() throws; "" when it throws nothing (any other exception propagates).
template <class E = std::exception, class F>
std::string thrown_message(F&& f) {
  try {
    std::forward<F>(f)();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

}  // namespace unav::common
