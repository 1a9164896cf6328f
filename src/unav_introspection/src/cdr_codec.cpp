// Plain CDR (XCDR1) encoder/decoder driven by StructType, and the `ros2 topic echo` printer.
// Wire rules follow Fast CDR 1.x as used by Fast DDS 2.x / rmw_fastrtps: primitives aligned to
// their size from the end of the encapsulation header, no alignment for empty arrays, strings as
// uint32 length (with NUL) + bytes + NUL, sequences as uint32 count + elements.
#include "unav_introspection/cdr_codec.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <cstdio>
#include <map>
#include <regex>
#include <string_view>
#include <utility>

#include "unav_introspection/type_registry.hpp"

namespace unav_introspection {

namespace {

constexpr size_t kHeaderSize = 4;
constexpr const char* kDummyMember = "structure_needs_at_least_one_member";

std::string show_path(const std::string& path) { return path.empty() ? "(message)" : path; }

std::string member_path(const std::string& parent, const std::string& name) {
  return parent.empty() ? name : parent + "." + name;
}

std::string type_display_name(const StructType& type) {
  try {
    return dds_to_ros_name(type.name);
  } catch (const UnknownTypeError&) {
    return type.name;
  }
}

// A sole member named structure_needs_at_least_one_member stands for an empty message; ROS 2
// tools hide it.
bool is_empty_message(const StructType& type) {
  return type.fields.size() == 1 && type.fields[0].name == kDummyMember;
}

// ---------------------------------------------------------------- encoding

class Writer {
 public:
  Writer() : buf_{0x00, 0x01, 0x00, 0x00} {}  // CDR_LE, options 0

  void align(size_t n) {
    while ((buf_.size() - kHeaderSize) % n != 0) buf_.push_back(0);
  }

  void put_unsigned(uint64_t bits, size_t size) {
    align(size);
    for (size_t i = 0; i < size; ++i) buf_.push_back(static_cast<uint8_t>(bits >> (8 * i)));
  }

  void put_bytes(const std::string& bytes) { buf_.insert(buf_.end(), bytes.begin(), bytes.end()); }

  std::vector<uint8_t> take() { return std::move(buf_); }

 private:
  std::vector<uint8_t> buf_;
};

std::string describe(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  YAML::Emitter e;
  e << YAML::Flow << node;
  std::string text = e.c_str();
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return std::string(node.IsMap() ? "a mapping " : "a sequence ") + text;
}

struct ParsedInt {
  bool negative = false;
  unsigned long long magnitude = 0;
};

// Integer as YAML 1.1 (PyYAML, hence `ros2 topic pub`) reads it: 12, -3, +4, 0x1F, 0b101, 017
// (octal), 0o17, underscores allowed.
bool parse_int(std::string text, ParsedInt& out) {
  text.erase(std::remove(text.begin(), text.end(), '_'), text.end());
  size_t i = 0;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) out.negative = text[i++] == '-';
  if (i >= text.size()) return false;
  int base = 10;
  if (text.size() - i > 2 && text[i] == '0' && (text[i + 1] == 'x' || text[i + 1] == 'X')) {
    base = 16;
    i += 2;
  } else if (text.size() - i > 2 && text[i] == '0' && (text[i + 1] == 'b' || text[i + 1] == 'B')) {
    base = 2;
    i += 2;
  } else if (text.size() - i > 2 && text[i] == '0' && (text[i + 1] == 'o' || text[i + 1] == 'O')) {
    base = 8;
    i += 2;
  } else if (text.size() - i > 1 && text[i] == '0') {
    base = 8;
    i += 1;
  }
  const char* first = text.data() + i;
  const char* last = text.data() + text.size();
  const auto result = std::from_chars(first, last, out.magnitude, base);
  return result.ec == std::errc() && result.ptr == last;
}

bool parse_float(const std::string& text, double& out) {
  static const std::map<std::string, double> kSpecial = {
      {".inf", HUGE_VAL},  {".Inf", HUGE_VAL},   {".INF", HUGE_VAL},   {"+.inf", HUGE_VAL},
      {"+.Inf", HUGE_VAL}, {"+.INF", HUGE_VAL},  {"-.inf", -HUGE_VAL}, {"-.Inf", -HUGE_VAL},
      {"-.INF", -HUGE_VAL}, {".nan", NAN},       {".NaN", NAN},        {".NAN", NAN},
      {"inf", HUGE_VAL},   {"-inf", -HUGE_VAL},  {"nan", NAN},
  };
  const auto it = kSpecial.find(text);
  if (it != kSpecial.end()) {
    out = it->second;
    return true;
  }
  if (text.empty()) return false;
  std::string clean = text;
  clean.erase(std::remove(clean.begin(), clean.end(), '_'), clean.end());
  ParsedInt as_int;
  if (parse_int(clean, as_int)) {  // 0x10, 017 are integers in YAML 1.1
    out = static_cast<double>(as_int.magnitude) * (as_int.negative ? -1.0 : 1.0);
    return true;
  }
  errno = 0;
  char* end = nullptr;
  out = std::strtod(clean.c_str(), &end);
  return end == clean.c_str() + clean.size() && std::isfinite(out);
}

class Encoder {
 public:
  std::vector<uint8_t> run(const StructType& type, const YAML::Node& value) {
    encode_struct(type, value, "");
    return writer_.take();
  }

