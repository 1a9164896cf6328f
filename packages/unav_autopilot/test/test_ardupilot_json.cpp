// The ArduPilot JSON backend's protocol (ardupilot_json.hpp) with a scripted peer that sends servo
// packets as ArduPilot's documentation describes them: both magics, repeats, restarts, malformed
// packets, the reply's fields, units and frames, and lockstep determinism.
#include "unav_autopilot/ardupilot_json.hpp"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "unav_physics/vehicle.hpp"

namespace ua = unav::autopilot;
using nlohmann::json;

namespace {

const std::string kRoot = UNAV_REPO_ROOT;
const std::string kMap = kRoot + "/config/autopilot/ardusub_bluerov2_heavy.yaml";

// A scenario at rest at 5 m depth over a flat seabed at 9 m.
unav::scene::Scenario scenario() {
  const std::string dir = ::testing::TempDir() + "unav_ardupilot_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/world.yaml") << "seabed: {depth_m: 9.0}\n";
  std::ofstream(dir + "/scenario.yaml") << "world: world.yaml\nvehicle: {initial_position: [2.0, -1.0, 5.0]}\n";
  return unav::scene::load_scenario(dir + "/scenario.yaml");
}

ua::JsonBackend backend() {
  const auto s = scenario();
  return ua::JsonBackend(s, unav::scene::load_world(s.world), ua::load_motor_map(kMap), kMap);
}

std::string send(ua::JsonBackend& b, std::uint32_t frame, const std::vector<std::uint16_t>& pwm,
                 std::uint16_t rate = 1000) {
  const auto p = ua::encode_servo_packet(rate, frame, pwm);
  return b.handle(p.data(), p.size());
}

json parse(const std::string& reply) {
  EXPECT_GE(reply.size(), 2u);
  EXPECT_EQ(reply.front(), '\n');  // framed by "\n" before and after
  EXPECT_EQ(reply.back(), '\n');
  EXPECT_EQ(reply.find(' '), std::string::npos) << "compact: no spaces";
  return json::parse(reply.substr(1, reply.size() - 2));
}

const std::vector<std::uint16_t> kNeutral(16, 1500);

}  // namespace

TEST(ArduPilotJson, RestAtFiveMetresReadsGravityAndDepth) {
  auto b = backend();
  const json j = parse(send(b, 0, kNeutral));
  // Neutral PWM, neutral buoyancy, at rest: the accelerometer reads -g along body z (FRD),
  // exactly (nothing moves in 1 ms of zero thrust).
  EXPECT_DOUBLE_EQ(j["timestamp"].get<double>(), 0.001);
  const auto acc = j["imu"]["accel_body"].get<std::vector<double>>();
  EXPECT_NEAR(acc[0], 0.0, 1e-9);
  EXPECT_NEAR(acc[1], 0.0, 1e-9);
  EXPECT_NEAR(acc[2], -9.81, 1e-9);
  EXPECT_EQ(j["imu"]["gyro"].get<std::vector<double>>(), std::vector<double>({0, 0, 0}));
  const auto pos = j["position"].get<std::vector<double>>();
  EXPECT_DOUBLE_EQ(pos[0], 2.0);
  EXPECT_DOUBLE_EQ(pos[1], -1.0);
  EXPECT_NEAR(pos[2], 5.0, 1e-9);  // NED from home at the surface: down = depth
  EXPECT_EQ(j["quaternion"].get<std::vector<double>>(), std::vector<double>({1, 0, 0, 0}));
  EXPECT_EQ(j["attitude"].size(), 3u);
  EXPECT_EQ(j["velocity"].size(), 3u);
  EXPECT_NEAR(j["rng_1"].get<double>(), 4.0, 1e-9);  // the seabed 4 m below
}

