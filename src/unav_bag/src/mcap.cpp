// MCAP (https://mcap.dev/spec, version 0) writer and reader, ROS 2 profile: schemas are ros2msg
// text, messages cdr, channel metadata carries `offered_qos_profiles` as rosbag2_storage_mcap
// writes it. The writer puts messages into chunks (uncompressed or zstd) with message indexes,
// and ends with a summary (schemas, channels, statistics, chunk indexes), summary offsets and a
// footer, so indexed readers (rosbags, mcap, Foxglove) open it without scanning.
#include <zlib.h>
#include <zstd.h>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>

#include "storage.hpp"

namespace unav::bag {
namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
enum Op : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Little-endian record building.
struct Buf {
  std::string b;
  void u8(uint8_t v) { b.push_back(static_cast<char>(v)); }
  void u16(uint16_t v) { raw(&v, 2); }
  void u32(uint32_t v) { raw(&v, 4); }
  void u64(uint64_t v) { raw(&v, 8); }
  void raw(const void* p, size_t n) { b.append(static_cast<const char*>(p), n); }
  void str(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    b += s;
  }
  void string_map(const std::map<std::string, std::string>& m) {
    Buf body;
    for (const auto& [k, v] : m) {
      body.str(k);
      body.str(v);
    }
    u32(static_cast<uint32_t>(body.b.size()));
    b += body.b;
  }
};

void append_record(std::string& out, uint8_t op, const std::string& content) {
  Buf r;
  r.u8(op);
  r.u64(content.size());
  out += r.b;
  out += content;
}

static_assert(sizeof(uint64_t) == 8 && sizeof(uint16_t) == 2, "little-endian 64-bit host expected");

class McapStorage final : public BagWriter::Storage {
 public:
  McapStorage(const std::string& path, const BagWriter::Options& options) : path_(path), options_(options) {
    f_ = std::fopen(path.c_str(), "wb");
    if (!f_) throw BagError(path + ": cannot create: " + std::strerror(errno));
    std::string head(reinterpret_cast<const char*>(kMagic), sizeof(kMagic));
    Buf h;
    h.str("ros2");
    h.str("unav-sim unav_bag");
    append_record(head, kHeader, h.b);
    emit(head);
    if (std::fflush(f_) != 0) fail("write");
    good_offset_ = offset_;
  }
  ~McapStorage() override {
    if (f_) std::fclose(f_);
  }

  void add_topic(size_t index, const TopicMetadata& topic) override {
    // One schema per type, one channel per topic; ids start at 1 (schema 0 means "none").
    uint16_t schema_id = 0;
    const auto it = schema_ids_.find(topic.type);
    if (it != schema_ids_.end()) {
      schema_id = it->second;
    } else {
      schema_id = static_cast<uint16_t>(schema_ids_.size() + 1);
      schema_ids_[topic.type] = schema_id;
      Buf s;
      s.u16(schema_id);
      s.str(topic.type);
      s.str(topic.message_definition.empty() ? "" : "ros2msg");
      s.str(topic.message_definition);
      schema_records_.push_back(s.b);
      append_record(chunk_, kSchema, s.b);
    }
    Buf c;
    const auto channel_id = static_cast<uint16_t>(index + 1);
    c.u16(channel_id);
    c.u16(schema_id);
    c.str(topic.name);
    c.str(topic.serialization_format);
    c.string_map({{"offered_qos_profiles", topic.offered_qos_profiles}});
    channel_records_.push_back(c.b);
    append_record(chunk_, kChannel, c.b);
    channel_counts_[channel_id];  // present in statistics even with no message
  }

  void write(size_t topic, int64_t timestamp_ns, const uint8_t* data, size_t size) override {
    if (broken_) throw BagError(path_ + ": not written: an earlier write failed");
    const auto channel_id = static_cast<uint16_t>(topic + 1);
    const auto t = static_cast<uint64_t>(timestamp_ns);
    chunk_index_[channel_id].emplace_back(t, chunk_.size());
    Buf m;
    m.u8(kMessage);
    m.u64(2 + 4 + 8 + 8 + size);
    m.u16(channel_id);
    m.u32(++sequence_[channel_id]);
    m.u64(t);  // log time
    m.u64(t);  // publish time (rosbag2 stores the receive time in both)
    chunk_ += m.b;
    chunk_.append(reinterpret_cast<const char*>(data), size);
    if (chunk_messages_++ == 0) {
      chunk_start_ = chunk_end_ = t;
    } else {
      chunk_start_ = std::min(chunk_start_, t);
      chunk_end_ = std::max(chunk_end_, t);
    }
    if (message_count_++ == 0) {
      start_ = end_ = t;
    } else {
      start_ = std::min(start_, t);
      end_ = std::max(end_, t);
    }
    ++channel_counts_[channel_id];
    if (chunk_.size() >= options_.chunk_size) flush_chunk();
  }