 private:
  [[noreturn]] static void fail(const std::string& path, const std::string& message) {
    throw CodecError(show_path(path) + ": " + message);
  }

  static bool is_null(const YAML::Node& node) { return !node.IsDefined() || node.IsNull(); }

  void encode_struct(const StructType& type, const YAML::Node& value, const std::string& path) {
    std::map<std::string, YAML::Node> given;
    if (!is_null(value)) {
      if (!value.IsMap()) {
        fail(path, "expected a mapping for " + type_display_name(type) + ", got " + describe(value));
      }
      for (const auto& kv : value) {
        const std::string key = kv.first.as<std::string>();
        bool known = false;
        for (const Field& f : type.fields) known = known || f.name == key;
        if (!known) {
          std::string names;
          for (const Field& f : type.fields) names += (names.empty() ? "" : ", ") + f.name;
          fail(member_path(path, key),
               "unknown field of " + type_display_name(type) + " (fields: " + names + ")");
        }
        given[key] = kv.second;
      }
    }
    for (const Field& field : type.fields) {
      const std::string field_path = member_path(path, field.name);
      const auto it = given.find(field.name);
      if (it != given.end() && !is_null(it->second)) {
        encode_field(field, it->second, field_path);
      } else if (field.default_value.IsDefined() && !field.default_value.IsNull()) {
        encode_field(field, field.default_value, field_path + " (@default)");
      } else {
        encode_field(field, YAML::Node(), field_path);
      }
    }
  }

  void encode_field(const Field& field, const YAML::Node& value, const std::string& path) {
    if (field.container == Field::Container::kSingle) {
      encode_element(field.type, value, path);
      return;
    }
    const std::string type_text = field_type_string(field);
    if (!is_null(value) && !value.IsSequence()) {
      fail(path, "expected a list for " + type_text + ", got " + describe(value));
    }
    const size_t count = is_null(value) ? 0 : value.size();
    if (field.container == Field::Container::kArray) {
      if (is_null(value)) {
        for (size_t i = 0; i < field.array_size; ++i) encode_element(field.type, YAML::Node(), path);
        return;
      }
      if (count != field.array_size) {
        fail(path, "expected exactly " + std::to_string(field.array_size) + " elements for " +
                       type_text + ", got " + std::to_string(count));
      }
    } else {
      if (field.sequence_bound && count > field.sequence_bound) {
        fail(path, std::to_string(count) + " elements exceed the bound of " + type_text);
      }
      if (count > std::numeric_limits<uint32_t>::max()) fail(path, "too many elements");
      writer_.put_unsigned(count, 4);
    }
    for (size_t i = 0; i < count; ++i) {
      encode_element(field.type, value[i], path + "[" + std::to_string(i) + "]");
    }
  }

  void encode_element(const ElementType& type, const YAML::Node& value, const std::string& path) {
    switch (type.kind) {
      case ElementType::Kind::kStruct:
        encode_struct(*type.struct_type, value, path);
        return;
      case ElementType::Kind::kString: {
        std::string text;
        if (!is_null(value)) {
          if (!value.IsScalar()) fail(path, "expected a string, got " + describe(value));
          text = value.Scalar();
        }
        if (type.string_bound && text.size() > type.string_bound) {
          fail(path, "string of " + std::to_string(text.size()) + " bytes exceeds the bound of " +
                         element_type_string(type));
        }
        if (text.find('\0') != std::string::npos) fail(path, "strings cannot contain NUL");
        writer_.put_unsigned(text.size() + 1, 4);
        writer_.put_bytes(text);
        writer_.put_bytes(std::string(1, '\0'));
        return;
      }
      case ElementType::Kind::kPrimitive:
        encode_primitive(type.primitive, value, path);
        return;
    }
  }

