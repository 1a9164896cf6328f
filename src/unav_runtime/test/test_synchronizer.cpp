// Stamp synchronisation policies (message_filters' ExactTime / ApproximateTime), without DDS.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "unav_runtime/synchronizer.hpp"

namespace {
constexpr int64_t kMs = 1000000;
using Pairs = std::vector<std::pair<int, std::string>>;
}  // namespace

TEST(ExactTime, PairsEqualStampsInEitherArrivalOrderAndCountsTheRest) {
  Pairs out;
  unav::sync::ExactTime<int, std::string> sync(3, [&](const int& a, const std::string& b) { out.emplace_back(a, b); });
  sync.add_first(100 * kMs, 1);
  sync.add_second(100 * kMs, "x");  // partner already waiting
  sync.add_second(200 * kMs, "y");  // second stream first this time
  sync.add_first(150 * kMs, 2);     // no partner at 150: waits
  sync.add_first(200 * kMs, 3);     // matches "y"; 150 can never match now
  ASSERT_EQ(out, (Pairs{{1, "x"}, {3, "y"}}));
  EXPECT_EQ(sync.matched(), 2u);
  EXPECT_EQ(sync.dropped(), 1u);
  // A stream running ahead keeps at most queue_size unmatched messages.
  for (int i = 0; i < 5; ++i) sync.add_first((300 + i) * kMs, 10 + i);
  EXPECT_EQ(sync.dropped(), 3u);
  sync.add_second(304 * kMs, "z");  // the newest of the kept three
  EXPECT_EQ(out.back(), (std::pair<int, std::string>{14, "z"}));
}

TEST(ApproximateTime, PairsNearestStampsWithinTheIntervalOnceDecided) {
  Pairs out;
  // A camera at 10 Hz with stamps jittered by up to 3 ms, poses at 100 Hz: each image gets the
  // nearest pose, decided when a pose at or after the image has arrived.
  unav::sync::ApproximateTime<int, std::string> sync(
      100, 5 * kMs, [&](const int& a, const std::string& b) { out.emplace_back(a, b); });
  for (int64_t k = 0; k <= 10; ++k) sync.add_second(k * 10 * kMs, "p" + std::to_string(k * 10));
  sync.add_first(98 * kMs, 1);  // poses up to 100 ms known: nearest is p100 (2 ms)
  ASSERT_EQ(out, (Pairs{{1, "p100"}}));
  sync.add_first(203 * kMs, 2);  // no pose at or after 203 yet: wait
  EXPECT_EQ(out.size(), 1u);
  for (int64_t k = 11; k <= 21; ++k) sync.add_second(k * 10 * kMs, "p" + std::to_string(k * 10));
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out.back(), (std::pair<int, std::string>{2, "p200"}));  // 3 ms away, p210 is 7 ms
  // An image with no pose within 5 ms is dropped, not paired with a far one.
  sync.add_first(256 * kMs, 3);
  for (int64_t k = 22; k <= 27; ++k) sync.add_second(k * 10 * kMs + 9 * kMs, "late");  // 229, 239, ...: 259 is 3 ms off
  EXPECT_EQ(out.back().first, 3);
  Pairs far;
  unav::sync::ApproximateTime<int, std::string> strict(
      10, 1 * kMs, [&](const int& a, const std::string& b) { far.emplace_back(a, b); });
  strict.add_first(100 * kMs, 7);
  strict.add_second(150 * kMs, "q");
  EXPECT_TRUE(far.empty());
  EXPECT_EQ(strict.dropped(), 1u);
}
