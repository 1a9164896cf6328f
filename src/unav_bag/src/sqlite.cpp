// rosbag2's sqlite3 storage as ROS 2 Humble writes it (schema version 3): tables schema,
// metadata, topics (with offered_qos_profiles) and messages, plus the timestamp index. Writes
// are batched in transactions; a transaction is committed every kCommitEvery messages, so a
// crash loses at most that many.
#include <sqlite3.h>

#include <string>

#include "storage.hpp"

namespace unav::bag {
namespace {

constexpr int kCommitEvery = 200;
constexpr const char* kSchemaSql =
    "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);"
    "INSERT INTO schema(schema_version, ros_distro) VALUES (3, 'humble');"
    "CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,metadata TEXT NOT NULL);"
    "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
    "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL);"
    "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,timestamp INTEGER NOT NULL,"
    " data BLOB NOT NULL);"
    "CREATE INDEX timestamp_idx ON messages (timestamp ASC);";

class Db {
 public:
  Db(const std::string& path, int flags) : path_(path) {
    if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
      const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw BagError(path + ": cannot open sqlite3 database: " + msg);
    }
  }
  ~Db() {
    for (auto* s : statements_) sqlite3_finalize(s);
    if (db_) sqlite3_close(db_);
  }
  Db(const Db&) = delete;
  Db& operator=(const Db&) = delete;

  void exec(const std::string& sql) {
    char* err = nullptr;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
      const std::string msg = err ? err : sqlite3_errmsg(db_);
      sqlite3_free(err);
      throw BagError(path_ + ": sqlite3: " + msg);
    }
  }
  sqlite3_stmt* prepare(const std::string& sql) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &s, nullptr) != SQLITE_OK)
      throw BagError(path_ + ": sqlite3: " + sqlite3_errmsg(db_) + " in '" + sql + "'");
    statements_.push_back(s);
    return s;
  }
  void step_done(sqlite3_stmt* s) {
    const int rc = sqlite3_step(s);
    sqlite3_reset(s);
    if (rc != SQLITE_DONE) throw BagError(path_ + ": sqlite3: " + sqlite3_errmsg(db_));
  }
  bool has_table(const std::string& name) {
    sqlite3_stmt* s = nullptr;
    sqlite3_prepare_v2(db_, "SELECT count(*) FROM sqlite_master WHERE type='table' AND name=?", -1, &s, nullptr);
    sqlite3_bind_text(s, 1, name.c_str(), -1, SQLITE_TRANSIENT);
    const bool yes = sqlite3_step(s) == SQLITE_ROW && sqlite3_column_int(s, 0) > 0;
    sqlite3_finalize(s);
    return yes;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
  std::vector<sqlite3_stmt*> statements_;
};

std::string column_text(sqlite3_stmt* s, int i) {
  const auto* t = sqlite3_column_text(s, i);
  return t ? reinterpret_cast<const char*>(t) : "";
}

class SqliteStorage final : public BagWriter::Storage {
 public:
  explicit SqliteStorage(const std::string& path) : db_(path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE) {
    // As rosbag2's default (no preset) profile: journal in memory, no fsync per transaction.
    db_.exec("PRAGMA journal_mode=MEMORY; PRAGMA synchronous=OFF;");
    db_.exec(kSchemaSql);
    insert_topic_ = db_.prepare(
        "INSERT INTO topics (id, name, type, serialization_format, offered_qos_profiles) VALUES (?, ?, ?, ?, ?)");
    insert_message_ = db_.prepare("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)");
    db_.exec("BEGIN");
  }

