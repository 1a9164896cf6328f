// Data-sharing delivery of images between processes: a camera-like writer with a bound, a reader
// in another process that asks for data-sharing and one that does not (it stands for ROS 2,
// Cyclone or any plain reader of the unbounded type). Both get every image byte-exact; only the
// first reads through a data-sharing segment. Fast DDS must not run in a process that forks, so
// the readers are this executable started again (posix_spawn) in its helper mode:
//   test_data_sharing --reader plain|shared DOMAIN COUNT OUTFILE
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include "sensor_msgs/msg/image.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/shm_cleanup.hpp"
#include "unav_runtime/testing.hpp"

extern char** environ;  // NOLINT(readability-redundant-declaration): posix_spawn's environment

using namespace std::chrono_literals;

namespace {

constexpr int kImages = 20;
// History deeper than the stream: a reader delayed on a loaded machine loses nothing (keep last).
constexpr int32_t kDepth = kImages + 2;

// The image number `i` of the stream: 640x480 rgb8, content a function of (i, byte index).
sensor_msgs::msg::Image make_image(int i, uint32_t height = 480) {
  sensor_msgs::msg::Image img;
  img.header().frame_id("camera_front_optical");
  img.header().stamp().sec(i);
  img.height(height);
  img.width(640);
  img.encoding("rgb8");
  img.step(1920);
  img.data().resize(size_t{1920} * height);
  for (size_t k = 0; k < img.data().size(); ++k)
    img.data()[k] = static_cast<uint8_t>((k * 7u + static_cast<size_t>(i) * 13u) >> 3);
  return img;
}

// Fast DDS names the shared-memory segment of a data-sharing endpoint after its GUID: a writer's
// payload pool, a reader's notification segment (DataSharingNotification::generate_segment_name).
bool has_data_sharing_segment(const eprosima::fastrtps::rtps::GUID_t& guid) {
  std::ostringstream name;
  name << "/dev/shm/fast_datasharing_" << guid.guidPrefix << "_" << guid.entityId;
  return std::filesystem::exists(name.str());
}

unav::ContextOptions options_on(int domain) {
  unav::ContextOptions o;
  o.domain_id = domain;
  o.handle_signals = false;
  return o;
}

// Helper mode: subscribe, wait for the writer, check every image, report
// "<received> <intact> <data-sharing segment 0|1>" into `out`.
int run_reader(bool shared, int domain, int count, const std::string& out) {
  unav::Context ctx(options_on(domain));
  unav::Node node(shared ? "shared_reader" : "plain_reader", {&ctx});
  int received = 0, intact = 0;
  auto sub = node.create_subscription<sensor_msgs::msg::Image>(
      "/camera/image_raw", shared ? unav::QoS::reliable(kDepth).with_data_sharing() : unav::QoS::reliable(kDepth),
      [&](const sensor_msgs::msg::Image& m) {
        ++received;
        if (m.data() == make_image(m.header().stamp().sec()).data() && m.encoding() == "rgb8") ++intact;
      });
  const bool segment = has_data_sharing_segment(sub->reader()->guid());
  ctx.spin_until([&] { return received >= count; }, 60s);
  std::ofstream(out) << received << " " << intact << " " << (segment ? 1 : 0) << "\n";
  return 0;
}

std::string segment_name(const eprosima::fastrtps::rtps::GUID_t& guid) {
  std::ostringstream name;
  name << "fast_datasharing_" << guid.guidPrefix << "_" << guid.entityId;
  return name.str();
}

// Helper mode: a data-sharing image writer that writes its pool's segment name into `out` and
// then waits to be killed.
int run_writer(int domain, const std::string& out) {
  unav::Context ctx(options_on(domain));
  unav::Node cam("doomed_camera", {&ctx});
  auto pub = cam.create_publisher<sensor_msgs::msg::Image>(
      "/camera/image_raw", unav::QoS::reliable(4).with_data_sharing(unav::serialized_bytes(make_image(0))));
  pub->publish(make_image(0));
  { std::ofstream(out + ".tmp") << segment_name(pub->writer()->guid()) << "\n"; }
  std::filesystem::rename(out + ".tmp", out);
  std::this_thread::sleep_for(300s);
  return 0;
}

pid_t spawn_reader(const char* mode, int domain, const std::string& out) {
  const std::string d = std::to_string(domain), n = std::to_string(kImages);
  const char* argv[] = {"/proc/self/exe", "--reader", mode, d.c_str(), n.c_str(), out.c_str(), nullptr};
  pid_t pid = -1;
  if (posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, const_cast<char* const*>(argv), environ) != 0) return -1;
  return pid;
}

}  // namespace

