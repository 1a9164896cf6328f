// Distributions in config files, and the one seeded sampler that resolves them (Drake's
// stochastic schema, DESIGN.md section 9). Any leaf of a config struct (or one element of a
// numeric list) may be written as a distribution instead of a value:
//   {uniform: [lo, hi]}          double fields, lo <= hi
//   {normal: {mean: m, std: s}}  double fields; draws clipped to the field's range
//   {int: [lo, hi]}              integer fields, both ends included
//   {choice: [a, b, ...]}        any leaf: one of the listed values, equally likely
// and a list field may be written as
//   {repeat: {count: C, each: E}}  C elements (C a whole number, {int: [lo, hi]} or {choice}),
//                                  each drawn anew from E (values, distributions, repeats)
// Sample(seed) draws every distribution from its own generator, seeded from (seed, key path),
// so a sample is reproduced bit for bit by its seed and adding a field shifts no other field's
// draw (a repeat's count: "<list>.count"; its elements: "<list>[i].<key>"). The generators are SplitMix64 and the
// transforms are written here (not <random>'s, whose algorithms differ between standard libraries).
//
//   auto s = unav::common::LoadStochasticYamlFile<Scenario>("my.yaml");   // checks everything
//   Scenario a = s.Sample(7);                                              // concrete, typed
//
// Checks before any draw: a distribution's syntax, its kind against the field's type, and its
// whole support (both ends, every choice, the mean) against the field's rule (a repeat's list
// at its shortest and at its longest); errors are
// ConfigError(file, key path, value as written, rule), like every config error.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "unav_common/config.hpp"

namespace unav::common {

/// SplitMix64 (Steele, Lea, Flood 2014): the generator of every seeded draw in the workspace.
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t Next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1), 53 bits.
  double Uniform01() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
};

/// One SplitMix64 step of `x`: a decorrelated 64-bit seed derived from another.
inline std::uint64_t MixSeed(std::uint64_t x) { return SplitMix64{x}.Next(); }

/// The seed of the generator of key `path` ("water.turbidity") in the sample drawn with `seed`.
std::uint64_t KeySeed(std::uint64_t seed, const std::string& path);

/// True if `node` is written as a distribution: a one-key map whose key is a distribution kind.
bool IsDistribution(const YAML::Node& node);

/// Checks a distribution's syntax (not its support); throws ConfigError(file, path.kind, ...).
void CheckDistributionSyntax(const YAML::Node& node, const std::string& file, const std::string& path);

/// The values that bound a checked distribution's support: both ends ({uniform}, {int}), every
/// choice, the mean ({normal}).
std::vector<YAML::Node> DistributionSupport(const YAML::Node& node);

/// One draw of a checked distribution with `rng`; {normal} draws are clipped to [lo, hi].
YAML::Node DrawDistribution(const YAML::Node& node, SplitMix64* rng, double lo, double hi);

namespace detail {
/// The spec tree with every distribution checked against the schema of `defaults`; `check`
/// loads a concrete tree into a fresh config (throws ConfigError).
YAML::Node CheckStochastic(const YAML::Node& spec, const std::string& file, Target defaults,
                           const std::function<void(const YAML::Node&)>& check);
/// `spec` (checked) with every distribution replaced by its draw for `seed`.
YAML::Node SampleStochastic(const YAML::Node& spec, std::uint64_t seed, Target defaults);
}  // namespace detail

/// A config of type T whose fields may be distributions: checked on construction, sampled into
/// concrete T values by seed.
template <class T>
class Stochastic {
 public:
  /// Checks `spec` (a YAML mapping of T's keys, values or distributions). Throws ConfigError.
  Stochastic(const YAML::Node& spec, std::string file) : file_(std::move(file)) {
    const T defaults{};
    spec_ = detail::CheckStochastic(spec, file_, detail::MakeTarget(&defaults), [this](const YAML::Node& n) {
      T probe{};
      LoadYaml(n, file_, &probe);
    });
  }
  // Copies own their spec: yaml-cpp's Node assignment writes through every copy of a node.
  Stochastic(const Stochastic& o) : spec_(YAML::Clone(o.spec_)), file_(o.file_) {}
  Stochastic& operator=(const Stochastic& o) {
    if (this != &o) {
      spec_.reset(YAML::Clone(o.spec_));
      file_ = o.file_;
    }
    return *this;
  }
  ~Stochastic() = default;
  /// The concrete config drawn with `seed` (the same seed: the same config, bit for bit).
  T Sample(std::uint64_t seed) const {
    T out{};
    LoadYaml(SampledYaml(seed), file_, &out);
    return out;
  }
  /// The concrete YAML drawn with `seed` (what Sample() reads), for manifests and child processes.
  YAML::Node SampledYaml(std::uint64_t seed) const {
    const T defaults{};
    return detail::SampleStochastic(spec_, seed, detail::MakeTarget(&defaults));
  }
  const YAML::Node& spec() const { return spec_; }
  const std::string& file() const { return file_; }

 private:
  YAML::Node spec_;
  std::string file_;
};

/// Reads and checks `path` (or its sub-map `root`) as a Stochastic<T>. Throws ConfigError.
template <class T>
Stochastic<T> LoadStochasticYamlFile(const std::string& path, const std::string& root = "") {
  YAML::Node node = detail::ReadYamlFile(path);
  if (!root.empty()) {
    if (!node.IsMap() || !node[root].IsDefined())
      throw ConfigError(path, root, "", "section not found (the file has no '" + root + "')");
    node = node[root];
  }
  return Stochastic<T>(node, path);
}

}  // namespace unav::common
