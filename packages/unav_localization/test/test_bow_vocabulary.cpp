// Tests of the bag-of-binary-words vocabulary and database (no DDS, no renderer): synthetic
// descriptors with known structure, and ORB features of synthetic textures.
#include "unav_localization/bow_vocabulary.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include "unav_common/thrown.hpp"

namespace ul = unav::localization;
namespace fs = std::filesystem;

namespace {

cv::Mat RandomDescriptors(int n, std::mt19937& rng) {
  cv::Mat d(n, 32, CV_8UC1);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < 32; ++c) d.at<uint8_t>(r, c) = static_cast<uint8_t>(byte(rng));
  return d;
}

/// Copy of `row` (1 x 32) with exactly `bits` distinct bits flipped, chosen among `allowed`
/// bit positions (all 256 when empty).
cv::Mat Flip(const cv::Mat& row, int bits, std::mt19937& rng, std::vector<int> allowed = {}) {
  if (allowed.empty())
    for (int b = 0; b < 256; ++b) allowed.push_back(b);
  std::shuffle(allowed.begin(), allowed.end(), rng);
  cv::Mat out = row.clone();
  for (int i = 0; i < bits; ++i) out.at<uint8_t>(0, allowed[i] / 8) ^= static_cast<uint8_t>(1u << (allowed[i] % 8));
  return out;
}

cv::Mat FlipAll(const cv::Mat& d, int bits, std::mt19937& rng) {
  cv::Mat out(d.rows, 32, CV_8UC1);
  for (int r = 0; r < d.rows; ++r) Flip(d.row(r), bits, rng).copyTo(out.row(r));
  return out;
}

double L1(const ul::BowVector& v) {
  double s = 0;
  for (const auto& e : v) s += e.second;
  return s;
}

/// Uniform noise blurred with a Gaussian (sigma 2 px) and stretched to 0..255: a texture with
/// plenty of corners at ORB's scales and nothing in common between seeds.
cv::Mat Texture(uint64_t seed, cv::Size size = {480, 360}) {
  cv::RNG rng(seed);
  cv::Mat noise(size, CV_8UC1);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::Mat blurred;
  cv::GaussianBlur(noise, blurred, cv::Size(0, 0), 2.0);
  cv::normalize(blurred, blurred, 0, 255, cv::NORM_MINMAX);
  return blurred;
}

cv::Mat Orb(const cv::Mat& gray, int features = 500) {
  auto orb = cv::ORB::create(features, 1.2f, 8);
  std::vector<cv::KeyPoint> kps;
  cv::Mat d;
  orb->detectAndCompute(gray, cv::noArray(), kps, d);
  return d;
}

struct TempDir {
  fs::path path;
  TempDir() {
    path =
        fs::temp_directory_path() / ("bow_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                     "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string ReadAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}
void WriteAll(const fs::path& p, const std::string& s) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(s.data(), static_cast<std::streamsize>(s.size()));
}

/// A small vocabulary on random descriptors, shared by tests that only need some vocabulary.
ul::BowVocabulary RandomVocabulary(std::vector<cv::Mat>* images = nullptr) {
  std::mt19937 rng(7);
  std::vector<cv::Mat> imgs;
  imgs.reserve(20);
  for (int i = 0; i < 20; ++i) imgs.push_back(RandomDescriptors(200, rng));
  ul::VocabularyOptions o;
  o.branching = 6;
  o.levels = 3;
  if (images) *images = imgs;
  return ul::BowVocabulary::Train(imgs, o);
}

}  // namespace

