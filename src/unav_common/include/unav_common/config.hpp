// Declarative config schema: each config struct names each field once, in a Serialize()
// method (Drake's Serialize/Visit model, STYLE.md items 6 and 14), and one generic archive
// per job reads, checks, documents, overrides and writes every config struct:
//
//   struct MpcParams {
//     int horizon_steps = 20;
//     double dt = 0.05;
//     Eigen::Vector3d position_weights{200, 200, 200};
//     template <class Archive>
//     void Serialize(Archive* a) {
//       a->Visit(unav::common::Field("horizon_steps", &horizon_steps).Range(1, 500).Doc("N, prediction steps"));
//       a->Visit(unav::common::Field("dt", &dt).Above(0.0).Unit("s").Doc("model step"));
//       a->Visit(unav::common::Field("position_weights", &position_weights).Min(0.0).Doc("Q, position"));
//     }
//   };
//   MpcParams p = unav::common::LoadYamlFile<MpcParams>("config/controllers/mpc.yaml");
//
// Field value types: bool, int, int64_t, uint32_t, double, std::string, std::vector<double>,
// std::vector<int>, std::vector<std::string>, Eigen::Vector2d, Eigen::Vector3d (YAML list of 2
// or 3 numbers), Eigen::Matrix3d and Eigen::Matrix<double, 6, 6> (n numbers, the diagonal, or n
// lists of n numbers, the rows; written back diagonal when the matrix is), a struct with its own Serialize() (YAML
// mapping, key path "a.b") and a std::vector of such structs (YAML list of mappings, key path "a[2].b"). Rules:
// Range(lo, hi), Min(lo), Max(hi) are inclusive, Above(lo), Below(hi) exclusive; on lists and Eigen vectors they apply
// to every element. OneOf({...}) for strings. NaN and Inf are always rejected for doubles.
//
// Errors are unav::ConfigError(file, key path, value as written, rule), e.g.
//   "config/controllers/mpc.yaml: horizon_steps = -3: must be in [1, 500]".
//
// Serialize() is instantiated once per config struct, for the archive base class
// (ConfigArchive); the reading, checking and formatting live in config.cpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "unav_common/errors.hpp"

namespace unav::common {

/// Kinds of leaf value a field can hold.
enum class ValueType {
  kBool,
  kInt,
  kInt64,
  kUint32,
  kDouble,
  kString,
  kDoubleList,
  kIntList,
  kStringList,
  kVector2,
  kVector3,
  kMatrix3,  ///< Eigen::Matrix3d
  kMatrix6   ///< Eigen::Matrix<double, 6, 6>
};

/// A typed pointer to a leaf value; built only by the MakeValueRef overloads.
struct ValueRef {
  ValueType type;
  void* ptr;
};
inline ValueRef MakeValueRef(bool* p) { return {ValueType::kBool, p}; }
inline ValueRef MakeValueRef(int* p) { return {ValueType::kInt, p}; }
inline ValueRef MakeValueRef(int64_t* p) { return {ValueType::kInt64, p}; }
inline ValueRef MakeValueRef(uint32_t* p) { return {ValueType::kUint32, p}; }
inline ValueRef MakeValueRef(double* p) { return {ValueType::kDouble, p}; }
inline ValueRef MakeValueRef(std::string* p) { return {ValueType::kString, p}; }
inline ValueRef MakeValueRef(std::vector<double>* p) { return {ValueType::kDoubleList, p}; }
inline ValueRef MakeValueRef(std::vector<int>* p) { return {ValueType::kIntList, p}; }
inline ValueRef MakeValueRef(std::vector<std::string>* p) { return {ValueType::kStringList, p}; }
inline ValueRef MakeValueRef(Eigen::Vector2d* p) { return {ValueType::kVector2, p}; }
inline ValueRef MakeValueRef(Eigen::Vector3d* p) { return {ValueType::kVector3, p}; }
inline ValueRef MakeValueRef(Eigen::Matrix3d* p) { return {ValueType::kMatrix3, p}; }
inline ValueRef MakeValueRef(Eigen::Matrix<double, 6, 6>* p) { return {ValueType::kMatrix6, p}; }

/// Everything a field declares besides its value (the non-template half of Field<T>).
struct FieldSpec {
  std::string name;
  std::string doc;
  std::string unit;
  bool has_lo = false, lo_open = false;  ///< lower bound; open = exclusive
  bool has_hi = false, hi_open = false;  ///< upper bound; open = exclusive
  double lo = 0.0, hi = 0.0;
  std::vector<std::string> one_of;  ///< allowed strings; empty = any

