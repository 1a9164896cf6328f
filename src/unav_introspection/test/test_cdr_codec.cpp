#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "idl_fixture.hpp"
#include "unav_introspection/cdr_codec.hpp"
#include "unav_introspection/type_registry.hpp"

namespace unav::introspection::test {
namespace {

using Bytes = std::vector<uint8_t>;

class CodecTest : public IdlFixture {
 protected:
  void SetUp() override {
    IdlFixture::SetUp();
    registry_.add_root(write_std_types());
    write("idl", "test_msgs/msg/Padding.idl",
          "module test_msgs { module msg { module dds_ {\n"
          "  struct Padding_ { uint8 a; double b; };\n"
          "}; }; };\n");
    write("idl", "test_msgs/msg/ItemList.idl", R"IDL(
module test_msgs { module msg { module dds_ {
  struct Item_ { uint8 id; uint16 value; };
  struct ItemList_ { sequence<Item_> items; };
}; }; };
)IDL");
    write("idl", "test_msgs/msg/Fixed.idl", R"IDL(
module test_msgs { module msg {
  module Fixed_Constants { const uint32 N = 2; };
  module dds_ {
    struct Fixed_ { int16 values[3]; double d[Fixed_Constants::N]; };
  };
}; };
)IDL");
    write("idl", "test_msgs/msg/Limits.idl", R"IDL(
module test_msgs { module msg { module dds_ {
  struct Limits_ {
    sequence<int16, 3> bounded;
    string<4> name;
    uint8 small;
    @default (value=1.5)
    float gain;  // [1]
    boolean flag;
    int64 big;
    char letter;
    octet raw;
  };
}; }; };
)IDL");
    write("idl", "test_msgs/msg/Vector3.idl",
          "module test_msgs { module msg { module dds_ {\n"
          "  struct Vector3_ { double x; double y; double z; };\n"
          "}; }; };\n");
    write("idl", "test_msgs/msg/Status.idl", R"IDL(#include "std_msgs/msg/Header.idl"
#include "test_msgs/msg/Vector3.idl"
module test_msgs { module msg { module dds_ {
  struct Status_ {
    std_msgs::msg::dds_::Header_ header;
    Vector3_ velocity;  // [m/s]
    sequence<Vector3_> waypoints;
    float covariance[3];
    sequence<uint8> data;
    string note;
    sequence<string> tags;
    boolean ok;
    int8 mode;
  };
}; }; };
)IDL");
    write("idl", "test_msgs/msg/Blob.idl", R"IDL(
module test_msgs { module msg { module dds_ {
  struct Blob_ {
    sequence<uint8> data;
    string text;
    float values[4];
    sequence<double, 5> bounded;
  };
}; }; };
)IDL");
  }

  const StructType& type(const std::string& name) { return registry_.load(name); }

  static std::string error_of(const StructType& t, const std::string& yaml) {
    try {
      encode(t, YAML::Load(yaml));
    } catch (const CodecError& e) {
      return e.what();
    }
    return "(no error)";
  }

  static const char* status_yaml() {
    return R"IDL(
header: {stamp: {sec: 1, nanosec: 2}, frame_id: ''}
velocity: {x: 1, y: 0.1, z: 1.0e-5}
waypoints:
  - {x: 1.0, y: 2.0, z: 3.0}
  - {x: -1.5, z: 1.0e+20}
covariance: [0.1, 0, -2.5]
data: [1, 2, 3]
note: '123'
tags: ['on', a b, it's]
ok: true
mode: -3
)IDL";
  }

