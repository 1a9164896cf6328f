// Internal to the CDR codec: helpers shared by cdr_encode.cpp, cdr_decode.cpp and cdr_echo.cpp,
// and the decoded value tree the echo printer formats.
#pragma once

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <regex>
#include <string_view>
#include <utility>
#include "unav_introspection/cdr_codec.hpp"
#include "unav_introspection/type_registry.hpp"

namespace unav::introspection::cdr_detail {

constexpr size_t kHeaderSize = 4;
constexpr const char* kDummyMember = "structure_needs_at_least_one_member";

inline std::string show_path(const std::string& path) { return path.empty() ? "(message)" : path; }

inline std::string member_path(const std::string& parent, const std::string& name) {
  return parent.empty() ? name : parent + "." + name;
}

inline std::string type_display_name(const StructType& type) {
  try {
    return dds_to_ros_name(type.name);
  } catch (const UnknownTypeError&) {
    return type.name;
  }
}

// A sole member named structure_needs_at_least_one_member stands for an empty message; ROS 2
// tools hide it.
inline bool is_empty_message(const StructType& type) {
  return type.fields.size() == 1 && type.fields[0].name == kDummyMember;
}

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

inline std::string utf8_of(uint32_t code) {
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
inline std::u32string decode_utf8(const std::string& s) {
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

inline std::string encode_utf8(const std::u32string& s, size_t begin = 0, size_t end = std::u32string::npos) {
  std::string out;
  end = std::min(end, s.size());
  for (size_t i = begin; i < end; ++i) out += utf8_of(s[i]);
  return out;
}

/// Decodes one sample into a value tree (echo options: truncation of arrays and strings; null:
/// none). Throws DecodeError as decode() does.
Value decode_value(const StructType& type, const uint8_t* data, size_t size, const EchoOptions* echo);

}  // namespace unav::introspection::cdr_detail