  void close(const std::string& /*metadata_yaml*/) override {
    if (broken_) {
      // write() failed earlier (disk full): the file was cut back to its last complete chunk and
      // closed with a data end + footer. No metadata.yaml: its counts would include lost messages.
      throw BagError(path_ + ": the bag ends after its last complete chunk (byte " + std::to_string(good_offset_) +
                     ", " + std::to_string(persisted_messages_) +
                     " messages); no metadata.yaml (readers scan the file)");
    }
    if (!f_) return;
    flush_chunk();
    // Data end: CRC of every byte of the data section.
    Buf de;
    de.u32(data_crc_);
    std::string tail;
    append_record(tail, kDataEnd, de.b);
    emit(tail);

    // Summary: schema, channel, statistics and chunk index groups, then their offsets.
    const uint64_t summary_start = offset_;
    std::string summary;
    struct Group {
      uint8_t op;
      uint64_t start, length;
    };
    std::vector<Group> groups;
    auto group = [&](uint8_t op, const std::vector<std::string>& records) {
      if (records.empty()) return;
      const uint64_t start = summary_start + summary.size();
      for (const auto& r : records) append_record(summary, op, r);
      groups.push_back({op, start, summary_start + summary.size() - start});
    };
    group(kSchema, schema_records_);
    group(kChannel, channel_records_);
    Buf st;
    st.u64(message_count_);
    st.u16(static_cast<uint16_t>(schema_records_.size()));
    st.u32(static_cast<uint32_t>(channel_records_.size()));
    st.u32(0);  // attachments
    st.u32(0);  // metadata records
    st.u32(static_cast<uint32_t>(chunk_index_records_.size()));
    st.u64(message_count_ ? start_ : 0);
    st.u64(message_count_ ? end_ : 0);
    st.u32(static_cast<uint32_t>(channel_counts_.size() * 10));
    for (const auto& [id, n] : channel_counts_) {
      st.u16(id);
      st.u64(n);
    }
    group(kStatistics, {st.b});
    group(kChunkIndex, chunk_index_records_);
    const uint64_t summary_offset_start = summary_start + summary.size();
    for (const auto& g : groups) {
      Buf so;
      so.u8(g.op);
      so.u64(g.start);
      so.u64(g.length);
      append_record(summary, kSummaryOffset, so.b);
    }
    // Footer: the CRC covers the summary section, the offsets and the footer's first fields.
    std::string footer;
    Buf fo;
    fo.u64(summary_start);
    fo.u64(summary_offset_start);
    std::string footer_head;
    footer_head.push_back(static_cast<char>(kFooter));
    Buf flen;
    flen.u64(8 + 8 + 4);
    footer_head += flen.b + fo.b;
    uLong crc = crc32(0L, Z_NULL, 0);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(summary.data()), static_cast<uInt>(summary.size()));
    crc = crc32(crc, reinterpret_cast<const Bytef*>(footer_head.data()), static_cast<uInt>(footer_head.size()));
    Buf fcrc;
    fcrc.u32(static_cast<uint32_t>(crc));
    footer = summary + footer_head + fcrc.b + std::string(reinterpret_cast<const char*>(kMagic), sizeof(kMagic));
    emit(footer);
    if (std::fflush(f_) != 0 || std::ferror(f_)) fail("flush");
    if (std::fclose(f_) != 0) {
      f_ = nullptr;
      fail("close");
    }
    f_ = nullptr;
  }

