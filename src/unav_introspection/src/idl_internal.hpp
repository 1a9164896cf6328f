// Internal to the IDL parser and the type registry: tokens, lexer helpers and the registry
// state the parser fills.
#pragma once

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <system_error>
#include <utility>

#include "unav_introspection/type_registry.hpp"

namespace unav::introspection {

namespace fs = std::filesystem;

namespace idl {

enum class TokenKind { kIdent, kNumber, kString, kChar, kPunct, kDirective, kEnd };

struct Token {
  TokenKind kind;
  std::string text;  // string and char literals: unescaped content
  int line;
};

inline bool is_ident_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
inline bool is_ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

inline bool is_identifier(const std::string& s) {
  if (s.empty() || !is_ident_start(s[0])) return false;
  return std::all_of(s.begin(), s.end(), is_ident_char);
}

inline std::vector<std::string> split(const std::string& s, const std::string& sep) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    const size_t pos = s.find(sep, start);
    if (pos == std::string::npos) {
      parts.push_back(s.substr(start));
      return parts;
    }
    parts.push_back(s.substr(start, pos - start));
    start = pos + sep.size();
  }
}

inline std::string join(const std::vector<std::string>& parts, const std::string& sep, size_t begin = 0,
                        size_t end = std::string::npos) {
  std::string out;
  end = std::min(end, parts.size());
  for (size_t i = begin; i < end; ++i) {
    if (i > begin) out += sep;
    out += parts[i];
  }
  return out;
}

inline std::string trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

inline char unescape_char(char c) {
  switch (c) {
    case 'n':
      return '\n';
    case 't':
      return '\t';
    case 'r':
      return '\r';
    case '0':
      return '\0';
    case 'a':
      return '\a';
    case 'b':
      return '\b';
    case 'f':
      return '\f';
    case 'v':
      return '\v';
    default:
      return c;
  }
}

// Integer literal as IDL writes it (decimal, 0x hex, leading-0 octal); nullopt when not one.
inline std::optional<unsigned long long> parse_integer_literal(const std::string& text) {
  if (text.empty() || !std::isdigit(static_cast<unsigned char>(text[0]))) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const unsigned long long v = std::strtoull(text.c_str(), &end, 0);
  if (errno != 0 || end != text.c_str() + text.size()) return std::nullopt;
  return v;
}

struct Alias {
  ElementType type;
  Field::Container container = Field::Container::kSingle;
  size_t array_size = 0;
  size_t sequence_bound = 0;
};

struct Annotation {
  std::string name;
  std::vector<Token> args;
  int line;
};

/// Splits IDL text into tokens (comments dropped, literals unescaped). Throws IdlError.
std::vector<Token> tokenize(const std::string& text, const std::string& file);

}  // namespace idl

using namespace idl;  // NOLINT(google-build-using-namespace)

namespace detail {

// Everything the parser and the registry share; TypeRegistry::Impl is just this.
struct RegistryState {
  std::vector<std::string> roots;
  std::map<std::string, std::unique_ptr<StructType>> structs;  // by scoped DDS name
  std::map<std::string, Alias> aliases;                        // typedefs by scoped name
  std::map<std::string, Constant> constants;                   // by scoped name
  std::set<std::string> files_seen;                            // canonical, parsed or in progress
  std::map<std::string, std::vector<const StructType*>> file_structs;

  std::vector<const StructType*> parse_file(const fs::path& path, const std::string& root);
  std::string root_of(const fs::path& path) const;
  const StructType* try_load_by_name(const std::string& scoped_name);
  std::string roots_text() const;
};

}  // namespace detail

namespace idl {
/// Parses the tokens of one IDL file into `registry` (structs, typedefs, constants; included
/// files through registry.parse_file). Returns the structs the file declares. Throws IdlError.
std::vector<const StructType*> parse(detail::RegistryState& registry, const std::string& file, const std::string& root,
                                     std::vector<Token> tokens);
}  // namespace idl

}  // namespace unav::introspection
