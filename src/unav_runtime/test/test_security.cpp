// DDS Security: the SROS2-style keystore (files, signatures, identities, policies) and, over
// real Fast DDS with its built-in plugins, what it must deny: a participant without keys can
// neither read a secured topic nor drive the vehicle, and an enclave is held to its permissions.
#include <gtest/gtest.h>
#include "unav_common/thrown.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "nav_msgs/msg/odometry.hpp"
#include "unav_msgs/msg/thruster_command.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/security.hpp"
#include "unav_runtime/testing.hpp"

using namespace std::chrono_literals;
using namespace unav;
namespace fs = std::filesystem;
namespace sec = unav::security;
using unav::testing::make_link;
using unav::testing::test_context_options;

namespace {

std::string read(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// One keystore for the whole test program: key generation is quick, but every test reusing it
// also checks that enclaves added later work with the same CA.
const std::string& keystore() {
  static const std::string dir = [] {
    std::string d = ::testing::TempDir() + "unav_keystore_" + std::to_string(::getpid());
    fs::remove_all(d);
    sec::create_keystore(d);
    sec::create_enclave(d, "/rov/trusted");
    sec::create_enclave(d, "/rov/peer");
    sec::Permissions thrusters_only;
    thrusters_only.allow_publish = {"rt/rov/thrusters/command"};
    sec::create_enclave(d, "/rov/teleop", thrusters_only);
    return d;
  }();
  return dir;
}

ContextOptions secured(const std::string& enclave) {
  ContextOptions o = test_context_options();
  sec::Environment env;
  env.enable = true;
  env.enforce = true;
  env.keystore = keystore();
  o.security = env;
  o.enclave = enclave;
  return o;
}

ContextOptions unsecured() {
  ContextOptions o = test_context_options();
  o.security = sec::Environment{};  // ROS_SECURITY_ENABLE unset
  return o;
}

}  // namespace

TEST(Keystore, HasTheSros2LayoutAndVerifiableSignatures) {
  const fs::path ks(keystore());
  for (const char* f : {"public/ca.cert.pem", "public/identity_ca.cert.pem", "public/permissions_ca.cert.pem",
                        "private/ca.key.pem", "enclaves/governance.xml", "enclaves/governance.p7s"})
    EXPECT_TRUE(fs::exists(ks / f)) << f;
  // The CA key is readable by its owner only.
  EXPECT_EQ(fs::status(ks / "private/ca.key.pem").permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write);
  const fs::path enclave = ks / "enclaves/rov/trusted";
  for (const char* f : {"cert.pem", "key.pem", "identity_ca.cert.pem", "permissions_ca.cert.pem", "governance.p7s",
                        "permissions.xml", "permissions.p7s"})
    EXPECT_TRUE(fs::exists(enclave / f)) << f;

  // The signed documents carry exactly the XML next to them, signed by the permissions CA.
  EXPECT_EQ(sec::verify_signed(keystore(), (ks / "enclaves/governance.p7s").string()),
            read(ks / "enclaves/governance.xml"));
  const std::string permissions = sec::verify_signed(keystore(), (enclave / "permissions.p7s").string());
  EXPECT_EQ(permissions, read(enclave / "permissions.xml"));
  EXPECT_NE(permissions.find("<subject_name>CN=/rov/trusted</subject_name>"), std::string::npos);
  EXPECT_EQ(sec::verify_identity(keystore(), "/rov/trusted"), "CN=/rov/trusted");
  EXPECT_EQ(sec::list_enclaves(keystore()), (std::vector<std::string>{"/rov/peer", "/rov/teleop", "/rov/trusted"}));

  // A tampered document does not verify.
  std::string p7s = read(enclave / "permissions.p7s");
  const size_t at = p7s.find("<topic>*</topic>");
  ASSERT_NE(at, std::string::npos);
  p7s.replace(at, 16, "<topic>X</topic>");
  const fs::path forged = fs::path(::testing::TempDir()) / "forged.p7s";
  std::ofstream(forged) << p7s;
  EXPECT_NE(
      unav::common::thrown_message([&] { sec::verify_signed(keystore(), forged.string()); }).find("does not verify"),
      std::string::npos);
  // An identity from another keystore is not accepted by this one's CA.
  const std::string other = ::testing::TempDir() + "unav_other_keystore_" + std::to_string(::getpid());
  fs::remove_all(other);
  sec::create_keystore(other);
  sec::create_enclave(other, "/rov/trusted");
  fs::copy_file(fs::path(other) / "enclaves/rov/trusted/cert.pem", fs::path(other) / "foreign.pem");
  fs::copy_file(fs::path(keystore()) / "public/ca.cert.pem", fs::path(other) / "public/ca.cert.pem",
                fs::copy_options::overwrite_existing);
  EXPECT_NE(unav::common::thrown_message([&] { sec::verify_identity(other, "/rov/trusted"); }).find("not issued by"),
            std::string::npos);
}

TEST(Keystore, RejectsBadInputNamingIt) {
  EXPECT_NE(unav::common::thrown_message([] { sec::create_keystore(keystore()); }).find("already exists"),
            std::string::npos);
  const std::string bad = unav::common::thrown_message([] { sec::create_enclave(keystore(), "rov/no_slash"); });
  EXPECT_NE(bad.find("enclave 'rov/no_slash'"), std::string::npos) << bad;
  const std::string none = unav::common::thrown_message([] { sec::create_enclave("/nonexistent/ks", "/a"); });
  EXPECT_NE(none.find("create_keystore /nonexistent/ks"), std::string::npos) << none;
}

TEST(Keystore, Sros2PolicyResolvesTopicsAndServices) {
  const std::string path = ::testing::TempDir() + "policy.xml";
  std::ofstream(path) << R"(<?xml version="1.0"?>
<policy version="0.2.0">
  <enclaves>
    <enclave path="/rov/controller">
      <profiles>
        <profile ns="/rov" node="mpc">
          <topics publish="ALLOW"><topic>thrusters/command</topic><topic>/diagnostics</topic></topics>
          <topics subscribe="ALLOW"><topic>odometry</topic><topic>~/status</topic></topics>
          <topics publish="DENY"><topic>ground_truth/odom</topic></topics>
          <services reply="ALLOW"><service>set_mode</service></services>
        </profile>
      </profiles>
    </enclave>
  </enclaves>
</policy>
)";
  const sec::Permissions p = sec::load_policy(path, "/rov/controller");
  EXPECT_EQ(p.allow_publish,
            (std::vector<std::string>{"rt/rov/thrusters/command", "rt/diagnostics", "rr/rov/set_modeReply"}));
  EXPECT_EQ(p.allow_subscribe,
            (std::vector<std::string>{"rt/rov/odometry", "rt/rov/mpc/status", "rq/rov/set_modeRequest"}));
  EXPECT_EQ(p.deny_publish, (std::vector<std::string>{"rt/rov/ground_truth/odom"}));
  const std::string xml = sec::permissions_xml("/rov/controller", p);
  EXPECT_LT(xml.find("<deny_rule>"), xml.find("<allow_rule>"));  // first match wins: deny first
  EXPECT_NE(xml.find("<default>DENY</default>"), std::string::npos);

