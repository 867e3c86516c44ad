#include "semrec/io/bag_storage.h"

#include <sqlite3.h>

#include <algorithm>
#include <map>
#include <mutex>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "semrec/core/error.h"
#include "semrec/io/layouts.h"
#include "semrec/io/mcap_reader.h"

namespace fs = std::filesystem;

namespace semrec::io::internal {
namespace {

class McapStorage : public BagStorage {
 public:
  explicit McapStorage(const std::vector<fs::path>& files) {
    for (const fs::path& f : files) {
      readers_.push_back(std::make_unique<McapReader>(f));
    }
  }

  uint64_t Extent() const override {
    uint64_t bytes = 0;
    std::error_code ec;
    for (const auto& r : readers_) bytes += fs::file_size(r->path(), ec);
    return bytes;
  }

  void Scan(const std::function<void(const BagMessage&)>& visit) override {
    uint64_t before = 0;  // bytes of the files already scanned
    std::error_code ec;
    for (uint32_t f = 0; f < readers_.size(); ++f) {
      McapReader& r = *readers_[f];
      r.Scan([&](const McapMessageInfo& info, const uint8_t* data,
                 size_t size) {
        const McapChannel& ch = r.channels().at(info.channel_id);
        static const std::string kUnknown;
        const auto schema = r.schemas().find(ch.schema_id);
        BagMessage m;
        m.topic = &ch.topic;
        m.type = schema == r.schemas().end() ? &kUnknown : &schema->second.name;
        m.log_time_ns = static_cast<int64_t>(info.log_time_ns);
        m.data = data;
        m.size = size;
        m.ref = {f, info.ref.chunk_offset, info.ref.offset, info.ref.size};
        m.done = before + (info.ref.chunk_offset == McapMessageRef::kNoChunk
                               ? info.ref.offset
                               : info.ref.chunk_offset);
        visit(m);
      });
      before += fs::file_size(r.path(), ec);
    }
  }

  std::vector<uint8_t> Read(const BagMessageRef& ref) override {
    return readers_.at(ref.file)->Read({ref.a, ref.b, ref.c});
  }
  std::string Storage() const override { return "mcap"; }
  std::string Describe() const override {
    std::map<std::string, size_t> chunks;
    for (const auto& r : readers_) {
      for (const auto& [c, n] : r->chunk_compressions()) chunks[c] += n;
    }
    std::string text = fmt::format("{} MCAP file(s), profile '{}'",
                                   readers_.size(), readers_[0]->profile());
    for (const auto& [c, n] : chunks) {
      text +=
          fmt::format(", {} {} chunk(s)", n, c.empty() ? "uncompressed" : c);
    }
    const bool indexed =
        std::all_of(readers_.begin(), readers_.end(),
                    [](const auto& r) { return r->used_chunk_index(); });
    return text + (indexed ? ", read by the summary's chunk index"
                           : ", read by a linear scan");
  }
  fs::path File(const BagMessageRef& ref) const override {
    return readers_.at(ref.file)->path();
  }

 private:
  std::vector<std::unique_ptr<McapReader>> readers_;
};

class SqliteStorage : public BagStorage {
 public:
  explicit SqliteStorage(const std::vector<fs::path>& files) : files_(files) {
    for (const fs::path& f : files) {
      sqlite3* db = nullptr;
      if (sqlite3_open_v2(f.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) !=
          SQLITE_OK) {
        const std::string why = db ? sqlite3_errmsg(db) : "out of memory";
        sqlite3_close(db);
        throw FormatError(f, "cannot open the SQLite bag: " + why);
      }
      dbs_.emplace_back(db, &sqlite3_close);
      std::map<int64_t, std::pair<std::string, std::string>> topics;
      Query(dbs_.size() - 1, "SELECT id, name, type FROM topics",
            [&](sqlite3_stmt* s) {
              topics[sqlite3_column_int64(s, 0)] = {Text(s, 1), Text(s, 2)};
            });
      topics_.push_back(std::move(topics));
      Query(dbs_.size() - 1, "SELECT COUNT(*) FROM messages",
            [&](sqlite3_stmt* s) { count_ += sqlite3_column_int64(s, 0); });
    }
  }

  uint64_t Extent() const override { return count_; }

  void Scan(const std::function<void(const BagMessage&)>& visit) override {
    uint64_t done = 0;
    for (uint32_t f = 0; f < dbs_.size(); ++f) {
      Query(f,
            "SELECT id, topic_id, timestamp, data FROM messages ORDER BY "
            "timestamp, id",
            [&](sqlite3_stmt* s) {
              const auto t = topics_[f].find(sqlite3_column_int64(s, 1));
              if (t == topics_[f].end()) {
                throw FormatError(files_[f],
                                  "a message names a topic id that the "
                                  "topics table lacks");
              }
              BagMessage m;
              m.topic = &t->second.first;
              m.type = &t->second.second;
              m.log_time_ns = sqlite3_column_int64(s, 2);
              m.data = static_cast<const uint8_t*>(sqlite3_column_blob(s, 3));
              m.size = static_cast<size_t>(sqlite3_column_bytes(s, 3));
              m.ref = {f, static_cast<uint64_t>(sqlite3_column_int64(s, 0)), 0,
                       0};
              m.done = ++done;
              visit(m);
            });
    }
  }