TEST(DataSharing, PlainAndSharedReadersInOtherProcessesGetEveryImage) {
  unav::Context ctx(unav::testing::test_context_options());
  unav::Node cam("camera", {&ctx});
  const auto proto = make_image(0);
  auto pub = cam.create_publisher<sensor_msgs::msg::Image>(
      "/camera/image_raw", unav::QoS::reliable(kDepth).with_data_sharing(unav::serialized_bytes(proto)));
  // The type on the wire is ROS 2's: rmw_fastrtps and Cyclone readers match it by this name.
  EXPECT_EQ(pub->writer()->get_topic()->get_type_name(), "sensor_msgs::msg::dds_::Image_");
  EXPECT_TRUE(has_data_sharing_segment(pub->writer()->guid())) << "the writer has no data-sharing pool";

  const std::string dir = ::testing::TempDir();
  const std::string plain_out = dir + "/ds_plain_" + std::to_string(getpid());
  const std::string shared_out = dir + "/ds_shared_" + std::to_string(getpid());
  const pid_t plain = spawn_reader("plain", ctx.domain_id(), plain_out);
  const pid_t shared = spawn_reader("shared", ctx.domain_id(), shared_out);
  ASSERT_GT(plain, 0);
  ASSERT_GT(shared, 0);
  // Both readers matched from the writer's side; each reader waits for its own side (it counts
  // the writer before it reports), and reliable delivery repairs a sample sent in between.
  const auto until = std::chrono::steady_clock::now() + 60s;
  while (pub->subscription_count() < 2 && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(20ms);
  ASSERT_EQ(pub->subscription_count(), 2);
  std::this_thread::sleep_for(500ms);  // the readers' side of the match (see testing.hpp)

  // A sample over the bound does not fit the shared pool: refused, and the stream goes on.
  EXPECT_FALSE(pub->publish(make_image(99, 481)));
  for (int i = 0; i < kImages; ++i) {
    ASSERT_TRUE(pub->publish(make_image(i))) << "image " << i;
    std::this_thread::sleep_for(30ms);  // a 30 Hz camera
  }
  int status = 0;
  ASSERT_EQ(waitpid(plain, &status, 0), plain);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_EQ(waitpid(shared, &status, 0), shared);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  int received = 0, intact = 0, segment = -1;
  std::ifstream(plain_out) >> received >> intact >> segment;
  EXPECT_EQ(received, kImages) << "plain reader";
  EXPECT_EQ(intact, kImages) << "plain reader";
  EXPECT_EQ(segment, 0) << "the plain reader must take the transports";
  std::ifstream(shared_out) >> received >> intact >> segment;
  EXPECT_EQ(received, kImages) << "shared reader";
  EXPECT_EQ(intact, kImages) << "shared reader";
  EXPECT_EQ(segment, 1) << "the shared reader has no data-sharing segment";
  std::filesystem::remove(plain_out);
  std::filesystem::remove(shared_out);
}

TEST(DataSharing, OffByOptionKeepsUnboundedTransport) {
  auto o = unav::testing::test_context_options();
  o.data_sharing = false;  // what UNAV_DATA_SHARING=off does
  unav::Context ctx(o);
  unav::Node cam("camera", {&ctx});
  auto pub = cam.create_publisher<sensor_msgs::msg::Image>(
      "/camera/image_raw", unav::QoS::reliable(10).with_data_sharing(unav::serialized_bytes(make_image(0))));
  EXPECT_FALSE(has_data_sharing_segment(pub->writer()->guid()));
  EXPECT_TRUE(pub->publish(make_image(1, 481)));  // no pool, no bound
  // Refused out of resources twice over 0.6 s: a transports writer has no payload pool to be
  // stuck in, so it is kept (only a data-sharing writer is created again).
  const auto guid = pub->writer()->guid();
  pub->refuse_writes_for_test(2);
  EXPECT_FALSE(pub->publish(make_image(2)));
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  EXPECT_FALSE(pub->publish(make_image(3)));
  EXPECT_EQ(pub->writer_recreations(), 0);
  EXPECT_EQ(pub->writer()->guid(), guid);
}

TEST(DataSharing, WriterWithoutABoundIsAConfigError) {
  unav::Context ctx(unav::testing::test_context_options());
  unav::Node cam("camera", {&ctx});
  try {
    cam.create_publisher<sensor_msgs::msg::Image>("/camera/image_raw", unav::QoS::reliable().with_data_sharing());
    FAIL() << "accepted a data-sharing writer without max_sample_bytes";
  } catch (const unav::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("rt/camera/image_raw"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("max_sample_bytes"), std::string::npos) << e.what();
  }
}

TEST(DataSharing, SerializedBytesIsTheCdrSize) {
  // 640x480 rgb8 with a 20-character frame id: header (8 + 4 + 21 + pad 3) + height, width (8)
  // + encoding (4 + 5) + is_bigendian (1 + pad 2) + step (4) + data (4 + 921600).
  EXPECT_EQ(unav::serialized_bytes(make_image(0)), 8u + 4 + 21 + 3 + 8 + 4 + 5 + 1 + 2 + 4 + 4 + 921600);
}

// A writer SIGKILLed leaves its pool in /dev/shm (Fast DDS 2.9 never removes it); the next
// participant on the host removes it (Context: shm::clean_data_sharing), and only it: a live
// writer's pool stays.
TEST(DataSharing, DeadWritersPoolIsRemovedAndLiveOnesKept) {
  unav::Context ctx(unav::testing::test_context_options());
  unav::Node cam("camera", {&ctx});
  auto pub = cam.create_publisher<sensor_msgs::msg::Image>(
      "/camera/image_raw", unav::QoS::reliable(4).with_data_sharing(unav::serialized_bytes(make_image(0))));
  const std::string live = segment_name(pub->writer()->guid());
  const std::string ready = ::testing::TempDir() + "/ds_writer_" + std::to_string(getpid());
  const std::string d = std::to_string(ctx.domain_id());
  const char* argv[] = {"/proc/self/exe", "--writer", d.c_str(), ready.c_str(), nullptr};
  pid_t pid = -1;
  ASSERT_EQ(posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, const_cast<char* const*>(argv), environ), 0);
  const auto until = std::chrono::steady_clock::now() + 60s;
  while (!std::filesystem::exists(ready) && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(20ms);
  ASSERT_TRUE(std::filesystem::exists(ready)) << "the writer did not start";
  std::string doomed;
  std::ifstream(ready) >> doomed;
  std::filesystem::remove(ready);
  ASSERT_TRUE(std::filesystem::exists("/dev/shm/" + doomed)) << doomed;
  const auto parsed = unav::shm::parse_data_sharing_name(doomed);
  ASSERT_TRUE(parsed.has_value()) << doomed;
  EXPECT_EQ(parsed->pid16, static_cast<std::uint16_t>(pid & 0xFFFF));
  kill(pid, SIGKILL);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(std::filesystem::exists("/dev/shm/" + doomed)) << "Fast DDS removed it itself: nothing to clean";
  const auto& prefix = ctx.participant()->guid().guidPrefix.value;
  const unav::shm::CleanReport r =
      unav::shm::clean_data_sharing("/dev/shm", false, std::array<std::uint8_t, 2>{prefix[2], prefix[3]});
  EXPECT_FALSE(std::filesystem::exists("/dev/shm/" + doomed)) << "the dead writer's pool is still there";
  EXPECT_TRUE(std::filesystem::exists("/dev/shm/" + live)) << "a live writer's pool was removed";
  EXPECT_GE(r.removed, 1);
  EXPECT_GT(r.removed_bytes, 900000u) << "an image pool is ~1 MB a sample";
  EXPECT_TRUE(r.errors.empty());
  EXPECT_TRUE(pub->publish(make_image(1)));  // the live writer goes on
}

TEST(DataSharing, SegmentNamesAndDeadOwnersInAFolder) {
  EXPECT_FALSE(unav::shm::parse_data_sharing_name("fastrtps_port7411").has_value());
  EXPECT_FALSE(unav::shm::parse_data_sharing_name("fast_datasharing_zz.0f.78.fd.6c.6e.1c.75.00.00.00.00_0.0.4.3"));
  const auto s = unav::shm::parse_data_sharing_name("fast_datasharing_01.0f.78.fd.6c.6e.1c.75.01.00.00.00_0.0.4.3");
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->pid16, 0x6e6c);
  EXPECT_EQ(s->host[0], 0x78);
  EXPECT_EQ(s->host[1], 0xfd);
  // A folder with the segment of this (live) process and one of a process that has exited.
  const std::string dir = ::testing::TempDir() + "/shm_" + std::to_string(getpid());
  std::filesystem::create_directories(dir);
  auto name_for = [](pid_t p, int host) {
    char n[96];
    std::snprintf(n, sizeof(n), "fast_datasharing_01.0f.%02x.fd.%02x.%02x.1c.75.00.00.00.00_0.0.4.3", host,
                  static_cast<unsigned>(p & 0xFF), static_cast<unsigned>((p >> 8) & 0xFF));
    return std::string(n);
  };
  pid_t gone = -1;
  const char* argv[] = {"/bin/true", nullptr};
  ASSERT_EQ(posix_spawn(&gone, "/bin/true", nullptr, nullptr, const_cast<char* const*>(argv), environ), 0);
  int status = 0;
  ASSERT_EQ(waitpid(gone, &status, 0), gone);
  // Its pid's low 16 bits may belong to another live process (then it is kept: conservative).
  const bool gone_is_free = !unav::shm::live_pid16()[static_cast<std::size_t>(gone & 0xFFFF)];
  for (const auto& n : {name_for(getpid(), 0x78), name_for(gone, 0x78), name_for(gone, 0x11)})
    std::ofstream(dir + "/" + n) << std::string(1000, 'x');
  const auto dry = unav::shm::clean_data_sharing(dir, true, std::array<std::uint8_t, 2>{0x78, 0xfd});
  EXPECT_EQ(dry.segments.size(), 3u);
  EXPECT_EQ(dry.removed, 0);
  EXPECT_TRUE(std::filesystem::exists(dir + "/" + name_for(gone, 0x78)));
  const auto r = unav::shm::clean_data_sharing(dir, false, std::array<std::uint8_t, 2>{0x78, 0xfd});
  EXPECT_TRUE(std::filesystem::exists(dir + "/" + name_for(getpid(), 0x78))) << "a live owner's segment";
  EXPECT_TRUE(std::filesystem::exists(dir + "/" + name_for(gone, 0x11))) << "another host id's segment";
  EXPECT_EQ(std::filesystem::exists(dir + "/" + name_for(gone, 0x78)), !gone_is_free);
  EXPECT_EQ(r.removed, gone_is_free ? 1 : 0);
  std::filesystem::remove_all(dir);
}