  void encode_primitive(PrimitiveKind kind, const YAML::Node& value, const std::string& path) {
    const size_t size = primitive_size(kind);
    if (is_null(value)) {
      writer_.put_unsigned(0, size);
      return;
    }
    const char* name = primitive_name(kind);
    if (!value.IsScalar()) fail(path, std::string("expected ") + name + ", got " + describe(value));
    const std::string& text = value.Scalar();
    switch (kind) {
      case PrimitiveKind::kBool: {
        static const std::map<std::string, bool> kWords = {
            {"true", true},  {"True", true},   {"TRUE", true},   {"yes", true},  {"Yes", true},
            {"YES", true},   {"on", true},     {"On", true},     {"ON", true},   {"false", false},
            {"False", false}, {"FALSE", false}, {"no", false},    {"No", false},  {"NO", false},
            {"off", false},  {"Off", false},   {"OFF", false},
        };
        const auto it = kWords.find(text);
        if (it == kWords.end()) fail(path, "value '" + text + "' is not a boolean (true or false)");
        writer_.put_unsigned(it->second ? 1 : 0, 1);
        return;
      }
      case PrimitiveKind::kChar: {
        uint32_t code = 0;
        const auto c0 = static_cast<unsigned char>(text.empty() ? 0 : text[0]);
        if (text.size() == 1) {
          code = c0;
        } else if (text.size() == 2 && (c0 & 0xE0) == 0xC0) {
          code = ((c0 & 0x1Fu) << 6) | (static_cast<unsigned char>(text[1]) & 0x3Fu);
        } else {
          fail(path, "value '" + text + "' is not a single character (char)");
        }
        if (code > 0xFF) fail(path, "value '" + text + "' does not fit a char (code point > 255)");
        writer_.put_unsigned(code, 1);
        return;
      }
      case PrimitiveKind::kFloat:
      case PrimitiveKind::kDouble: {
        double v = 0;
        if (!parse_float(text, v)) fail(path, "value '" + text + "' is not a number (" + name + ")");
        if (kind == PrimitiveKind::kFloat) {
          if (std::isfinite(v) && std::fabs(v) > std::numeric_limits<float>::max()) {
            fail(path, "value '" + text + "' is out of range for float (|x| <= 3.4028235e+38)");
          }
          const float f = static_cast<float>(v);
          uint32_t bits = 0;
          std::memcpy(&bits, &f, 4);
          writer_.put_unsigned(bits, 4);
        } else {
          uint64_t bits = 0;
          std::memcpy(&bits, &v, 8);
          writer_.put_unsigned(bits, 8);
        }
        return;
      }
      default:
        break;
    }
    // Integer kinds (octet included).
    ParsedInt parsed;
    if (!parse_int(text, parsed)) fail(path, "value '" + text + "' is not an integer (" + name + ")");
    const bool is_signed = kind == PrimitiveKind::kInt8 || kind == PrimitiveKind::kInt16 ||
                           kind == PrimitiveKind::kInt32 || kind == PrimitiveKind::kInt64;
    const unsigned bits = static_cast<unsigned>(size * 8);
    const unsigned long long max_pos =
        is_signed ? (1ULL << (bits - 1)) - 1 : (bits == 64 ? ~0ULL : (1ULL << bits) - 1);
    const unsigned long long max_neg = is_signed ? (1ULL << (bits - 1)) : 0;
    if ((parsed.negative && parsed.magnitude > max_neg) ||
        (!parsed.negative && parsed.magnitude > max_pos)) {
      const std::string low = is_signed ? "-" + std::to_string(max_neg) : "0";
      fail(path, "value '" + text + "' is out of range for " + name + " [" + low + ", " +
                     std::to_string(max_pos) + "]");
    }
    const uint64_t raw = parsed.negative ? ~parsed.magnitude + 1 : parsed.magnitude;
    writer_.put_unsigned(raw, size);
  }

  Writer writer_;
};

// ---------------------------------------------------------------- decoding

// Decoded value, kept with enough kind information to print it like PyYAML.
struct Value {
  enum class Kind : uint8_t { kPlain, kString, kMap, kList };
  Kind kind = Kind::kPlain;
  std::string text;  // kPlain: printed as is; kString: string content (UTF-8)
  std::vector<std::pair<std::string, Value>> fields;
  std::vector<Value> items;

  static Value plain(std::string t) {
    Value v;
    v.text = std::move(t);
    return v;
  }
  static Value string(std::string t) {
    Value v;
    v.kind = Kind::kString;
    v.text = std::move(t);
    return v;
  }
};

std::string utf8_of(uint32_t code) {
  std::string out;
  if (code < 0x80) {
    out += static_cast<char>(code);
  } else if (code < 0x800) {
    out += static_cast<char>(0xC0 | (code >> 6));
    out += static_cast<char>(0x80 | (code & 0x3F));
  } else if (code < 0x10000) {
    out += static_cast<char>(0xE0 | (code >> 12));
    out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (code & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (code >> 18));
    out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (code & 0x3F));
  }
  return out;
}