  TypeRegistry registry_;
};

TEST_F(CodecTest, HeaderBytesMatchHandComputedCdr) {
  const Bytes bytes = encode(type("std_msgs/msg/Header"), YAML::Load("{stamp: {sec: 1, nanosec: 2}, frame_id: ab}"));
  const Bytes expected = {0x00, 0x01, 0x00, 0x00,  // CDR_LE encapsulation
                          0x01, 0x00, 0x00, 0x00,  // stamp.sec
                          0x02, 0x00, 0x00, 0x00,  // stamp.nanosec
                          0x03, 0x00, 0x00, 0x00,  // frame_id length incl. NUL
                          0x61, 0x62, 0x00};       // "ab\0"
  EXPECT_EQ(bytes, expected);
}

TEST_F(CodecTest, DoubleAfterUint8IsAlignedToEight) {
  const Bytes bytes = encode(type("test_msgs/Padding"), YAML::Load("{a: 7, b: 1.0}"));
  const Bytes expected = {0x00, 0x01, 0x00, 0x00,                           // header
                          0x07, 0,    0,    0,    0,    0,    0,    0,      // a + 7 padding
                          0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xF0, 0x3F};  // 1.0 = 0x3FF0...
  EXPECT_EQ(bytes, expected);
}

TEST_F(CodecTest, SequenceOfStructsAlignsEachElement) {
  const Bytes bytes =
      encode(type("test_msgs/msg/ItemList"), YAML::Load("{items: [{id: 1, value: 10}, {id: 2, value: 11}]}"));
  const Bytes expected = {0x00, 0x01, 0x00, 0x00,  // header
                          0x02, 0x00, 0x00, 0x00,  // 2 elements
                          0x01, 0x00, 0x0A, 0x00,  // id, pad, value
                          0x02, 0x00, 0x0B, 0x00};
  EXPECT_EQ(bytes, expected);
  const YAML::Node back = decode(type("test_msgs/msg/ItemList"), bytes.data(), bytes.size());
  EXPECT_EQ(back["items"][1]["value"].as<int>(), 11);
}

TEST_F(CodecTest, FixedArraysHaveNoLengthPrefix) {
  const StructType& fixed = type("test_msgs/msg/Fixed");
  const Bytes bytes = encode(fixed, YAML::Load("{values: [1, 2, 3], d: [1.0, -2.0]}"));
  const Bytes expected = {0x00, 0x01, 0x00, 0x00,                           // header
                          0x01, 0x00, 0x02, 0x00, 0x03, 0x00, 0,    0,      // int16[3] + 2 padding
                          0,    0,    0,    0,    0,    0,    0xF0, 0x3F,   // 1.0
                          0,    0,    0,    0,    0,    0,    0x00, 0xC0};  // -2.0
  EXPECT_EQ(bytes, expected);
  EXPECT_EQ(error_of(fixed, "{values: [1, 2]}"), "values: expected exactly 3 elements for int16[3], got 2");
}

TEST_F(CodecTest, MissingFieldsTakeDefaultOrZero) {
  const Bytes bytes = encode(type("test_msgs/msg/Limits"), YAML::Load("{}"));
  const Bytes expected = {0x00, 0x01, 0x00, 0x00,              // header
                          0,    0,    0,    0,                 // bounded: 0 elements
                          1,    0,    0,    0,    0,           // name: "" (length 1, NUL)
                          0,                                   // small
                          0,    0,                             // padding to 4
                          0x00, 0x00, 0xC0, 0x3F,              // gain = @default 1.5f
                          0,                                   // flag
                          0,    0,    0,    0,    0, 0, 0,     // padding to 8
                          0,    0,    0,    0,    0, 0, 0, 0,  // big
                          0,    0};                            // letter, raw
  EXPECT_EQ(bytes, expected);
}

TEST_F(CodecTest, ValueErrorsNameFieldPathValueAndRule) {
  const StructType& limits = type("test_msgs/msg/Limits");
  EXPECT_EQ(error_of(limits, "{bounded: [1, 2, 3, 4]}"), "bounded: 4 elements exceed the bound of sequence<int16, 3>");
  EXPECT_EQ(error_of(limits, "{name: abcde}"), "name: string of 5 bytes exceeds the bound of string<4>");
  EXPECT_EQ(error_of(limits, "{small: 300}"), "small: value '300' is out of range for uint8 [0, 255]");
  EXPECT_EQ(error_of(limits, "{small: -1}"), "small: value '-1' is out of range for uint8 [0, 255]");
  EXPECT_EQ(error_of(limits, "{small: 1.5}"), "small: value '1.5' is not an integer (uint8)");
  EXPECT_EQ(error_of(limits, "{flag: 2}"), "flag: value '2' is not a boolean (true or false)");
  EXPECT_EQ(error_of(limits, "{gain: 1.0e39}"),
            "gain: value '1.0e39' is out of range for float (|x| <= 3.4028235e+38)");
  EXPECT_EQ(error_of(limits, "[1, 2]"),
            "(message): expected a mapping for test_msgs/msg/Limits, got a sequence [1, 2]");

  const StructType& header = type("std_msgs/msg/Header");
  EXPECT_EQ(error_of(header, "{stamp: {sec: 1, nsec: 2}}"),
            "stamp.nsec: unknown field of builtin_interfaces/msg/Time (fields: sec, nanosec)");
  EXPECT_EQ(error_of(header, "{stamp: {sec: {a: 1}}}"), "stamp.sec: expected int32, got a mapping {a: 1}");
  EXPECT_EQ(error_of(type("test_msgs/msg/ItemList"), "{items: [{id: 1}, {value: x}]}"),
            "items[1].value: value 'x' is not an integer (uint16)");

  // Limits of the widest integers, and YAML 1.1 spellings that ros2 topic pub accepts.
  EXPECT_NO_THROW(encode(limits, YAML::Load("{big: -9223372036854775808, small: 0xff, flag: yes}")));
  EXPECT_EQ(error_of(limits, "{big: 9223372036854775808}"),
            "big: value '9223372036854775808' is out of range for int64 "
            "[-9223372036854775808, 9223372036854775807]");
}

TEST_F(CodecTest, RoundTripEncodeDecodeEncodeGivesEqualBytes) {
  const StructType& status = type("test_msgs/msg/Status");
  const Bytes first = encode(status, YAML::Load(status_yaml()));
  const YAML::Node decoded = decode(status, first.data(), first.size());
  EXPECT_EQ(decoded["velocity"]["x"].as<std::string>(), "1.0");
  EXPECT_EQ(decoded["covariance"][0].as<std::string>(), "0.10000000149011612");
  EXPECT_EQ(decoded["note"].as<std::string>(), "123");
  EXPECT_EQ(decoded["mode"].as<int>(), -3);
  EXPECT_EQ(decode(status, first.data(), first.size())["ok"].as<bool>(), true);
  const Bytes second = encode(status, decoded);
  EXPECT_EQ(first, second);

  const StructType& limits = type("test_msgs/msg/Limits");
  const Bytes l1 = encode(limits, YAML::Load("{bounded: [-1, 2], name: abcd, letter: z, raw: 255, big: -5}"));
  const YAML::Node l_decoded = decode(limits, l1.data(), l1.size());
  EXPECT_EQ(l_decoded["raw"].as<int>(), 255);
  EXPECT_EQ(l_decoded["letter"].as<std::string>(), "z");
  EXPECT_EQ(encode(limits, l_decoded), l1);
}

TEST_F(CodecTest, TruncatedOrMalformedInputThrows) {
  const StructType& status = type("test_msgs/msg/Status");
  const Bytes full = encode(status, YAML::Load(status_yaml()));
  for (size_t size = 0; size < full.size(); ++size) {
    // A copy of exactly `size` bytes, so that reading past it is caught by sanitizers too.
    const Bytes prefix(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(size));
    EXPECT_THROW(decode(status, prefix.data(), prefix.size()), CodecError) << "size " << size;
    EXPECT_THROW(to_echo_yaml(status, prefix.data(), prefix.size()), CodecError) << "size " << size;
  }
  EXPECT_NO_THROW(decode(status, full.data(), full.size()));

  const StructType& header = type("std_msgs/msg/Header");
  Bytes huge = {0x00, 0x01, 0x00, 0x00, 1, 0, 0, 0, 2, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF, 'a'};
  EXPECT_THROW(decode(header, huge.data(), huge.size()), CodecError);
  Bytes list = {0x00, 0x01, 0x00, 0x00, 0xFF, 0xFF, 0xFF, 0x7F, 1, 0, 2, 0};
  EXPECT_THROW(decode(type("test_msgs/msg/ItemList"), list.data(), list.size()), CodecError);
  Bytes bad_encapsulation = {0x00, 0x03, 0x00, 0x00, 7, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  EXPECT_THROW(decode(type("test_msgs/msg/Padding"), bad_encapsulation.data(), bad_encapsulation.size()), CodecError);
  Bytes limits = encode(type("test_msgs/msg/Limits"), YAML::Load("{}"));
  limits[4 + 16] = 2;  // flag byte: neither 0 nor 1
  EXPECT_THROW(decode(type("test_msgs/msg/Limits"), limits.data(), limits.size()), CodecError);
  const Bytes too_long = [&] {
    Bytes b = encode(header, YAML::Load("{frame_id: ab}"));
    b.insert(b.end(), 8, 0);
    return b;
  }();
  EXPECT_THROW(decode(header, too_long.data(), too_long.size()), CodecError);
}

TEST_F(CodecTest, DecodesBigEndianWithByteSwapping) {
  const Bytes header_be = {0x00, 0x00, 0x00, 0x00,  // CDR_BE
                           0x00, 0x00, 0x00, 0x01,  // sec
                           0x00, 0x00, 0x00, 0x02,  // nanosec
                           0x00, 0x00, 0x00, 0x03,  // length
                           0x61, 0x62, 0x00};
  const YAML::Node header = decode(type("std_msgs/msg/Header"), header_be.data(), header_be.size());
  EXPECT_EQ(header["stamp"]["sec"].as<int>(), 1);
  EXPECT_EQ(header["stamp"]["nanosec"].as<int>(), 2);
  EXPECT_EQ(header["frame_id"].as<std::string>(), "ab");

  const Bytes padding_be = {0x00, 0x00, 0x00, 0x00, 0x07, 0,    0,    0,    0,    0,
                            0,    0,    0xC0, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00};  // -2.5
  const YAML::Node padding = decode(type("test_msgs/msg/Padding"), padding_be.data(), padding_be.size());
  EXPECT_EQ(padding["a"].as<int>(), 7);
  EXPECT_EQ(padding["b"].as<std::string>(), "-2.5");
}

TEST_F(CodecTest, EchoTextOfNestedMessageMatchesRos2TopicEcho) {
  const StructType& status = type("test_msgs/msg/Status");
  const Bytes bytes = encode(status, YAML::Load(status_yaml()));
  // What `ros2 topic echo` (Humble, PyYAML block style) prints for this sample.
  const std::string expected =
      "header:\n"
      "  stamp:\n"
      "    sec: 1\n"
      "    nanosec: 2\n"
      "  frame_id: ''\n"
      "velocity:\n"
      "  x: 1.0\n"
      "  y: 0.1\n"
      "  z: 1.0e-05\n"
      "waypoints:\n"
      "- x: 1.0\n"
      "  y: 2.0\n"
      "  z: 3.0\n"
      "- x: -1.5\n"
      "  y: 0.0\n"
      "  z: 1.0e+20\n"
      "covariance:\n"
      "- 0.10000000149011612\n"
      "- 0.0\n"
      "- -2.5\n"
      "data:\n"
      "- 1\n"
      "- 2\n"
      "- 3\n"
      "note: '123'\n"
      "tags:\n"
      "- 'on'\n"
      "- a b\n"
      "- it's\n"
      "ok: true\n"
      "mode: -3\n";
  EXPECT_EQ(to_echo_yaml(status, bytes.data(), bytes.size()), expected);

  const Bytes header = encode(type("std_msgs/Header"), YAML::Load("{stamp: {sec: 1, nanosec: 2}, frame_id: ab}"));
  EXPECT_EQ(to_echo_yaml(type("std_msgs/Header"), header.data(), header.size()),
            "stamp:\n  sec: 1\n  nanosec: 2\nframe_id: ab\n");
}

TEST_F(CodecTest, EchoTruncatesAndAbbreviatesLikeRos2) {
  const StructType& blob = type("test_msgs/msg/Blob");
  YAML::Node value;
  for (int i = 0; i < 200; ++i) value["data"].push_back(i);
  value["text"] = std::string(130, 'a');
  value["bounded"].push_back(1.0);
  value["bounded"].push_back(2.0);
  const Bytes bytes = encode(blob, value);

  EchoOptions short_options;
  short_options.truncate_length = 2;
  EXPECT_EQ(to_echo_yaml(blob, bytes.data(), bytes.size(), short_options),
            "data:\n- 0\n- 1\n- '...'\ntext: aa...\nvalues:\n- 0.0\n- 0.0\n- '...'\nbounded:\n- 1.0\n- 2.0\n");

  const std::string full = to_echo_yaml(blob, bytes.data(), bytes.size());  // default 128
  EXPECT_NE(full.find("- 127\n- '...'\ntext: " + std::string(128, 'a') + "...\n"), std::string::npos);
  EXPECT_EQ(full.find("- 128\n"), std::string::npos);

  EchoOptions full_length;
  full_length.truncate_length = EchoOptions::kFullLength;
  const std::string all = to_echo_yaml(blob, bytes.data(), bytes.size(), full_length);
  EXPECT_NE(all.find("- 199\ntext: " + std::string(130, 'a') + "\n"), std::string::npos);

  EchoOptions no_arr;
  no_arr.no_arr = true;
  no_arr.no_str = true;
  EXPECT_EQ(to_echo_yaml(blob, bytes.data(), bytes.size(), no_arr),
            "data: '<sequence type: uint8, length: 200>'\n"
            "text: '<string length: <130>>'\n"
            "values: '<array type: float[4]>'\n"
            "bounded: '<sequence type: double[5], length: 2>'\n");
}

TEST_F(CodecTest, EchoQuotesStringsLikePyYaml) {
  const StructType& header = type("std_msgs/msg/Header");
  const auto echo_frame = [&](const std::string& frame_id) {
    YAML::Node value;
    value["frame_id"] = frame_id;
    const Bytes bytes = encode(header, value);
    const std::string text = to_echo_yaml(header, bytes.data(), bytes.size());
    return text.substr(text.find("frame_id: ") + 10);
  };
  EXPECT_EQ(echo_frame("base_link"), "base_link\n");
  EXPECT_EQ(echo_frame(""), "''\n");
  EXPECT_EQ(echo_frame("123"), "'123'\n");
  EXPECT_EQ(echo_frame("1.5"), "'1.5'\n");
  EXPECT_EQ(echo_frame("1e5"), "1e5\n");  // not a float for YAML 1.1 resolvers
  EXPECT_EQ(echo_frame("null"), "'null'\n");
  EXPECT_EQ(echo_frame("Yes"), "'Yes'\n");
  EXPECT_EQ(echo_frame("2024-01-31"), "'2024-01-31'\n");
  EXPECT_EQ(echo_frame("a: b"), "'a: b'\n");
  EXPECT_EQ(echo_frame("a:b"), "a:b\n");
  EXPECT_EQ(echo_frame("x #y"), "'x #y'\n");
  EXPECT_EQ(echo_frame("- x"), "'- x'\n");
  EXPECT_EQ(echo_frame("*star"), "'*star'\n");
  EXPECT_EQ(echo_frame(" lead"), "' lead'\n");
  EXPECT_EQ(echo_frame("it's"), "it's\n");
  EXPECT_EQ(echo_frame("'q'"), "'''q'''\n");
  EXPECT_EQ(echo_frame("tab\there"), "\"tab\\there\"\n");
  EXPECT_EQ(echo_frame("x\ny"), "'x\n\n  y'\n");
  EXPECT_EQ(echo_frame("caf\xC3\xA9"), "caf\xC3\xA9\n");  // allow_unicode=True
}

TEST(FloatFormat, MatchesPythonRepr) {
  EXPECT_EQ(format_float_like_python(1.0), "1.0");
  EXPECT_EQ(format_float_like_python(0.1), "0.1");
  EXPECT_EQ(format_float_like_python(1.0e-5), "1.0e-05");
  EXPECT_EQ(format_float_like_python(0.0001), "0.0001");
  EXPECT_EQ(format_float_like_python(123.456), "123.456");
  EXPECT_EQ(format_float_like_python(-2.5), "-2.5");
  EXPECT_EQ(format_float_like_python(0.0), "0.0");
  EXPECT_EQ(format_float_like_python(-0.0), "-0.0");
  EXPECT_EQ(format_float_like_python(1.0e15), "1000000000000000.0");
  EXPECT_EQ(format_float_like_python(1.0e16), "1.0e+16");
  EXPECT_EQ(format_float_like_python(1.5e300), "1.5e+300");
  EXPECT_EQ(format_float_like_python(static_cast<double>(0.1f)), "0.10000000149011612");
  EXPECT_EQ(format_float_like_python(NAN), ".nan");
  EXPECT_EQ(format_float_like_python(-INFINITY), "-.inf");
  EXPECT_EQ(format_float_like_python(INFINITY), ".inf");
}

}  // namespace
}  // namespace unav::introspection::test
