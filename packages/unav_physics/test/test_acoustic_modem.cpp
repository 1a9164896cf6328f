// The acoustic modem link: travel plus transmission time, one packet at a time per end, limits,
// losses with range, determinism.
#include "unav_physics/acoustic_modem.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using unav::physics::AcousticModem;
using unav::physics::AcousticModemParams;
using End = AcousticModem::End;

namespace {

AcousticModemParams lossless() {
  AcousticModemParams p;
  p.enabled = true;
  p.bit_rate_bps = 100.0;
  p.station_position = Eigen::Vector3d(0.0, 0.0, 1.0);
  p.sound_speed_mps = 1500.0;
  p.loss_at_max_range = 0.0;
  return p;
}

// Steps at 1 kHz to `seconds` with the vehicle's modem at `p_W`; the arrivals.
std::vector<AcousticModem::Packet> run(AcousticModem& m, double from, double seconds, const Eigen::Vector3d& p_W,
                                       int* lost = nullptr) {
  std::vector<AcousticModem::Packet> out;
  for (long k = std::lround(from * 1000.0); k <= std::lround(seconds * 1000.0); ++k) {
    const int l = m.step(1e-3 * static_cast<double>(k), p_W, &out);
    if (lost) *lost += l;
  }
  return out;
}

}  // namespace

// 750 m apart at 1500 m/s: 0.5 s of travel; 10 bytes at 100 bit/s: 0.8 s on the air. A second
// packet from the same end waits for the first (leaves at 0.8 s); the other end sends at the same
// time (each end has its own transducer).
TEST(AcousticModem, ArrivesAfterTravelPlusTransmissionOnePacketAtATime) {
  AcousticModem m(lossless(), 1);
  const Eigen::Vector3d vehicle(0.0, 0.0, 751.0);
  const std::vector<std::uint8_t> ten(10, 0xAB), five{1, 2, 3, 4, 5};
  ASSERT_EQ(m.send(0.0, End::kVehicle, ten), AcousticModem::Send::kQueued);
  ASSERT_EQ(m.send(0.0, End::kVehicle, five), AcousticModem::Send::kQueued);
  ASSERT_EQ(m.send(0.0, End::kStation, five), AcousticModem::Send::kQueued);
  const auto got = run(m, 0.0, 3.0, vehicle);
  ASSERT_EQ(got.size(), 3u);            // in arrival order
  EXPECT_EQ(got[0].to, End::kVehicle);  // 5 bytes from the station at 0: 0.5 + 0.4
  EXPECT_NEAR(got[0].arrival, 0.9, 1e-12);
  EXPECT_EQ(got[0].data, five);
  EXPECT_EQ(got[1].to, End::kStation);  // 10 bytes from the vehicle: 0.5 + 0.8
  EXPECT_NEAR(got[1].arrival, 1.3, 1e-12);
  EXPECT_EQ(got[1].data, ten);
  EXPECT_DOUBLE_EQ(got[1].range_m, 750.0);
  EXPECT_EQ(got[2].to, End::kStation);  // then 5 more from 0.8 s, when the first is out: 0.8 + 0.5 + 0.4
  EXPECT_NEAR(got[2].arrival, 1.7, 1e-12);
}

TEST(AcousticModem, LimitsAndRange) {
  AcousticModemParams p = lossless();
  p.max_packet_bytes = 8;
  p.queue_packets = 2;
  p.max_range_m = 500.0;
  AcousticModem m(p, 1);
  EXPECT_EQ(m.send(0.0, End::kVehicle, std::vector<std::uint8_t>(9)), AcousticModem::Send::kTooLong);
  EXPECT_EQ(m.send(0.0, End::kVehicle, {1}), AcousticModem::Send::kQueued);
  EXPECT_EQ(m.send(0.0, End::kVehicle, {2}), AcousticModem::Send::kQueued);
  EXPECT_EQ(m.send(0.0, End::kVehicle, {3}), AcousticModem::Send::kQueueFull);
  int lost = 0;
  EXPECT_TRUE(run(m, 0.0, 2.0, Eigen::Vector3d(600.0, 0.0, 1.0), &lost).empty());  // beyond range
  EXPECT_EQ(lost, 2);
}

// Losses at 0.7071 of max range with loss_at_max_range 0.5: probability 0.25 (binomial sigma
// over 2000 packets 0.0097: +-0.05 is 5 sigma). The same seed loses the same packets.
TEST(AcousticModem, LossesGrowWithRangeAndRepeatPerSeed) {
  AcousticModemParams p = lossless();
  p.bit_rate_bps = 1e5;
  p.max_range_m = 100.0 / 0.70710678;
  p.loss_at_max_range = 0.5;
  const auto lost_of = [&](std::uint64_t seed) {
    AcousticModem m(p, seed);
    std::vector<bool> arrived;
    for (int i = 0; i < 2000; ++i) {
      EXPECT_EQ(m.send(0.1 * i, End::kStation, {static_cast<std::uint8_t>(i & 0xFF)}), AcousticModem::Send::kQueued);
      std::vector<AcousticModem::Packet> out;
      m.step(0.1 * i, Eigen::Vector3d(60.0, 80.0, 1.0), &out);
      m.step(0.1 * i + 0.09, Eigen::Vector3d(60.0, 80.0, 1.0), &out);
      arrived.push_back(!out.empty());
    }
    return arrived;
  };
  const std::vector<bool> a = lost_of(5), b = lost_of(5), c = lost_of(6);
  const double share = 1.0 - static_cast<double>(std::count(a.begin(), a.end(), true)) / static_cast<double>(a.size());
  EXPECT_NEAR(share, 0.25, 0.05);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}