TEST(BowVocabulary, OptionsAndBadInput) {
  std::string msg;
  EXPECT_TRUE(ul::VocabularyOptions{}.IsValid(&msg)) << msg;
  ul::VocabularyOptions o;
  o.branching = 1;
  EXPECT_FALSE(o.IsValid(&msg));
  EXPECT_NE(msg.find("branching"), std::string::npos) << msg;
  o = {};
  o.levels = 0;
  EXPECT_FALSE(o.IsValid(&msg));
  o = {};
  o.branching = 64;
  o.levels = 6;  // 2^36 words would not fit 32-bit ids
  EXPECT_FALSE(o.IsValid(&msg));
  EXPECT_THROW(ul::BowVocabulary::Train({}, ul::VocabularyOptions{}), std::invalid_argument);
  EXPECT_THROW(ul::BowVocabulary::Train({cv::Mat()}, ul::VocabularyOptions{}), std::invalid_argument);
  EXPECT_THROW(ul::BowVocabulary::Train({cv::Mat(5, 32, CV_32FC1, cv::Scalar(0))}, ul::VocabularyOptions{}),
               std::invalid_argument);
  EXPECT_THROW(ul::BowVocabulary::Train({cv::Mat(5, 31, CV_8UC1, cv::Scalar(0))}, ul::VocabularyOptions{}),
               std::invalid_argument);

  ul::BowVocabulary empty;
  EXPECT_TRUE(empty.empty());
  EXPECT_EQ(empty.size(), 0u);
  EXPECT_THROW(empty.Word(cv::Mat(1, 32, CV_8UC1, cv::Scalar(0))), std::logic_error);
  const ul::BowVocabulary voc = RandomVocabulary();
  EXPECT_THROW(voc.Word(cv::Mat(2, 32, CV_8UC1, cv::Scalar(0))), std::invalid_argument);
  ul::BowVector v;
  EXPECT_THROW(voc.Transform(cv::Mat(2, 16, CV_8UC1, cv::Scalar(0)), &v), std::invalid_argument);
  voc.Transform(cv::Mat(), &v);
  EXPECT_TRUE(v.empty());
}

// Degenerate training sets: identical descriptors make one word (the root is the leaf); fewer
// distinct descriptors than k make one word each.
TEST(BowVocabulary, DegenerateTrainingSets) {
  std::mt19937 rng(2);
  const cv::Mat one = RandomDescriptors(1, rng);
  cv::Mat same;
  for (int i = 0; i < 50; ++i) same.push_back(one);
  ul::BowVocabulary voc = ul::BowVocabulary::Train({same, same}, ul::VocabularyOptions{});
  ASSERT_EQ(voc.size(), 1u);
  EXPECT_EQ(voc.Word(RandomDescriptors(1, rng)), 0u);
  EXPECT_EQ(voc.Weight(0), 0.0);  // in both images: log(2 / 2)
  ul::BowVector v;
  ul::FeatureVector fv;
  voc.Transform(same, &v, &fv);
  EXPECT_TRUE(v.empty());  // the only word has zero weight
  ASSERT_EQ(fv.size(), 1u);
  EXPECT_EQ(fv.at(0).size(), 50u);

  const cv::Mat three = RandomDescriptors(3, rng);
  voc = ul::BowVocabulary::Train({three, three.row(0)}, ul::VocabularyOptions{});
  ASSERT_EQ(voc.size(), 3u);
  std::set<ul::WordId> words;
  for (int r = 0; r < 3; ++r) words.insert(voc.Word(three.row(r)));
  EXPECT_EQ(words.size(), 3u);
  EXPECT_EQ(voc.Weight(voc.Word(three.row(0))), 0.0);                   // in both images
  EXPECT_DOUBLE_EQ(voc.Weight(voc.Word(three.row(1))), std::log(2.0));  // in one of two
}

// Five random centres (pairwise ~128 bits apart) and 200 descriptors within 8 bits of each: with
// k = 5 and one level, each cluster must become one word, the word of its centre. Noise of 8 bits
// is far below the half-distance between centres (~64 bits), so nearest-centre assignment is
// unambiguous; the bitwise majority of 200 copies with 8/256 of the bits flipped recovers the
// centre exactly (a bit would need 100 of 200 flips at p = 1/32).
TEST(BowVocabulary, FlatTrainingRecoversKnownCentres) {
  std::mt19937 rng(11);
  const cv::Mat centres = RandomDescriptors(5, rng);
  std::vector<cv::Mat> images(10);
  std::vector<std::vector<int>> centre_of(10);
  for (int c = 0; c < 5; ++c)
    for (int j = 0; j < 200; ++j) {
      const int img = j % 10;
      images[img].push_back(Flip(centres.row(c), 8, rng));
      centre_of[img].push_back(c);
    }
  ul::VocabularyOptions o;
  o.branching = 5;
  o.levels = 1;
  const ul::BowVocabulary voc = ul::BowVocabulary::Train(images, o);
  ASSERT_EQ(voc.size(), 5u);
  std::set<ul::WordId> centre_words;
  for (int c = 0; c < 5; ++c) centre_words.insert(voc.Word(centres.row(c)));
  EXPECT_EQ(centre_words.size(), 5u);
  for (int i = 0; i < 10; ++i)
    for (int r = 0; r < images[i].rows; ++r)
      ASSERT_EQ(voc.Word(images[i].row(r)), voc.Word(centres.row(centre_of[i][r]))) << "image " << i << " row " << r;
  // Every word occurs in every image: idf = log(10/10) = 0, so no word carries weight.
  for (ul::WordId w = 0; w < voc.size(); ++w) EXPECT_EQ(voc.Weight(w), 0.0);
}