// UTF-8 to code points; invalid bytes become U+FFFD as rclpy's "replace" decoding does.
std::u32string decode_utf8(const std::string& s) {
  std::u32string out;
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    size_t len = 0;
    uint32_t code = 0;
    if (c < 0x80) {
      len = 1;
      code = c;
    } else if ((c & 0xE0) == 0xC0 && c >= 0xC2) {
      len = 2;
      code = c & 0x1Fu;
    } else if ((c & 0xF0) == 0xE0) {
      len = 3;
      code = c & 0x0Fu;
    } else if ((c & 0xF8) == 0xF0 && c <= 0xF4) {
      len = 4;
      code = c & 0x07u;
    }
    bool ok = len > 0 && i + len <= s.size();
    for (size_t k = 1; ok && k < len; ++k) {
      const auto d = static_cast<unsigned char>(s[i + k]);
      ok = (d & 0xC0) == 0x80;
      code = (code << 6) | (d & 0x3Fu);
    }
    if (ok && ((len == 3 && (code < 0x800 || (code >= 0xD800 && code <= 0xDFFF))) ||
               (len == 4 && (code < 0x10000 || code > 0x10FFFF)))) {
      ok = false;
    }
    if (!ok) {
      out += U'\uFFFD';
      ++i;
    } else {
      out += static_cast<char32_t>(code);
      i += len;
    }
  }
  return out;
}

std::string encode_utf8(const std::u32string& s, size_t begin = 0, size_t end = std::u32string::npos) {
  std::string out;
  end = std::min(end, s.size());
  for (size_t i = begin; i < end; ++i) out += utf8_of(s[i]);
  return out;
}

class Reader {
 public:
  Reader(const uint8_t* data, size_t size) : data_(data), size_(size) {
    if (data == nullptr || size < kHeaderSize) {
      throw CodecError("(message): truncated data: " + std::to_string(size) +
                       " bytes, less than the 4-byte encapsulation header");
    }
    if (data[0] != 0x00 || (data[1] != 0x00 && data[1] != 0x01)) {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%02x %02x", data[0], data[1]);
      throw CodecError(std::string("(message): unsupported encapsulation ") + buf +
                       " (expected 00 01 CDR_LE or 00 00 CDR_BE)");
    }
    big_endian_ = data[1] == 0x00;
    pos_ = kHeaderSize;
  }

  void align(size_t n) {
    const size_t rel = pos_ - kHeaderSize;
    pos_ += (n - rel % n) % n;
  }

  void need(size_t n, const std::string& path) const {
    if (pos_ > size_ || size_ - pos_ < n) {
      throw CodecError(show_path(path) + ": truncated data: need " + std::to_string(n) +
                       " bytes at offset " + std::to_string(pos_) + ", sample has " +
                       std::to_string(size_) + " bytes");
    }
  }

  uint64_t get_unsigned(size_t size, const std::string& path) {
    align(size);
    need(size, path);
    uint64_t v = 0;
    for (size_t i = 0; i < size; ++i) {
      const uint64_t byte = data_[pos_ + (big_endian_ ? size - 1 - i : i)];
      v |= byte << (8 * i);
    }
    pos_ += size;
    return v;
  }

  std::string get_bytes(size_t n, const std::string& path) {
    need(n, path);
    std::string out(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return out;
  }

  void skip(size_t element_size, size_t count, const std::string& path) {
    if (count == 0) return;
    align(element_size);
    if (count > std::numeric_limits<size_t>::max() / element_size) need(SIZE_MAX, path);
    need(element_size * count, path);
    pos_ += element_size * count;
  }

  size_t remaining() const { return pos_ >= size_ ? 0 : size_ - pos_; }
  size_t position() const { return pos_; }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  bool big_endian_ = false;
};

size_t min_wire_size(const ElementType& type);

size_t min_wire_size(const StructType& type) {
  size_t total = 0;
  for (const Field& f : type.fields) {
    if (f.container == Field::Container::kSequence) {
      total += 4;
    } else {
      total += min_wire_size(f.type) * (f.container == Field::Container::kArray ? f.array_size : 1);
    }
  }
  return total;
}

size_t min_wire_size(const ElementType& type) {
  switch (type.kind) {
    case ElementType::Kind::kPrimitive: return primitive_size(type.primitive);
    case ElementType::Kind::kString: return 4;
    case ElementType::Kind::kStruct: return min_wire_size(*type.struct_type);
  }
  return 1;
}

class Decoder {
 public:
  // `echo` null: plain decoding for decode(); otherwise ros2 topic echo conversions.
  Decoder(const uint8_t* data, size_t size, const EchoOptions* echo)
      : reader_(data, size), echo_(echo) {}

  Value run(const StructType& type) {
    Value v = decode_struct(type, "");
    // Fast DDS may pad the payload to a multiple of 4 bytes; anything beyond is not this type.
    if (reader_.remaining() > 3) {
      throw CodecError("(message): " + std::to_string(reader_.remaining()) +
                       " unexpected bytes after the end of " + type_display_name(type) +
                       " at offset " + std::to_string(reader_.position()) +
                       " (wrong type for this data?)");
    }
    return v;
  }

 private:
  Value decode_struct(const StructType& type, const std::string& path) {
    Value v;
    v.kind = Value::Kind::kMap;
    const bool hide = is_empty_message(type);
    for (const Field& field : type.fields) {
      Value fv = decode_field(field, member_path(path, field.name));
      if (!hide) v.fields.emplace_back(field.name, std::move(fv));
    }
    return v;
  }

