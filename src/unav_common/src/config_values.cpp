// The leaf values behind config.hpp (config_values.hpp): formatting, rules, reading YAML scalars and
// lists into each ValueType, checking and writing them back. Everything type-specific is a switch
// over ValueType here, so a config struct costs one instantiation of its Serialize() and nothing else.
#include "config_values.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace unav::common::config_values {

// ------------------------------------------------------------------ formatting

/// Shortest text that reads back to the same double ("0.05", "200", "1e-07").
std::string ShortestNumber(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

/// A double as YAML text that stays a float for other readers: "200.0", "0.05", "1e-07".
std::string DoubleText(double v) {
  std::string s = ShortestNumber(v);
  if (s.find_first_of(".enai") == std::string::npos) s += ".0";
  return s;
}

/// YAML text of a string: as is, quoted when a YAML reader would not read it back as this
/// string (empty, a number, a bool or null word, leading/trailing blanks, special characters).
std::string StringText(const std::string& s) {
  bool plain = !s.empty() && s.front() != ' ' && s.back() != ' ' &&
               s.find_first_of(":#,[]{}&*!|>'\"%@`\n\t") == std::string::npos && s.front() != '-' && s.front() != '?';
  if (plain) {
    try {
      const YAML::Node n = YAML::Load(s);
      plain = n.IsScalar() && n.Scalar() == s;
    } catch (const YAML::Exception&) {
      plain = false;
    }
    static const char* const kWords[] = {"true", "True", "TRUE", "false", "False", "FALSE", "yes",  "Yes", "YES",
                                         "no",   "No",   "NO",   "on",    "On",    "ON",    "off",  "Off", "OFF",
                                         "y",    "Y",    "n",    "N",     "null",  "Null",  "NULL", "~"};
    for (const char* w : kWords) plain = plain && s != w;
    char* end = nullptr;
    std::strtod(s.c_str(), &end);
    plain = plain && !(end != nullptr && *end == '\0') && s[0] != '.';
  }
  if (plain) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out + "\"";
}

std::string JoinTexts(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

template <class V, class F>
std::string ListText(const V& values, long n, F&& text) {
  std::vector<std::string> items;
  for (long i = 0; i < n; ++i) items.push_back(text(values[i]));
  return "[" + JoinTexts(items) + "]";
}

/// Order n of a square-matrix value type, else 0. The matrices are Eigen's fixed-size types,
/// column-major doubles, so one Map reads and writes both.
int MatrixOrder(ValueType t) { return t == ValueType::kMatrix3 ? 3 : t == ValueType::kMatrix6 ? 6 : 0; }
Eigen::Map<Eigen::MatrixXd> MatrixOf(ValueRef v) {
  const int n = MatrixOrder(v.type);
  return {static_cast<double*>(v.ptr), n, n};
}
bool IsDiagonal(const Eigen::Ref<const Eigen::MatrixXd>& m) {
  return (m - Eigen::MatrixXd(m.diagonal().asDiagonal())).cwiseAbs().maxCoeff() == 0.0;
}

/// The current value as flow YAML text.
std::string ValueText(ValueRef v) {
  if (const int n = MatrixOrder(v.type)) {
    const auto m = MatrixOf(v);
    if (IsDiagonal(m)) return ListText(m.diagonal(), n, DoubleText);
    std::vector<std::string> rows;
    rows.reserve(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) rows.push_back(ListText(m.row(i), n, DoubleText));
    return "[" + JoinTexts(rows) + "]";
  }
  switch (v.type) {
    case ValueType::kBool:
      return *static_cast<const bool*>(v.ptr) ? "true" : "false";
    case ValueType::kInt:
      return std::to_string(*static_cast<const int*>(v.ptr));
    case ValueType::kInt64:
      return std::to_string(*static_cast<const int64_t*>(v.ptr));
    case ValueType::kUint32:
      return std::to_string(*static_cast<const uint32_t*>(v.ptr));
    case ValueType::kDouble:
      return DoubleText(*static_cast<const double*>(v.ptr));
    case ValueType::kString:
      return StringText(*static_cast<const std::string*>(v.ptr));
    case ValueType::kDoubleList: {
      const auto& l = *static_cast<const std::vector<double>*>(v.ptr);
      return ListText(l, static_cast<long>(l.size()), DoubleText);
    }
    case ValueType::kIntList: {
      const auto& l = *static_cast<const std::vector<int>*>(v.ptr);
      return ListText(l, static_cast<long>(l.size()), [](int x) { return std::to_string(x); });
    }
    case ValueType::kStringList: {
      const auto& l = *static_cast<const std::vector<std::string>*>(v.ptr);
      return ListText(l, static_cast<long>(l.size()), StringText);
    }
    case ValueType::kVector2:
      return ListText(*static_cast<const Eigen::Vector2d*>(v.ptr), 2, DoubleText);
    case ValueType::kVector3:
      return ListText(*static_cast<const Eigen::Vector3d*>(v.ptr), 3, DoubleText);
    case ValueType::kMatrix3:
    case ValueType::kMatrix6:
      break;  // above
  }
  return "";
}

const char* TypeName(ValueType t) {
  switch (t) {
    case ValueType::kBool:
      return "bool";
    case ValueType::kInt:
      return "int";
    case ValueType::kInt64:
      return "int64";
    case ValueType::kUint32:
      return "uint32";
    case ValueType::kDouble:
      return "double";
    case ValueType::kString:
      return "string";
    case ValueType::kDoubleList:
      return "double[]";
    case ValueType::kIntList:
      return "int[]";
    case ValueType::kStringList:
      return "string[]";
    case ValueType::kVector2:
      return "double[2]";
    case ValueType::kVector3:
      return "double[3]";
    case ValueType::kMatrix3:
      return "double[3x3]";
    case ValueType::kMatrix6:
      return "double[6x6]";
  }
  return "";
}

/// The value of a YAML node as it was written: the scalar text (quoted strings in quotes),
/// "null", or the collection in flow style.
std::string Written(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "null";
  if (n.IsScalar()) return n.Tag() == "!" ? "\"" + n.Scalar() + "\"" : n.Scalar();
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

std::string ChildPath(const std::string& parent, const std::string& name) {
  return parent.empty() ? name : parent + "." + name;
}
std::string IndexPath(const std::string& parent, std::size_t i) { return parent + "[" + std::to_string(i) + "]"; }

// ------------------------------------------------------------------ rules

bool NumberOk(const FieldSpec& s, double v) {
  if (s.has_lo && !(s.lo_open ? v > s.lo : v >= s.lo)) return false;
  if (s.has_hi && !(s.hi_open ? v < s.hi : v <= s.hi)) return false;
  return true;
}

std::string NumberRule(const FieldSpec& s) {
  if (s.has_lo && s.has_hi)
    return "in " + std::string(s.lo_open ? "(" : "[") + ShortestNumber(s.lo) + ", " + ShortestNumber(s.hi) +
           (s.hi_open ? ")" : "]");
  if (s.has_lo) return std::string(s.lo_open ? "> " : ">= ") + ShortestNumber(s.lo);
  if (s.has_hi) return std::string(s.hi_open ? "< " : "<= ") + ShortestNumber(s.hi);
  return "";
}

bool TextOk(const FieldSpec& s, const std::string& v) {
  return s.one_of.empty() || std::find(s.one_of.begin(), s.one_of.end(), v) != s.one_of.end();
}

std::string TextRule(const FieldSpec& s) {
  std::vector<std::string> items;
  for (const auto& a : s.one_of) items.push_back(StringText(a));
  return "one of {" + JoinTexts(items) + "}";
}

const char* kFinite = "must be finite (NaN/Inf rejected)";

/// Where errors go: ConfigError(file, key path, value text, rule).

/// Checks one number against the field's rule (finite for doubles).
void CheckNumber(const Reporter& r, const FieldSpec& s, double v, bool is_double, const std::string& path,
                 const std::string& text) {
  if (is_double && !std::isfinite(v)) r.Fail(path, text, kFinite);
  if (!NumberOk(s, v)) r.Fail(path, text, "must be " + NumberRule(s));
}

void CheckText(const Reporter& r, const FieldSpec& s, const std::string& v, const std::string& path,
               const std::string& text) {
  if (!TextOk(s, v)) r.Fail(path, text, "must be " + TextRule(s));
}

// ------------------------------------------------------------------ parsing YAML scalars

/// The text of an unquoted scalar; false for quoted strings, null and collections.
bool PlainScalar(const YAML::Node& n, std::string* text) {
  if (!n.IsScalar() || n.Tag() == "!") return false;
  *text = n.Scalar();
  return true;
}

bool ParseInt64(const std::string& text, int64_t* out, bool* overflow) {
  *overflow = false;
  const char* b = text.data();
  const char* e = b + text.size();
  if (b != e && *b == '+') {
    ++b;
    if (b == e || *b == '+' || *b == '-') return false;
  }
  int64_t v = 0;
  const auto r = std::from_chars(b, e, v);
  if (r.ec == std::errc::result_out_of_range) {
    const char* digits = b + (*b == '-' ? 1 : 0);
    *overflow = digits != e && std::all_of(digits, e, [](char c) { return c >= '0' && c <= '9'; });
    return false;
  }
  if (r.ec != std::errc() || r.ptr != e) return false;
  *out = v;
  return true;
}

/// Parses a YAML number (int or float forms, .inf/.nan included); non-finite results are
/// returned as such, for the caller to reject.
bool ParseDouble(const std::string& text, double* out) {
  std::string lower;
  for (char c : text) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower == ".nan") {
    *out = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  if (lower == ".inf" || lower == "+.inf" || lower == "-.inf") {
    *out = lower[0] == '-' ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
    return true;
  }
  const char* b = text.data();
  const char* e = b + text.size();
  if (b != e && *b == '+') {
    ++b;
    if (b == e || *b == '+' || *b == '-') return false;
  }
  double v = 0.0;
  const auto r = std::from_chars(b, e, v);
  if (r.ptr != e) return false;
  if (r.ec == std::errc::result_out_of_range) {
    v = std::strtod(std::string(b, e).c_str(), nullptr);  // +-HUGE_VAL (rejected later) or a tiny value
  } else if (r.ec != std::errc()) {
    return false;
  }
  *out = v;
  return true;
}

const char* IntegerRule(ValueType t) {
  switch (t) {
    case ValueType::kUint32:
      return "must be an integer in [0, 4294967295]";
    case ValueType::kInt64:
      return "must be an integer in [-9223372036854775808, 9223372036854775807]";
    default:
      return "must be an integer in [-2147483648, 2147483647]";
  }
}

/// Reads an integer of type `t` (kInt, kInt64, kUint32) and checks the rule.
int64_t ReadInteger(const Reporter& r, const FieldSpec& s, const YAML::Node& n, ValueType t, const std::string& path) {
  std::string text;
  int64_t v = 0;
  bool overflow = false;
  if (!PlainScalar(n, &text) || !ParseInt64(text, &v, &overflow)) {
    r.Fail(path, Written(n), overflow ? IntegerRule(t) : "must be an integer");
  }
  const bool fits =
      t == ValueType::kInt64 ||
      (t == ValueType::kUint32 ? v >= 0 && v <= int64_t{std::numeric_limits<uint32_t>::max()}
                               : v >= std::numeric_limits<int>::min() && v <= std::numeric_limits<int>::max());
  if (!fits) r.Fail(path, text, IntegerRule(t));
  CheckNumber(r, s, static_cast<double>(v), false, path, text);
  return v;
}

double ReadDouble(const Reporter& r, const FieldSpec& s, const YAML::Node& n, const std::string& path) {
  std::string text;
  double v = 0.0;
  if (!PlainScalar(n, &text) || !ParseDouble(text, &v)) r.Fail(path, Written(n), "must be a number");
  CheckNumber(r, s, v, true, path, text);
  return v;
}

bool ReadBool(const Reporter& r, const YAML::Node& n, const std::string& path) {
  std::string text;
  if (PlainScalar(n, &text)) {
    if (text == "true" || text == "True" || text == "TRUE") return true;
    if (text == "false" || text == "False" || text == "FALSE") return false;
  }
  r.Fail(path, Written(n), "must be true or false");
}

std::string ReadString(const Reporter& r, const FieldSpec& s, const YAML::Node& n, const std::string& path) {
  if (!n.IsScalar()) r.Fail(path, Written(n), "must be a string");
  const std::string& v = n.Scalar();
  CheckText(r, s, v, path, Written(n));
  return v;
}

/// Element type of a list-like value.
bool IsListType(ValueType t) {
  return t == ValueType::kDoubleList || t == ValueType::kIntList || t == ValueType::kStringList ||
         t == ValueType::kVector2 || t == ValueType::kVector3;
}

const char* ListRule(ValueType t) {
  switch (t) {
    case ValueType::kIntList:
      return "must be a list of integers";
    case ValueType::kStringList:
      return "must be a list of strings";
    case ValueType::kVector2:
      return "must be a list of 2 numbers";
    case ValueType::kVector3:
      return "must be a list of 3 numbers";
    default:
      return "must be a list of numbers";
  }
}

const char* ElementRule(ValueType t) {
  switch (t) {
    case ValueType::kIntList:
      return "must be an integer";
    case ValueType::kStringList:
      return "must be a string";
    default:
      return "must be a number";
  }
}

std::size_t ListSize(ValueRef v) {
  switch (v.type) {
    case ValueType::kDoubleList:
      return static_cast<const std::vector<double>*>(v.ptr)->size();
    case ValueType::kIntList:
      return static_cast<const std::vector<int>*>(v.ptr)->size();
    case ValueType::kStringList:
      return static_cast<const std::vector<std::string>*>(v.ptr)->size();
    case ValueType::kVector2:
      return 2;
    case ValueType::kVector3:
      return 3;
    default:
      return 0;
  }
}

/// Reads element `i` of a list-like value from `n` (already known to be a scalar slot).
void ReadElement(const Reporter& r, const FieldSpec& s, const YAML::Node& n, ValueRef v, std::size_t i,
                 const std::string& path) {
  switch (v.type) {
    case ValueType::kDoubleList:
      (*static_cast<std::vector<double>*>(v.ptr))[i] = ReadDouble(r, s, n, path);
      break;
    case ValueType::kIntList:
      (*static_cast<std::vector<int>*>(v.ptr))[i] = static_cast<int>(ReadInteger(r, s, n, ValueType::kInt, path));
      break;
    case ValueType::kStringList:
      (*static_cast<std::vector<std::string>*>(v.ptr))[i] = ReadString(r, s, n, path);
      break;
    case ValueType::kVector2:
      (*static_cast<Eigen::Vector2d*>(v.ptr))[static_cast<Eigen::Index>(i)] = ReadDouble(r, s, n, path);
      break;
    case ValueType::kVector3:
      (*static_cast<Eigen::Vector3d*>(v.ptr))[static_cast<Eigen::Index>(i)] = ReadDouble(r, s, n, path);
      break;
    default:
      break;
  }
}

/// Resizes a variable-length list (fixed-size vectors ignore it).
void ResizeList(ValueRef v, std::size_t size) {
  switch (v.type) {
    case ValueType::kDoubleList:
      static_cast<std::vector<double>*>(v.ptr)->assign(size, 0.0);
      break;
    case ValueType::kIntList:
      static_cast<std::vector<int>*>(v.ptr)->assign(size, 0);
      break;
    case ValueType::kStringList:
      static_cast<std::vector<std::string>*>(v.ptr)->assign(size, "");
      break;
    default:
      break;
  }
}

/// Copies a list-like value (so a failed read leaves the target unchanged).
struct ListCopy {
  std::vector<double> d;
  std::vector<int> i;
  std::vector<std::string> s;
  Eigen::Vector2d v2;
  Eigen::Vector3d v3;
  ValueRef ref{ValueType::kDoubleList, nullptr};

  explicit ListCopy(ValueRef v) : ref{v.type, nullptr} {
    switch (v.type) {
      case ValueType::kDoubleList:
        d = *static_cast<const std::vector<double>*>(v.ptr);
        ref.ptr = &d;
        break;
      case ValueType::kIntList:
        i = *static_cast<const std::vector<int>*>(v.ptr);
        ref.ptr = &i;
        break;
      case ValueType::kStringList:
        s = *static_cast<const std::vector<std::string>*>(v.ptr);
        ref.ptr = &s;
        break;
      case ValueType::kVector2:
        v2 = *static_cast<const Eigen::Vector2d*>(v.ptr);
        ref.ptr = &v2;
        break;
      case ValueType::kVector3:
        v3 = *static_cast<const Eigen::Vector3d*>(v.ptr);
        ref.ptr = &v3;
        break;
      default:
        break;
    }
  }
  void StoreInto(ValueRef v) {
    switch (v.type) {
      case ValueType::kDoubleList:
        *static_cast<std::vector<double>*>(v.ptr) = std::move(d);
        break;
      case ValueType::kIntList:
        *static_cast<std::vector<int>*>(v.ptr) = std::move(i);
        break;
      case ValueType::kStringList:
        *static_cast<std::vector<std::string>*>(v.ptr) = std::move(s);
        break;
      case ValueType::kVector2:
        *static_cast<Eigen::Vector2d*>(v.ptr) = v2;
        break;
      case ValueType::kVector3:
        *static_cast<Eigen::Vector3d*>(v.ptr) = v3;
        break;
      default:
        break;
    }
  }
};

/// Tag of the maps ApplyOverride builds for "name[i]" (index -> value); never read from files.
const char* kIndexTag = "!unav_index";

bool ParseIndex(const std::string& text, std::size_t* out) {
  if (text.empty() || !std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; })) return false;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), *out);
  return r.ec == std::errc() && r.ptr == text.data() + text.size();
}

