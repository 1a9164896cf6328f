#include "unav_localization/bow_vocabulary.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numeric>
#include <random>
#include <stdexcept>
#include <unordered_set>

// Hamming distances use __builtin_popcountll. Without -mpopcnt, x86-64 GCC/Clang compile it to a
// libgcc call several times slower than the POPCNT instruction, so the hot loops are cloned for
// CPUs with POPCNT and the best clone is picked once at load time (ifunc). Elsewhere (aarch64,
// or builds that already target POPCNT) the builtin is a native instruction.
#if defined(__x86_64__) && defined(__GNUC__) && defined(__linux__) && !defined(__POPCNT__)
#define UNAV_BOW_POPCNT_CLONES __attribute__((target_clones("popcnt", "default")))
#else
#define UNAV_BOW_POPCNT_CLONES
#endif

namespace unav::localization {

namespace {

constexpr int kDescriptorBytes = 32;
constexpr char kMagic[8] = {'U', 'N', 'A', 'V', 'B', 'O', 'W', '1'};
constexpr uint32_t kFormatVersion = 1;
constexpr size_t kHeaderBytes = 8 + 5 * 4;               // magic, version, k, L, nodes, words
constexpr size_t kNodeBytes = 4 * 4 + kDescriptorBytes;  // parent, first child, children, word, centre
constexpr size_t kWordBytes = 8;                         // idf weight (IEEE double)
constexpr size_t kFooterBytes = 8;                       // FNV-1a 64 of everything before

void CheckDescriptorMatrix(const cv::Mat& m, const char* what) {
  if (m.empty()) return;
  if (m.type() != CV_8UC1 || m.cols != kDescriptorBytes)
    throw std::invalid_argument(std::string(what) + ": descriptors must be CV_8UC1 with 32 columns, got type " +
                                std::to_string(m.type()) + " with " + std::to_string(m.cols) + " columns");
}

uint64_t Fnv1a64(const std::string& bytes, size_t n) {
  uint64_t h = 1469598103934665603ull;
  for (size_t i = 0; i < n; ++i) {
    h ^= static_cast<uint8_t>(bytes[i]);
    h *= 1099511628211ull;
  }
  return h;
}

void PutU32(std::string* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void PutU64(std::string* out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

/// Bounds-checked little-endian reader over a whole file; errors name the path.
class Reader {
 public:
  Reader(const std::string& path, const std::string& bytes) : path_(path), bytes_(bytes) {}
  uint32_t U32(const char* what) {
    Need(4, what);
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(static_cast<uint8_t>(bytes_[pos_ + i])) << (8 * i);
    pos_ += 4;
    return v;
  }
  uint64_t U64(const char* what) {
    Need(8, what);
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(static_cast<uint8_t>(bytes_[pos_ + i])) << (8 * i);
    pos_ += 8;
    return v;
  }
  void Bytes(void* dst, size_t n, const char* what) {
    Need(n, what);
    std::memcpy(dst, bytes_.data() + pos_, n);
    pos_ += n;
  }
  size_t pos() const { return pos_; }
  [[noreturn]] void Fail(const std::string& why) const {
    throw std::runtime_error("BowVocabulary::Load: " + path_ + ": " + why);
  }

 private:
  void Need(size_t n, const char* what) const {
    if (bytes_.size() - pos_ < n)
      Fail(std::string("truncated file: ") + std::to_string(bytes_.size()) + " bytes, ended while reading " + what +
           " at byte " + std::to_string(pos_));
  }
  const std::string& path_;
  const std::string& bytes_;
  size_t pos_ = 0;
};

/// Deterministic on every platform (std::uniform_*_distribution are implementation-defined).
double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

}  // namespace

bool VocabularyOptions::IsValid(std::string* msg) const {
  auto fail = [&](const std::string& m) {
    if (msg) *msg = m;
    return false;
  };
  if (branching < 2 || branching > 64) return fail("branching must be in [2, 64], got " + std::to_string(branching));
  if (levels < 1 || levels > 10) return fail("levels must be in [1, 10], got " + std::to_string(levels));
  if (kmeans_iterations < 1) return fail("kmeans_iterations must be >= 1, got " + std::to_string(kmeans_iterations));
  if (levels * std::log2(static_cast<double>(branching)) > 31.0)
    return fail("branching^levels must be below 2^31, got " + std::to_string(branching) + "^" + std::to_string(levels));
  return true;
}

// Kernels and training; a friend of BowVocabulary so that it can use its private tree types.
class BowVocabularyImpl {
 public:
  using Descriptor = BowVocabulary::Descriptor;
  using Node = BowVocabulary::Node;

  static Descriptor Row(const uint8_t* p) {
    Descriptor d;
    std::memcpy(d.data(), p, kDescriptorBytes);
    return d;
  }
  static std::vector<Descriptor> Rows(const cv::Mat& m) {
    std::vector<Descriptor> out(static_cast<size_t>(m.rows));
    for (int r = 0; r < m.rows; ++r) out[static_cast<size_t>(r)] = Row(m.ptr<uint8_t>(r));
    return out;
  }

  __attribute__((always_inline)) static inline int Hamming(const Descriptor& a, const Descriptor& b) {
    return __builtin_popcountll(a[0] ^ b[0]) + __builtin_popcountll(a[1] ^ b[1]) + __builtin_popcountll(a[2] ^ b[2]) +
           __builtin_popcountll(a[3] ^ b[3]);
  }

  /// For each descriptor: its leaf, and (if group != nullptr) the node at depth group_depth on
  /// its path, or the leaf when the path ends above that depth.
  UNAV_BOW_POPCNT_CLONES static void DescendBatch(const Node* nodes, const Descriptor* centres, const Descriptor* ds,
                                                  size_t n, uint32_t group_depth, NodeId* leaf, NodeId* group) {
    for (size_t i = 0; i < n; ++i) {
      const Descriptor& d = ds[i];
      NodeId node = 0, g = 0;
      uint32_t depth = 0;
      while (nodes[node].num_children > 0) {
        const NodeId first = nodes[node].first_child;
        const NodeId end = first + nodes[node].num_children;
        NodeId best = first;
        int best_dist = INT_MAX;
        for (NodeId c = first; c < end; ++c) {
          const int dist = Hamming(centres[c], d);
          if (dist < best_dist) {
            best_dist = dist;
            best = c;
          }
        }
        node = best;
        if (++depth == group_depth) g = node;
      }
      leaf[i] = node;
      if (group) group[i] = depth < group_depth ? node : g;
    }
  }

  /// assign[i] = nearest of the k centres to all[idx[i]] (lowest index on ties); returns how many
  /// assignments changed.
  UNAV_BOW_POPCNT_CLONES static size_t AssignBatch(const Descriptor* centres, int k, const Descriptor* all,
                                                   const uint32_t* idx, size_t n, int* assign) {
    size_t changed = 0;
    for (size_t i = 0; i < n; ++i) {
      const Descriptor& d = all[idx[i]];
      int best = 0, best_dist = INT_MAX;
      for (int c = 0; c < k; ++c) {
        const int dist = Hamming(centres[c], d);
        if (dist < best_dist) {
          best_dist = dist;
          best = c;
        }
      }
      changed += assign[i] != best;
      assign[i] = best;
    }
    return changed;
  }

  /// d2[i] = min(d2[i], Hamming(c, all[idx[i]])^2); returns the sum of the new d2 (without
  /// writing it when write == false).
  UNAV_BOW_POPCNT_CLONES static double UpdatePotential(const Descriptor& c, const Descriptor* all, const uint32_t* idx,
                                                       size_t n, uint32_t* d2, bool write) {
    uint64_t sum = 0;
    for (size_t i = 0; i < n; ++i) {
      const uint32_t h = static_cast<uint32_t>(Hamming(c, all[idx[i]]));
      const uint32_t v = std::min(d2[i], h * h);
      sum += v;
      if (write) d2[i] = v;
    }
    return static_cast<double>(sum);
  }

  /// Greedy k-means++ seeding (Arthur & Vassilvitskii 2007, with 2 + ln k candidates per step as
  /// in scikit-learn): each step samples candidates with probability proportional to the squared
  /// distance to the nearest chosen centre and keeps the one that lowers the total most. Stops
  /// early when every descriptor coincides with a chosen centre.
  static std::vector<Descriptor> Seed(const std::vector<Descriptor>& all, const std::vector<uint32_t>& idx, int k,
                                      std::mt19937_64& rng) {
    const size_t n = idx.size();
    const int trials = 2 + static_cast<int>(std::log(static_cast<double>(k)));
    std::vector<Descriptor> centres{all[idx[rng() % n]]};
    std::vector<uint32_t> d2(n, UINT32_MAX);
    double potential = UpdatePotential(centres[0], all.data(), idx.data(), n, d2.data(), true);
    while (static_cast<int>(centres.size()) < k && potential > 0) {
      size_t best_i = n;
      double best_potential = potential;
      for (int t = 0; t < trials; ++t) {
        // Sample i with probability d2[i] / potential.
        const double r = Uniform01(rng) * potential;
        double acc = 0;
        size_t i = 0;
        for (; i + 1 < n; ++i) {
          acc += d2[i];
          if (acc > r && d2[i] > 0) break;
        }
        while (d2[i] == 0 && i > 0) --i;  // rounding at the end of the range: take a positive one
        const double p = UpdatePotential(all[idx[i]], all.data(), idx.data(), n, d2.data(), false);
        if (best_i == n || p < best_potential) {
          best_potential = p;
          best_i = i;
        }
      }
      if (d2[best_i] == 0) break;  // only coincident descriptors left
      centres.push_back(all[idx[best_i]]);
      potential = UpdatePotential(centres.back(), all.data(), idx.data(), n, d2.data(), true);
    }
    return centres;
  }

  /// Bitwise majority of each cluster (ties -> 0); empty clusters keep their centre.
  static void Majority(const std::vector<Descriptor>& all, const std::vector<uint32_t>& idx,
                       const std::vector<int>& assign, std::vector<Descriptor>* centres) {
    const size_t k = centres->size();
    std::vector<uint32_t> counts(k * 256, 0), members(k, 0);
    for (size_t i = 0; i < idx.size(); ++i) {
      const Descriptor& d = all[idx[i]];
      uint32_t* cnt = &counts[static_cast<size_t>(assign[i]) * 256];
      ++members[static_cast<size_t>(assign[i])];
      for (int w = 0; w < 4; ++w)
        for (int b = 0; b < 64; ++b) cnt[w * 64 + b] += static_cast<uint32_t>((d[w] >> b) & 1u);
    }
    for (size_t c = 0; c < k; ++c) {
      if (members[c] == 0) continue;
      Descriptor m{};
      const uint32_t* cnt = &counts[c * 256];
      for (int w = 0; w < 4; ++w)
        for (int b = 0; b < 64; ++b)
          if (2 * cnt[w * 64 + b] > members[c]) m[w] |= uint64_t{1} << b;
      (*centres)[c] = m;
    }
  }

  /// Splits node `node` (at `depth`) with descriptors idx into children, recursively.
  static void Split(BowVocabulary* voc, const std::vector<Descriptor>& all, std::vector<uint32_t> idx, NodeId node,
                    uint32_t depth, const VocabularyOptions& o, std::mt19937_64& rng) {
    if (static_cast<int>(depth) >= o.levels || idx.size() <= 1) return;
    const Descriptor& first = all[idx[0]];
    if (std::all_of(idx.begin(), idx.end(), [&](uint32_t i) { return all[i] == first; })) return;

    std::vector<Descriptor> centres = Seed(all, idx, o.branching, rng);
    int k = static_cast<int>(centres.size());
    std::vector<int> assign(idx.size(), -1);
    AssignBatch(centres.data(), k, all.data(), idx.data(), idx.size(), assign.data());
    for (int it = 0; it < o.kmeans_iterations; ++it) {
      std::vector<Descriptor> updated = centres;
      Majority(all, idx, assign, &updated);
      if (updated == centres) break;
      centres.swap(updated);
      if (AssignBatch(centres.data(), k, all.data(), idx.data(), idx.size(), assign.data()) == 0) break;
    }
    // The assignment is the nearest-centre one for the final centres, so descending the tree
    // reproduces it. Empty clusters are dropped; that does not change anyone's nearest centre.
    std::vector<std::vector<uint32_t>> members(static_cast<size_t>(k));
    for (size_t i = 0; i < idx.size(); ++i) members[static_cast<size_t>(assign[i])].push_back(idx[i]);
    std::vector<uint32_t>().swap(idx);
    std::vector<size_t> kept;
    for (size_t c = 0; c < members.size(); ++c)
      if (!members[c].empty()) kept.push_back(c);

    const NodeId first_child = static_cast<NodeId>(voc->nodes_.size());
    voc->nodes_[node].first_child = first_child;
    voc->nodes_[node].num_children = static_cast<uint32_t>(kept.size());
    for (size_t c : kept) {
      Node child;
      child.parent = node;
      voc->nodes_.push_back(child);
      voc->centres_.push_back(centres[c]);
    }
    for (size_t j = 0; j < kept.size(); ++j)
      Split(voc, all, std::move(members[kept[j]]), first_child + static_cast<NodeId>(j), depth + 1, o, rng);
  }
};

BowVocabulary BowVocabulary::Train(const std::vector<cv::Mat>& descriptors_per_image,
                                   const VocabularyOptions& options) {
  std::string msg;
  if (!options.IsValid(&msg)) throw std::invalid_argument("BowVocabulary::Train: VocabularyOptions: " + msg);
  if (descriptors_per_image.empty()) throw std::invalid_argument("BowVocabulary::Train: no training images");
  using Impl = BowVocabularyImpl;
  std::vector<Descriptor> all;
  std::vector<uint32_t> image_of;
  for (size_t i = 0; i < descriptors_per_image.size(); ++i) {
    const cv::Mat& m = descriptors_per_image[i];
    CheckDescriptorMatrix(m, ("BowVocabulary::Train: image " + std::to_string(i)).c_str());
    for (int r = 0; r < m.rows; ++r) {
      all.push_back(Impl::Row(m.ptr<uint8_t>(r)));
      image_of.push_back(static_cast<uint32_t>(i));
    }
  }
  if (all.empty()) throw std::invalid_argument("BowVocabulary::Train: the training images have no descriptors");
  if (all.size() > UINT32_MAX / 2) throw std::invalid_argument("BowVocabulary::Train: too many descriptors");

  BowVocabulary voc;
  voc.branching_ = options.branching;
  voc.levels_ = options.levels;
  voc.nodes_.emplace_back();
  voc.centres_.emplace_back();  // the root has no centre
  std::mt19937_64 rng(options.seed);
  std::vector<uint32_t> idx(all.size());
  std::iota(idx.begin(), idx.end(), 0u);
  Impl::Split(&voc, all, std::move(idx), 0, 0, options, rng);

  for (NodeId n = 0; n < voc.nodes_.size(); ++n) {
    if (voc.nodes_[n].num_children > 0) continue;
    voc.nodes_[n].word = static_cast<WordId>(voc.words_.size());
    voc.words_.push_back(n);
  }

  // idf: log(N / n_w), n_w = number of images with a descriptor reaching word w.
  std::vector<NodeId> leaf(all.size());
  Impl::DescendBatch(voc.nodes_.data(), voc.centres_.data(), all.data(), all.size(), 0, leaf.data(), nullptr);
  std::vector<uint32_t> images_with(voc.words_.size(), 0), last_image(voc.words_.size(), UINT32_MAX);
  for (size_t i = 0; i < all.size(); ++i) {
    const WordId w = voc.nodes_[leaf[i]].word;
    if (last_image[w] != image_of[i]) {  // descriptors are grouped by image, so this counts images
      last_image[w] = image_of[i];
      ++images_with[w];
    }
  }
  const double n_images = static_cast<double>(descriptors_per_image.size());
  voc.weights_.resize(voc.words_.size());
  for (size_t w = 0; w < voc.words_.size(); ++w)
    voc.weights_[w] = std::log(n_images / std::max<double>(1.0, images_with[w]));
  return voc;
}

double BowVocabulary::Weight(WordId word) const { return word < weights_.size() ? weights_[word] : 0.0; }

NodeId BowVocabulary::Descend(const Descriptor& d) const {
  NodeId leaf = 0;
  BowVocabularyImpl::DescendBatch(nodes_.data(), centres_.data(), &d, 1, 0, &leaf, nullptr);
  return leaf;
}

WordId BowVocabulary::Word(const cv::Mat& descriptor_row) const {
  if (empty()) throw std::logic_error("BowVocabulary::Word: empty vocabulary");
  if (descriptor_row.rows != 1 || descriptor_row.type() != CV_8UC1 || descriptor_row.cols != kDescriptorBytes)
    throw std::invalid_argument("BowVocabulary::Word: need a 1 x 32 CV_8UC1 descriptor, got " +
                                std::to_string(descriptor_row.rows) + " x " + std::to_string(descriptor_row.cols) +
                                " of type " + std::to_string(descriptor_row.type()));
  return nodes_[Descend(BowVocabularyImpl::Row(descriptor_row.ptr<uint8_t>(0)))].word;
}

void BowVocabulary::Transform(const cv::Mat& descriptors, BowVector* bow, FeatureVector* fv, int levels_up) const {
  if (empty()) throw std::logic_error("BowVocabulary::Transform: empty vocabulary");
  if (levels_up < 0) throw std::invalid_argument("BowVocabulary::Transform: levels_up must be >= 0");
  CheckDescriptorMatrix(descriptors, "BowVocabulary::Transform");
  if (bow) bow->clear();
  if (fv) fv->clear();
  if (descriptors.empty()) return;
  const std::vector<Descriptor> ds = BowVocabularyImpl::Rows(descriptors);
  std::vector<NodeId> leaf(ds.size()), group(fv ? ds.size() : 0);
  const uint32_t group_depth = static_cast<uint32_t>(std::max(0, levels_ - levels_up));
  BowVocabularyImpl::DescendBatch(nodes_.data(), centres_.data(), ds.data(), ds.size(), group_depth, leaf.data(),
                                  fv ? group.data() : nullptr);
  // Sorted keys are appended at the end of the maps (amortised O(1) instead of a tree search).
  if (bow) {
    std::vector<WordId> words;
    words.reserve(leaf.size());
    for (NodeId l : leaf)
      if (weights_[nodes_[l].word] > 0) words.push_back(nodes_[l].word);
    std::sort(words.begin(), words.end());
    double total = 0;
    for (size_t i = 0; i < words.size();) {
      size_t j = i;
      while (j < words.size() && words[j] == words[i]) ++j;
      const double weight = static_cast<double>(j - i) * weights_[words[i]];
      bow->emplace_hint(bow->end(), words[i], weight);
      total += weight;
      i = j;
    }
    for (auto& entry : *bow) entry.second /= total;
  }
  if (fv) {
    std::vector<std::pair<NodeId, int>> by_node(ds.size());
    for (size_t i = 0; i < ds.size(); ++i) by_node[i] = {group[i], static_cast<int>(i)};
    std::sort(by_node.begin(), by_node.end());
    auto it = fv->end();
    for (const auto& [node, feature] : by_node) {
      if (it == fv->end() || it->first != node) it = fv->emplace_hint(fv->end(), node, std::vector<int>());
      it->second.push_back(feature);
    }
  }
}

namespace {
/// Contribution of a word present in both vectors to the L1 score (DBoW2's form, min(a, b) for
/// non-negative weights); Score and BowDatabase::Query both use it so their results agree.
inline double SharedTerm(double a, double b) { return 0.5 * (std::fabs(a) + std::fabs(b) - std::fabs(a - b)); }
inline double ClampScore(double s) { return std::min(1.0, std::max(0.0, s)); }
}  // namespace

double BowVocabulary::Score(const BowVector& a, const BowVector& b) {
  double s = 0;
  auto ia = a.begin(), ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first < ib->first) {
      ia = a.lower_bound(ib->first);
    } else if (ib->first < ia->first) {
      ib = b.lower_bound(ia->first);
    } else {
      s += SharedTerm(ia->second, ib->second);
      ++ia;
      ++ib;
    }
  }
  return ClampScore(s);
}

void BowVocabulary::Save(const std::string& path) const {
  if (empty()) throw std::runtime_error("BowVocabulary::Save: " + path + ": the vocabulary is empty");
  std::string out;
  out.reserve(kHeaderBytes + nodes_.size() * kNodeBytes + words_.size() * kWordBytes + kFooterBytes);
  out.append(kMagic, sizeof(kMagic));
  PutU32(&out, kFormatVersion);
  PutU32(&out, static_cast<uint32_t>(branching_));
  PutU32(&out, static_cast<uint32_t>(levels_));
  PutU32(&out, static_cast<uint32_t>(nodes_.size()));
  PutU32(&out, static_cast<uint32_t>(words_.size()));
  for (size_t n = 0; n < nodes_.size(); ++n) {
    PutU32(&out, nodes_[n].parent);
    PutU32(&out, nodes_[n].first_child);
    PutU32(&out, nodes_[n].num_children);
    PutU32(&out, nodes_[n].word);
    char bytes[kDescriptorBytes];
    std::memcpy(bytes, centres_[n].data(), kDescriptorBytes);  // the descriptor's own byte order
    out.append(bytes, kDescriptorBytes);
  }
  for (double w : weights_) {
    uint64_t bits;
    std::memcpy(&bits, &w, sizeof(bits));
    PutU64(&out, bits);
  }
  PutU64(&out, Fnv1a64(out, out.size()));

  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error("BowVocabulary::Save: cannot open " + path + " for writing");
  f.write(out.data(), static_cast<std::streamsize>(out.size()));
  f.close();
  if (!f) throw std::runtime_error("BowVocabulary::Save: failed writing " + path);
}

BowVocabulary BowVocabulary::Load(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("BowVocabulary::Load: cannot open " + path);
  std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw std::runtime_error("BowVocabulary::Load: failed reading " + path);

  Reader in(path, bytes);
  char magic[sizeof(kMagic)];
  in.Bytes(magic, sizeof(magic), "the magic header");
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) in.Fail("bad magic: not a UNav-Sim vocabulary file");
  const uint32_t version = in.U32("the format version");
  if (version != kFormatVersion)
    in.Fail("unsupported format version " + std::to_string(version) + " (this build reads " +
            std::to_string(kFormatVersion) + ")");
  BowVocabulary voc;
  voc.branching_ = static_cast<int>(in.U32("branching"));
  voc.levels_ = static_cast<int>(in.U32("levels"));
  const uint32_t num_nodes = in.U32("the node count");
  const uint32_t num_words = in.U32("the word count");
  const uint64_t expected =
      kHeaderBytes + uint64_t{num_nodes} * kNodeBytes + uint64_t{num_words} * kWordBytes + kFooterBytes;
  if (bytes.size() < expected)
    in.Fail("truncated file: " + std::to_string(bytes.size()) + " bytes, the header announces " +
            std::to_string(num_nodes) + " nodes and " + std::to_string(num_words) + " words (" +
            std::to_string(expected) + " bytes)");
  if (bytes.size() > expected)
    in.Fail(std::to_string(bytes.size() - expected) + " unexpected bytes after the end of the vocabulary");
  const uint64_t checksum = Fnv1a64(bytes, bytes.size() - kFooterBytes);