TEST(ArduPilotJson, FullForwardAcceleratesAlongBodyX) {
  auto b = backend();
  // ArduSub's forward factors of vectored_6dof: M1, M2 -1; M3, M4 +1 (full: 1100 / 1900 us).
  std::vector<std::uint16_t> pwm = kNeutral;
  pwm[0] = 1100;
  pwm[1] = 1100;
  pwm[2] = 1900;
  pwm[3] = 1900;
  json j;
  for (std::uint32_t f = 0; f < 500; ++f) j = parse(send(b, f, pwm));
  EXPECT_NEAR(j["timestamp"].get<double>(), 0.5, 1e-9);
  const auto acc = j["imu"]["accel_body"].get<std::vector<double>>();
  const auto vel = j["velocity"].get<std::vector<double>>();
  // Four T200 at 45 deg: ~4 x 40 N x 0.707 = 113 N forward on 13.5 + 6.4 kg; after the thrusters'
  // spin-up (0.1 s) and 0.5 s of drag the vehicle moves north at several dm/s, not sideways.
  EXPECT_GT(acc[0], 0.5);
  EXPECT_GT(vel[0], 0.5);
  EXPECT_LT(std::abs(vel[1]), 1e-6 + 1e-3 * vel[0]);
  EXPECT_GT(b.simulator().state().v_WB_B.x(), 0.5);
  for (int i = 0; i < 4; ++i) EXPECT_DOUBLE_EQ(std::abs(b.command()[static_cast<std::size_t>(i)]), 1.0);
}

TEST(ArduPilotJson, BothMagicsAndTheVerticalMotorsDive) {
  auto b = backend();
  std::vector<std::uint16_t> pwm32(32, 1500);
  for (int k = 4; k < 8; ++k) pwm32[static_cast<std::size_t>(k)] = 1900;  // throttle factor -1: > 1500 dives
  json j;
  for (std::uint32_t f = 0; f < 1000; ++f) j = parse(send(b, f, pwm32));
  EXPECT_EQ(b.stats().frames, 1000u);
  EXPECT_GT(j["position"][2].get<double>(), 5.1) << "deeper after 1 s of dive thrust";
  EXPECT_GT(j["velocity"][2].get<double>(), 0.2);
}

TEST(ArduPilotJson, LockstepOnePacketOneStepAndRepeatable) {
  auto run = [] {
    auto b = backend();
    std::string last;
    for (std::uint32_t f = 0; f < 2000; ++f) {
      std::vector<std::uint16_t> pwm = kNeutral;
      pwm[static_cast<std::size_t>(f % 8)] = static_cast<std::uint16_t>(1500 + (f % 7) * 50);
      last = send(b, f, pwm);
    }
    EXPECT_EQ(b.stats().steps, 2000u);  // N packets at 1 kHz = N ms of physics
    EXPECT_NEAR(b.simulator().time(), 2.0, 1e-9);
    return last;
  };
  EXPECT_EQ(run(), run());  // bit for bit
  // At 400 Hz a frame is 2.5 steps: whole steps, the remainder carried (2, 3, 2, 3, ...).
  auto b = backend();
  for (std::uint32_t f = 0; f < 400; ++f) send(b, f, kNeutral, 400);
  EXPECT_EQ(b.stats().steps, 1000u);
  EXPECT_NEAR(b.simulator().time(), 1.0, 1e-9);
}

TEST(ArduPilotJson, RepeatsAreAnsweredWithoutSteppingAndARestartResets) {
  auto b = backend();
  std::vector<std::uint16_t> pwm = kNeutral;
  for (int k = 4; k < 8; ++k) pwm[static_cast<std::size_t>(k)] = 1800;
  std::string r;
  for (std::uint32_t f = 0; f < 300; ++f) r = send(b, f, pwm);
  const double t = b.simulator().time();
  // SITL resends its last frame after 10 s without an answer: same reply, no physics.
  EXPECT_EQ(send(b, 299, pwm), r);
  EXPECT_EQ(send(b, 299, kNeutral), r);
  EXPECT_EQ(b.simulator().time(), t);
  EXPECT_EQ(b.stats().repeats, 2u);
  // SITL restarted: frame_count back to 0 -> the scenario's initial state at time 0.
  const json j = parse(send(b, 0, kNeutral));
  EXPECT_EQ(b.stats().resets, 1u);
  EXPECT_DOUBLE_EQ(j["timestamp"].get<double>(), 0.001);
  EXPECT_NEAR(j["position"][2].get<double>(), 5.0, 1e-9);
  // A jump in frame_count (lost packets) is counted; still one frame of physics.
  send(b, 5, kNeutral);
  EXPECT_EQ(b.stats().gaps, 1u);
  EXPECT_NEAR(b.simulator().time(), 0.002, 1e-12);
}

