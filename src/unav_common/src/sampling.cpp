// The distribution language of sampling.hpp: checks against a config schema, and the sampler.
#include "unav_common/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <variant>

namespace unav::common {
namespace {

constexpr const char* kKinds[] = {"uniform", "normal", "int", "choice"};
constexpr const char* kForms = "{uniform: [lo, hi]}, {normal: {mean: m, std: s}}, {int: [lo, hi]} or {choice: [...]}";

std::string Written(const YAML::Node& n) {
  if (!n.IsDefined()) return "";
  if (n.IsScalar()) return n.Scalar();
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

double Number(const YAML::Node& n, const std::string& file, const std::string& path) {
  double v = 0;
  if (!n.IsScalar() || !YAML::convert<double>::decode(n, v))
    throw ConfigError(file, path, Written(n), "expected a number");
  if (!std::isfinite(v)) throw ConfigError(file, path, Written(n), "must be finite");
  return v;
}

// A step of a key path: a map key or a list index.
using Step = std::variant<std::string, std::size_t>;

std::string PathText(const std::vector<Step>& steps) {
  std::string s;
  for (const auto& st : steps) {
    if (const auto* k = std::get_if<std::string>(&st))
      s += (s.empty() ? "" : ".") + *k;
    else
      s += "[" + std::to_string(std::get<std::size_t>(st)) + "]";
  }
  return s;
}

// The schema row of a concrete path: list-of-struct indices become "[i]"; a trailing index of a
// leaf list is an element of that leaf (element = true).
const FieldInfo* Row(const std::map<std::string, FieldInfo>& rows, const std::vector<Step>& steps, bool* element) {
  std::string pattern;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (const auto* k = std::get_if<std::string>(&steps[i])) {
      pattern += (pattern.empty() ? "" : ".") + *k;
    } else if (i + 1 == steps.size()) {
      const auto it = rows.find(pattern);
      *element = true;
      return it == rows.end() ? nullptr : &it->second;
    } else {
      pattern += "[i]";
    }
  }
  *element = false;
  const auto it = rows.find(pattern);
  return it == rows.end() ? nullptr : &it->second;
}

struct Found {
  std::vector<Step> steps;
  YAML::Node node;
};

// Calls visit(child) for every entry of a mapping or element of a sequence, with its step (the
// key, or the index) on `steps` meanwhile.
template <class Visit>
void ForEachChild(const YAML::Node& n, std::vector<Step>* steps, Visit&& visit) {
  if (n.IsMap()) {
    for (const auto& kv : n) {
      steps->push_back(kv.first.IsScalar() ? kv.first.Scalar() : Written(kv.first));
      visit(kv.second);
      steps->pop_back();
    }
  } else if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i) {
      steps->push_back(i);
      visit(n[i]);
      steps->pop_back();
    }
  }
}

// A key twice in one mapping (yaml-cpp keeps both, and lookups find the first): refused by path.
void CheckDuplicateKeys(const YAML::Node& n, std::vector<Step>* steps, const std::string& file) {
  std::set<std::string> seen;
  ForEachChild(n, steps, [&](const YAML::Node& child) {
    if (n.IsMap() && !seen.insert(std::get<std::string>(steps->back())).second)
      throw ConfigError(file, PathText(*steps), Written(child), "appears twice in the same mapping");
    CheckDuplicateKeys(child, steps, file);
  });
}

void Collect(const YAML::Node& n, std::vector<Step>* steps, std::vector<Found>* out) {
  if (IsDistribution(n)) {
    out->push_back({*steps, n});
    return;
  }
  ForEachChild(n, steps, [&](const YAML::Node& child) { Collect(child, steps, out); });
}

// Replaces the node at `steps` in `root` (a tree of its own, from YAML::Clone) by `value`.
void Put(const YAML::Node& root, const std::vector<Step>& steps, const YAML::Node& value) {
  YAML::Node at = root;
  for (std::size_t i = 0; i + 1 < steps.size(); ++i) {
    const YAML::Node next = std::holds_alternative<std::string>(steps[i]) ? at[std::get<std::string>(steps[i])]
                                                                          : at[std::get<std::size_t>(steps[i])];
    at.reset(next);
  }
  if (std::holds_alternative<std::string>(steps.back()))
    at[std::get<std::string>(steps.back())] = value;
  else
    at[std::get<std::size_t>(steps.back())] = value;
}