  Value decode_field(const Field& field, const std::string& path) {
    if (field.container == Field::Container::kSingle) return decode_element(field.type, path);
    size_t count = field.array_size;
    if (field.container == Field::Container::kSequence) {
      count = static_cast<size_t>(reader_.get_unsigned(4, path));
      if (field.sequence_bound && count > field.sequence_bound) {
        throw CodecError(show_path(path) + ": malformed data: " + std::to_string(count) +
                         " elements exceed the bound of " + field_type_string(field));
      }
      const size_t min_size = std::max<size_t>(1, min_wire_size(field.type));
      if (count > reader_.remaining() / min_size) {
        throw CodecError(show_path(path) + ": truncated data: sequence claims " +
                         std::to_string(count) + " elements but only " +
                         std::to_string(reader_.remaining()) + " bytes remain");
      }
    }
    if (echo_ && echo_->no_arr) {
      skip_elements(field.type, count, 0, path);
      const std::string element = field.type.kind == ElementType::Kind::kString
                                      ? std::string("string")
                                      : element_type_string(field.type);
      if (field.container == Field::Container::kArray) {
        return Value::string("<array type: " + element + "[" + std::to_string(count) + "]>");
      }
      if (field.sequence_bound) {
        return Value::string("<sequence type: " + element + "[" +
                             std::to_string(field.sequence_bound) +
                             "], length: " + std::to_string(count) + ">");
      }
      return Value::string("<sequence type: " + element + ", length: " + std::to_string(count) + ">");
    }
    Value list;
    list.kind = Value::Kind::kList;
    const size_t keep = echo_ ? std::min(count, echo_->truncate_length) : count;
    list.items.reserve(keep + 1);
    for (size_t i = 0; i < keep; ++i) {
      list.items.push_back(decode_element(field.type, path + "[" + std::to_string(i) + "]"));
    }
    if (keep < count) {
      skip_elements(field.type, count, keep, path);
      list.items.push_back(Value::string("..."));
    }
    return list;
  }

  // Reads elements [from, count) without keeping them.
  void skip_elements(const ElementType& type, size_t count, size_t from, const std::string& path) {
    if (type.kind == ElementType::Kind::kPrimitive && type.primitive != PrimitiveKind::kBool) {
      reader_.skip(primitive_size(type.primitive), count - from, path);
      return;
    }
    for (size_t i = from; i < count; ++i) decode_element(type, path + "[" + std::to_string(i) + "]");
  }

  Value decode_element(const ElementType& type, const std::string& path) {
    switch (type.kind) {
      case ElementType::Kind::kStruct:
        return decode_struct(*type.struct_type, path);
      case ElementType::Kind::kString:
        return decode_string(path);
      case ElementType::Kind::kPrimitive:
        return decode_primitive(type.primitive, path);
    }
    return Value();
  }

  Value decode_string(const std::string& path) {
    const size_t length = static_cast<size_t>(reader_.get_unsigned(4, path));
    std::string text = reader_.get_bytes(length, path);
    if (!text.empty() && text.back() == '\0') text.pop_back();
    if (!echo_) return Value::string(std::move(text));
    const std::u32string code_points = decode_utf8(text);
    if (echo_->no_str) {
      return Value::string("<string length: <" + std::to_string(code_points.size()) + ">>");
    }
    if (code_points.size() > echo_->truncate_length) {
      return Value::string(encode_utf8(code_points, 0, echo_->truncate_length) + "...");
    }
    return Value::string(encode_utf8(code_points));
  }

  Value decode_primitive(PrimitiveKind kind, const std::string& path) {
    const size_t size = primitive_size(kind);
    const uint64_t raw = reader_.get_unsigned(size, path);
    switch (kind) {
      case PrimitiveKind::kBool:
        if (raw > 1) {
          throw CodecError(show_path(path) + ": malformed data: boolean byte " +
                           std::to_string(raw) + " is neither 0 nor 1");
        }
        return Value::plain(raw ? "true" : "false");
      case PrimitiveKind::kChar:
        return Value::string(utf8_of(static_cast<uint32_t>(raw)));
      case PrimitiveKind::kOctet:
        // rclpy gives bytes, which ros2 topic echo prints as a one-character string.
        if (echo_) return Value::string(utf8_of(static_cast<uint32_t>(raw)));
        return Value::plain(std::to_string(raw));
      case PrimitiveKind::kInt8:
        return Value::plain(std::to_string(static_cast<int8_t>(raw)));
      case PrimitiveKind::kInt16:
        return Value::plain(std::to_string(static_cast<int16_t>(raw)));
      case PrimitiveKind::kInt32:
        return Value::plain(std::to_string(static_cast<int32_t>(raw)));
      case PrimitiveKind::kInt64:
        return Value::plain(std::to_string(static_cast<int64_t>(raw)));
      case PrimitiveKind::kUint8:
      case PrimitiveKind::kUint16:
      case PrimitiveKind::kUint32:
      case PrimitiveKind::kUint64:
        return Value::plain(std::to_string(raw));
      case PrimitiveKind::kFloat: {
        const auto bits = static_cast<uint32_t>(raw);
        float f = 0;
        std::memcpy(&f, &bits, 4);
        return Value::plain(format_float_like_python(static_cast<double>(f)));
      }
      case PrimitiveKind::kDouble: {
        double d = 0;
        std::memcpy(&d, &raw, 8);
        return Value::plain(format_float_like_python(d));
      }
    }
    return Value();
  }

