#include <sys/stat.h>

#include <string>
#include <vector>

#include "fake_prefix.hpp"
#include "unav_launch/launch_description.hpp"
#include "unav_launch/package_index.hpp"

namespace unav::launch::test {
namespace {

using Strings = std::vector<std::string>;

class LaunchFileTest : public FakePrefix {
 protected:
  void SetUp() override {
    FakePrefix::SetUp();
    script("talker", "exit 0");
    write(prefix_ + "/share/fakepkg/config/talker.yaml", "talker:\n  ros__parameters: {rate: 1.0}\n");
  }

  // Loads `yaml` and returns the LaunchError message ("" when it loads).
  std::string error_of(const std::string& yaml, const std::map<std::string, std::string>& args = {}) {
    try {
      load_launch_file(launch_file("bad", yaml), args);
    } catch (const LaunchError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(LaunchFileTest, SubstitutionsResolve) {
  ::setenv("UNAV_TEST_VALUE", "from_env", 1);
  ::unsetenv("UNAV_TEST_UNSET");
  const std::string file = launch_file("subst", R"yaml(
launch:
  - arg: {name: rate, default: "10.0", description: "publish rate [Hz]"}
  - arg: {name: pkg, default: fakepkg}
  - arg: {name: robot, default: "rov"}
  - node:
      pkg: $(var pkg)
      exec: talker
      namespace: $(var robot)
      param:
        - {name: rate, value: "$(var rate)"}
        - {name: env, value: "$(env UNAV_TEST_VALUE)"}
        - {name: fallback, value: "$(env UNAV_TEST_UNSET default value)"}
        - {name: share, value: "$(find-pkg-share $(var pkg))"}
        - {name: prefix, value: "$(find-pkg-prefix fakepkg)"}
        - {name: here, value: "$(dirname)/x"}
        - {name: list, value: [1, "$(var rate)"]}
)yaml");
  const LaunchDescription description = load_launch_file(file, {{"robot", "auv"}});
  ASSERT_EQ(description.nodes.size(), 1u);
  const NodeDescription& node = description.nodes[0];
  EXPECT_EQ(node.ns, "/auv");  // command line beats the default
  const std::vector<std::pair<std::string, std::string>> expected{
      {"rate", "10.0"},    {"env", "from_env"},    {"fallback", "default value"}, {"share", prefix_ + "/share/fakepkg"},
      {"prefix", prefix_}, {"here", root_ + "/x"}, {"list", "[1, 10.0]"}};
  ASSERT_EQ(node.parameters.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(node.parameters[i].name, expected[i].first);
    EXPECT_EQ(node.parameters[i].value, expected[i].second);
  }
  ASSERT_EQ(description.arguments.size(), 3u);
  EXPECT_EQ(description.arguments[0].description, "publish rate [Hz]");
  EXPECT_EQ(description.arguments[2].value, "auv");
}

TEST_F(LaunchFileTest, ArgvFollowsRosConventions) {
  const std::string file = launch_file("full", R"yaml(
launch:
  - node:
      pkg: fakepkg
      exec: talker
      name: talker
      namespace: rov
      param:
        - {from: "$(find-pkg-share fakepkg)/config/talker.yaml"}
        - {name: rate, value: "10.0"}
      remap:
        - {from: chatter, to: /rov/chatter}
      args: "--extra  flag"
      ros_args: "--enclave /rov/talker"
      env: [{name: FOO, value: bar}]
      respawn: true
      respawn_delay: 1.5
      on_exit: shutdown
      output: both
)yaml");
  const NodeDescription node = load_launch_file(file).nodes.at(0);
  const std::string exe = prefix_ + "/lib/fakepkg/talker";
  EXPECT_EQ(node_argv(node), (Strings{exe, "--extra", "flag", "--ros-args", "-r", "__node:=talker", "-r", "__ns:=/rov",
                                      "--params-file", prefix_ + "/share/fakepkg/config/talker.yaml", "-p",
                                      "rate:=10.0", "-r", "chatter:=/rov/chatter", "--enclave", "/rov/talker"}));
  EXPECT_TRUE(node.respawn);
  EXPECT_DOUBLE_EQ(node.respawn_delay_s, 1.5);
  EXPECT_TRUE(node.required);
  EXPECT_EQ(node.output, "both");
  EXPECT_EQ(node.env, (std::vector<std::pair<std::string, std::string>>{{"FOO", "bar"}}));

  NodeDescription bare;
  bare.executable_path = "/x/y";
  EXPECT_EQ(node_argv(bare), Strings{"/x/y"});  // no empty --ros-args
}

TEST_F(LaunchFileTest, IncludePassesArgumentsAndScopesDirname) {
  write(root_ + "/sub/child.launch.yaml", R"yaml(
launch:
  - arg: {name: child_name, default: unused}
  - node: {pkg: fakepkg, exec: talker, name: "$(var child_name)", namespace: "$(var robot)",
           param: [{name: dir, value: "$(dirname)"}]}
)yaml");
  const std::string file = launch_file("parent", R"yaml(
launch:
  - arg: {name: robot, default: rov}
  - include: {file: "sub/child.launch.yaml", arg: [{name: child_name, value: "first"}]}
  - include: {file: "$(dirname)/sub/child.launch.yaml", arg: [{name: child_name, value: second}]}
)yaml");
  const LaunchDescription description = load_launch_file(file);
  ASSERT_EQ(description.nodes.size(), 2u);
  EXPECT_EQ(description.nodes[0].name, "first");
  EXPECT_EQ(description.nodes[1].name, "second");
  EXPECT_EQ(description.nodes[1].ns, "/rov");  // parent arguments are visible in the child
  EXPECT_EQ(description.nodes[0].parameters.at(0).value, root_ + "/sub");
}

struct BadCase {
  std::string yaml;
  Strings expected;  // substrings of the message, besides the file name
};

TEST_F(LaunchFileTest, InvalidInputNamesFileEntryAndValue) {
  const std::string node = "launch:\n  - arg: {name: a, default: x}\n  - node: ";
  const std::string entry = "bad.launch.yaml:3: launch[1].node (pkg 'fakepkg', exec 'talker')";
  const std::vector<BadCase> cases{
      {"launch: [node: {pkg: fakepkg, exec: talker}", {"bad.launch.yaml:", "malformed YAML"}},
      {"nodes: []", {"unknown top-level key 'nodes'"}},
      {"launch: {node: {}}", {"'launch' must be a sequence"}},
      {"launch:\n  - executable: {cmd: ls}", {"launch[0]: unknown entry 'executable'"}},
      {node + "{pkg: fakepkg, exec: talker, namepsace: rov}", {entry, "unknown key 'namepsace'"}},
      {node + "{pkg: fakepkg}", {"launch[1].node (pkg 'fakepkg', exec '?')", "missing required key 'exec'"}},
      {node + "{exec: talker}", {"missing required key 'pkg'"}},
      {node + "{pkg: fakepkg, exec: [talker]}", {"exec must be a string, got a sequence"}},
      {node + "{pkg: fakepkg, exec: talker, respawn: maybe}", {entry, "respawn must be true or false, got 'maybe'"}},
      {node + "{pkg: fakepkg, exec: talker, respawn_delay: -1}", {entry, "respawn_delay", "'-1'"}},
      {node + "{pkg: fakepkg, exec: talker, remap: chatter}", {entry, "remap must be a sequence"}},
      {node + "{pkg: fakepkg, exec: talker, param: [{name: r, value: {x: 1}}]}",
       {entry, "param[0]: value must be a string, got a map"}},
      {node + "{pkg: fakepkg, exec: talker, param: [{nme: r}]}", {entry, "param[0]: unknown key 'nme'"}},
      {node + "{pkg: fakepkg, exec: talker, on_exit: restart}", {entry, "on_exit must be 'shutdown', got 'restart'"}},
      {node + "{pkg: fakepkg, exec: talker, output: file}", {entry, "output must be screen, log or both, got 'file'"}},
      {node + "{pkg: fakepkg, exec: talker, name: 'bad name'}", {entry, "name 'bad name' is not a valid"}},
      {node + "{pkg: fakepkg, exec: talker, name: t, namespace: rov}\n  - node: {pkg: fakepkg, exec: talker, name: t, "
              "namespace: /rov/}",
       {"bad.launch.yaml:4: launch[2].node (pkg 'fakepkg', exec 'talker')", "duplicate node name '/rov/t'",
        "bad.launch.yaml:3 launch[1].node"}},
      {node + "{pkg: fakepkg, exec: talker, param: [{from: /nonexistent/p.yaml}]}",
       {entry, "param[0]: parameter file '/nonexistent/p.yaml' not found"}},
      {node + "{pkg: fakepkg, exec: talkr}",
       {"launch[1].node (pkg 'fakepkg', exec 'talkr')",
        "executable 'talkr' not found in package 'fakepkg' (searched: " + prefix_ + "/lib/fakepkg)"}},
      {node + "{pkg: nopkg, exec: talker}", {"package 'nopkg' not found (searched prefixes: " + prefix_}},
      {node + "{pkg: fakepkg, exec: talker, name: $(var nope)}",
       {entry, "name: $(var nope): argument 'nope' is not declared"}},
      {node + "{pkg: fakepkg, exec: talker, name: $(env UNAV_TEST_UNSET)}",
       {"environment variable 'UNAV_TEST_UNSET' is not set"}},
      {node + "{pkg: fakepkg, exec: talker, name: $(anon x)}", {"unknown substitution '$(anon x)'"}},
      {node + "{pkg: fakepkg, exec: talker, name: $(var a}", {"unterminated substitution"}},
      {"launch:\n  - arg: {name: needed}",
       {"launch[0].arg 'needed': argument 'needed' has no default", "needed:=VALUE"}},
      {"launch:\n  - include: {file: missing.launch.yaml}",
       {"launch[0].include: included file '" + root_ + "/missing.launch.yaml' not found"}},
      {"launch:\n  - include: {file: bad.launch.yaml}", {"nested deeper than 32"}},
  };
  ::unsetenv("UNAV_TEST_UNSET");
  for (const auto& bad : cases) {
    const std::string message = error_of(bad.yaml);
    EXPECT_NE(message.find(root_ + "/bad.launch.yaml"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    for (const auto& part : bad.expected) {
      EXPECT_NE(message.find(part), std::string::npos) << "expected '" << part << "' in: " << message;
    }
  }
  EXPECT_NE(error_of("launch: []", {{"ratee", "1"}}).find("argument 'ratee' given on the command line is not declared"),
            std::string::npos);
  EXPECT_NE(error_of("launch: [").find("malformed YAML"), std::string::npos);
  try {
    load_launch_file(root_ + "/none.launch.yaml");
    ADD_FAILURE() << "no error for a missing launch file";
  } catch (const LaunchError& e) {
    EXPECT_NE(std::string(e.what()).find("none.launch.yaml: launch file not found"), std::string::npos);
  }
}

TEST_F(LaunchFileTest, ParseLaunchArguments) {
  EXPECT_EQ(parse_launch_arguments({"rate:=5", "name:=a:=b", "empty:="}),
            (std::map<std::string, std::string>{{"rate", "5"}, {"name", "a:=b"}, {"empty", ""}}));
  EXPECT_THROW(parse_launch_arguments({"rate=5"}), LaunchError);
  EXPECT_THROW(parse_launch_arguments({":=5"}), LaunchError);
}

TEST_F(LaunchFileTest, PackageIndexSearchesAllPrefixVariables) {
  // Isolated colcon layout: ROOT/pkg/{share,lib}/pkg; merged: ROOT/{share,lib}/pkg.
  write(root_ + "/iso/isopkg/share/isopkg/package.xml", "");
  write(root_ + "/iso/isopkg/lib/isopkg/run", "");
  ::chmod((root_ + "/iso/isopkg/lib/isopkg/run").c_str(), 0755);
  write(root_ + "/merged/share/mergedpkg/package.xml", "");
  write(root_ + "/merged/lib/mergedpkg/plain", "");  // not executable
  ::setenv("COLCON_PREFIX_PATH", (root_ + "/iso:" + root_ + "/merged").c_str(), 1);

  EXPECT_EQ(find_package_prefix("fakepkg"), prefix_);
  EXPECT_EQ(find_package_share("isopkg"), root_ + "/iso/isopkg/share/isopkg");
  EXPECT_EQ(find_executable("isopkg", "run"), root_ + "/iso/isopkg/lib/isopkg/run");
  EXPECT_EQ(find_package_prefix("mergedpkg"), root_ + "/merged");
  std::vector<std::string> searched;
  EXPECT_FALSE(find_executable("mergedpkg", "plain", &searched));
  EXPECT_EQ(searched, Strings{root_ + "/merged/lib/mergedpkg"});
  EXPECT_FALSE(find_package_prefix("absent"));
  EXPECT_FALSE(find_executable("fakepkg", "../fakepkg/talker"));
  EXPECT_EQ(package_search_prefixes("x"),
            (Strings{prefix_, root_ + "/iso/x", root_ + "/iso", root_ + "/merged/x", root_ + "/merged"}));
}

}  // namespace
}  // namespace unav::launch::test
