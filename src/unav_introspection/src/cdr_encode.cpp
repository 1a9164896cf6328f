// Plain CDR (XCDR1) encoding of YAML values, driven by StructType (see cdr_codec.hpp for the wire rules).
#include "cdr_internal.hpp"

namespace unav::introspection {

using namespace cdr_detail;  // NOLINT(google-build-using-namespace)

namespace {

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
      {".inf", HUGE_VAL},  {".Inf", HUGE_VAL},   {".INF", HUGE_VAL},   {"+.inf", HUGE_VAL},  {"+.Inf", HUGE_VAL},
      {"+.INF", HUGE_VAL}, {"-.inf", -HUGE_VAL}, {"-.Inf", -HUGE_VAL}, {"-.INF", -HUGE_VAL}, {".nan", NAN},
      {".NaN", NAN},       {".NAN", NAN},        {"inf", HUGE_VAL},    {"-inf", -HUGE_VAL},  {"nan", NAN},
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
          fail(member_path(path, key), "unknown field of " + type_display_name(type) + " (fields: " + names + ")");
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
        fail(path, "expected exactly " + std::to_string(field.array_size) + " elements for " + type_text + ", got " +
                       std::to_string(count));
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
          fail(path,
               "string of " + std::to_string(text.size()) + " bytes exceeds the bound of " + element_type_string(type));
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
            {"true", true}, {"True", true}, {"TRUE", true}, {"yes", true},    {"Yes", true},    {"YES", true},
            {"on", true},   {"On", true},   {"ON", true},   {"false", false}, {"False", false}, {"FALSE", false},
            {"no", false},  {"No", false},  {"NO", false},  {"off", false},   {"Off", false},   {"OFF", false},
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
    const unsigned long long max_pos = is_signed ? (1ULL << (bits - 1)) - 1 : (bits == 64 ? ~0ULL : (1ULL << bits) - 1);
    const unsigned long long max_neg = is_signed ? (1ULL << (bits - 1)) : 0;
    if ((parsed.negative && parsed.magnitude > max_neg) || (!parsed.negative && parsed.magnitude > max_pos)) {
      const std::string low = is_signed ? "-" + std::to_string(max_neg) : "0";
      fail(path,
           "value '" + text + "' is out of range for " + name + " [" + low + ", " + std::to_string(max_pos) + "]");
    }
    const uint64_t raw = parsed.negative ? ~parsed.magnitude + 1 : parsed.magnitude;
    writer_.put_unsigned(raw, size);
  }

  Writer writer_;
};

}  // namespace

std::vector<uint8_t> encode(const StructType& type, const YAML::Node& value) { return Encoder().run(type, value); }

}  // namespace unav::introspection