  Reader reader_;
  const EchoOptions* echo_;
};

YAML::Node to_yaml_node(const Value& v) {
  switch (v.kind) {
    case Value::Kind::kPlain:
    case Value::Kind::kString:
      return YAML::Node(v.text);
    case Value::Kind::kMap: {
      YAML::Node node(YAML::NodeType::Map);
      for (const auto& [key, value] : v.fields) node[key] = to_yaml_node(value);
      return node;
    }
    case Value::Kind::kList: {
      YAML::Node node(YAML::NodeType::Sequence);
      for (const Value& item : v.items) node.push_back(to_yaml_node(item));
      return node;
    }
  }
  return YAML::Node();
}

// ---------------------------------------------------------------- PyYAML-compatible printing
// ros2 topic echo prints yaml.dump(msg_dict, allow_unicode=True, width=sys.maxsize,
// default_flow_style=False); the functions below reproduce PyYAML's emitter for that case.

bool is_break(char32_t c) { return c == U'\n' || c == 0x85 || c == 0x2028 || c == 0x2029; }

bool is_blank_or_break(char32_t c) {
  return c == 0 || c == U' ' || c == U'\t' || c == U'\r' || is_break(c);
}

bool is_printable_unicode(char32_t c) {
  return c == 0x85 || (c >= 0xA0 && c <= 0xD7FF) || (c >= 0xE000 && c <= 0xFFFD) ||
         (c >= 0x10000 && c < 0x10FFFF);
}

struct ScalarAnalysis {
  bool multiline = false;
  bool allow_block_plain = true;
  bool allow_single_quoted = true;
};

// PyYAML Emitter.analyze_scalar (block context, allow_unicode=True).
ScalarAnalysis analyze_scalar(const std::u32string& s) {
  ScalarAnalysis a;
  if (s.empty()) return a;
  bool block_indicators = false;
  bool line_breaks = false;
  bool special_characters = false;
  bool leading_space = false, leading_break = false, trailing_space = false, trailing_break = false;
  bool break_space = false, space_break = false;
  if (s.compare(0, 3, U"---") == 0 || s.compare(0, 3, U"...") == 0) block_indicators = true;
  bool preceded_by_whitespace = true;
  bool followed_by_whitespace = s.size() == 1 || is_blank_or_break(s[1]);
  bool previous_space = false, previous_break = false;
  for (size_t i = 0; i < s.size(); ++i) {
    const char32_t ch = s[i];
    if (i == 0) {
      if (std::u32string_view(U"#,[]{}&*!|>'\"%@`").find(ch) != std::u32string_view::npos) {
        block_indicators = true;
      }
      if ((ch == U'?' || ch == U':') && followed_by_whitespace) block_indicators = true;
      if (ch == U'-' && followed_by_whitespace) block_indicators = true;
    } else {
      if (ch == U':' && followed_by_whitespace) block_indicators = true;
      if (ch == U'#' && preceded_by_whitespace) block_indicators = true;
    }
    if (is_break(ch)) line_breaks = true;
    if (!(ch == U'\n' || (ch >= 0x20 && ch <= 0x7E))) {
      if (!is_printable_unicode(ch) || ch == 0xFEFF) special_characters = true;
    }
    if (ch == U' ') {
      if (i == 0) leading_space = true;
      if (i == s.size() - 1) trailing_space = true;
      if (previous_break) break_space = true;
      previous_space = true;
      previous_break = false;
    } else if (is_break(ch)) {
      if (i == 0) leading_break = true;
      if (i == s.size() - 1) trailing_break = true;
      if (previous_space) space_break = true;
      previous_space = false;
      previous_break = true;
    } else {
      previous_space = false;
      previous_break = false;
    }
    preceded_by_whitespace = is_blank_or_break(ch);
    followed_by_whitespace = i + 2 >= s.size() || is_blank_or_break(s[i + 2]);
  }
  a.multiline = line_breaks;
  if (leading_space || leading_break || trailing_space || trailing_break) a.allow_block_plain = false;
  if (break_space) a.allow_block_plain = a.allow_single_quoted = false;
  if (space_break || special_characters) a.allow_block_plain = a.allow_single_quoted = false;
  if (line_breaks) a.allow_block_plain = false;
  if (block_indicators) a.allow_block_plain = false;
  return a;
}

// True when PyYAML's resolver reads the plain scalar as something other than a string
// (bool, int, float, null, timestamp, merge, value), so it must be quoted.
bool resolves_to_non_string(const std::string& s) {
  static const std::regex kPatterns[] = {
      std::regex("yes|Yes|YES|no|No|NO|true|True|TRUE|false|False|FALSE|on|On|ON|off|Off|OFF"),
      std::regex("[-+]?(?:[0-9][0-9_]*)\\.[0-9_]*(?:[eE][-+][0-9]+)?"
                 "|\\.[0-9][0-9_]*(?:[eE][-+][0-9]+)?"
                 "|[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+\\.[0-9_]*"
                 "|[-+]?\\.(?:inf|Inf|INF)|\\.(?:nan|NaN|NAN)"),
      std::regex("[-+]?0b[0-1_]+|[-+]?0[0-7_]+|[-+]?(?:0|[1-9][0-9_]*)|[-+]?0x[0-9a-fA-F_]+"
                 "|[-+]?[1-9][0-9_]*(?::[0-5]?[0-9])+"),
      std::regex("~|null|Null|NULL|"),
      std::regex("[0-9][0-9][0-9][0-9]-[0-9][0-9]-[0-9][0-9]"
                 "|[0-9][0-9][0-9][0-9]-[0-9][0-9]?-[0-9][0-9]?(?:[Tt]|[ \\t]+)[0-9][0-9]?"
                 ":[0-9][0-9]:[0-9][0-9](?:\\.[0-9]*)?(?:[ \\t]*(?:Z|[-+][0-9][0-9]?(?::[0-9][0-9])?))?"),
      std::regex("<<|=|!|&|\\*"),
  };
  // Python's `$` also matches before a final newline.
  const std::string body = !s.empty() && s.back() == '\n' ? s.substr(0, s.size() - 1) : s;
  for (const std::regex& r : kPatterns) {
    if (std::regex_match(s, r) || std::regex_match(body, r)) return true;
  }
  return false;
}

void write_single_quoted(std::string& out, const std::u32string& s, size_t indent) {
  out += '\'';
  bool spaces = false, breaks = false;
  size_t start = 0;
  for (size_t end = 0; end <= s.size(); ++end) {
    const bool at_end = end == s.size();
    const char32_t ch = at_end ? 0 : s[end];
    if (spaces) {
      if (at_end || ch != U' ') {
        out += encode_utf8(s, start, end);
        start = end;
      }
    } else if (breaks) {
      if (at_end || !is_break(ch)) {
        if (s[start] == U'\n') out += '\n';
        for (size_t k = start; k < end; ++k) out += utf8_of(s[k]);
        out.append(indent, ' ');
        start = end;
      }
    } else if (at_end || ch == U' ' || is_break(ch) || ch == U'\'') {
      if (start < end) {
        out += encode_utf8(s, start, end);
        start = end;
      }
    }
    if (!at_end && ch == U'\'') {
      out += "''";
      start = end + 1;
    }
    if (!at_end) {
      spaces = ch == U' ';
      breaks = is_break(ch);
    }
  }
  out += '\'';
}

void write_double_quoted(std::string& out, const std::u32string& s) {
  static const std::map<char32_t, const char*> kEscapes = {
      {0x00, "0"}, {0x07, "a"}, {0x08, "b"}, {0x09, "t"},  {0x0A, "n"},    {0x0B, "v"},
      {0x0C, "f"}, {0x0D, "r"}, {0x1B, "e"}, {U'"', "\""}, {U'\\', "\\"}, {0x85, "N"},
      {0xA0, "_"}, {0x2028, "L"}, {0x2029, "P"},
  };
  out += '"';
  for (const char32_t ch : s) {
    const bool printable = (ch >= 0x20 && ch <= 0x7E) || (ch >= 0xA0 && ch <= 0xD7FF) ||
                           (ch >= 0xE000 && ch <= 0xFFFD);
    if (printable && ch != U'"' && ch != U'\\' && ch != 0x2028 && ch != 0x2029 &&
        ch != 0xFEFF) {
      out += utf8_of(ch);
      continue;
    }
    const auto it = kEscapes.find(ch);
    char buf[16];
    if (it != kEscapes.end()) {
      std::snprintf(buf, sizeof(buf), "\\%s", it->second);
    } else if (ch <= 0xFF) {
      std::snprintf(buf, sizeof(buf), "\\x%02X", static_cast<unsigned>(ch));
    } else if (ch <= 0xFFFF) {
      std::snprintf(buf, sizeof(buf), "\\u%04X", static_cast<unsigned>(ch));
    } else {
      std::snprintf(buf, sizeof(buf), "\\U%08X", static_cast<unsigned>(ch));
    }
    out += buf;
  }
  out += '"';
}

// A string scalar as PyYAML writes it: plain, 'single' or "double" quoted. `indent` is where
// continuation lines of a multi-line single-quoted scalar start.
void write_string(std::string& out, const std::string& text, size_t indent, bool simple_key) {
  const std::u32string s = decode_utf8(text);
  const ScalarAnalysis a = analyze_scalar(s);
  if (!s.empty() && a.allow_block_plain && !(simple_key && a.multiline) &&
      !resolves_to_non_string(text)) {
    out += text;
  } else if (a.allow_single_quoted && !(simple_key && a.multiline)) {
    write_single_quoted(out, s, indent);
  } else {
    write_double_quoted(out, s);
  }
}

void write_scalar(std::string& out, const Value& v, size_t indent) {
  if (v.kind == Value::Kind::kPlain) {
    out += v.text;
  } else {
    write_string(out, v.text, indent, false);
  }
}

void write_list(std::string& out, const Value& list, size_t indent, bool first_inline);

void write_map(std::string& out, const Value& map, size_t indent, bool first_inline) {
  bool first = true;
  for (const auto& [key, value] : map.fields) {
    if (!(first && first_inline)) out.append(indent, ' ');
    first = false;
    write_string(out, key, indent + 2, true);
    out += ':';
    if (value.kind == Value::Kind::kMap) {
      if (value.fields.empty()) {
        out += " {}\n";
      } else {
        out += '\n';
        write_map(out, value, indent + 2, false);
      }
    } else if (value.kind == Value::Kind::kList) {
      if (value.items.empty()) {
        out += " []\n";
      } else {
        out += '\n';
        write_list(out, value, indent, false);  // block sequences in mappings are not indented
      }
    } else {
      out += ' ';
      write_scalar(out, value, indent + 2);
      out += '\n';
    }
  }
}

void write_list(std::string& out, const Value& list, size_t indent, bool first_inline) {
  bool first = true;
  for (const Value& item : list.items) {
    if (!(first && first_inline)) out.append(indent, ' ');
    first = false;
    out += '-';
    if (item.kind == Value::Kind::kMap && !item.fields.empty()) {
      out += ' ';
      write_map(out, item, indent + 2, true);
    } else if (item.kind == Value::Kind::kList && !item.items.empty()) {
      out += ' ';
      write_list(out, item, indent + 2, true);
    } else if (item.kind == Value::Kind::kMap) {
      out += " {}\n";
    } else if (item.kind == Value::Kind::kList) {
      out += " []\n";
    } else {
      out += ' ';
      write_scalar(out, item, indent + 2);
      out += '\n';
    }
  }
}

}  // namespace