std::map<std::string, FieldInfo> Rows(detail::Target defaults) {
  std::map<std::string, FieldInfo> rows;
  for (auto& r : detail::Describe(defaults)) rows.emplace(r.name, r);
  return rows;
}

// The type of the value a distribution at this row stands for: "double", "int", "bool", "string".
std::string ValueKind(const FieldInfo& row, bool element) {
  const std::string& t = row.type;
  if (element) {
    if (t.rfind("double", 0) == 0) return "double";
    if (t == "int[]") return "int";
    if (t == "string[]") return "string";
    return "";
  }
  if (t == "double") return "double";
  if (t == "int" || t == "int64" || t == "uint32") return "int";
  if (t == "bool" || t == "string") return t;
  return "";
}

// {repeat: {count: C, each: E}}: a list of C elements, each a fresh draw of E.
bool IsRepeat(const YAML::Node& n) {
  return n.IsMap() && n.size() == 1 && n.begin()->first.IsScalar() && n.begin()->first.Scalar() == "repeat";
}

constexpr int64_t kMaxRepeat = 10000;

// The counts a checked repeat's `count` may take: {min, max}.
std::pair<int64_t, int64_t> CountRange(const YAML::Node& count) {
  if (!IsDistribution(count)) return {count.as<int64_t>(), count.as<int64_t>()};
  const auto support = DistributionSupport(count);
  int64_t lo = kMaxRepeat, hi = 0;
  for (const auto& v : support) {
    lo = std::min(lo, static_cast<int64_t>(std::llround(v.as<double>())));
    hi = std::max(hi, static_cast<int64_t>(std::llround(v.as<double>())));
  }
  return {lo, hi};
}

void CheckRepeatSyntax(const YAML::Node& n, const std::string& file, const std::string& path) {
  const YAML::Node a = n.begin()->second;
  const std::string at = path + ".repeat";
  const char* form = "expected {count: n or {int: [lo, hi]} or {choice: [...]}, each: element}";
  if (!a.IsMap() || a.size() != 2 || !a["count"] || !a["each"]) throw ConfigError(file, at, Written(a), form);
  const YAML::Node count = a["count"];
  std::vector<YAML::Node> values{count};
  if (IsDistribution(count)) {
    CheckDistributionSyntax(count, file, at + ".count");
    const std::string kind = count.begin()->first.Scalar();
    if (kind != "int" && kind != "choice")
      throw ConfigError(file, at + ".count", Written(count), "a count takes n, {int: [lo, hi]} or {choice: [...]}");
    values = DistributionSupport(count);
  }
  for (const auto& v : values) {
    const double c = Number(v, file, at + ".count");
    if (c != std::floor(c) || c < 0 || c > static_cast<double>(kMaxRepeat))
      throw ConfigError(file, at + ".count", Written(count),
                        "a count is a whole number in [0, " + std::to_string(kMaxRepeat) + "]");
  }
}

// `node` with every repeat replaced by its list: of `count(path, repeat)` clones of its element
// (themselves expanded: repeats may nest).
YAML::Node Expand(const YAML::Node& node, std::vector<Step>* steps,
                  const std::function<int64_t(const std::string&, const YAML::Node&)>& count) {
  if (IsRepeat(node)) {
    const YAML::Node a = node.begin()->second;
    YAML::Node list(YAML::NodeType::Sequence);
    const int64_t n = count(PathText(*steps), a["count"]);
    for (int64_t i = 0; i < n; ++i) {
      steps->push_back(static_cast<std::size_t>(i));
      list.push_back(Expand(a["each"], steps, count));
      steps->pop_back();
    }
    return list;
  }
  if (IsDistribution(node)) return YAML::Clone(node);
  if (node.IsMap()) {
    YAML::Node out(YAML::NodeType::Map);
    for (const auto& kv : node) {
      steps->push_back(kv.first.Scalar());
      out[kv.first.Scalar()] = Expand(kv.second, steps, count);
      steps->pop_back();
    }
    return out;
  }
  if (node.IsSequence()) {
    YAML::Node out(YAML::NodeType::Sequence);
    for (std::size_t i = 0; i < node.size(); ++i) {
      steps->push_back(i);
      out.push_back(Expand(node[i], steps, count));
      steps->pop_back();
    }
    return out;
  }
  return YAML::Clone(node);
}

