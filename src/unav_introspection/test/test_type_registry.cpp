#include <gtest/gtest.h>

#include <string>

#include "idl_fixture.hpp"
#include "unav_introspection/type_registry.hpp"

namespace unav::introspection::test {
namespace {

using RegistryTest = IdlFixture;

// test_msgs/msg/Everything.idl: every kind of member, with `ints` after the plain scalars and
// `tail` after the string sequences (line 25 is the first line of `tail` when `ints` is one line).
std::string everything_idl(const std::string& ints, const std::string& tail) {
  return R"IDL(
#include "std_msgs/msg/Header.idl"
module test_msgs { module msg {
  module Everything_Constants {
    const uint8 ULTRASOUND = 0;
    const uint32 N = 4;
    const string NAME = "ev";
  };
  typedef double double__9[9];
  module dds_ {
    struct Everything_ {
      std_msgs::msg::dds_::Header_ header;
      boolean b; octet o; char c; int8 i8; uint8 u8; short s; unsigned short us;
      long l; unsigned long ul; long long ll; unsigned long long ull; float f; double d;
)IDL" + ints +
         R"IDL(      @verbatim (language="comment", text="Gain (unitless), see \"docs\" (1)")
      @default (value=1.5)
      float gain;
      double fixed[test_msgs::msg::Everything_Constants::N];
      double__9 covariance;
      sequence<int16> unbounded;
      sequence<int16, 3> bounded;
      string<4> short_name;
      sequence<string<8>, 2> names;
)IDL" + tail +
         R"IDL(    };
  };
};
};
)IDL";
}

TEST(NameConversion, DdsToRosAndBack) {
  EXPECT_EQ(dds_to_ros_name("sensor_msgs::msg::dds_::Image_"), "sensor_msgs/msg/Image");
  EXPECT_EQ(dds_to_ros_name("::std_msgs::msg::dds_::Header_"), "std_msgs/msg/Header");
  EXPECT_EQ(dds_to_ros_name("geometry_msgs::msg::Twist"), "geometry_msgs/msg/Twist");
  EXPECT_EQ(ros_to_dds_name("sensor_msgs/msg/Image"), "sensor_msgs::msg::dds_::Image_");
  EXPECT_EQ(ros_to_dds_name("sensor_msgs/Image"), "sensor_msgs::msg::dds_::Image_");
  EXPECT_EQ(ros_to_dds_name("std_srvs/srv/Trigger_Request"), "std_srvs::srv::dds_::Trigger_Request_");
  EXPECT_EQ(ros_to_dds_name(dds_to_ros_name("a_b::msg::dds_::C_")), "a_b::msg::dds_::C_");
  EXPECT_THROW(ros_to_dds_name("Image"), UnknownTypeError);
  EXPECT_THROW(ros_to_dds_name("a/b/c/d"), UnknownTypeError);
  EXPECT_THROW(ros_to_dds_name("sensor_msgs/"), UnknownTypeError);
  EXPECT_THROW(dds_to_ros_name("Image_"), UnknownTypeError);
  EXPECT_THROW(dds_to_ros_name("a::msg::dds_::B"), UnknownTypeError);
}

TEST_F(RegistryTest, LoadsHeaderWithIncludeAndFindsAllNameForms) {
  TypeRegistry registry;
  registry.add_root(write_std_types());
  const StructType& header = registry.load("std_msgs/Header");
  EXPECT_EQ(header.name, "std_msgs::msg::dds_::Header_");
  ASSERT_EQ(header.fields.size(), 2u);
  EXPECT_EQ(header.fields[0].name, "stamp");
  ASSERT_EQ(header.fields[0].type.kind, ElementType::Kind::kStruct);
  EXPECT_EQ(header.fields[0].type.struct_type->name, "builtin_interfaces::msg::dds_::Time_");
  EXPECT_EQ(header.fields[1].name, "frame_id");
  EXPECT_EQ(header.fields[1].type.kind, ElementType::Kind::kString);
  EXPECT_EQ(header.line, 5);

  EXPECT_EQ(registry.find("std_msgs::msg::dds_::Header_"), &header);
  EXPECT_EQ(registry.find("std_msgs/msg/Header"), &header);
  EXPECT_EQ(registry.find("std_msgs/Header"), &header);
  EXPECT_NE(registry.find("builtin_interfaces/msg/Time"), nullptr);  // via #include
  EXPECT_EQ(registry.find("std_msgs/msg/String"), nullptr);
  EXPECT_EQ(&registry.load("std_msgs::msg::dds_::Header_"), &header);
}