 private:
  // A write failed (disk full, file size limit): keep what is complete. The file is cut back to
  // the end of the last chunk that was written whole with its indexes (so it ends at a record
  // boundary), then a data end (CRC 0: not computed) and a footer (no summary) close it, in the
  // bytes the cut freed; if even that fails, it ends at the record boundary (readers that scan
  // records still read every complete chunk).
  void salvage() {
    broken_ = true;
    if (f_) std::fclose(f_);  // may flush part of the buffer: cut below
    f_ = nullptr;
    if (::truncate(path_.c_str(), static_cast<off_t>(good_offset_)) != 0) return;
    std::string tail;
    Buf de;
    de.u32(0);
    append_record(tail, kDataEnd, de.b);
    Buf fo;
    fo.u64(0);  // no summary section
    fo.u64(0);  // no summary offsets
    fo.u32(0);  // no summary CRC
    append_record(tail, kFooter, fo.b);
    tail.append(reinterpret_cast<const char*>(kMagic), sizeof(kMagic));
    FILE* f = std::fopen(path_.c_str(), "r+b");
    if (!f) return;
    const bool ok = std::fseek(f, static_cast<long>(good_offset_), SEEK_SET) == 0 &&
                    std::fwrite(tail.data(), 1, tail.size(), f) == tail.size() && std::fflush(f) == 0;
    std::fclose(f);
    if (!ok && ::truncate(path_.c_str(), static_cast<off_t>(good_offset_)) != 0) {
      // nothing more can be done: the error thrown by the caller names the failure
    }
  }

  [[noreturn]] void fail(const char* what) {
    throw BagError(path_ + ": " + what + " failed: " + std::strerror(errno) + " (" + std::to_string(offset_) +
                   " bytes written)");
  }
  void emit(const std::string& bytes) {
    if (bytes.empty()) return;
    if (std::fwrite(bytes.data(), 1, bytes.size(), f_) != bytes.size()) fail("write");
    data_crc_ = crc32(data_crc_, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size()));
    offset_ += bytes.size();
  }

  void flush_chunk() {
    if (chunk_.empty()) return;
    const uint32_t records_crc = static_cast<uint32_t>(
        crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(chunk_.data()), static_cast<uInt>(chunk_.size())));
    std::string payload;
    std::string compression;
    if (options_.compression == "zstd") {
      compression = "zstd";
      payload.resize(ZSTD_compressBound(chunk_.size()));
      const size_t n = ZSTD_compress(payload.data(), payload.size(), chunk_.data(), chunk_.size(), 1);
      if (ZSTD_isError(n)) throw BagError(path_ + ": zstd compression failed: " + ZSTD_getErrorName(n));
      payload.resize(n);
    } else {
      payload = chunk_;
    }
    Buf c;
    c.u64(chunk_messages_ ? chunk_start_ : 0);
    c.u64(chunk_messages_ ? chunk_end_ : 0);
    c.u64(chunk_.size());
    c.u32(records_crc);
    c.str(compression);
    c.u64(payload.size());
    std::string rec;
    Buf head;
    head.u8(kChunk);
    head.u64(c.b.size() + payload.size());
    rec = head.b + c.b;
    const uint64_t chunk_offset = offset_;
    try {
      emit(rec);
      emit(payload);
    } catch (const BagError&) {
      salvage();
      throw;
    }
    const uint64_t chunk_length = offset_ - chunk_offset;
    // One message index per channel with messages in this chunk, right after the chunk.
    std::string indexes;
    std::map<uint16_t, uint64_t> index_offsets;
    for (const auto& [channel, entries] : chunk_index_) {
      index_offsets[channel] = offset_ + indexes.size();
      Buf mi;
      mi.u16(channel);
      mi.u32(static_cast<uint32_t>(entries.size() * 16));
      for (const auto& [t, off] : entries) {
        mi.u64(t);
        mi.u64(off);
      }
      append_record(indexes, kMessageIndex, mi.b);
    }
    try {
      emit(indexes);
      if (std::fflush(f_) != 0) fail("write");
    } catch (const BagError&) {
      salvage();
      throw;
    }
    good_offset_ = offset_;
    persisted_messages_ += chunk_messages_;
    Buf ci;
    ci.u64(chunk_messages_ ? chunk_start_ : 0);
    ci.u64(chunk_messages_ ? chunk_end_ : 0);
    ci.u64(chunk_offset);
    ci.u64(chunk_length);
    ci.u32(static_cast<uint32_t>(index_offsets.size() * 10));
    for (const auto& [channel, off] : index_offsets) {
      ci.u16(channel);
      ci.u64(off);
    }
    ci.u64(indexes.size());
    ci.str(compression);
    ci.u64(payload.size());
    ci.u64(chunk_.size());
    chunk_index_records_.push_back(ci.b);
    chunk_.clear();
    chunk_index_.clear();
    chunk_messages_ = 0;
  }

  std::string path_;
  BagWriter::Options options_;
  std::FILE* f_ = nullptr;
  uint64_t offset_ = 0;
  uLong data_crc_ = crc32(0L, Z_NULL, 0);
  std::map<std::string, uint16_t> schema_ids_;
  std::vector<std::string> schema_records_, channel_records_, chunk_index_records_;
  std::map<uint16_t, uint64_t> channel_counts_;
  std::map<uint16_t, uint32_t> sequence_;
  std::string chunk_;  // uncompressed records of the open chunk
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;
  uint64_t chunk_start_ = 0, chunk_end_ = 0, chunk_messages_ = 0;
  uint64_t message_count_ = 0, start_ = 0, end_ = 0;
  uint64_t good_offset_ = 0;         ///< file size up to the last chunk written whole
  uint64_t persisted_messages_ = 0;  ///< messages in those chunks
  bool broken_ = false;              ///< a write failed: nothing more is written
};