// Two-level structure: 3 random group centres; each has 3 sub-centres that flip 20 bits of the
// group centre in disjoint bit ranges (so sub-centres of a group are 40 bits apart, groups ~128);
// 60 descriptors per sub-centre within 3 bits. With k = 3, L = 2 every descriptor must reach the
// word of its sub-centre, the 9 sub-centres 9 different words. Level 1 separates groups (128 vs
// <= 23 bits from a group's majority, which is the group centre because each bit is flipped in at
// most a third of its members); level 2 separates sub-centres (40 vs 3 bits).
TEST(BowVocabulary, HierarchicalTrainingRecoversKnownCentres) {
  std::mt19937 rng(5);
  const cv::Mat groups = RandomDescriptors(3, rng);
  std::vector<cv::Mat> subs;
  for (int g = 0; g < 3; ++g) {
    std::vector<int> bits(256);
    std::iota(bits.begin(), bits.end(), 0);
    std::shuffle(bits.begin(), bits.end(), rng);
    for (int s = 0; s < 3; ++s)
      subs.push_back(
          Flip(groups.row(g), 20, rng,
               std::vector<int>(bits.begin() + std::ptrdiff_t{20} * s, bits.begin() + std::ptrdiff_t{20} * s + 20)));
  }
  std::vector<cv::Mat> images(6);
  std::vector<std::vector<int>> sub_of(6);
  for (int s = 0; s < 9; ++s)
    for (int j = 0; j < 60; ++j) {
      images[j % 6].push_back(Flip(subs[s], 3, rng));
      sub_of[j % 6].push_back(s);
    }
  ul::VocabularyOptions o;
  o.branching = 3;
  o.levels = 2;
  const ul::BowVocabulary voc = ul::BowVocabulary::Train(images, o);
  ASSERT_EQ(voc.size(), 9u);
  std::set<ul::WordId> words;
  for (const cv::Mat& s : subs) words.insert(voc.Word(s));
  EXPECT_EQ(words.size(), 9u);
  for (int i = 0; i < 6; ++i)
    for (int r = 0; r < images[i].rows; ++r) ASSERT_EQ(voc.Word(images[i].row(r)), voc.Word(subs[sub_of[i][r]]));

  // The feature vector groups by the node levels_up = 1 above the leaves, i.e. the group: the
  // 9 sub-centres fall into 3 nodes of 3.
  cv::Mat all_subs;
  for (const cv::Mat& s : subs) all_subs.push_back(s);
  ul::BowVector bow;
  ul::FeatureVector fv;
  voc.Transform(all_subs, &bow, &fv, 1);
  ASSERT_EQ(fv.size(), 3u);
  for (const auto& [node, feats] : fv) {
    ASSERT_EQ(feats.size(), 3u);
    EXPECT_EQ(feats[0] / 3, feats[2] / 3) << "features of node " << node << " come from different groups";
  }
  voc.Transform(all_subs, &bow, &fv, 0);  // levels_up = 0: one node per word
  EXPECT_EQ(fv.size(), 9u);
  voc.Transform(all_subs, &bow, &fv, 5);  // above the root: everything under the root (node 0)
  ASSERT_EQ(fv.size(), 1u);
  EXPECT_EQ(fv.begin()->first, 0u);
  EXPECT_EQ(fv.begin()->second.size(), 9u);
}

