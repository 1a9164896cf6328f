// Plain CDR (XCDR1) decoding into a value tree / YAML, driven by StructType.
#include "cdr_internal.hpp"

namespace unav::introspection {

using namespace cdr_detail;  // NOLINT(google-build-using-namespace)

namespace {

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
      throw CodecError(show_path(path) + ": truncated data: need " + std::to_string(n) + " bytes at offset " +
                       std::to_string(pos_) + ", sample has " + std::to_string(size_) + " bytes");
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
    case ElementType::Kind::kPrimitive:
      return primitive_size(type.primitive);
    case ElementType::Kind::kString:
      return 4;
    case ElementType::Kind::kStruct:
      return min_wire_size(*type.struct_type);
  }
  return 1;
}

class Decoder {
 public:
  // `echo` null: plain decoding for decode(); otherwise ros2 topic echo conversions.
  Decoder(const uint8_t* data, size_t size, const EchoOptions* echo) : reader_(data, size), echo_(echo) {}

  Value run(const StructType& type) {
    Value v = decode_struct(type, "");
    // Fast DDS may pad the payload to a multiple of 4 bytes; anything beyond is not this type.
    if (reader_.remaining() > 3) {
      throw CodecError("(message): " + std::to_string(reader_.remaining()) + " unexpected bytes after the end of " +
                       type_display_name(type) + " at offset " + std::to_string(reader_.position()) +
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
        throw CodecError(show_path(path) + ": truncated data: sequence claims " + std::to_string(count) +
                         " elements but only " + std::to_string(reader_.remaining()) + " bytes remain");
      }
    }
    if (echo_ && echo_->no_arr) {
      skip_elements(field.type, count, 0, path);
      const std::string element =
          field.type.kind == ElementType::Kind::kString ? std::string("string") : element_type_string(field.type);
      if (field.container == Field::Container::kArray) {
        return Value::string("<array type: " + element + "[" + std::to_string(count) + "]>");
      }
      if (field.sequence_bound) {
        return Value::string("<sequence type: " + element + "[" + std::to_string(field.sequence_bound) +
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
          throw CodecError(show_path(path) + ": malformed data: boolean byte " + std::to_string(raw) +
                           " is neither 0 nor 1");
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

}  // namespace

YAML::Node decode(const StructType& type, const uint8_t* data, size_t size) {
  return to_yaml_node(Decoder(data, size, nullptr).run(type));
}

Value cdr_detail::decode_value(const StructType& type, const uint8_t* data, size_t size, const EchoOptions* echo) {
  return Decoder(data, size, echo).run(type);
}

}  // namespace unav::introspection