std::vector<uint8_t> encode(const StructType& type, const YAML::Node& value) {
  return Encoder().run(type, value);
}

YAML::Node decode(const StructType& type, const uint8_t* data, size_t size) {
  return to_yaml_node(Decoder(data, size, nullptr).run(type));
}

std::string to_echo_yaml(const StructType& type, const uint8_t* data, size_t size,
                         const EchoOptions& options) {
  const Value root = Decoder(data, size, &options).run(type);
  if (root.fields.empty()) return "{}\n";
  std::string out;
  write_map(out, root, 0, false);
  return out;
}

std::string format_float_like_python(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  char buf[64];
  const auto result = std::to_chars(buf, buf + sizeof(buf), value, std::chars_format::scientific);
  const std::string sci(buf, result.ptr);  // e.g. "-1.2345e-05", shortest round-trip digits
  const bool negative = sci[0] == '-';
  const size_t e_pos = sci.find('e');
  std::string digits;
  for (size_t i = negative ? 1 : 0; i < e_pos; ++i) {
    if (sci[i] != '.') digits += sci[i];
  }
  const int exponent = std::atoi(sci.c_str() + e_pos + 1);
  const int decpt = exponent + 1;  // digits are 0.d1d2... * 10^decpt
  std::string out = negative ? "-" : "";
  if (decpt <= -4 || decpt > 16) {  // Python repr switches to exponent notation here
    out += digits[0];
    out += '.';  // PyYAML writes 1.0e-05 where Python writes 1e-05
    out += digits.size() > 1 ? digits.substr(1) : "0";
    const int a = std::abs(exponent);
    out += exponent < 0 ? "e-" : "e+";
    if (a < 10) out += '0';
    out += std::to_string(a);
  } else if (decpt <= 0) {
    out += "0." + std::string(static_cast<size_t>(-decpt), '0') + digits;
  } else if (static_cast<size_t>(decpt) >= digits.size()) {
    out += digits + std::string(static_cast<size_t>(decpt) - digits.size(), '0') + ".0";
  } else {
    out += digits.substr(0, static_cast<size_t>(decpt)) + "." + digits.substr(static_cast<size_t>(decpt));
  }
  return out;
}

}  // namespace unav_introspection
