// `ros2 topic echo` printing: PyYAML-compatible YAML of a decoded sample.
#include "cdr_internal.hpp"

namespace unav::introspection {

using namespace cdr_detail;  // NOLINT(google-build-using-namespace)

namespace {

// ---------------------------------------------------------------- PyYAML-compatible printing
// ros2 topic echo prints yaml.dump(msg_dict, allow_unicode=True, width=sys.maxsize,
// default_flow_style=False); the functions below reproduce PyYAML's emitter for that case.

bool is_break(char32_t c) { return c == U'\n' || c == 0x85 || c == 0x2028 || c == 0x2029; }

bool is_blank_or_break(char32_t c) { return c == 0 || c == U' ' || c == U'\t' || c == U'\r' || is_break(c); }

bool is_printable_unicode(char32_t c) {
  return c == 0x85 || (c >= 0xA0 && c <= 0xD7FF) || (c >= 0xE000 && c <= 0xFFFD) || (c >= 0x10000 && c < 0x10FFFF);
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
      {0x00, "0"}, {0x07, "a"},  {0x08, "b"},   {0x09, "t"}, {0x0A, "n"}, {0x0B, "v"},   {0x0C, "f"},   {0x0D, "r"},
      {0x1B, "e"}, {U'"', "\""}, {U'\\', "\\"}, {0x85, "N"}, {0xA0, "_"}, {0x2028, "L"}, {0x2029, "P"},
  };
  out += '"';
  for (const char32_t ch : s) {
    const bool printable = (ch >= 0x20 && ch <= 0x7E) || (ch >= 0xA0 && ch <= 0xD7FF) || (ch >= 0xE000 && ch <= 0xFFFD);
    if (printable && ch != U'"' && ch != U'\\' && ch != 0x2028 && ch != 0x2029 && ch != 0xFEFF) {
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
  if (!s.empty() && a.allow_block_plain && !(simple_key && a.multiline) && !resolves_to_non_string(text)) {
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

std::string to_echo_yaml(const StructType& type, const uint8_t* data, size_t size, const EchoOptions& options) {
  const Value root = decode_value(type, data, size, &options);
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

}  // namespace unav::introspection
