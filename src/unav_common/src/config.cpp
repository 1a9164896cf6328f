// The archives behind config.hpp: reader (LoadYaml, ApplyOverride), describer, YAML writer and
// checker. Everything type-specific is a switch over ValueType here, so a config struct costs
// one instantiation of its Serialize() and nothing else.
#include "unav_common/config.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace unav::common {

ConfigArchive::~ConfigArchive() = default;

namespace {

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
struct Reporter {
  std::string file;
  [[noreturn]] void Fail(const std::string& path, const std::string& value, const std::string& rule) const {
    throw ConfigError(file, path, value, rule);
  }
};

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
    const std::string rule =
        "must be a list of " + count + " numbers (the diagonal) or " + count + " lists of " + count + " numbers (the rows)";
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

// ------------------------------------------------------------------ archives

/// LoadYaml and ApplyOverride: walks the YAML alongside the schema.
class Reader final : public ConfigArchive {
 public:
  Reader(std::string file, bool allow_index_maps) : reporter_{std::move(file)}, index_maps_(allow_index_maps) {}

  void Run(const YAML::Node& map, const std::string& path, detail::Target target) {
    frames_.emplace_back(map, path);
    target.serialize(target.object, this);
    CheckUnknown(frames_.back());
    frames_.pop_back();
  }

 protected:
  void Leaf(const FieldSpec& spec, ValueRef value) override {
    Frame& f = frames_.back();
    f.declared.push_back(spec.name);
    const YAML::Node n = Child(f, spec.name);
    if (!n.IsDefined()) return;
    ReadValue(reporter_, spec, n, value, ChildPath(f.path, spec.name), index_maps_);
  }

  bool BeginStruct(const FieldSpec& spec) override {
    Frame& f = frames_.back();
    f.declared.push_back(spec.name);
    const YAML::Node n = Child(f, spec.name);
    if (!n.IsDefined() || n.IsNull()) return false;
    const std::string path = ChildPath(f.path, spec.name);
    if (!n.IsMap() || IsIndexMap(n)) reporter_.Fail(path, Written(n), "must be a mapping (a nested config)");
    frames_.emplace_back(n, path);
    return true;
  }

  void EndStruct() override {
    CheckUnknown(frames_.back());
    frames_.pop_back();
  }

  ListPlan BeginList(const FieldSpec& spec, std::size_t size) override {
    Frame& f = frames_.back();
    f.declared.push_back(spec.name);
    const YAML::Node n = Child(f, spec.name);
    const std::string path = ChildPath(f.path, spec.name);
    ListPlan plan;
    if (!n.IsDefined()) {
      frames_.emplace_back(YAML::Node(), path);  // nothing to read: BeginElement skips all
      return plan;
    }
    if (IsIndexMap(n)) {
      for (const auto& kv : n) {
        std::size_t i = 0;
        ParseIndex(kv.first.Scalar(), &i);
        if (i >= size)
          reporter_.Fail(IndexPath(path, i), Written(kv.second),
                         "index out of range (the list has " + std::to_string(size) + " elements)");
      }
      frames_.emplace_back(n, path);
      frames_.back().index_map = true;
      return plan;
    }
    if (!n.IsSequence()) reporter_.Fail(path, Written(n), "must be a list of mappings");
    for (std::size_t i = 0; i < n.size(); ++i) {
      const YAML::Node e = n[i];
      if (!e.IsMap()) reporter_.Fail(IndexPath(path, i), Written(e), "must be a mapping (a list element)");
    }
    frames_.emplace_back(n, path);
    plan.mode = ListMode::kReplace;
    plan.size = n.size();
    return plan;
  }

  bool BeginElement(std::size_t index) override {
    const Frame& list = frames_.back();
    if (!list.node.IsDefined()) return false;
    const YAML::Node e = list.index_map ? list.node[std::to_string(index)] : list.node[index];
    if (!e.IsDefined()) return false;
    const std::string path = IndexPath(list.path, index);
    if (!e.IsMap() || IsIndexMap(e)) reporter_.Fail(path, Written(e), "must be a mapping (a list element)");
    frames_.emplace_back(e, path);
    return true;
  }

  void EndElement() override { EndStruct(); }
  void EndList() override { frames_.pop_back(); }

 private:
  struct Frame {
    Frame(const YAML::Node& n, std::string p) : node(n), path(std::move(p)) {}
    const YAML::Node node;
    std::string path;
    std::vector<std::string> declared;
    bool index_map = false;
  };