  void add_topic(size_t index, const TopicMetadata& t) override {
    sqlite3_bind_int64(insert_topic_, 1, static_cast<sqlite3_int64>(index) + 1);
    sqlite3_bind_text(insert_topic_, 2, t.name.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(insert_topic_, 3, t.type.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(insert_topic_, 4, t.serialization_format.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(insert_topic_, 5, t.offered_qos_profiles.c_str(), -1, SQLITE_TRANSIENT);
    db_.step_done(insert_topic_);
  }

  void write(size_t topic, int64_t timestamp_ns, const uint8_t* data, size_t size) override {
    sqlite3_bind_int64(insert_message_, 1, static_cast<sqlite3_int64>(topic) + 1);
    sqlite3_bind_int64(insert_message_, 2, timestamp_ns);
    sqlite3_bind_blob64(insert_message_, 3, data, size, SQLITE_STATIC);
    db_.step_done(insert_message_);
    if (++uncommitted_ >= kCommitEvery) {
      db_.exec("COMMIT; BEGIN");
      uncommitted_ = 0;
    }
  }

  void close(const std::string& metadata_yaml) override {
    if (closed_) return;
    closed_ = true;
    sqlite3_stmt* meta = db_.prepare("INSERT INTO metadata(metadata_version, metadata) VALUES (?, ?)");
    sqlite3_bind_int(meta, 1, 5);
    sqlite3_bind_text(meta, 2, metadata_yaml.c_str(), -1, SQLITE_TRANSIENT);
    db_.step_done(meta);
    db_.exec("COMMIT");
  }

 private:
  Db db_;
  sqlite3_stmt* insert_topic_ = nullptr;
  sqlite3_stmt* insert_message_ = nullptr;
  int uncommitted_ = 0;
  bool closed_ = false;
};

class SqliteSource final : public BagReader::Source {
 public:
  explicit SqliteSource(const std::string& path) : db_(path, SQLITE_OPEN_READONLY) {
    if (!db_.has_table("topics") || !db_.has_table("messages"))
      throw BagError(path + ": not a rosbag2 sqlite3 database (tables 'topics' and 'messages' missing)");
    const bool has_qos = [&] {
      sqlite3_stmt* s = db_.prepare("PRAGMA table_info(topics)");
      bool found = false;
      while (sqlite3_step(s) == SQLITE_ROW) found = found || column_text(s, 1) == "offered_qos_profiles";
      sqlite3_reset(s);
      return found;
    }();
    sqlite3_stmt* s = db_.prepare(std::string("SELECT id, name, type, serialization_format") +
                                  (has_qos ? ", offered_qos_profiles" : "") + " FROM topics ORDER BY id");
    while (sqlite3_step(s) == SQLITE_ROW) {
      TopicMetadata t;
      ids_[sqlite3_column_int64(s, 0)] = topics_.size();
      t.name = column_text(s, 1);
      t.type = column_text(s, 2);
      t.serialization_format = column_text(s, 3);
      if (has_qos) t.offered_qos_profiles = column_text(s, 4);
      topics_.push_back(t);
    }
    sqlite3_reset(s);
    messages_ = db_.prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id");
  }

  const std::vector<TopicMetadata>& topics() const override { return topics_; }

  bool next(Message& out) override {
    const int rc = sqlite3_step(messages_);
    if (rc == SQLITE_DONE) return false;
    if (rc != SQLITE_ROW)
      throw BagError(db_.path() + ": cannot read messages (sqlite3 code " + std::to_string(rc) + ")");
    const auto it = ids_.find(sqlite3_column_int64(messages_, 0));
    if (it == ids_.end())
      throw BagError(db_.path() + ": message with unknown topic_id " +
                     std::to_string(sqlite3_column_int64(messages_, 0)));
    out.topic = it->second;
    out.timestamp_ns = sqlite3_column_int64(messages_, 1);
    const auto* blob = static_cast<const uint8_t*>(sqlite3_column_blob(messages_, 2));
    out.data.assign(blob, blob + sqlite3_column_bytes(messages_, 2));
    return true;
  }

  void rewind() override { sqlite3_reset(messages_); }

  BagInfo scan_info() override {
    BagInfo info;
    info.storage_identifier = "sqlite3";
    scan_messages(*this, info);
    return info;
  }

 private:
  Db db_;
  std::map<int64_t, size_t> ids_;
  std::vector<TopicMetadata> topics_;
  sqlite3_stmt* messages_ = nullptr;
};

}  // namespace

std::unique_ptr<BagWriter::Storage> make_sqlite_storage(const std::string& path) {
  return std::make_unique<SqliteStorage>(path);
}

std::unique_ptr<BagReader::Source> open_sqlite_source(const std::string& path) {
  return std::make_unique<SqliteSource>(path);
}

}  // namespace unav::bag
