// The archives behind config.hpp: reader (LoadYaml, ApplyOverride), describer, YAML writer and
// checker, over the leaf values of config_values.hpp.
#include "unav_common/config.hpp"

#include "config_values.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <set>
#include <sstream>

namespace unav::common {

ConfigArchive::~ConfigArchive() = default;

namespace {

using namespace config_values;  // NOLINT(google-build-using-namespace): this file's own helpers

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
    std::set<std::string> seen;
    for (const auto& kv : f.node) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : Written(kv.first);
      if (!seen.insert(key).second)  // yaml-cpp keeps both and finds the first: refuse the ambiguity
        reporter_.Fail(ChildPath(f.path, key), Written(kv.second), "appears twice in the same mapping");
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