/// Reads a leaf value from `n` into `v`, checking type and rule.
void ReadValue(const Reporter& r, const FieldSpec& s, const YAML::Node& n, ValueRef v, const std::string& path,
               bool allow_index_map) {
  const bool index_map = allow_index_map && n.IsMap() && n.Tag() == kIndexTag;
  if (index_map && !IsListType(v.type))
    r.Fail(path, "", "is a " + std::string(TypeName(v.type)) + ", not a list: it has no elements to index");
  if (const int order = MatrixOrder(v.type)) {  // n numbers (the diagonal) or n rows of n
    const auto size = static_cast<std::size_t>(order);
    const std::string count = std::to_string(size);
    const std::string rule = "must be a list of " + count + " numbers (the diagonal) or " + count + " lists of " +
                             count + " numbers (the rows)";
    if (!n.IsSequence() || n.size() != size) r.Fail(path, Written(n), rule);
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(order, order);
    const bool rows = n[0].IsSequence();
    for (std::size_t i = 0; i < size; ++i) {
      const YAML::Node row = n[i];
      const auto ii = static_cast<Eigen::Index>(i);
      if (!rows) {
        if (!row.IsScalar()) r.Fail(path, Written(n), rule);
        m(ii, ii) = ReadDouble(r, s, row, IndexPath(path, i));
        continue;
      }
      if (!row.IsSequence() || row.size() != size) r.Fail(path, Written(n), rule);
      for (std::size_t j = 0; j < size; ++j)
        m(ii, static_cast<Eigen::Index>(j)) = ReadDouble(r, s, row[j], IndexPath(IndexPath(path, i), j));
    }
    MatrixOf(v) = m;
    return;
  }
  if (IsListType(v.type)) {
    ListCopy copy(v);
    if (index_map) {  // override of single elements: name[i]
      const std::size_t size = ListSize(v);
      for (const auto& kv : n) {
        std::size_t i = 0;
        ParseIndex(kv.first.Scalar(), &i);
        const std::string p = IndexPath(path, i);
        if (i >= size)
          r.Fail(p, Written(kv.second), "index out of range (the list has " + std::to_string(size) + " elements)");
        if (!kv.second.IsScalar()) r.Fail(p, Written(kv.second), ElementRule(v.type));
        ReadElement(r, s, kv.second, copy.ref, i, p);
      }
    } else {
      if (!n.IsSequence()) r.Fail(path, Written(n), ListRule(v.type));
      const std::size_t size = n.size();
      if ((v.type == ValueType::kVector2 && size != 2) || (v.type == ValueType::kVector3 && size != 3))
        r.Fail(path, Written(n), std::string(ListRule(v.type)) + " (got " + std::to_string(size) + ")");
      ResizeList(copy.ref, size);
      for (std::size_t i = 0; i < size; ++i) {
        const YAML::Node e = n[i];
        if (!e.IsScalar()) r.Fail(IndexPath(path, i), Written(e), ElementRule(v.type));
        ReadElement(r, s, e, copy.ref, i, IndexPath(path, i));
      }
    }
    copy.StoreInto(v);
    return;
  }
  switch (v.type) {
    case ValueType::kBool:
      *static_cast<bool*>(v.ptr) = ReadBool(r, n, path);
      break;
    case ValueType::kInt:
      *static_cast<int*>(v.ptr) = static_cast<int>(ReadInteger(r, s, n, v.type, path));
      break;
    case ValueType::kInt64:
      *static_cast<int64_t*>(v.ptr) = ReadInteger(r, s, n, v.type, path);
      break;
    case ValueType::kUint32:
      *static_cast<uint32_t*>(v.ptr) = static_cast<uint32_t>(ReadInteger(r, s, n, v.type, path));
      break;
    case ValueType::kDouble:
      *static_cast<double*>(v.ptr) = ReadDouble(r, s, n, path);
      break;
    case ValueType::kString:
      *static_cast<std::string*>(v.ptr) = ReadString(r, s, n, path);
      break;
    default:
      break;
  }
}