  EXPECT_NE(unav::common::thrown_message([&] {
              sec::load_policy(path, "/rov/other");
            }).find("no <enclave path=\"/rov/other\">"),
            std::string::npos);
  std::ofstream(path) << "<policy><enclaves><enclave path=\"/a\"><profiles><profile ns=\"/\" node=\"n\">\n"
                         "<topics publish=\"MAYBE\"><topic>x</topic></topics></profile></profiles></enclave>"
                         "</enclaves></policy>";
  const std::string msg = unav::common::thrown_message([&] { sec::load_policy(path, "/a"); });
  EXPECT_NE(msg.find("policy.xml:2: <topics> publish=\"MAYBE\": expected ALLOW or DENY"), std::string::npos) << msg;
}

TEST(Keystore, EnvironmentSwitchesFollowRos2) {
  sec::Environment env;
  EXPECT_FALSE(sec::participant_properties(env, "/rov/trusted"));  // security off
  env.enable = true;
  env.keystore = keystore();
  auto props = sec::participant_properties(env, "/rov/trusted");
  ASSERT_TRUE(props);
  std::map<std::string, std::string> m(props->begin(), props->end());
  EXPECT_EQ(m.at("dds.sec.auth.plugin"), "builtin.PKI-DH");
  EXPECT_EQ(m.at("dds.sec.access.plugin"), "builtin.Access-Permissions");
  EXPECT_EQ(m.at("dds.sec.crypto.plugin"), "builtin.AES-GCM-GMAC");
  EXPECT_EQ(m.at("dds.sec.auth.builtin.PKI-DH.identity_certificate"),
            "file://" + fs::canonical(fs::path(keystore()) / "enclaves/rov/trusted/cert.pem").string());
  // The override wins over the node's enclave.
  env.enclave_override = "/rov/peer";
  m = {};
  props = sec::participant_properties(env, "/rov/trusted");
  for (auto& [k, v] : *props) m[k] = v;
  EXPECT_NE(m.at("dds.sec.access.builtin.Access-Permissions.permissions").find("/rov/peer/"), std::string::npos);
  // A missing enclave: Permissive runs unsecured and says so; Enforce refuses, naming the fix.
  env.enclave_override = "/rov/unknown";
  std::string warning;
  EXPECT_FALSE(sec::participant_properties(env, "", &warning));
  EXPECT_NE(warning.find("WITHOUT security"), std::string::npos) << warning;
  env.enforce = true;
  const std::string msg = unav::common::thrown_message([&] { sec::participant_properties(env, ""); });
  EXPECT_NE(msg.find("Enforce"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unav security create_enclave " + keystore() + " /rov/unknown"), std::string::npos) << msg;
}

// Secured writer and reader exchange odometry; an unsecured participant on the same domain,
// with a reader on the same topic, discovers nothing and receives nothing while the secured pair
// exchanges 20 samples, and the secured writer counts exactly one matched reader.
TEST(SecureDds, ParticipantWithoutKeysCannotReadOdometry) {
  Context ctx_pub(secured("/rov/trusted")), ctx_sub(secured("/rov/peer")), ctx_spy(unsecured());
  EXPECT_EQ(ctx_pub.secured_enclave(), "/rov/trusted");
  EXPECT_EQ(ctx_spy.secured_enclave(), "");
  Node physics("physics", {&ctx_pub}, "rov");
  Node client("client", {&ctx_sub}, "rov");
  Node spy("spy", {&ctx_spy}, "rov");
  auto pub = physics.create_publisher<nav_msgs::msg::Odometry>("ground_truth/odom", QoS::reliable());
  int received = 0, spied = 0;
  auto sub = client.create_subscription<nav_msgs::msg::Odometry>("ground_truth/odom", QoS::reliable(),
                                                                 [&](const nav_msgs::msg::Odometry&) { ++received; });
  auto spy_sub = spy.create_subscription<nav_msgs::msg::Odometry>("ground_truth/odom", QoS::reliable(),
                                                                  [&](const nav_msgs::msg::Odometry&) { ++spied; });
  ASSERT_TRUE(unav::testing::wait_for_match({&ctx_pub, &ctx_sub, &ctx_spy}, {make_link(*pub, *sub)}, 60s))
      << "secured participants did not match";
  nav_msgs::msg::Odometry odom;
  for (int i = 0; i < 20; ++i) {  // one at a time: the reliable history keeps 10
    odom.pose().pose().position().x(i);
    pub->publish(odom);
    ASSERT_TRUE(unav::testing::spin_until(
        {&ctx_sub, &ctx_spy, &ctx_pub}, [&] { return received == i + 1; }, 20s))
        << received;
  }
  // Give the spy the same time again: encrypted discovery means it never learns of the writer.
  unav::testing::spin_for({&ctx_spy, &ctx_sub, &ctx_pub}, 2s);
  EXPECT_EQ(spied, 0);
  EXPECT_EQ(spy_sub->publisher_count(), 0);
  EXPECT_EQ(pub->subscription_count(), 1);
}

// An unsecured participant publishing thruster commands does not reach the secured vehicle;
// a secured one does (told apart by the values).
TEST(SecureDds, ParticipantWithoutKeysCannotCommandThrusters) {
  Context ctx_vehicle(secured("/rov/trusted")), ctx_pilot(secured("/rov/teleop")), ctx_intruder(unsecured());
  Node vehicle("physics", {&ctx_vehicle}, "rov");
  Node pilot("pilot", {&ctx_pilot}, "rov");
  Node intruder("intruder", {&ctx_intruder}, "rov");
  std::vector<double> last;
  int commands = 0, intruded = 0;
  auto sub = vehicle.create_subscription<unav_msgs::msg::ThrusterCommand>(
      "thrusters/command", QoS::reliable(), [&](const unav_msgs::msg::ThrusterCommand& m) {
        last = m.u();
        ++commands;
        if (!m.u().empty() && m.u()[0] == 1.0) ++intruded;
      });
  auto good = pilot.create_publisher<unav_msgs::msg::ThrusterCommand>("thrusters/command", QoS::reliable());
  auto evil = intruder.create_publisher<unav_msgs::msg::ThrusterCommand>("thrusters/command", QoS::reliable());
  ASSERT_TRUE(unav::testing::wait_for_match({&ctx_vehicle, &ctx_pilot, &ctx_intruder}, {make_link(*good, *sub)}, 60s));
  unav_msgs::msg::ThrusterCommand full, gentle;
  full.u(std::vector<double>(8, 1.0));
  gentle.u(std::vector<double>(8, 0.1));
  for (int i = 0; i < 10; ++i) {  // one at a time: the reliable history keeps 10
    evil->publish(full);
    good->publish(gentle);
    ASSERT_TRUE(unav::testing::spin_until(
        {&ctx_vehicle, &ctx_pilot, &ctx_intruder}, [&] { return commands >= i + 1; }, 20s));
  }
  unav::testing::spin_for({&ctx_vehicle, &ctx_pilot, &ctx_intruder}, 1s);
  EXPECT_EQ(commands, 10);
  EXPECT_EQ(intruded, 0);
  EXPECT_EQ(last, std::vector<double>(8, 0.1));
  EXPECT_EQ(evil->subscription_count(), 0);
}

// The /rov/teleop enclave may publish thruster commands and nothing else: its reader on
// ground_truth/odom and its writer there are refused by access control, with an error that
// names the enclave.
TEST(SecureDds, EnclaveIsHeldToItsPermissions) {
  Context ctx(secured("/rov/teleop"));
  Node teleop("teleop", {&ctx}, "rov");
  EXPECT_NO_THROW(teleop.create_publisher<unav_msgs::msg::ThrusterCommand>("thrusters/command", QoS::reliable()));
  const std::string read_error = unav::common::thrown_message([&] {
    teleop.create_subscription<nav_msgs::msg::Odometry>("ground_truth/odom", QoS::reliable(),
                                                        [](const nav_msgs::msg::Odometry&) {});
  });
  EXPECT_NE(read_error.find("reader on 'rt/rov/ground_truth/odom'"), std::string::npos) << read_error;
  EXPECT_NE(read_error.find("enclave '/rov/teleop'"), std::string::npos) << read_error;
  const std::string write_error = unav::common::thrown_message(
      [&] { teleop.create_publisher<nav_msgs::msg::Odometry>("ground_truth/odom", QoS::reliable()); });
  EXPECT_NE(write_error.find("writer on 'rt/rov/ground_truth/odom'"), std::string::npos) << write_error;
  EXPECT_EQ(unav::common::thrown_message([&] {
              teleop.create_subscription<unav_msgs::msg::ThrusterCommand>(
                  "thrusters/command", QoS::reliable(), [](const unav_msgs::msg::ThrusterCommand&) {});
            }).empty(),
            false);  // publish-only: subscribing to its own topic is refused too
}

TEST(SecureDds, EnforceWithoutKeysRefusesToStart) {
  ContextOptions o = secured("/rov/nobody");
  const std::string msg = unav::common::thrown_message([&] { Context ctx(o); });
  EXPECT_NE(msg.find("create_enclave"), std::string::npos) << msg;
}
