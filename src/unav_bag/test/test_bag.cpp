#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "unav_bag/async_recorder.hpp"
#include "unav_bag/bag.hpp"
#include "unav_bag/msg_definition.hpp"

namespace fs = std::filesystem;
using namespace unav::bag;

namespace {

unav::introspection::TypeRegistry registry() {
  unav::introspection::TypeRegistry reg;
  reg.add_root(ROS2_MSGS_IDL);
  reg.add_root(UNAV_MSGS_IDL);
  return reg;
}

std::string temp_dir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("unav_bag_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(p);
  fs::create_directories(p.parent_path());
  return p.string();
}

TopicMetadata topic(const std::string& name, const std::string& type, bool latched = false) {
  TopicMetadata t;
  t.name = name;
  t.type = type;
  t.offered_qos_profiles = offered_qos_yaml({{true, latched, latched ? 1 : 10}});
  t.message_definition = "int32 x\n";
  return t;
}

std::vector<uint8_t> payload(size_t n, int seed) {
  std::vector<uint8_t> v(n);
  std::mt19937 rng(static_cast<uint32_t>(seed));
  for (auto& b : v) b = static_cast<uint8_t>(rng());
  return v;
}

}  // namespace

TEST(MsgDefinition, HeaderWithItsDependency) {
  auto reg = registry();
  // As rosbag2 writes it: the dependency named as the field names it (pkg/Type, no "msg/"), which
  // is the name Foxglove's @foxglove/rosmsg looks up.
  EXPECT_EQ(ros2msg_definition(reg, "std_msgs/msg/Header"),
            "builtin_interfaces/Time stamp\nstring frame_id\n" + std::string(80, '=') +
                "\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n");
}

TEST(MsgDefinition, ArraysSequencesConstantsAndEachDependencyOnce) {
  auto reg = registry();
  const std::string imu = ros2msg_definition(reg, "sensor_msgs/msg/Imu");
  EXPECT_NE(imu.find("float64[9] orientation_covariance\n"), std::string::npos) << imu;
  EXPECT_NE(imu.find("geometry_msgs/Quaternion orientation\n"), std::string::npos) << imu;
  // Vector3 is used twice (angular velocity, linear acceleration) but defined once.
  size_t n = 0;
  for (size_t p = imu.find("MSG: geometry_msgs/Vector3\n"); p != std::string::npos;
       p = imu.find("MSG: geometry_msgs/Vector3\n", p + 1))
    ++n;
  EXPECT_EQ(n, 1u);
  const std::string image = ros2msg_definition(reg, "sensor_msgs/msg/Image");
  EXPECT_NE(image.find("uint8[] data\n"), std::string::npos) << image;
  const std::string range = ros2msg_definition(reg, "sensor_msgs/msg/Range");
  EXPECT_NE(range.find("uint8 ULTRASOUND=0\n"), std::string::npos) << range;
  EXPECT_NE(range.find("uint8 INFRARED=1\n"), std::string::npos) << range;
  EXPECT_THROW(ros2msg_definition(reg, "nope_msgs/msg/Missing"), std::exception);
}