  /// The rule as table text: "[1, 500]", "> 0", "(0, 1]", "<= 2", "{a, b}"; empty without one.
  std::string RuleText() const;
};

class ConfigArchive;

namespace detail {
template <class T, class = void>
struct IsConfigStruct : std::false_type {};
template <class T>
struct IsConfigStruct<T, std::void_t<decltype(std::declval<T&>().Serialize(static_cast<ConfigArchive*>(nullptr)))>>
    : std::true_type {};
template <class T>
struct IsStructList : std::false_type {};
template <class E, class A>
struct IsStructList<std::vector<E, A>> : IsConfigStruct<E> {};
template <class T, class = void>
struct IsLeaf : std::false_type {};
template <class T>
struct IsLeaf<T, std::void_t<decltype(MakeValueRef(static_cast<T*>(nullptr)))>> : std::true_type {};
template <class T>
constexpr bool kIsNumeric = IsLeaf<T>::value && !std::is_same_v<T, bool> && !std::is_same_v<T, std::string> &&
                            !std::is_same_v<T, std::vector<std::string>>;
template <class T>
constexpr bool kIsText = std::is_same_v<T, std::string> || std::is_same_v<T, std::vector<std::string>>;
}  // namespace detail

/// A named field of a config struct: Field("dt", &dt).Above(0.0).Unit("s").Doc("model step").
template <class T>
class Field {
 public:
  Field(std::string name, T* value) : value_(value) { spec_.name = std::move(name); }

  /// One line of documentation (shown by Describe/FormatHelp).
  Field& Doc(std::string text) {
    spec_.doc = std::move(text);
    return *this;
  }
  /// SI unit of the value ("s", "m", "rad/s"); documentation only.
  Field& Unit(std::string text) {
    spec_.unit = std::move(text);
    return *this;
  }
  /// lo <= value <= hi.
  Field& Range(double lo, double hi) { return Min(lo).Max(hi); }
  /// value >= lo.
  Field& Min(double lo) { return Lower(lo, false); }
  /// value <= hi.
  Field& Max(double hi) { return Upper(hi, false); }
  /// value > lo.
  Field& Above(double lo) { return Lower(lo, true); }
  /// value < hi.
  Field& Below(double hi) { return Upper(hi, true); }
  /// The value is one of `allowed` (strings and lists of strings).
  Field& OneOf(std::vector<std::string> allowed) {
    static_assert(detail::kIsText<T>, "OneOf() applies to std::string fields");
    spec_.one_of = std::move(allowed);
    return *this;
  }

  const FieldSpec& spec() const { return spec_; }
  T* value() const { return value_; }

 private:
  Field& Lower(double lo, bool open) {
    static_assert(detail::kIsNumeric<T>, "Range/Min/Max/Above/Below apply to numeric fields");
    spec_.has_lo = true;
    spec_.lo = lo;
    spec_.lo_open = open;
    return *this;
  }
  Field& Upper(double hi, bool open) {
    static_assert(detail::kIsNumeric<T>, "Range/Min/Max/Above/Below apply to numeric fields");
    spec_.has_hi = true;
    spec_.hi = hi;
    spec_.hi_open = open;
    return *this;
  }

  FieldSpec spec_;
  T* value_;
};

/// The archive every Serialize() receives. The archives (reader, describer, writer, checker)
/// derive from it in config.cpp; Serialize() itself only calls Visit().
class ConfigArchive {
 public:
  virtual ~ConfigArchive();

  template <class T>
  void Visit(const Field<T>& field) {
    if constexpr (detail::IsConfigStruct<T>::value) {
      if (BeginStruct(field.spec())) {
        field.value()->Serialize(this);
        EndStruct();
      }
    } else if constexpr (detail::IsStructList<T>::value) {
      VisitStructList(field.spec(), field.value());
    } else {
      static_assert(detail::IsLeaf<T>::value,
                    "unsupported config field type: use bool, int, int64_t, uint32_t, double, std::string, "
                    "std::vector<double|int|std::string>, Eigen::Vector2d/3d, a struct with Serialize() or a "
                    "std::vector of such structs");
      Leaf(field.spec(), MakeValueRef(field.value()));
    }
  }

  /// How BeginList() wants a list of structs visited.
  enum class ListMode {
    kExisting,  ///< visit the current elements (BeginElement may skip some)
    kReplace,   ///< replace the list by `size` default elements, then visit them
    kSchema     ///< visit one default-constructed element (index kSchemaElement)
  };
  struct ListPlan {
    ListMode mode = ListMode::kExisting;
    std::size_t size = 0;
  };
  static constexpr std::size_t kSchemaElement = static_cast<std::size_t>(-1);

 protected:
  virtual void Leaf(const FieldSpec& spec, ValueRef value) = 0;
  /// False: skip the nested struct (EndStruct is then not called).
  virtual bool BeginStruct(const FieldSpec& spec) = 0;
  virtual void EndStruct() = 0;
  /// Always followed by EndList().
  virtual ListPlan BeginList(const FieldSpec& spec, std::size_t size) = 0;
  /// False: skip this element (EndElement is then not called).
  virtual bool BeginElement(std::size_t index) = 0;
  virtual void EndElement() = 0;
  virtual void EndList() = 0;