TEST(BowVocabulary, TransformIsL1NormalisedTfIdf) {
  std::vector<cv::Mat> images;
  const ul::BowVocabulary voc = RandomVocabulary(&images);
  ASSERT_GT(voc.size(), 50u);
  for (int i = 0; i < 3; ++i) {
    ul::BowVector v;
    ul::FeatureVector fv;
    voc.Transform(images[i], &v, &fv);
    ASSERT_FALSE(v.empty());
    // Sum of a few hundred doubles each ~1e-2: rounding is ~1e-16 per addition.
    EXPECT_NEAR(L1(v), 1.0, 1e-12);
    for (const auto& e : v) EXPECT_GT(e.second, 0.0);
    // Weight of a word = count * idf / sum over the image, recomputed here.
    std::map<ul::WordId, int> count;
    double total = 0;
    for (int r = 0; r < images[i].rows; ++r) {
      const ul::WordId w = voc.Word(images[i].row(r));
      if (voc.Weight(w) > 0) {
        ++count[w];
        total += voc.Weight(w);
      }
    }
    ASSERT_EQ(count.size(), v.size());
    for (const auto& [w, c] : count) EXPECT_NEAR(v.at(w), c * voc.Weight(w) / total, 1e-12);
    // The feature vector holds every feature exactly once.
    std::vector<int> seen;
    for (const auto& e : fv) seen.insert(seen.end(), e.second.begin(), e.second.end());
    std::sort(seen.begin(), seen.end());
    ASSERT_EQ(static_cast<int>(seen.size()), images[i].rows);
    for (int r = 0; r < images[i].rows; ++r) EXPECT_EQ(seen[r], r);
  }
  // idf = log(20 / n_w) with 1 <= n_w <= 20 training images.
  for (ul::WordId w = 0; w < voc.size(); ++w) {
    EXPECT_GE(voc.Weight(w), 0.0);
    EXPECT_LE(voc.Weight(w), std::log(20.0) + 1e-12);
  }
}

TEST(BowVocabulary, Score) {
  ul::BowVector a, b, c;
  a[1] = 0.5;
  a[2] = 0.5;
  b[2] = 0.25;
  b[3] = 0.75;
  c[7] = 1.0;
  EXPECT_DOUBLE_EQ(ul::BowVocabulary::Score(a, a), 1.0);
  // 1 - 0.5 * (|0.5 - 0| + |0.5 - 0.25| + |0 - 0.75|) = 1 - 0.5 * 1.5 = 0.25
  EXPECT_DOUBLE_EQ(ul::BowVocabulary::Score(a, b), 0.25);
  EXPECT_DOUBLE_EQ(ul::BowVocabulary::Score(b, a), 0.25);
  EXPECT_EQ(ul::BowVocabulary::Score(a, c), 0.0);
  EXPECT_EQ(ul::BowVocabulary::Score(a, ul::BowVector{}), 0.0);

  std::vector<cv::Mat> images;
  const ul::BowVocabulary voc = RandomVocabulary(&images);
  ul::BowVector v;
  voc.Transform(images[0], &v);
  EXPECT_NEAR(ul::BowVocabulary::Score(v, v), 1.0, 1e-12);  // sum of the weights: L1 rounding
}

// An image's descriptors with 10% of their bits flipped (26 of 256) against its original and
// against other images. Descriptors come from a structured space, as ORB's do: 100 landmark
// classes (random centres, ~128 bits apart), each image seeing 30 of them with 8 descriptors each
// drawn within 10 bits of the class centre. Vocabulary k = 10, L = 2 (about one word per class)
// trained on 40 such images. The noisy copy stays within 36 bits of its class centre, far from
// the ~128 bits to the others, so it keeps its words: expected score ~1 (0.9 allows a few
// descriptors to land in a neighbouring word of a split class). Another image shares on average
// 30 * 30 / 100 = 9 of its 30 classes, an expected score of ~0.3 (up to ~0.5 for the luckiest of
// 39 others); the test asks for a margin of 0.3.
TEST(BowVocabulary, NoisyCopyScoresHighestAgainstItsOriginal) {
  std::mt19937 rng(3);
  const cv::Mat classes = RandomDescriptors(100, rng);
  std::vector<int> ids(100);
  std::iota(ids.begin(), ids.end(), 0);
  std::vector<cv::Mat> images(40);
  for (cv::Mat& img : images) {
    std::shuffle(ids.begin(), ids.end(), rng);
    for (int c = 0; c < 30; ++c)
      for (int j = 0; j < 8; ++j) img.push_back(Flip(classes.row(ids[c]), 10, rng));
  }
  ul::VocabularyOptions o;
  o.levels = 2;
  const ul::BowVocabulary voc = ul::BowVocabulary::Train(images, o);
  std::vector<ul::BowVector> bows(images.size());
  for (size_t i = 0; i < images.size(); ++i) voc.Transform(images[i], &bows[i]);
  for (int i = 0; i < 5; ++i) {
    ul::BowVector noisy;
    voc.Transform(FlipAll(images[i], 26, rng), &noisy);
    const double own = ul::BowVocabulary::Score(noisy, bows[i]);
    double best_other = 0;
    for (size_t j = 0; j < images.size(); ++j)
      if (static_cast<int>(j) != i) best_other = std::max(best_other, ul::BowVocabulary::Score(noisy, bows[j]));
    std::printf("image %d: score vs original %.3f, best other %.3f\n", i, own, best_other);
    EXPECT_GT(own, 0.9);
    EXPECT_GT(own - best_other, 0.3);
  }
}