// ---------------------------------------------------------------------------------------------
// Reader

struct Cursor {
  const uint8_t* p;
  const uint8_t* end;
  const std::string* where;
  void need(size_t n) const {
    if (static_cast<size_t>(end - p) < n) throw BagError(*where + ": truncated MCAP record");
  }
  template <typename T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, p, sizeof(T));
    p += sizeof(T);
    return v;
  }
  std::string str() {
    const auto n = get<uint32_t>();
    need(n);
    std::string s(reinterpret_cast<const char*>(p), n);
    p += n;
    return s;
  }
  std::map<std::string, std::string> string_map() {
    const auto n = get<uint32_t>();
    need(n);
    Cursor sub{p, p + n, where};
    std::map<std::string, std::string> m;
    while (sub.p < sub.end) {
      std::string k = sub.str();
      m[k] = sub.str();
    }
    p += n;
    return m;
  }
};

class McapSource final : public BagReader::Source {
 public:
  explicit McapSource(const std::string& path) : path_(path) {
    // Mapped, not read: a bag of camera images may be larger than memory.
    const int fd = ::open(path.c_str(), O_RDONLY);
    if (fd < 0) throw BagError(path + ": cannot open: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || st.st_size < 8) {
      ::close(fd);
      throw BagError(path + ": not an MCAP file (shorter than its magic)");
    }
    size_ = static_cast<size_t>(st.st_size);
    void* map = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
    ::close(fd);
    if (map == MAP_FAILED) throw BagError(path + ": cannot map: " + std::strerror(errno));
    data_ = static_cast<const uint8_t*>(map);
    if (std::memcmp(data_, kMagic, 8) != 0) {
      ::munmap(map, size_);
      throw BagError(path + ": not an MCAP file (bad magic)");
    }
    // Topics: one pass over the records (schemas and channels may be inside chunks).
    rewind();
    Message m;
    collecting_ = true;
    while (next(m)) {
    }
    collecting_ = false;
    rewind();
  }

  ~McapSource() override { ::munmap(const_cast<uint8_t*>(data_), size_); }
  McapSource(const McapSource&) = delete;
  McapSource& operator=(const McapSource&) = delete;

  const std::vector<TopicMetadata>& topics() const override { return topics_; }

  void rewind() override {
    pos_ = 8;
    chunk_.clear();
    chunk_pos_ = 0;
  }

  bool next(Message& out) override {
    for (;;) {
      if (chunk_pos_ < chunk_.size()) {
        Cursor c{chunk_.data() + chunk_pos_, chunk_.data() + chunk_.size(), &path_};
        const auto op = c.get<uint8_t>();
        const auto len = c.get<uint64_t>();
        c.need(len);
        chunk_pos_ += 9 + len;
        if (record(op, c.p, len, out)) return true;
        continue;
      }
      if (pos_ >= size_) return false;
      Cursor c{data_ + pos_, data_ + size_, &path_};
      if (size_ - pos_ == 8 && std::memcmp(c.p, kMagic, 8) == 0) return false;
      const auto op = c.get<uint8_t>();
      const auto len = c.get<uint64_t>();
      c.need(len);
      pos_ += 9 + len;
      if (op == kDataEnd || op == kFooter) {
        pos_ = size_;
        return false;
      }
      if (op == kChunk) {
        open_chunk(c.p, len);
        continue;
      }
      if (record(op, c.p, len, out)) return true;
    }
  }

  BagInfo scan_info() override {
    BagInfo info;
    info.storage_identifier = "mcap";
    scan_messages(*this, info);
    return info;
  }