// Checks the syntax of every repeat in `node` and that it stands for a list; true if any.
// `elements`: how many copies of `node` the repeats above it make (nested repeats multiply).
bool CheckRepeats(const YAML::Node& node, std::vector<Step>* steps, const std::map<std::string, FieldInfo>& rows,
                  const std::string& file, int64_t elements = 1) {
  if (IsDistribution(node)) return false;
  if (IsRepeat(node)) {
    const std::string path = PathText(*steps);
    CheckRepeatSyntax(node, file, path);
    bool element = false;
    const FieldInfo* row = Row(rows, *steps, &element);
    if (row != nullptr && (element || row->type.empty() || row->type.back() != ']'))
      throw ConfigError(file, path, Written(node), "a repeat stands for a list, not a " + row->type);
    elements *= std::max<int64_t>(1, CountRange(node.begin()->second["count"]).second);
    if (elements > kMaxRepeat)
      throw ConfigError(file, path, Written(node),
                        "nested repeats reach more than " + std::to_string(kMaxRepeat) + " elements");
    steps->push_back(std::size_t{0});
    CheckRepeats(node.begin()->second["each"], steps, rows, file, elements);
    steps->pop_back();
    return true;
  }
  bool any = false;
  if (node.IsMap()) {
    for (const auto& kv : node) {
      steps->push_back(kv.first.Scalar());
      any = CheckRepeats(kv.second, steps, rows, file, elements) || any;
      steps->pop_back();
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      steps->push_back(i);
      any = CheckRepeats(node[i], steps, rows, file, elements) || any;
      steps->pop_back();
    }
  }
  return any;
}

}  // namespace

std::uint64_t KeySeed(std::uint64_t seed, const std::string& path) {
  std::uint64_t h = 1469598103934665603ULL;  // FNV-1a of the path
  for (const unsigned char ch : path) h = (h ^ ch) * 1099511628211ULL;
  return SplitMix64{seed ^ h}.Next();
}

bool IsDistribution(const YAML::Node& node) {
  if (!node.IsMap() || node.size() != 1) return false;
  const YAML::Node key = node.begin()->first;
  if (!key.IsScalar()) return false;
  return std::any_of(std::begin(kKinds), std::end(kKinds), [&](const char* k) { return key.Scalar() == k; });
}

void CheckDistributionSyntax(const YAML::Node& node, const std::string& file, const std::string& path) {
  if (!IsDistribution(node)) throw ConfigError(file, path, Written(node), std::string("a distribution is ") + kForms);
  const std::string kind = node.begin()->first.Scalar();
  const YAML::Node a = node.begin()->second;
  const std::string at = path + "." + kind;
  if (kind == "uniform" || kind == "int") {
    if (!a.IsSequence() || a.size() != 2) throw ConfigError(file, at, Written(a), "expected [lo, hi]");
    const double lo = Number(a[0], file, at + "[0]"), hi = Number(a[1], file, at + "[1]");
    if (lo > hi) throw ConfigError(file, at, Written(a), "empty range: lo > hi");
    if (kind == "int" && (lo != std::floor(lo) || hi != std::floor(hi)))
      throw ConfigError(file, at, Written(a), "expected integer ends");
  } else if (kind == "normal") {
    if (!a.IsMap()) throw ConfigError(file, at, Written(a), "expected {mean: m, std: s}");
    for (const auto& kv : a)
      if (kv.first.Scalar() != "mean" && kv.first.Scalar() != "std")
        throw ConfigError(file, at + "." + kv.first.Scalar(), Written(kv.second),
                          "unknown key; allowed keys: mean, std");
    if (!a["mean"] || !a["std"]) throw ConfigError(file, at, Written(a), "needs mean and std");
    Number(a["mean"], file, at + ".mean");
    if (!(Number(a["std"], file, at + ".std") >= 0.0))
      throw ConfigError(file, at + ".std", Written(a["std"]), "must be >= 0");
  } else {  // choice
    if (!a.IsSequence() || a.size() == 0) throw ConfigError(file, at, Written(a), "expected a non-empty list");
    for (std::size_t i = 0; i < a.size(); ++i)
      if (!a[i].IsScalar() && !a[i].IsSequence())
        throw ConfigError(file, at + "[" + std::to_string(i) + "]", Written(a[i]), "expected a value");
  }
}