TEST(BowVocabulary, SaveLoadRoundTrip) {
  TempDir dir;
  const ul::BowVocabulary voc = RandomVocabulary();
  const fs::path file = dir.path / "voc.bin";
  voc.Save(file.string());
  const ul::BowVocabulary loaded = ul::BowVocabulary::Load(file.string());
  ASSERT_EQ(loaded.size(), voc.size());
  EXPECT_EQ(loaded.branching(), voc.branching());
  EXPECT_EQ(loaded.levels(), voc.levels());
  for (ul::WordId w = 0; w < voc.size(); ++w) EXPECT_EQ(loaded.Weight(w), voc.Weight(w));  // bit-exact doubles
  std::mt19937 rng(99);
  const cv::Mat probe = RandomDescriptors(1000, rng);
  for (int r = 0; r < probe.rows; ++r) ASSERT_EQ(loaded.Word(probe.row(r)), voc.Word(probe.row(r)));
  ul::BowVector a, b;
  ul::FeatureVector fa, fb;
  voc.Transform(probe, &a, &fa);
  loaded.Transform(probe, &b, &fb);
  EXPECT_EQ(a, b);
  EXPECT_EQ(fa, fb);
  // Header 28 bytes + 48 per node + 8 per word + 8 checksum: a compact format.
  EXPECT_LT(fs::file_size(file), 28 + 48 * (voc.size() * 7 / 5 + 1) + 8 * voc.size() + 8);
}