TEST(ArduPilotJson, MalformedPacketsAreCountedAndDropped) {
  auto b = backend();
  send(b, 0, kNeutral);
  const double t = b.simulator().time();
  auto good = ua::encode_servo_packet(1000, 1, kNeutral);
  EXPECT_EQ(b.handle(good.data(), 7), "");  // short header
  EXPECT_EQ(b.last_status(), ua::PacketStatus::kShort);
  EXPECT_EQ(b.handle(good.data(), 39), "");  // 16 channels need 40 bytes
  auto bad_magic = good;
  bad_magic[0] = 0x12;
  EXPECT_EQ(b.handle(bad_magic.data(), bad_magic.size()), "");
  EXPECT_EQ(b.last_status(), ua::PacketStatus::kUnknownMagic);
  auto zero_rate = ua::encode_servo_packet(0, 1, kNeutral);
  EXPECT_EQ(b.handle(zero_rate.data(), zero_rate.size()), "");
  EXPECT_EQ(b.last_status(), ua::PacketStatus::kZeroFrameRate);
  std::vector<std::uint16_t> wild = kNeutral;
  wild[2] = 2400;
  auto out_of_range = ua::encode_servo_packet(1000, 1, wild);
  EXPECT_EQ(b.handle(out_of_range.data(), out_of_range.size()), "");
  EXPECT_EQ(b.last_status(), ua::PacketStatus::kPwmOutOfRange);
  // A channel past the motors may hold anything; a motor channel at 0 is "no output".
  std::vector<std::uint16_t> idle = kNeutral;
  idle[0] = 0;
  idle[12] = 65000;
  EXPECT_NE(send(b, 1, idle), "");
  EXPECT_EQ(b.command()[0], 0.0);
  EXPECT_EQ(b.stats().dropped_total(), 5u);
  EXPECT_EQ(b.stats().dropped[static_cast<std::size_t>(ua::PacketStatus::kShort)], 2u);
  EXPECT_NEAR(b.simulator().time(), t + 0.001, 1e-12) << "nothing dropped was integrated";
}

TEST(ArduPilotJson, AMotorMapThatDoesNotFitTheVehicleIsRefused) {
  const auto vehicle = unav::physics::load_vehicle(kRoot + "/config/vehicles/bluerov2_heavy.yaml");
  ua::MotorMap m = ua::load_motor_map(kMap);
  EXPECT_NO_THROW(ua::check_motor_map(m, vehicle, "map.yaml"));
  auto error_of = [&](const ua::MotorMap& bad) {
    try {
      ua::check_motor_map(bad, vehicle, "map.yaml");
    } catch (const unav::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  ua::MotorMap flipped = m;
  flipped.motors[0].direction = 1;
  EXPECT_EQ(error_of(flipped).rfind("map.yaml: motors[0] = T1 direction 1: motor 1 of ArduSub's vectored_6dof has yaw "
                                    "factor +1, but this thruster's yaw effect is",
                                    0),
            0u)
      << error_of(flipped);
  ua::MotorMap swapped = m;
  std::swap(swapped.motors[4], swapped.motors[5]);  // front right and front left vertical swapped
  EXPECT_NE(error_of(swapped).find("motor 5 of ArduSub's vectored_6dof has roll factor +1"), std::string::npos);
  ua::MotorMap unknown = m;
  unknown.motors[7].thruster = "T9";
  EXPECT_EQ(error_of(unknown),
            "map.yaml: motors[7].thruster = T9: no thruster of that name in bluerov2_heavy (T1, T2, "
            "T3, T4, T5, T6, T7, T8)");
  ua::MotorMap twice = m;
  twice.motors[7].thruster = "T7";
  EXPECT_NE(error_of(twice).find("drives a thruster another motor drives too"), std::string::npos);
  ua::MotorMap short_map = m;
  short_map.motors.pop_back();
  EXPECT_EQ(error_of(short_map),
            "map.yaml: motors = 7 motors: the vectored_6dof frame drives 8 (M1-M4 horizontal, M5-M8 vertical)");
}