  voc.nodes_.resize(num_nodes);
  voc.centres_.resize(num_nodes);
  for (uint32_t n = 0; n < num_nodes; ++n) {
    Node& node = voc.nodes_[n];
    node.parent = in.U32("a node");
    node.first_child = in.U32("a node");
    node.num_children = in.U32("a node");
    node.word = in.U32("a node");
    in.Bytes(voc.centres_[n].data(), kDescriptorBytes, "a node centre");
  }
  voc.weights_.resize(num_words);
  for (uint32_t w = 0; w < num_words; ++w) {
    const uint64_t bits = in.U64("a word weight");
    std::memcpy(&voc.weights_[w], &bits, sizeof(bits));
  }
  if (in.U64("the checksum") != checksum) in.Fail("checksum mismatch: the file is corrupt");
  try {
    voc.ValidateAndIndex();
  } catch (const std::runtime_error& e) {
    in.Fail(std::string("inconsistent vocabulary: ") + e.what());
  }
  return voc;
}

void BowVocabulary::ValidateAndIndex() {
  auto fail = [](const std::string& m) { throw std::runtime_error(m); };
  VocabularyOptions o;
  o.branching = branching_;
  o.levels = levels_;
  std::string msg;
  if (!o.IsValid(&msg)) fail(msg);
  if (nodes_.empty()) fail("no nodes");
  if (weights_.empty()) fail("no words");
  // Node ids and word ids are read from the file: check every index before it is used.
  std::vector<NodeId> words(weights_.size(), kNoWord);
  std::vector<uint32_t> depth(nodes_.size(), 0);
  std::vector<char> is_child(nodes_.size(), 0);
  for (NodeId n = 0; n < nodes_.size(); ++n) {
    const Node& node = nodes_[n];
    const std::string at = "node " + std::to_string(n) + ": ";
    if (n > 0 && !is_child[n]) fail(at + "not a child of its parent");
    if (node.num_children > 0) {
      if (node.word != kNoWord) fail(at + "inner node with a word");
      if (node.num_children > static_cast<uint32_t>(branching_)) fail(at + "more children than the branching");
      // Children come after their parent: this makes the tree acyclic and depth computable.
      if (node.first_child <= n || node.num_children > nodes_.size() ||
          node.first_child > nodes_.size() - node.num_children)
        fail(at + "children out of range");
      for (NodeId c = node.first_child; c < node.first_child + node.num_children; ++c) {
        if (nodes_[c].parent != n || is_child[c]) fail(at + "child " + std::to_string(c) + " has another parent");
        is_child[c] = 1;
        depth[c] = depth[n] + 1;
        if (depth[c] > static_cast<uint32_t>(levels_)) fail(at + "deeper than the levels");
      }
    } else {
      if (node.word >= words.size() || words[node.word] != kNoWord) fail(at + "leaf with a bad or repeated word id");
      words[node.word] = n;
    }
  }
  for (size_t w = 0; w < weights_.size(); ++w) {
    if (words[w] == kNoWord) fail("word " + std::to_string(w) + " has no leaf");
    if (!std::isfinite(weights_[w]) || weights_[w] < 0) fail("word " + std::to_string(w) + " has a bad weight");
  }
  words_ = std::move(words);
}