TEST(OfferedQos, RoundTripsThroughTheRosbag2String) {
  const std::vector<QosProfile> in = {{true, true, 1}, {false, false, 5}};
  const std::string yaml = offered_qos_yaml(in);
  EXPECT_NE(yaml.find("reliability: 1"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("durability: 1"), std::string::npos) << yaml;
  const auto out = parse_offered_qos_yaml(yaml);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_TRUE(out[0].reliable && out[0].transient_local);
  EXPECT_FALSE(out[1].reliable || out[1].transient_local);
  EXPECT_EQ(out[1].depth, 5);
  // Later distros write names instead of numbers.
  const auto named = parse_offered_qos_yaml("- {reliability: best_effort, durability: transient_local, depth: 3}");
  ASSERT_EQ(named.size(), 1u);
  EXPECT_FALSE(named[0].reliable);
  EXPECT_TRUE(named[0].transient_local);
}

class RoundTrip : public ::testing::TestWithParam<std::pair<std::string, std::string>> {};

TEST_P(RoundTrip, EveryMessageBackWithItsTopicAndTimestamp) {
  const auto [storage, compression] = GetParam();
  const std::string dir = temp_dir("rt_" + storage + "_" + compression);
  std::vector<std::tuple<size_t, int64_t, std::vector<uint8_t>>> written;
  {
    BagWriter::Options opt;
    opt.storage_id = storage;
    opt.compression = compression;
    opt.chunk_size = 100000;  // several chunks, and images larger than a chunk
    BagWriter w(dir, opt);
    EXPECT_EQ(w.add_topic(topic("/a", "std_msgs/msg/Float64")), 0u);
    EXPECT_EQ(w.add_topic(topic("/b/image", "sensor_msgs/msg/Image")), 1u);
    EXPECT_EQ(w.add_topic(topic("/c", "std_msgs/msg/String", true)), 2u);  // no messages
    EXPECT_THROW(w.add_topic(topic("/a", "std_msgs/msg/Float64")), BagError);
    for (int i = 0; i < 50; ++i) {
      const size_t t = i % 5 == 0 ? 1 : 0;
      written.emplace_back(t, 1000000000LL + i * 1000LL, payload(t == 1 ? 640 * 480 * 3 : 12 + i, i));
      const auto& [tt, ts, data] = written.back();
      w.write(tt, ts, data.data(), data.size());
    }
    w.close();
    // metadata.yaml appears only at close; the storage file is named after the folder.
    EXPECT_EQ(w.storage_file(), "rt_" + storage + "_" + compression + "_0" + (storage == "mcap" ? ".mcap" : ".db3"));
  }
  ASSERT_TRUE(fs::exists(fs::path(dir) / "metadata.yaml"));
  BagReader r(dir);
  ASSERT_EQ(r.topics().size(), 3u);
  EXPECT_EQ(r.topics()[1].name, "/b/image");
  EXPECT_EQ(r.topics()[1].type, "sensor_msgs/msg/Image");
  EXPECT_TRUE(parse_offered_qos_yaml(r.topics()[2].offered_qos_profiles).at(0).transient_local);
  if (storage == "mcap") {
    EXPECT_EQ(r.topics()[0].message_definition, "int32 x\n");
  }
  EXPECT_EQ(r.info().storage_identifier, storage);
  EXPECT_EQ(r.info().message_count, 50u);
  EXPECT_EQ(r.info().starting_time_ns, 1000000000LL);
  EXPECT_EQ(r.info().duration_ns, 49000);
  EXPECT_EQ(r.info().topics.at(1).message_count, 10u);
  EXPECT_EQ(r.info().topics.at(2).message_count, 0u);
  for (int pass = 0; pass < 2; ++pass) {  // and again after rewind()
    Message m;
    size_t i = 0;
    while (r.next(m)) {
      ASSERT_LT(i, written.size());
      EXPECT_EQ(m.topic, std::get<0>(written[i]));
      EXPECT_EQ(m.timestamp_ns, std::get<1>(written[i]));
      EXPECT_TRUE(m.data == std::get<2>(written[i])) << "message " << i;
      ++i;
    }
    EXPECT_EQ(i, written.size());
    r.rewind();
  }
  // Without metadata.yaml the storage file alone gives the same statistics (scanned).
  fs::remove(fs::path(dir) / "metadata.yaml");
  BagReader scanned(dir);
  EXPECT_EQ(scanned.info().message_count, 50u);
  EXPECT_EQ(scanned.info().duration_ns, 49000);
  EXPECT_EQ(scanned.info().topics.at(1).message_count, 10u);
}

INSTANTIATE_TEST_SUITE_P(Storages, RoundTrip,
                         ::testing::Values(std::make_pair(std::string("mcap"), std::string("none")),
                                           std::make_pair(std::string("mcap"), std::string("zstd")),
                                           std::make_pair(std::string("sqlite3"), std::string("none"))));

// A bag rosbag2 split over files (max_bag_size): read one file after the other in metadata.yaml's
// order, each file's topics (listed in its own order) merged by name.
TEST(BagReader, ReadsABagSplitOverFiles) {
  struct Part {
    std::vector<TopicMetadata> topics;
    std::vector<std::pair<size_t, int64_t>> messages;  // (topic index in the part, stamp)
  };
  const std::vector<Part> parts = {
      {{topic("/x", "std_msgs/msg/Float64"), topic("/y", "std_msgs/msg/String")}, {{0, 10}, {1, 20}, {0, 30}}},
      {{topic("/z", "std_msgs/msg/Float64"), topic("/y", "std_msgs/msg/String")}, {{1, 40}, {0, 50}}},
  };
  const std::string split = temp_dir("split");
  fs::create_directories(split);
  BagInfo info;
  for (size_t k = 0; k < parts.size(); ++k) {
    const std::string dir = temp_dir("part" + std::to_string(k));
    BagWriter::Options opt;
    opt.storage_id = k == 0 ? "sqlite3" : "mcap";  // the reader picks each file's storage by its name
    BagWriter w(dir, opt);
    for (const auto& t : parts[k].topics) w.add_topic(t);
    for (const auto& [t, ns] : parts[k].messages) {
      const auto data = payload(8, static_cast<int>(ns));
      w.write(t, ns, data.data(), data.size());
    }
    w.close();
    const BagInfo part = read_metadata(dir);
    const std::string name = "split_" + std::to_string(k) + (k == 0 ? ".db3" : ".mcap");
    fs::copy_file(fs::path(dir) / part.files.at(0).path, fs::path(split) / name);
    info.storage_identifier = part.storage_identifier;
    info.files.push_back({name, part.starting_time_ns, part.duration_ns, part.message_count});
    info.message_count += part.message_count;
    for (const auto& t : part.topics) info.topics.push_back(t);
  }
  info.starting_time_ns = 10;
  info.duration_ns = 40;
  {
    std::ofstream out(fs::path(split) / "metadata.yaml");
    out << to_metadata_yaml(info);
  }
  BagReader r(split);
  ASSERT_EQ(r.topics().size(), 3u);  // /x, /y, /z: /y once
  std::vector<std::pair<std::string, int64_t>> read;
  Message m;
  while (r.next(m)) read.emplace_back(r.topics().at(m.topic).name, m.timestamp_ns);
  const std::vector<std::pair<std::string, int64_t>> expected = {
      {"/x", 10}, {"/y", 20}, {"/x", 30}, {"/y", 40}, {"/z", 50}};
  EXPECT_EQ(read, expected);
  r.rewind();
  ASSERT_TRUE(r.next(m));
  EXPECT_EQ(m.timestamp_ns, 10);
  EXPECT_TRUE(m.data == payload(8, 10));

  // A topic whose type changes between the files is refused, naming both.
  const std::string bad = temp_dir("split_bad");
  fs::create_directories(bad);
  const std::string bad_part = temp_dir("bad_part");
  {
    BagWriter w(bad_part, {});
    w.add_topic(topic("/y", "std_msgs/msg/Float64"));
    w.close();
  }
  fs::copy_file(fs::path(split) / "split_0.db3", fs::path(bad) / "bad_0.db3");
  fs::copy_file(fs::path(bad_part) / "bad_part_0.mcap", fs::path(bad) / "bad_1.mcap");
  info.files = {{"bad_0.db3", 10, 20, 3}, {"bad_1.mcap", 0, 0, 0}};
  {
    std::ofstream out(fs::path(bad) / "metadata.yaml");
    out << to_metadata_yaml(info);
  }
  try {
    BagReader rb(bad);
    FAIL() << "a type change was accepted";
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find("'/y' has type std_msgs/msg/Float64 here and std_msgs/msg/String"),
              std::string::npos)
        << e.what();
  }
}