/// Checks a leaf's current value against its rule (Validate).
void CheckValue(const Reporter& r, const FieldSpec& s, ValueRef v, const std::string& path) {
  auto number = [&](double x, bool is_double, const std::string& p) {
    CheckNumber(r, s, x, is_double, p, is_double ? DoubleText(x) : ShortestNumber(x));
  };
  switch (v.type) {
    case ValueType::kBool:
      break;
    case ValueType::kInt:
      number(*static_cast<const int*>(v.ptr), false, path);
      break;
    case ValueType::kInt64: {
      const int64_t x = *static_cast<const int64_t*>(v.ptr);
      if (!NumberOk(s, static_cast<double>(x))) r.Fail(path, std::to_string(x), "must be " + NumberRule(s));
      break;
    }
    case ValueType::kUint32: {
      const uint32_t x = *static_cast<const uint32_t*>(v.ptr);
      if (!NumberOk(s, static_cast<double>(x))) r.Fail(path, std::to_string(x), "must be " + NumberRule(s));
      break;
    }
    case ValueType::kDouble:
      number(*static_cast<const double*>(v.ptr), true, path);
      break;
    case ValueType::kString: {
      const auto& x = *static_cast<const std::string*>(v.ptr);
      CheckText(r, s, x, path, StringText(x));
      break;
    }
    case ValueType::kDoubleList: {
      const auto& l = *static_cast<const std::vector<double>*>(v.ptr);
      for (std::size_t i = 0; i < l.size(); ++i) number(l[i], true, IndexPath(path, i));
      break;
    }
    case ValueType::kIntList: {
      const auto& l = *static_cast<const std::vector<int>*>(v.ptr);
      for (std::size_t i = 0; i < l.size(); ++i) number(l[i], false, IndexPath(path, i));
      break;
    }
    case ValueType::kStringList: {
      const auto& l = *static_cast<const std::vector<std::string>*>(v.ptr);
      for (std::size_t i = 0; i < l.size(); ++i) CheckText(r, s, l[i], IndexPath(path, i), StringText(l[i]));
      break;
    }
    case ValueType::kVector2: {
      const auto& x = *static_cast<const Eigen::Vector2d*>(v.ptr);
      for (Eigen::Index i = 0; i < 2; ++i) number(x[i], true, IndexPath(path, static_cast<std::size_t>(i)));
      break;
    }
    case ValueType::kVector3: {
      const auto& x = *static_cast<const Eigen::Vector3d*>(v.ptr);
      for (Eigen::Index i = 0; i < 3; ++i) number(x[i], true, IndexPath(path, static_cast<std::size_t>(i)));
      break;
    }
    case ValueType::kMatrix3:
    case ValueType::kMatrix6: {
      const auto m = MatrixOf(v);
      for (Eigen::Index i = 0; i < m.rows(); ++i)
        for (Eigen::Index j = 0; j < m.cols(); ++j)
          number(m(i, j), true, IndexPath(IndexPath(path, static_cast<std::size_t>(i)), static_cast<std::size_t>(j)));
      break;
    }
  }
}