 private:
  template <class E, class A>
  void VisitStructList(const FieldSpec& spec, std::vector<E, A>* list) {
    const ListPlan plan = BeginList(spec, list->size());
    if (plan.mode == ListMode::kSchema) {
      E element{};
      if (BeginElement(kSchemaElement)) {
        element.Serialize(this);
        EndElement();
      }
    } else {
      if (plan.mode == ListMode::kReplace) {
        list->clear();
        list->resize(plan.size);
      }
      for (std::size_t i = 0; i < list->size(); ++i) {
        if (BeginElement(i)) {
          (*list)[i].Serialize(this);
          EndElement();
        }
      }
    }
    EndList();
  }
};

/// One row of a config's documentation (Describe).
struct FieldInfo {
  std::string name;           ///< key path: "dt", "current.speed", "thrusters[i].direction"
  std::string type;           ///< "bool", "int", "int64", "uint32", "double", "string", "double[3]",
                              ///< "double[]", "int[]", "string[]", "mapping", "mapping[]"
  std::string default_value;  ///< flow YAML text: "20", "0.05", "[200.0, 200.0, 200.0]", "\"\""
  std::string rule;           ///< FieldSpec::RuleText(): "[1, 500]", "> 0", "{a, b}", ""
  std::string unit;
  std::string doc;
  FieldSpec spec;  ///< the declared rule as data (bounds, allowed strings)
};

/// An aligned table, one row per field, columns name, type, default, rule, unit, doc (empty
/// cells shown as "-"), each line indented by two spaces:
///   "  horizon_steps  int     20    [1, 500]  -  N, prediction steps"
std::string FormatHelp(const std::vector<FieldInfo>& fields);

namespace detail {
/// A config struct with its type erased: the object and its Serialize(ConfigArchive*).
struct Target {
  void* object;
  void (*serialize)(void* object, ConfigArchive* archive);
};
template <class T>
Target MakeTarget(const T* object) {
  return {const_cast<T*>(object), [](void* o, ConfigArchive* a) { static_cast<T*>(o)->Serialize(a); }};
}
YAML::Node ReadYamlFile(const std::string& path);
void LoadYaml(const YAML::Node& node, const std::string& file, const std::string& root, Target out);
void ApplyOverride(Target cfg, const std::string& name, const std::string& yaml_value, const std::string& source);
std::vector<FieldInfo> Describe(Target defaults);
YAML::Node ToYaml(Target cfg);
void Validate(Target cfg, const std::string& where);
}  // namespace detail

/// Reads the mapping `node` (or its sub-map at the dotted path `root`, e.g.
/// "mpc_controller.ros__parameters" of a ROS 2 params file) into *out. Keys absent from the
/// YAML keep the values *out had. Unknown keys, wrong types, values breaking a rule and
/// NaN/Inf throw ConfigError(file, key path, value as written, rule); *out is then unchanged.
template <class T>
void LoadYaml(const YAML::Node& node, const std::string& file, T* out, const std::string& root = "") {
  T result = *out;
  detail::LoadYaml(node, file, root, detail::MakeTarget(&result));
  *out = std::move(result);
}

/// LoadYaml() of a file. Also throws ConfigError when the file is missing or malformed.
template <class T>
void LoadYamlFile(const std::string& path, T* out, const std::string& root = "") {
  LoadYaml(detail::ReadYamlFile(path), path, out, root);
}

/// LoadYamlFile() starting from a default-constructed T.
template <class T>
T LoadYamlFile(const std::string& path, const std::string& root = "") {
  T out{};
  LoadYamlFile(path, &out, root);
  return out;
}

/// Sets one field from YAML text ("30", "0.1", "[1, 2, 3]", "true", "{a: 1}"), with the checks
/// and errors of LoadYaml; `source` says where the text came from ("-p", "command line") and
/// takes the place of the file name in errors. `name` is a key path: "dt", "current.speed",
/// "thrusters[3].direction", "position_weights[2]" (one element of a list). Unknown names
/// throw ConfigError listing the allowed keys; *cfg is unchanged on error.
template <class T>
void ApplyOverride(T* cfg, const std::string& name, const std::string& yaml_value, const std::string& source) {
  T result = *cfg;
  detail::ApplyOverride(detail::MakeTarget(&result), name, yaml_value, source);
  *cfg = std::move(result);
}

/// One row per field (nested fields with their dotted path; a list of structs as one
/// "mapping[]" row followed by the rows of a default element, named "list[i].field").
template <class T>
std::vector<FieldInfo> Describe(const T& defaults) {
  return detail::Describe(detail::MakeTarget(&defaults));
}

/// The config as a YAML mapping in declaration order (for logs and run manifests); LoadYaml
/// of it gives back the same values (doubles are written in shortest round-trip form, with
/// ".0" when integral). yaml-cpp quotes only empty and null-like strings, so a string field
/// holding "123" or "yes" is written plain: LoadYaml reads it back as that string, a YAML 1.1
/// reader elsewhere may not.
template <class T>
YAML::Node ToYaml(const T& cfg) {
  return detail::ToYaml(detail::MakeTarget(&cfg));
}

/// Checks the current values against the rules (for configs built in code); throws
/// ConfigError(where, key path, value, rule) for the first broken one.
template <class T>
void Validate(const T& cfg, const std::string& where) {
  detail::Validate(detail::MakeTarget(&cfg), where);
}

}  // namespace unav::common