int main(int argc, char** argv) {
  if (argc == 4 && std::string(argv[1]) == "--writer") return run_writer(std::stoi(argv[2]), argv[3]);
  if (argc == 6 && std::string(argv[1]) == "--reader")
    return run_reader(std::string(argv[2]) == "shared", std::stoi(argv[3]), std::stoi(argv[4]), argv[5]);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

// A data-sharing writer refused out of resources twice in a row over 0.5 s is deleted and created
// again, and its readers match the new one. (The stall it answers, a pool that stays full with
// several data-sharing readers, is Fast DDS's and not reproducible on demand: the refusals are
// injected.)
TEST(DataSharing, WriterStuckOutOfResourcesIsCreatedAgain) {
  unav::Context ctx(unav::testing::test_context_options());
  unav::Node cam("camera", {&ctx});
  unav::Node viewer("viewer", {&ctx});
  std::atomic<int> received{0};
  auto pub = cam.create_publisher<sensor_msgs::msg::Image>(
      "/camera/image_raw", unav::QoS::reliable(4).with_data_sharing(unav::serialized_bytes(make_image(0))));
  auto sub = viewer.create_subscription<sensor_msgs::msg::Image>(
      "/camera/image_raw", unav::QoS::reliable(4).with_data_sharing(),
      [&](const sensor_msgs::msg::Image& m) { received += m.data() == make_image(7).data() ? 1 : 0; });
  ASSERT_TRUE(ctx.spin_until([&] { return pub->subscription_count() == 1 && sub->publisher_count() == 1; }, 30s));
  const auto guid = pub->writer()->guid();

  EXPECT_FALSE(pub->publish(make_image(1, 481)));  // over the bound: an error, not out of resources
  std::this_thread::sleep_for(600ms);
  EXPECT_FALSE(pub->publish(make_image(2, 481)));
  EXPECT_EQ(pub->writer_recreations(), 0);
  EXPECT_TRUE(pub->publish(make_image(0)));

  pub->refuse_writes_for_test(2);
  EXPECT_FALSE(pub->publish(make_image(1)));
  EXPECT_EQ(pub->writer_recreations(), 0);  // one refusal is not a stuck writer
  std::this_thread::sleep_for(600ms);
  EXPECT_TRUE(pub->publish(make_image(2)));  // 2nd in a row, 0.6 s on: created again, and sent by the new one
  ASSERT_EQ(pub->writer_recreations(), 1);
  EXPECT_NE(pub->writer()->guid(), guid);
  pub->refuse_writes_for_test(2);
  EXPECT_FALSE(pub->publish(make_image(3)));
  std::this_thread::sleep_for(600ms);
  EXPECT_FALSE(pub->publish(make_image(4)));  // at most once every 10 s
  EXPECT_EQ(pub->writer_recreations(), 1);

  // The reader matches the new writer, and a sample within the bound gets through.
  ASSERT_TRUE(ctx.spin_until([&] { return pub->subscription_count() == 1 && sub->publisher_count() == 1; }, 30s));
  std::this_thread::sleep_for(500ms);  // the reader's side of the match (see testing.hpp)
  ASSERT_TRUE(pub->publish(make_image(7)));
  EXPECT_TRUE(ctx.spin_until([&] { return received.load() == 1; }, 30s));
}