TEST(BagWriter, BadInputNamesTheValue) {
  const std::string dir = temp_dir("bad");
  BagWriter::Options opt;
  opt.storage_id = "bag1";
  try {
    BagWriter w(dir, opt);
    FAIL();
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find("'bag1'"), std::string::npos) << e.what();
  }
  opt.storage_id = "sqlite3";
  opt.compression = "zstd";
  EXPECT_THROW(BagWriter(dir, opt), BagError);  // chunk compression is an MCAP feature
  opt.compression = "none";
  { BagWriter w(dir, opt); }
  try {
    BagWriter again(dir, opt);
    FAIL();
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find("exists"), std::string::npos) << e.what();
  }
  EXPECT_THROW(BagReader(temp_dir("nothing_here")), BagError);
}

TEST(BagReader, RejectsATruncatedMcap) {
  const std::string dir = temp_dir("truncated");
  {
    BagWriter w(dir, {});
    w.add_topic(topic("/a", "std_msgs/msg/Float64"));
    const auto data = payload(5000, 1);
    for (int i = 0; i < 10; ++i) w.write(0, i, data.data(), data.size());
  }
  const fs::path file = fs::path(dir) / "truncated_0.mcap";
  fs::resize_file(file, fs::file_size(file) / 2);
  fs::remove(fs::path(dir) / "metadata.yaml");
  EXPECT_THROW(BagReader r(dir), BagError);
}

TEST(AsyncRecorder, DropsAreCountedNeverSilent) {
  const std::string dir = temp_dir("async_drop");
  // A queue of 1 byte: a message is accepted only when the previous one is on disk, so a burst
  // of 200 x 1 MB (enqueued in microseconds, written in ~0.1 ms each at best) must drop some.
  AsyncRecorder rec(std::make_unique<BagWriter>(dir, BagWriter::Options{}), 1);
  const size_t t = rec.add_topic(topic("/img", "sensor_msgs/msg/Image"));
  size_t accepted = 0;
  for (int i = 0; i < 200; ++i) accepted += rec.enqueue(t, i, std::vector<uint8_t>(1 << 20, 7)) ? 1 : 0;
  rec.close();
  const auto c = rec.counts().at(0);
  EXPECT_EQ(c.received, 200u);
  EXPECT_EQ(c.written, accepted);
  EXPECT_EQ(c.written + c.dropped, c.received);
  EXPECT_GT(c.dropped, 0u);
  EXPECT_EQ(BagReader(dir).info().message_count, c.written);
}