 private:
  void open_chunk(const uint8_t* p, uint64_t len) {
    Cursor c{p, p + len, &path_};
    c.get<uint64_t>();  // start
    c.get<uint64_t>();  // end
    const auto uncompressed_size = c.get<uint64_t>();
    c.get<uint32_t>();  // crc
    const std::string compression = c.str();
    const auto n = c.get<uint64_t>();
    c.need(n);
    if (compression.empty()) {
      if (uncompressed_size != n)
        throw BagError(path_ + ": corrupt chunk at byte " + std::to_string(pos_) + ": uncompressed size " +
                       std::to_string(uncompressed_size) + " != its " + std::to_string(n) + " bytes");
      chunk_.assign(c.p, c.p + n);
    } else if (compression == "zstd") {
      // The declared size drives an allocation: it must agree with the zstd frame and stay within
      // a ratio no real bag reaches (found by fuzz_mcap: a forged size exhausted memory).
      const unsigned long long frame = ZSTD_getFrameContentSize(c.p, n);
      if (frame != uncompressed_size || uncompressed_size > 1000ull * n + (1u << 16))
        throw BagError(path_ + ": corrupt zstd chunk at byte " + std::to_string(pos_) + ": declared size " +
                       std::to_string(uncompressed_size) + " for " + std::to_string(n) + " compressed bytes");
      chunk_.resize(uncompressed_size);
      const size_t got = ZSTD_decompress(chunk_.data(), chunk_.size(), c.p, n);
      if (ZSTD_isError(got) || got != uncompressed_size)
        throw BagError(path_ + ": corrupt zstd chunk at byte " + std::to_string(pos_));
    } else {
      throw BagError(path_ + ": chunk compression '" + compression + "' is not supported (none, zstd)");
    }
    chunk_pos_ = 0;
  }

  // Handles one record; true when it produced a message in `out`.
  bool record(uint8_t op, const uint8_t* p, uint64_t len, Message& out) {
    Cursor c{p, p + len, &path_};
    if (op == kSchema && collecting_) {
      const auto id = c.get<uint16_t>();
      Schema s;
      s.name = c.str();
      s.encoding = c.str();
      s.data = c.str();
      schemas_[id] = s;
    } else if (op == kChannel && collecting_) {
      const auto id = c.get<uint16_t>();
      const auto schema = c.get<uint16_t>();
      if (channels_.count(id)) return false;
      TopicMetadata t;
      t.name = c.str();
      t.serialization_format = c.str();
      const auto meta = c.string_map();
      const auto q = meta.find("offered_qos_profiles");
      if (q != meta.end()) t.offered_qos_profiles = q->second;
      const auto s = schemas_.find(schema);
      if (s != schemas_.end()) {
        t.type = s->second.name;
        if (s->second.encoding == "ros2msg") t.message_definition = s->second.data;
      }
      channels_[id] = topics_.size();
      topics_.push_back(t);
    } else if (op == kMessage) {
      const auto channel = c.get<uint16_t>();
      c.get<uint32_t>();  // sequence
      const auto log_time = c.get<uint64_t>();
      c.get<uint64_t>();  // publish time
      const auto it = channels_.find(channel);
      if (it == channels_.end()) {
        if (collecting_) return false;
        throw BagError(path_ + ": message on unknown channel " + std::to_string(channel));
      }
      if (collecting_) return false;
      if (log_time > static_cast<uint64_t>(std::numeric_limits<int64_t>::max()))
        throw BagError(path_ + ": message log time " + std::to_string(log_time) + " ns is beyond 2262: corrupt");
      out.topic = it->second;
      out.timestamp_ns = static_cast<int64_t>(log_time);
      out.data.assign(c.p, p + len);
      return true;
    }
    return false;
  }

  struct Schema {
    std::string name, encoding, data;
  };
  std::string path_;
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  size_t pos_ = 8;
  std::vector<uint8_t> chunk_;
  size_t chunk_pos_ = 0;
  bool collecting_ = false;
  std::map<uint16_t, Schema> schemas_;
  std::map<uint16_t, size_t> channels_;
  std::vector<TopicMetadata> topics_;
};

}  // namespace

std::unique_ptr<BagWriter::Storage> make_mcap_storage(const std::string& path, const BagWriter::Options& options) {
  return std::make_unique<McapStorage>(path, options);
}

std::unique_ptr<BagReader::Source> open_mcap_source(const std::string& path) {
  return std::make_unique<McapSource>(path);
}

}  // namespace unav::bag