std::vector<YAML::Node> DistributionSupport(const YAML::Node& node) {
  const std::string kind = node.begin()->first.Scalar();
  const YAML::Node a = node.begin()->second;
  std::vector<YAML::Node> out;
  if (kind == "normal") {
    out.push_back(YAML::Clone(a["mean"]));
  } else {
    for (std::size_t i = 0; i < a.size(); ++i) out.push_back(YAML::Clone(a[i]));
  }
  if (kind == "int")  // written as reals ("1.0") they still stand for integers
    for (auto& v : out) v = YAML::Node(static_cast<int64_t>(std::llround(v.as<double>())));
  return out;
}

YAML::Node DrawDistribution(const YAML::Node& node, SplitMix64* rng, double lo, double hi) {
  const std::string kind = node.begin()->first.Scalar();
  const YAML::Node a = node.begin()->second;
  if (kind == "uniform") {
    const double l = a[0].as<double>(), h = a[1].as<double>();
    return YAML::Node(l + (h - l) * rng->Uniform01());
  }
  if (kind == "int") {
    const auto l = static_cast<int64_t>(std::llround(a[0].as<double>()));
    const auto h = static_cast<int64_t>(std::llround(a[1].as<double>()));
    const auto span = static_cast<std::uint64_t>(h - l) + 1;
    return YAML::Node(l + static_cast<int64_t>(rng->Next() % span));
  }
  if (kind == "normal") {  // Box-Muller, clipped
    const double u1 = 1.0 - rng->Uniform01(), u2 = rng->Uniform01();
    const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
    return YAML::Node(std::clamp(a["mean"].as<double>() + a["std"].as<double>() * z, lo, hi));
  }
  return YAML::Clone(a[static_cast<std::size_t>(rng->Next() % a.size())]);
}