  static YAML::Node Child(const Frame& f, const std::string& name) {
    if (!f.node.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
    return f.node[name];
  }

  bool IsIndexMap(const YAML::Node& n) const { return index_maps_ && n.IsMap() && n.Tag() == kIndexTag; }

  void CheckUnknown(const Frame& f) const {
    if (!f.node.IsMap()) return;
    for (const auto& kv : f.node) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : Written(kv.first);
      if (std::find(f.declared.begin(), f.declared.end(), key) != f.declared.end()) continue;
      std::string allowed = JoinTexts(f.declared);
      reporter_.Fail(ChildPath(f.path, key), Written(kv.second),
                     "unknown key; allowed keys: " + (allowed.empty() ? std::string("none") : allowed));
    }
  }

  Reporter reporter_;
  bool index_maps_;
  std::vector<Frame> frames_;
};

/// Describe: one FieldInfo per leaf, nested struct and list of structs.
class Describer final : public ConfigArchive {
 public:
  std::vector<FieldInfo> rows;

 protected:
  void Leaf(const FieldSpec& spec, ValueRef value) override {
    rows.push_back(
        {Path(spec.name), TypeName(value.type), ValueText(value), spec.RuleText(), spec.unit, spec.doc, spec});
  }
  bool BeginStruct(const FieldSpec& spec) override {
    rows.push_back({Path(spec.name), "mapping", "", "", spec.unit, spec.doc, spec});
    prefix_.push_back(rows.back().name);
    return true;
  }
  void EndStruct() override { prefix_.pop_back(); }
  ListPlan BeginList(const FieldSpec& spec, std::size_t size) override {
    rows.push_back({Path(spec.name), "mapping[]",
                    size == 0 ? "[]" : "[" + std::to_string(size) + (size == 1 ? " element]" : " elements]"), "",
                    spec.unit, spec.doc, spec});
    prefix_.push_back(rows.back().name);
    return {ListMode::kSchema, 0};
  }
  bool BeginElement(std::size_t) override {
    prefix_.push_back(prefix_.back() + "[i]");
    return true;
  }
  void EndElement() override { prefix_.pop_back(); }
  void EndList() override { prefix_.pop_back(); }

 private:
  std::string Path(const std::string& name) const { return prefix_.empty() ? name : ChildPath(prefix_.back(), name); }
  std::vector<std::string> prefix_;
};

/// ToYaml: builds mappings bottom-up (a finished child is attached to its parent).
class Writer final : public ConfigArchive {
 public:
  Writer() { frames_.push_back({YAML::Node(YAML::NodeType::Map), ""}); }
  YAML::Node Result() const { return frames_.front().node; }

 protected:
  void Leaf(const FieldSpec& spec, ValueRef value) override { frames_.back().node[spec.name] = ValueNode(value); }
  bool BeginStruct(const FieldSpec& spec) override {
    frames_.push_back({YAML::Node(YAML::NodeType::Map), spec.name});
    return true;
  }
  void EndStruct() override {
    const Frame done = frames_.back();
    frames_.pop_back();
    if (frames_.back().node.IsSequence()) {
      frames_.back().node.push_back(done.node);
    } else {
      frames_.back().node[done.name] = done.node;
    }
  }
  ListPlan BeginList(const FieldSpec& spec, std::size_t) override {
    frames_.push_back({YAML::Node(YAML::NodeType::Sequence), spec.name});
    return {ListMode::kExisting, 0};
  }
  bool BeginElement(std::size_t) override {
    frames_.push_back({YAML::Node(YAML::NodeType::Map), ""});
    return true;
  }
  void EndElement() override { EndStruct(); }
  void EndList() override { EndStruct(); }

 private:
  struct Frame {
    YAML::Node node;
    std::string name;
  };
  std::vector<Frame> frames_;
};

/// Validate: checks every current value against its rule.
class Checker final : public ConfigArchive {
 public:
  explicit Checker(std::string where) : reporter_{std::move(where)} { paths_.push_back(""); }

 protected:
  void Leaf(const FieldSpec& spec, ValueRef value) override {
    CheckValue(reporter_, spec, value, ChildPath(paths_.back(), spec.name));
  }
  bool BeginStruct(const FieldSpec& spec) override {
    paths_.push_back(ChildPath(paths_.back(), spec.name));
    return true;
  }
  void EndStruct() override { paths_.pop_back(); }
  ListPlan BeginList(const FieldSpec& spec, std::size_t) override {
    paths_.push_back(ChildPath(paths_.back(), spec.name));
    return {ListMode::kExisting, 0};
  }
  bool BeginElement(std::size_t index) override {
    paths_.push_back(IndexPath(paths_.back(), index));
    return true;
  }
  void EndElement() override { paths_.pop_back(); }
  void EndList() override { paths_.pop_back(); }

 private:
  Reporter reporter_;
  std::vector<std::string> paths_;
};

}  // namespace