// A full disk, made by a file size limit (RLIMIT_FSIZE: writes beyond it fail with EFBIG, as
// ENOSPC would) in a child process: the recorder reports it, and the bag on disk stays readable
// with every message of the chunks written whole, each intact, the file closed with a footer.
TEST(AsyncRecorder, FullDiskLeavesAValidBagOfWhatWasWritten) {
  const std::string dir = temp_dir("full_disk");
  const std::string err_file = dir + ".err";
  constexpr size_t kMessage = 20000, kLimit = 600000;
  const pid_t child = ::fork();
  if (child == 0) {
    ::signal(SIGXFSZ, SIG_IGN);
    rlimit lim{kLimit, kLimit};
    ::setrlimit(RLIMIT_FSIZE, &lim);
    BagWriter::Options o;
    o.chunk_size = size_t{64} * 1024;
    AsyncRecorder rec(std::make_unique<BagWriter>(dir, o), 64u << 20);
    const size_t t = rec.add_topic(topic("/img", "sensor_msgs/msg/Image"));
    for (int i = 0; i < 100; ++i) rec.enqueue(t, 1000 + i, payload(kMessage, i));
    std::string error;
    try {
      rec.close();
    } catch (const BagError& e) {
      error = e.what();
    }
    std::ofstream(err_file) << error;
    ::_exit(error.empty() ? 1 : 0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the full disk was not reported";
  std::ifstream in(err_file);
  const std::string error((std::istreambuf_iterator<char>(in)), {});
  std::printf("recorder on a full disk: %s\n", error.c_str());
  EXPECT_NE(error.find("File too large"), std::string::npos) << error;
  EXPECT_NE(error.find("ends after its last complete chunk"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(fs::path(dir) / "metadata.yaml"));
  const fs::path file = fs::path(dir) / "full_disk_0.mcap";
  EXPECT_LE(fs::file_size(file), kLimit);
  {
    std::ifstream f(file, std::ios::binary);
    f.seekg(-8, std::ios::end);
    char magic[8];
    f.read(magic, 8);
    EXPECT_EQ(std::string(magic, 8), std::string("\x89MCAP0\r\n", 8));  // closed, not cut mid-record
  }
  BagReader r(dir);
  Message m;
  int n = 0;
  while (r.next(m)) {
    ASSERT_EQ(m.timestamp_ns, 1000 + n);
    ASSERT_EQ(m.data, payload(kMessage, n)) << "message " << n;
    ++n;
  }
  std::printf("%d messages of %zu bytes readable from a %zu-byte file (limit %zu)\n", n, kMessage,
              static_cast<size_t>(fs::file_size(file)), kLimit);
  // Chunks of >= 64 KB hold 4 messages each: everything up to the last whole chunk under the
  // limit, i.e. at least (600000 - one chunk and its indexes) / 20000 ~ 26 messages.
  EXPECT_GE(n, 24);
  EXPECT_LT(n, 30);
}

TEST(AsyncRecorder, AmpleQueueKeepsEverythingFromManyThreads) {
  const std::string dir = temp_dir("async_all");
  AsyncRecorder rec(std::make_unique<BagWriter>(dir, BagWriter::Options{}), 64u << 20);
  std::vector<std::thread> threads;
  threads.reserve(4);
  for (int k = 0; k < 4; ++k) {
    threads.emplace_back([&rec, k] {
      const size_t t = rec.add_topic(topic("/t" + std::to_string(k), "std_msgs/msg/Float64"));
      for (int i = 0; i < 500; ++i) rec.enqueue(t, k * 1000000 + i, payload(64, i));
    });
  }
  for (auto& th : threads) th.join();
  rec.close();
  EXPECT_EQ(rec.dropped(), 0u);
  BagReader r(dir);
  EXPECT_EQ(r.info().message_count, 2000u);
  for (const auto& ti : r.info().topics) EXPECT_EQ(ti.message_count, 500u);
}

TEST(OfferedQos, MalformedProfilesAreABagErrorNotACrash) {
  // Found by fuzz_mcap: a list of scalars threw YAML::BadSubscript out of play/info.
  EXPECT_THROW(parse_offered_qos_yaml("- reliable\n- 3\n"), BagError);
  EXPECT_THROW(parse_offered_qos_yaml("{unclosed"), BagError);
  // Odd values inside a map are ignored, not fatal.
  const auto q = parse_offered_qos_yaml("- {reliability: [1], depth: {x: 1}}");
  ASSERT_EQ(q.size(), 1u);
  EXPECT_TRUE(q[0].reliable);
}