namespace detail {

namespace {

// CheckStochastic() of a tree without repeats.
void CheckExpanded(const YAML::Node& tree, const std::string& file, const std::map<std::string, FieldInfo>& rows,
                   const std::function<void(const YAML::Node&)>& check) {
  std::vector<Found> found;
  std::vector<Step> steps;
  Collect(tree, &steps, &found);
  // Kind against type: a distribution stands for one leaf value (or one element of a list).
  for (const auto& f : found) {
    if (f.steps.empty())  // the whole document is one, e.g. a file holding `choice: [a, b]`
      throw ConfigError(file, "", Written(f.node), "a distribution stands for one value, not the whole file");
    const std::string path = PathText(f.steps);
    CheckDistributionSyntax(f.node, file, path);
    bool element = false;
    const FieldInfo* row = Row(rows, f.steps, &element);
    if (row == nullptr) continue;  // an unknown key: the load below names it
    const std::string vk = ValueKind(*row, element);
    const std::string kind = f.node.begin()->first.Scalar();
    if (vk.empty())
      throw ConfigError(file, path, Written(f.node),
                        row->type.back() == ']' && row->type != "mapping[]"
                            ? "a distribution stands for one value: write one per element of the list"
                            : "a distribution stands for one value, not a " + row->type);
    if ((kind == "uniform" || kind == "normal") && vk != "double")
      throw ConfigError(file, path + "." + kind, Written(f.node.begin()->second),
                        "a " + vk + " field takes " + (vk == "int" ? "{int: [lo, hi]} or " : "") + "{choice: [...]}");
    if (kind == "int" && vk != "int" && vk != "double")
      throw ConfigError(file, path + ".int", Written(f.node.begin()->second),
                        "a " + vk + " field takes {choice: [...]}");
  }
  // Support against the rules: the tree with each distribution at its first support value is a
  // valid config (unknown keys, types, other fields), and so is every end, choice and mean.
  const auto owner = [&](const ConfigError& e) -> const Found* {
    if (e.rule().rfind("unknown key", 0) == 0) return nullptr;
    for (const auto& f : found) {
      const std::string path = PathText(f.steps);
      if (e.key() == path || path.rfind(e.key() + "[", 0) == 0 || e.key().rfind(path + "[", 0) == 0) return &f;
    }
    return nullptr;
  };
  const auto reaches = [&](const Found& f, const YAML::Node& v, const ConfigError& e) {
    return ConfigError(file, PathText(f.steps), Written(f.node),
                       "the distribution reaches " + Written(v) + ", which " + e.rule());
  };
  YAML::Node base = YAML::Clone(tree);
  for (const auto& f : found) Put(base, f.steps, DistributionSupport(f.node).front());
  try {
    check(base);
  } catch (const ConfigError& e) {
    const Found* f = owner(e);
    if (f == nullptr) throw;
    throw reaches(*f, DistributionSupport(f->node).front(), e);
  }
  for (const auto& f : found) {
    for (const YAML::Node& v : DistributionSupport(f.node)) {
      YAML::Node probe = YAML::Clone(base);
      Put(probe, f.steps, v);
      try {
        check(probe);
      } catch (const ConfigError& e) {
        if (owner(e) != &f) throw;
        throw reaches(f, v, e);
      }
    }
  }
}

}  // namespace

YAML::Node CheckStochastic(const YAML::Node& spec, const std::string& file, Target defaults,
                           const std::function<void(const YAML::Node&)>& check) {
  if (spec.IsDefined() && !spec.IsNull() && !spec.IsMap())
    throw ConfigError(file, "", Written(spec), "must be a mapping of config keys");
  const YAML::Node tree = spec.IsDefined() && !spec.IsNull() ? YAML::Clone(spec) : YAML::Node(YAML::NodeType::Map);
  const auto rows = Rows(defaults);
  std::vector<Step> steps;
  CheckDuplicateKeys(tree, &steps, file);
  if (!CheckRepeats(tree, &steps, rows, file)) {
    CheckExpanded(tree, file, rows, check);
    return tree;
  }
  // Every element of a repeat is drawn from the same spec: the lists at their shortest and at
  // their longest cover every rule (a list's length, each element's support).
  for (const bool longest : {false, true}) {
    const auto count = [longest](const std::string& /*path*/, const YAML::Node& c) {
      const auto [lo, hi] = CountRange(c);
      return longest ? hi : lo;
    };
    CheckExpanded(Expand(tree, &steps, count), file, rows, check);
  }
  return tree;
}

YAML::Node SampleStochastic(const YAML::Node& spec, std::uint64_t seed, Target defaults) {
  std::vector<Step> steps;
  // Repeats first: each count from the generator of "<list path>.count".
  YAML::Node out = Expand(spec, &steps, [seed](const std::string& path, const YAML::Node& c) {
    if (!IsDistribution(c)) return c.as<int64_t>();
    SplitMix64 rng{KeySeed(seed, path + ".count")};
    return static_cast<int64_t>(std::llround(DrawDistribution(c, &rng, 0.0, kMaxRepeat).as<double>()));
  });
  std::vector<Found> found;
  Collect(out, &steps, &found);
  if (found.empty()) return out;
  const auto rows = Rows(defaults);
  for (const auto& f : found) {
    const std::string path = PathText(f.steps);
    double lo = -std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::max();
    bool element = false;
    if (const FieldInfo* row = Row(rows, f.steps, &element)) {
      const FieldSpec& s = row->spec;
      if (s.has_lo) lo = s.lo_open ? std::nextafter(s.lo, hi) : s.lo;
      if (s.has_hi) hi = s.hi_open ? std::nextafter(s.hi, lo) : s.hi;
    }
    SplitMix64 rng{KeySeed(seed, path)};
    Put(out, f.steps, DrawDistribution(f.node, &rng, lo, hi));
  }
  return out;
}

}  // namespace detail
}  // namespace unav::common