std::string FieldSpec::RuleText() const {
  if (!one_of.empty()) {
    std::vector<std::string> items;
    for (const auto& a : one_of) items.push_back(StringText(a));
    return "{" + JoinTexts(items) + "}";
  }
  const std::string rule = NumberRule(*this);
  return rule.rfind("in ", 0) == 0 ? rule.substr(3) : rule;
}

std::string FormatHelp(const std::vector<FieldInfo>& fields) {
  auto cell = [](const std::string& s) { return s.empty() ? std::string("-") : s; };
  std::vector<std::array<std::string, 6>> table;
  std::array<std::size_t, 6> width{};
  for (const auto& f : fields) {
    table.push_back({f.name, f.type, cell(f.default_value), cell(f.rule), cell(f.unit), f.doc});
    for (std::size_t c = 0; c < 6; ++c) width[c] = std::max(width[c], table.back()[c].size());
  }
  std::string out;
  for (const auto& row : table) {
    std::string line = " ";
    for (std::size_t c = 0; c < 6; ++c) {
      line += " " + row[c];
      if (c + 1 < 6) line += std::string(width[c] - row[c].size() + 1, ' ');
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    out += line + "\n";
  }
  return out;
}

namespace detail {

YAML::Node ReadYamlFile(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path, "", "", "cannot be opened (missing or unreadable)");
  } catch (const YAML::ParserException& e) {
    throw ConfigError(path, "", "",
                      "malformed YAML at line " + std::to_string(e.mark.line + 1) + ", column " +
                          std::to_string(e.mark.column + 1) + ": " + e.msg);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path, "", "", std::string("malformed YAML: ") + e.what());
  }
}

void LoadYaml(const YAML::Node& node, const std::string& file, const std::string& root, Target out) {
  YAML::Node map = node;  // handle: rebinding it below does not touch `node`
  std::string path;
  if (!root.empty()) {
    std::stringstream parts(root);
    std::string part;
    while (std::getline(parts, part, '.')) {
      path = ChildPath(path, part);
      const YAML::Node parent = map;
      if (!parent.IsMap()) throw ConfigError(file, path, "", "section not found (the file has no '" + root + "')");
      const YAML::Node child = parent[part];
      if (!child.IsDefined()) throw ConfigError(file, path, "", "section not found (the file has no '" + root + "')");
      map.reset(child);
    }
  }
  if (map.IsDefined() && !map.IsNull() && !map.IsMap())
    throw ConfigError(file, path, Written(map), "must be a mapping of config keys");
  Reader(file, false).Run(map, path, out);
}

void ApplyOverride(Target cfg, const std::string& name, const std::string& yaml_value, const std::string& source) {
  // "a.b[3].c" -> components a, b, [3], c.
  struct Part {
    std::string key;
    bool is_index;
  };
  std::vector<Part> parts;
  const auto bad_name = [&] {
    return ConfigError(source, name, yaml_value, "malformed parameter name (expected a key path like a.b or a[2].b)");
  };
  std::size_t i = 0;
  while (i <= name.size()) {
    const std::size_t end = name.find_first_of(".[", i);
    const std::string key = name.substr(i, end == std::string::npos ? std::string::npos : end - i);
    if (key.empty() || key.find(']') != std::string::npos) throw bad_name();
    parts.push_back({key, false});
    if (end == std::string::npos) break;
    i = end;
    while (i < name.size() && name[i] == '[') {
      const std::size_t close = name.find(']', i);
      std::size_t index = 0;
      if (close == std::string::npos || !ParseIndex(name.substr(i + 1, close - i - 1), &index)) throw bad_name();
      parts.push_back({std::to_string(index), true});
      i = close + 1;
    }
    if (i == name.size()) break;
    if (name[i] != '.') throw bad_name();
    ++i;
    if (i == name.size()) throw bad_name();
  }
  YAML::Node value;
  try {
    value = YAML::Load(yaml_value);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source, name, yaml_value, "malformed YAML value: " + e.msg);
  }
  // Nest the value under the path; "[i]" becomes an index map tagged kIndexTag.
  for (auto p = parts.rbegin(); p != parts.rend(); ++p) {
    YAML::Node wrapper(YAML::NodeType::Map);
    wrapper[p->key] = value;
    if (p->is_index) wrapper.SetTag(kIndexTag);
    value.reset(wrapper);
  }
  Reader(source, true).Run(value, "", cfg);
}

std::vector<FieldInfo> Describe(Target defaults) {
  Describer d;
  defaults.serialize(defaults.object, &d);
  return std::move(d.rows);
}

YAML::Node ToYaml(Target cfg) {
  Writer w;
  cfg.serialize(cfg.object, &w);
  return w.Result();
}

void Validate(Target cfg, const std::string& where) {
  Checker c(where);
  cfg.serialize(cfg.object, &c);
}

}  // namespace detail
}  // namespace unav::common