TEST(BowVocabulary, LoadRejectsBadFiles) {
  TempDir dir;
  const ul::BowVocabulary voc = RandomVocabulary();
  const fs::path good = dir.path / "good.bin";
  voc.Save(good.string());
  const std::string bytes = ReadAll(good);

  const fs::path missing = dir.path / "missing.bin";
  std::string m = unav::common::thrown_message<std::runtime_error>([&] { ul::BowVocabulary::Load(missing.string()); });
  EXPECT_NE(m.find(missing.string()), std::string::npos) << m;

  const fs::path truncated = dir.path / "truncated.bin";
  for (size_t keep : {size_t{0}, size_t{5}, size_t{20}, bytes.size() / 2, bytes.size() - 1}) {
    WriteAll(truncated, bytes.substr(0, keep));
    m = unav::common::thrown_message<std::runtime_error>([&] { ul::BowVocabulary::Load(truncated.string()); });
    EXPECT_NE(m.find(truncated.string()), std::string::npos) << m;
    EXPECT_NE(m.find("truncated"), std::string::npos) << "keep " << keep << ": " << m;
  }

  const fs::path magic = dir.path / "magic.bin";
  std::string bad = bytes;
  bad[0] = 'X';
  WriteAll(magic, bad);
  m = unav::common::thrown_message<std::runtime_error>([&] { ul::BowVocabulary::Load(magic.string()); });
  EXPECT_NE(m.find(magic.string()), std::string::npos) << m;
  EXPECT_NE(m.find("magic"), std::string::npos) << m;

  const fs::path version = dir.path / "version.bin";
  bad = bytes;
  bad[8] = 9;
  WriteAll(version, bad);
  m = unav::common::thrown_message<std::runtime_error>([&] { ul::BowVocabulary::Load(version.string()); });
  EXPECT_NE(m.find("version 9"), std::string::npos) << m;

  const fs::path corrupt = dir.path / "corrupt.bin";
  bad = bytes;
  bad[bytes.size() / 2] ^= 0x10;
  WriteAll(corrupt, bad);
  m = unav::common::thrown_message<std::runtime_error>([&] { ul::BowVocabulary::Load(corrupt.string()); });
  EXPECT_NE(m.find(corrupt.string()), std::string::npos) << m;
  EXPECT_NE(m.find("checksum"), std::string::npos) << m;

  // A well-formed file (right checksum) with an impossible tree: node 0 (at byte 28: parent,
  // first child, child count, word) claiming 2^32 - 1 children, or children before itself.
  auto with_checksum = [](std::string b) {
    uint64_t h = 1469598103934665603ull;  // FNV-1a 64, as the format specifies
    for (size_t i = 0; i + 8 < b.size(); ++i) {
      h ^= static_cast<uint8_t>(b[i]);
      h *= 1099511628211ull;
    }
    for (int i = 0; i < 8; ++i) b[b.size() - 8 + i] = static_cast<char>((h >> (8 * i)) & 0xFF);
    return b;
  };
  const fs::path inconsistent = dir.path / "inconsistent.bin";
  WriteAll(inconsistent, with_checksum(bytes));  // unchanged tree: loads
  EXPECT_EQ(ul::BowVocabulary::Load(inconsistent.string()).size(), voc.size());
  for (int field : {1, 2}) {
    bad = bytes;
    for (int i = 0; i < 4; ++i) bad[28 + 4 * field + i] = field == 2 ? '\xff' : '\0';
    WriteAll(inconsistent, with_checksum(bad));
    m = unav::common::thrown_message<std::runtime_error>([&] { ul::BowVocabulary::Load(inconsistent.string()); });
    EXPECT_NE(m.find(inconsistent.string()), std::string::npos) << m;
    EXPECT_NE(m.find("inconsistent"), std::string::npos) << m;
  }

  const fs::path longer = dir.path / "longer.bin";
  WriteAll(longer, bytes + "x");
  m = unav::common::thrown_message<std::runtime_error>([&] { ul::BowVocabulary::Load(longer.string()); });
  EXPECT_NE(m.find("unexpected bytes"), std::string::npos) << m;

  m = unav::common::thrown_message<std::runtime_error>(
      [&] { ul::BowVocabulary().Save((dir.path / "empty.bin").string()); });
  EXPECT_NE(m.find("empty.bin"), std::string::npos) << m;
  m = unav::common::thrown_message<std::runtime_error>(
      [&] { voc.Save((dir.path / "no_such_dir" / "v.bin").string()); });
  EXPECT_NE(m.find("no_such_dir"), std::string::npos) << m;
}

TEST(BowDatabase, QueryReturnsTheRightEntryFirst) {
  std::vector<cv::Mat> images;
  const ul::BowVocabulary voc = RandomVocabulary(&images);
  ul::BowDatabase db;
  std::vector<ul::BowVector> bows(10);
  for (int i = 0; i < 10; ++i) {
    voc.Transform(images[i], &bows[i]);
    db.Add(100 + i, bows[i]);
  }
  EXPECT_EQ(db.size(), 10u);
  // Query with a subset (half the features) of image 3: it shares all its words with entry 103.
  ul::BowVector q;
  voc.Transform(images[3].rowRange(0, 100), &q);
  auto res = db.Query(q, 0.0);
  ASSERT_FALSE(res.empty());
  EXPECT_EQ(res[0].first, 103);
  for (size_t i = 0; i < res.size(); ++i) {
    // Same summation order as Score: identical doubles.
    EXPECT_EQ(res[i].second, ul::BowVocabulary::Score(q, bows[res[i].first - 100]));
    if (i > 0) {
      EXPECT_GE(res[i - 1].second, res[i].second);
    }
  }
  ASSERT_GE(res.size(), 2u);
  EXPECT_GT(res[0].second, 1.5 * res[1].second);

  res = db.Query(q, 0.0, {103});
  for (const auto& r : res) EXPECT_NE(r.first, 103);
  res = db.Query(q, 0.0, {}, 2);
  EXPECT_EQ(res.size(), 2u);
  const double s1 = db.Query(q, 0.0)[1].second;
  res = db.Query(q, s1 + 1e-9);
  ASSERT_EQ(res.size(), 1u);
  EXPECT_EQ(res[0].first, 103);

  db.Remove(103);
  db.Remove(12345);  // unknown: no effect
  EXPECT_EQ(db.size(), 9u);
  for (const auto& r : db.Query(q, 0.0)) EXPECT_NE(r.first, 103);
  db.Add(105, bows[3]);  // replaces entry 105
  EXPECT_EQ(db.size(), 9u);
  res = db.Query(q, 0.0);
  ASSERT_FALSE(res.empty());
  EXPECT_EQ(res[0].first, 105);
  EXPECT_TRUE(db.Query(ul::BowVector{}, 0.0).empty());
}