TEST_F(RegistryTest, ParsesTypesArraysSequencesConstantsTypedefsAndDefaults) {
  const std::string root = write_std_types();
  write("idl", "test_msgs/msg/Everything.idl",
        everything_idl("      int16 i16; uint16 u16; int32 i32; uint32 u32; int64 i64; uint64 u64;\n",
                       "      sequence<Header_Alias> headers;\n"));
  // Header_Alias is not declared: the error must point to its line.
  TypeRegistry registry;
  registry.add_root(root);
  try {
    registry.load("test_msgs/msg/Everything");
    FAIL() << "expected IdlError";
  } catch (const IdlError& e) {
    EXPECT_EQ(e.line(), 25) << e.what();
    EXPECT_NE(std::string(e.what()).find("Everything.idl:25: unknown type 'Header_Alias'"), std::string::npos)
        << e.what();
  }

  write("idl", "test_msgs/msg/Everything.idl",
        everything_idl("",
                       "      sequence<std_msgs::msg::dds_::Header_> headers;\n      @default (value=\"(1, 2)\")\n"
                       "      int32 pair[2];\n"));
  const StructType& t = registry.load("test_msgs/msg/Everything");
  auto field = [&](const std::string& name) -> const Field& {
    for (const Field& f : t.fields) {
      if (f.name == name) return f;
    }
    throw std::runtime_error("no field " + name);
  };
  EXPECT_EQ(field("header").type.struct_type, registry.find("std_msgs/Header"));
  EXPECT_EQ(field("s").type.primitive, PrimitiveKind::kInt16);
  EXPECT_EQ(field("us").type.primitive, PrimitiveKind::kUint16);
  EXPECT_EQ(field("l").type.primitive, PrimitiveKind::kInt32);
  EXPECT_EQ(field("ul").type.primitive, PrimitiveKind::kUint32);
  EXPECT_EQ(field("ll").type.primitive, PrimitiveKind::kInt64);
  EXPECT_EQ(field("ull").type.primitive, PrimitiveKind::kUint64);
  EXPECT_EQ(field("o").type.primitive, PrimitiveKind::kOctet);
  EXPECT_EQ(field("gain").default_value.as<double>(), 1.5);
  EXPECT_EQ(field_type_string(field("fixed")), "double[4]");
  EXPECT_EQ(field_type_string(field("covariance")), "double[9]");
  EXPECT_EQ(field_type_string(field("unbounded")), "sequence<int16>");
  EXPECT_EQ(field_type_string(field("bounded")), "sequence<int16, 3>");
  EXPECT_EQ(field_type_string(field("short_name")), "string<4>");
  EXPECT_EQ(field_type_string(field("names")), "sequence<string<8>, 2>");
  EXPECT_EQ(field_type_string(field("headers")), "sequence<std_msgs/msg/Header>");
  ASSERT_TRUE(field("pair").default_value.IsSequence());
  EXPECT_EQ(field("pair").default_value[1].as<int>(), 2);

  const Constant* ultrasound = registry.find_constant("test_msgs::msg::Everything_Constants::ULTRASOUND");
  ASSERT_NE(ultrasound, nullptr);
  EXPECT_EQ(ultrasound->type, "uint8");
  EXPECT_EQ(ultrasound->value, "0");
  EXPECT_EQ(registry.find_constant("test_msgs::msg::Everything_Constants::NAME")->value, "ev");
}