/// A leaf as a YAML node (numbers and strings as plain scalars, lists in flow style).
YAML::Node ValueNode(ValueRef v) {
  if (const int n = MatrixOrder(v.type)) {  // the diagonal when the matrix is, else its rows
    const auto m = MatrixOf(v);
    const auto flow = [](const auto& values, int count) {
      YAML::Node seq(YAML::NodeType::Sequence);
      seq.SetStyle(YAML::EmitterStyle::Flow);
      for (int i = 0; i < count; ++i) seq.push_back(DoubleText(values[i]));
      return seq;
    };
    if (IsDiagonal(m)) return flow(Eigen::VectorXd(m.diagonal()), n);
    YAML::Node rows(YAML::NodeType::Sequence);
    for (int i = 0; i < n; ++i) rows.push_back(flow(Eigen::VectorXd(m.row(i).transpose()), n));
    return rows;
  }
  if (IsListType(v.type)) {
    YAML::Node seq(YAML::NodeType::Sequence);
    seq.SetStyle(YAML::EmitterStyle::Flow);
    const std::size_t n = ListSize(v);
    for (std::size_t i = 0; i < n; ++i) {
      switch (v.type) {
        case ValueType::kDoubleList:
          seq.push_back(DoubleText((*static_cast<const std::vector<double>*>(v.ptr))[i]));
          break;
        case ValueType::kIntList:
          seq.push_back((*static_cast<const std::vector<int>*>(v.ptr))[i]);
          break;
        case ValueType::kStringList:
          seq.push_back((*static_cast<const std::vector<std::string>*>(v.ptr))[i]);
          break;
        case ValueType::kVector2:
          seq.push_back(DoubleText((*static_cast<const Eigen::Vector2d*>(v.ptr))[static_cast<Eigen::Index>(i)]));
          break;
        case ValueType::kVector3:
          seq.push_back(DoubleText((*static_cast<const Eigen::Vector3d*>(v.ptr))[static_cast<Eigen::Index>(i)]));
          break;
        default:
          break;
      }
    }
    return seq;
  }
  switch (v.type) {
    case ValueType::kBool:
      return YAML::Node(*static_cast<const bool*>(v.ptr));
    case ValueType::kInt:
      return YAML::Node(*static_cast<const int*>(v.ptr));
    case ValueType::kInt64:
      return YAML::Node(std::to_string(*static_cast<const int64_t*>(v.ptr)));
    case ValueType::kUint32:
      return YAML::Node(std::to_string(*static_cast<const uint32_t*>(v.ptr)));
    case ValueType::kDouble:
      return YAML::Node(DoubleText(*static_cast<const double*>(v.ptr)));
    case ValueType::kString:
      return YAML::Node(*static_cast<const std::string*>(v.ptr));
    default:
      return YAML::Node();
  }
}

}  // namespace unav::common::config_values