// ORB features of blurred-noise textures: train a default vocabulary (k = 10, L = 4) on 8
// textures, then relocalise a rotated (8 degrees), shifted and 5% scaled view of textures 0 and 5
// against a database of all 8. The textures have the same statistics, so unrelated ones still
// share words (scores ~0.1 seen); the right one shares the features that survive the warp
// (~0.35 seen). Asking for twice the runner-up leaves room for other ORB/OpenCV versions.
TEST(BowVocabulary, RealOrbFeaturesRelocalise) {
  std::vector<cv::Mat> textures, descriptors;
  for (int i = 0; i < 8; ++i) {
    textures.push_back(Texture(1000 + i));
    descriptors.push_back(Orb(textures.back()));
    ASSERT_GT(descriptors.back().rows, 400);
  }
  const ul::BowVocabulary voc = ul::BowVocabulary::Train(descriptors, ul::VocabularyOptions{});
  // ~4000 descriptors for up to 10^4 leaves: most leaves hold one or a few descriptors.
  EXPECT_GT(voc.size(), 2000u);
  EXPECT_LE(voc.size(), 10000u);
  ul::BowDatabase db;
  for (int i = 0; i < 8; ++i) {
    ul::BowVector v;
    voc.Transform(descriptors[i], &v);
    EXPECT_NEAR(L1(v), 1.0, 1e-12);
    db.Add(i, v);
  }
  for (int target : {0, 5}) {
    const cv::Mat& t = textures[target];
    cv::Mat warp = cv::getRotationMatrix2D(cv::Point2f(t.cols / 2.f, t.rows / 2.f), 8.0, 1.05);
    warp.at<double>(0, 2) += 12;
    warp.at<double>(1, 2) -= 7;
    cv::Mat view;
    cv::warpAffine(t, view, warp, t.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
    ul::BowVector q;
    voc.Transform(Orb(view), &q);
    const auto res = db.Query(q, 0.0);
    ASSERT_GE(res.size(), 2u);
    std::printf("relocalise %d: best %d (%.3f), second %d (%.3f)\n", target, res[0].first, res[0].second, res[1].first,
                res[1].second);
    EXPECT_EQ(res[0].first, target);
    EXPECT_GT(res[0].second, 2.0 * res[1].second);
  }
}

// Word() on 1000 descriptors with a k = 10, L = 4 vocabulary: every descriptor gets a valid word.
// The time is printed for the record only (a shared machine times nothing reliably; the speed
// figures come from bench_mono_slam).
TEST(BowVocabulary, WordTiming) {
  std::mt19937 rng(17);
  std::vector<cv::Mat> images;
  images.reserve(50);
  for (int i = 0; i < 50; ++i) images.push_back(RandomDescriptors(400, rng));
  const auto t0 = std::chrono::steady_clock::now();
  const ul::BowVocabulary voc = ul::BowVocabulary::Train(images, ul::VocabularyOptions{});
  const double train_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const cv::Mat probe = RandomDescriptors(1000, rng);
  double best_ms = 1e9;
  uint64_t sink = 0;
  for (int rep = 0; rep < 20; ++rep) {
    const auto t1 = std::chrono::steady_clock::now();
    for (int r = 0; r < probe.rows; ++r) {
      const auto w = voc.Word(probe.row(r));
      ASSERT_LT(static_cast<std::size_t>(w), voc.size());
      sink += static_cast<uint64_t>(w);
    }
    best_ms =
        std::min(best_ms, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count());
  }
  std::printf("train 20000 descriptors: %.3f s, %zu words; Word() x1000: %.3f ms (sink %llu)\n", train_s, voc.size(),
              best_ms, static_cast<unsigned long long>(sink));
  RecordProperty("word_x1000_us", static_cast<int>(best_ms * 1000));
}