TEST_F(RegistryTest, ParseErrorsReportFileAndLine) {
  struct Case {
    std::string text;
    int line;
    std::string message;
  };
  const Case cases[] = {
      {"module a { module msg { module dds_ {\n struct B_ {\n  float128 x;\n };\n}; }; };\n", 3,
       "unknown type 'float128'"},
      {"module a { module msg { module dds_ {\n struct B_ {\n  int32 x\n };\n}; }; };\n", 4,
       "expected ';' after member"},
      {"module a { module msg { module dds_ {\n\n struct B_ {\n  int32 x;\n", 3, "missing '}' to close struct 'B_'"},
      {"module a { module msg { module dds_ {\n struct B_ {\n  wstring w;\n };\n}; }; };\n", 3,
       "type 'wstring' is not supported"},
      {"module a {\n enum Color { RED };\n};\n", 2, "'enum' is not supported"},
      {"#include \"nope/msg/Missing.idl\"\n", 1, "cannot find included file 'nope/msg/Missing.idl'"},
      {"module a { module msg { module dds_ {\n struct B_ {\n  int32 x[N];\n };\n}; }; };\n", 3,
       "unknown constant 'N'"},
      {"module a { module msg { module dds_ {\n struct B_ {\n  int32 x; int32 x;\n };\n}; }; };\n", 3,
       "duplicate member 'x'"},
      {"/* never closed\n", 1, "unterminated /* comment"},
  };
  for (const Case& c : cases) {
    const std::string root = write("bad", "a/msg/B.idl", c.text);
    TypeRegistry registry;
    registry.add_root(root);
    try {
      registry.load("a/msg/B");
      ADD_FAILURE() << "no error for:\n" << c.text;
    } catch (const IdlError& e) {
      const std::string expected = path("bad", "a/msg/B.idl") + ":" + std::to_string(c.line) + ": ";
      EXPECT_EQ(std::string(e.what()).rfind(expected, 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
      EXPECT_EQ(e.line(), c.line);
    }
  }
}

TEST_F(RegistryTest, UnknownTypeNamesTypeAndRoots) {
  TypeRegistry registry;
  const std::string root = write_std_types();
  registry.add_root(root);
  try {
    registry.load("sensor_msgs/msg/Image");
    FAIL() << "expected UnknownTypeError";
  } catch (const UnknownTypeError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("sensor_msgs/msg/Image"), std::string::npos) << what;
    EXPECT_NE(what.find("sensor_msgs/msg/Image.idl"), std::string::npos) << what;
    EXPECT_NE(what.find(root), std::string::npos) << what;
  }
  EXPECT_THROW(registry.load("NotAName"), UnknownTypeError);
}

TEST_F(RegistryTest, IncludesResolveInTheSameRootFirst) {
  // Both roots hold pkg/msg/Inner.idl with different members; Outer lives in the second root
  // and must get the second root's Inner even though the first root is searched first otherwise.
  const std::string first =
      write("first", "pkg/msg/Inner.idl",
            "module pkg { module msg { module dds_ { struct Inner_ { int8 from_first; }; }; }; };");
  const std::string second =
      write("second", "pkg/msg/Inner.idl",
            "module pkg { module msg { module dds_ { struct Inner_ { int8 from_second; }; }; }; };");
  write("second", "pkg/msg/Outer.idl", R"IDL(#include "pkg/msg/Inner.idl"
#include "other/msg/Only.idl"
module pkg { module msg { module dds_ { struct Outer_ { Inner_ inner; other::msg::dds_::Only_ only; }; }; }; };)IDL");
  write("first", "other/msg/Only.idl", "module other { module msg { module dds_ { struct Only_ { uint8 x; }; }; }; };");
  TypeRegistry registry;
  registry.add_root(first);
  registry.add_root(second);
  const StructType& outer = registry.load("pkg/msg/Outer");
  ASSERT_EQ(outer.fields.size(), 2u);
  EXPECT_EQ(outer.fields[0].type.struct_type->fields[0].name, "from_second");
  EXPECT_EQ(outer.fields[1].type.struct_type->name, "other::msg::dds_::Only_");
}

TEST_F(RegistryTest, FindsReferencedTypesWithoutIncludeByFileName) {
  TypeRegistry registry;
  registry.add_root(write_std_types());
  write("idl", "nav/msg/Odom.idl",
        "module nav { module msg { module dds_ {\n"
        "  struct Odom_ { ::std_msgs::msg::dds_::Header_ header; };\n"
        "}; }; };\n");
  const StructType& odom = registry.load("nav::msg::dds_::Odom_");
  EXPECT_EQ(odom.fields[0].type.struct_type, registry.find("std_msgs/msg/Header"));
}

TEST_F(RegistryTest, ListsTypesUnderAllRoots) {
  TypeRegistry registry;
  registry.add_root(write_std_types());
  registry.add_root(write("more", "geometry_msgs/msg/Vector3.idl", "// not parsed by list()"));
  write("more", "geometry_msgs/msg/README.md", "not an IDL");
  const std::vector<std::string> expected = {"builtin_interfaces/msg/Time", "geometry_msgs/msg/Vector3",
                                             "std_msgs/msg/Header"};
  EXPECT_EQ(registry.list(), expected);
}

TEST_F(RegistryTest, AddsIdlFoldersOfAnInstallPrefix) {
  write("prefix", "share/std_msgs/idl/std_msgs/msg/Empty.idl",
        "module std_msgs { module msg { module dds_ { struct Empty_ { uint8 structure_needs_at_least_one_member; }; }; "
        "}; };");
  write("prefix", "share/other/cmake/x.cmake", "");
  TypeRegistry registry;
  EXPECT_EQ(registry.add_install_prefix(path("prefix", "")), 1u);
  EXPECT_EQ(registry.load("std_msgs/Empty").fields.size(), 1u);
}

}  // namespace
}  // namespace unav::introspection::test