void BowDatabase::Add(int id, const BowVector& v) {
  Remove(id);
  for (const auto& [word, weight] : v) inverted_[word].emplace_back(id, weight);
  entries_[id] = v;
}

void BowDatabase::Remove(int id) {
  auto it = entries_.find(id);
  if (it == entries_.end()) return;
  for (const auto& entry : it->second) {
    auto list = inverted_.find(entry.first);
    if (list == inverted_.end()) continue;
    auto& l = list->second;
    l.erase(std::remove_if(l.begin(), l.end(), [id](const std::pair<int, double>& p) { return p.first == id; }),
            l.end());
    if (l.empty()) inverted_.erase(list);
  }
  entries_.erase(it);
}

std::vector<std::pair<int, double>> BowDatabase::Query(const BowVector& v, double min_score,
                                                       const std::set<int>& exclude, size_t max_results) const {
  // Words of v in increasing order, as in BowVocabulary::Score, so that the sums are identical.
  std::unordered_map<int, double> acc;
  for (const auto& [word, weight] : v) {
    auto list = inverted_.find(word);
    if (list == inverted_.end()) continue;
    for (const auto& [id, entry_weight] : list->second) acc[id] += SharedTerm(weight, entry_weight);
  }
  std::vector<std::pair<int, double>> out;
  out.reserve(acc.size());
  for (const auto& [id, s] : acc) {
    const double score = ClampScore(s);
    if (score >= min_score && !exclude.count(id)) out.emplace_back(id, score);
  }
  auto better = [](const std::pair<int, double>& a, const std::pair<int, double>& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  };
  if (out.size() > max_results) {
    std::partial_sort(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(max_results), out.end(), better);
    out.resize(max_results);
  } else {
    std::sort(out.begin(), out.end(), better);
  }
  return out;
}

}  // namespace unav::localization
