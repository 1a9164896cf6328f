// Bag of binary words for 256-bit ORB descriptors (after Galvez-Lopez & Tardos, "Bags of Binary
// Words for Fast Place Recognition in Image Sequences", T-RO 2012; our own implementation).
//
// A vocabulary tree is built by hierarchical k-majority clustering (k-medians in Hamming space:
// nearest centre by Hamming distance, centre = bitwise majority of its members, k-means++
// seeding). Its leaves are the words. An image's descriptors become a tf-idf weighted,
// L1-normalised word histogram (BowVector) that is compared with the L1 score; a BowDatabase is
// an inverted index over such vectors for loop-closure and relocalisation queries. A
// FeatureVector groups an image's features by a tree node above the leaves, so that descriptor
// matching between two images can be restricted to features under the same node.
//
// Descriptors: cv::Mat rows of 32 bytes (CV_8UC1, 32 columns), as cv::ORB computes them.
// Distances are Hamming distances in bits (0..256).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace unav::localization {

using WordId = uint32_t;
using NodeId = uint32_t;

/// Word -> tf-idf weight. Vectors made by BowVocabulary::Transform are L1-normalised (weights sum
/// to 1) and hold only words of positive weight.
struct BowVector : std::map<WordId, double> {};

/// Tree node -> indices (rows of the descriptor matrix given to Transform) of the features whose
/// path through the tree goes through that node. See BowVocabulary::Transform for which node.
struct FeatureVector : std::map<NodeId, std::vector<int>> {};

struct VocabularyOptions {
  int branching = 10;          ///< k: children per node, in [2, 64]
  int levels = 4;              ///< L: depth of the tree below the root, in [1, 10]; up to k^L words
  int kmeans_iterations = 10;  ///< maximum k-majority iterations per node, >= 1
  uint32_t seed = 1;           ///< seed of the k-means++ sampling; same seed, same vocabulary
  bool IsValid(std::string* msg) const;
};

class BowVocabulary {
 public:
  BowVocabulary() = default;

  /// Trains a vocabulary. descriptors_per_image: one cv::Mat per training image, rows are
  /// 32-byte ORB descriptors (CV_8UC1 with 32 columns; an image may have none). Each node's
  /// descriptors are split into at most k clusters (k-means++ seeding on squared Hamming
  /// distance, then up to kmeans_iterations rounds of nearest-centre assignment and bitwise
  /// majority centres, ties in both broken towards the lower bit value / lower index); a cluster
  /// becomes a leaf at depth L, or earlier when all of its descriptors are identical. After
  /// training every training descriptor descends to the leaf of the cluster it ended in.
  /// idf weight of each word: log(N / n), N = number of training images (those without
  /// descriptors included), n = how many of them have a descriptor that reaches the word.
  /// Throws std::invalid_argument for invalid options, no images, a descriptor matrix of the
  /// wrong type or width, or no descriptors at all.
  static BowVocabulary Train(const std::vector<cv::Mat>& descriptors_per_image, const VocabularyOptions& options);

  /// Writes a compact binary file (magic "UNAVBOW1", format version, tree, idf weights,
  /// checksum). Throws std::runtime_error naming the path when it cannot be written.
  void Save(const std::string& path) const;

  /// Reads a file written by Save. Throws std::runtime_error naming the path and what is wrong
  /// (cannot open, truncated, bad magic, unsupported version, inconsistent tree, bad checksum).
  static BowVocabulary Load(const std::string& path);

  bool empty() const { return words_.empty(); }
  /// Number of leaf words.
  size_t size() const { return words_.size(); }
  int branching() const { return branching_; }
  int levels() const { return levels_; }
  /// idf weight of a word (0 for a word found in every training image); 0 for an unknown id.
  double Weight(WordId word) const;

  /// The word of one descriptor: descends from the root to the nearest child (Hamming distance,
  /// first one on ties) until a leaf. descriptor_row: 1 x 32 CV_8UC1 (a row of a descriptor
  /// matrix). Throws std::invalid_argument for another shape or type, std::logic_error on an
  /// empty vocabulary.
  WordId Word(const cv::Mat& descriptor_row) const;

  /// bow: tf-idf vector of an image's descriptors (N x 32 CV_8UC1; empty gives an empty vector):
  /// each feature adds its word's idf weight, words of zero weight are left out, then the vector
  /// is L1-normalised. fv (optional): every feature's row index under the node at depth
  /// levels() - levels_up on its path (depth 0 is the root; levels_up >= levels() groups all
  /// features under the root 0; a path ending above that depth uses its leaf). With a full tree
  /// this is the ancestor levels_up levels above the leaf. fv also holds the features of
  /// zero-weight words. Throws like Word, and std::invalid_argument for levels_up < 0.
  void Transform(const cv::Mat& descriptors, BowVector* bow, FeatureVector* fv = nullptr, int levels_up = 2) const;

  /// DBoW2 L1 score of two L1-normalised vectors with non-negative weights:
  /// 1 - 0.5 * |a - b|_1 = sum over shared words of min(a_w, b_w), in [0, 1]; 1 for identical
  /// vectors, 0 when no word is shared (also when either is empty).
  static double Score(const BowVector& a, const BowVector& b);

 private:
  using Descriptor = std::array<uint64_t, 4>;  ///< the 32 bytes of a row, as 4 machine words
  struct Node {
    NodeId parent = 0;
    NodeId first_child = 0;  ///< children are stored contiguously: [first_child, +num_children)
    uint32_t num_children = 0;
    WordId word = kNoWord;  ///< leaf word id, kNoWord for inner nodes
  };
  static constexpr WordId kNoWord = 0xFFFFFFFFu;

  NodeId Descend(const Descriptor& d) const;
  /// Checks the tree read from a file and fills words_; throws std::runtime_error with the reason.
  void ValidateAndIndex();

  int branching_ = 0;
  int levels_ = 0;
  std::vector<Node> nodes_;          ///< nodes_[0] is the root
  std::vector<Descriptor> centres_;  ///< per node (the root's is unused)
  std::vector<NodeId> words_;        ///< word id -> leaf node
  std::vector<double> weights_;      ///< word id -> idf weight

  friend class BowVocabularyImpl;  // training and distance kernels (bow_vocabulary.cpp)
};

/// Inverted index of BowVectors (one per keyframe id) for retrieval.
class BowDatabase {
 public:
  /// Adds (or replaces) the vector of entry id.
  void Add(int id, const BowVector& v);
  /// Removes entry id; nothing happens for an unknown id.
  void Remove(int id);
  size_t size() const { return entries_.size(); }

  /// Entries sharing at least one word with v, with BowVocabulary::Score(v, entry), best first
  /// (equal scores: lower id first), only those with score >= min_score and not in exclude, at
  /// most max_results of them.
  std::vector<std::pair<int, double>> Query(const BowVector& v, double min_score, const std::set<int>& exclude = {},
                                            size_t max_results = 50) const;

 private:
  std::unordered_map<WordId, std::vector<std::pair<int, double>>> inverted_;  ///< word -> (id, weight)
  std::unordered_map<int, BowVector> entries_;
};

}  // namespace unav::localization