  std::vector<uint8_t> Read(const BagMessageRef& ref) override {
    std::vector<uint8_t> out;
    bool found = false;
    Query(ref.file,
          fmt::format("SELECT data FROM messages WHERE id = {}", ref.a),
          [&](sqlite3_stmt* s) {
            const auto* p =
                static_cast<const uint8_t*>(sqlite3_column_blob(s, 0));
            out.assign(p, p + sqlite3_column_bytes(s, 0));
            found = true;
          });
    if (!found) {
      throw FormatError(files_.at(ref.file),
                        fmt::format("message {} is gone", ref.a));
    }
    return out;
  }
  std::string Storage() const override { return "sqlite3"; }
  std::string Describe() const override {
    return fmt::format("{} SQLite file(s)", files_.size());
  }
  fs::path File(const BagMessageRef& ref) const override {
    return files_.at(ref.file);
  }

 private:
  static std::string Text(sqlite3_stmt* s, int col) {
    const auto* p = sqlite3_column_text(s, col);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
  void Query(size_t f, const std::string& sql,
             const std::function<void(sqlite3_stmt*)>& row) {
    sqlite3_stmt* raw = nullptr;
    if (sqlite3_prepare_v2(dbs_[f].get(), sql.c_str(), -1, &raw, nullptr) !=
        SQLITE_OK) {
      throw FormatError(files_[f], fmt::format("not a rosbag2 SQLite bag ({})",
                                               sqlite3_errmsg(dbs_[f].get())));
    }
    std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)> stmt(
        raw, &sqlite3_finalize);
    int rc = 0;
    while ((rc = sqlite3_step(stmt.get())) == SQLITE_ROW) row(stmt.get());
    if (rc != SQLITE_DONE) {
      throw FormatError(files_[f], fmt::format("reading the bag failed ({})",
                                               sqlite3_errmsg(dbs_[f].get())));
    }
  }

  std::vector<fs::path> files_;
  std::vector<std::unique_ptr<sqlite3, decltype(&sqlite3_close)>> dbs_;
  std::vector<std::map<int64_t, std::pair<std::string, std::string>>> topics_;
  uint64_t count_ = 0;
};

bool IsSqlite(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char head[16] = {};
  return in.read(head, 16) && std::string(head, 15) == "SQLite format 3";
}

// rosbag2's metadata.yaml: the storage and the files, in order.
std::unique_ptr<BagStorage> FromMetadata(const fs::path& folder) {
  const fs::path yaml = folder / "metadata.yaml";
  YAML::Node info;
  try {
    info = YAML::LoadFile(yaml.string())["rosbag2_bagfile_information"];
  } catch (const YAML::Exception& e) {
    throw FormatError(yaml, std::string("not valid YAML: ") + e.what());
  }
  if (!info) return nullptr;  // another tool's metadata.yaml: not a bag
  const std::string compression = info["compression_mode"].as<std::string>("");
  if (!compression.empty()) {
    throw FormatError(
        yaml, fmt::format("a compressed rosbag2 bag "
                          "(compression_mode: {}, {}) is not "
                          "read: decompress it first (ros2 bag "
                          "decompress, or ros2 bag convert)",
                          compression,
                          info["compression_format"].as<std::string>("")));
  }
  const std::string storage = info["storage_identifier"].as<std::string>("");
  std::vector<fs::path> files;
  for (const auto& f : info["relative_file_paths"]) {
    const fs::path p = folder / f.as<std::string>();
    if (!fs::exists(p)) {
      throw IoError(p, "listed in " + yaml.string() + " but missing");
    }
    files.push_back(p);
  }
  if (files.empty()) throw FormatError(yaml, "lists no bag files");
  if (storage == "mcap") return std::make_unique<McapStorage>(files);
  if (storage == "sqlite3") return std::make_unique<SqliteStorage>(files);
  throw FormatError(
      yaml, "storage '" + storage + "' is not read (mcap and sqlite3 are)");
}

}  // namespace

std::unique_ptr<BagStorage> OpenBag(const fs::path& path) {
  std::error_code ec;
  if (fs::is_regular_file(path, ec)) {
    if (IsMcapFile(path))
      return std::make_unique<McapStorage>(std::vector<fs::path>{path});
    if (path.extension() == ".db3" && IsSqlite(path)) {
      return std::make_unique<SqliteStorage>(std::vector<fs::path>{path});
    }
    if (path.extension() == ".mcap") {
      throw FormatError(path, "not an MCAP file (no MCAP magic)");
    }
    return nullptr;
  }
  if (!fs::is_directory(path, ec)) return nullptr;
  if (fs::exists(path / "metadata.yaml")) {
    if (auto bag = FromMetadata(path)) return bag;
  }
  std::vector<fs::path> files = ListFiles(path, {".mcap"});
  if (!files.empty()) return std::make_unique<McapStorage>(files);
  files = ListFiles(path, {".db3"});
  if (!files.empty()) return std::make_unique<SqliteStorage>(files);
  return nullptr;
}

}  // namespace semrec::io::internal
