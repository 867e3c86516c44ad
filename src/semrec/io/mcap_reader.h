// MCAP files (https://mcap.dev/spec), read by our own code: the container
// ROS 2 writes by default since Iron. A file is a magic, a Header record, data
// records (Schema, Channel, Message, Chunk, Attachment, Metadata, ...), a
// DataEnd, an optional summary and a Footer. Chunks hold Schema / Channel /
// Message records, uncompressed or compressed with zstd or lz4 (frame format);
// their CRC is checked unless it is 0 ("not computed").
//
// Reading goes chunk by chunk in log-time order by the summary's chunk index
// when the file has one, else by a linear scan of the data section (one chunk
// decompressed at a time): Scan() visits every message with its location,
// Read() fetches one message's bytes again by that location (the chunk it lies
// in is decompressed and kept with the three read before it: a frame's colour
// and depth often lie in different chunks). Memory does not grow with the
// file, only with what the caller keeps (a location is 32 bytes).
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace semrec::io {

struct McapSchema {
  uint16_t id = 0;
  std::string name;      // e.g. "sensor_msgs/msg/Image"
  std::string encoding;  // e.g. "ros2msg"
  std::string data;      // e.g. the .msg text
};

struct McapChannel {
  uint16_t id = 0;
  uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  // e.g. "cdr"
  std::map<std::string, std::string> metadata;
};

struct McapMetadata {
  std::string name;
  std::map<std::string, std::string> values;
};

/// Where a message's bytes lie: in the chunk whose record starts at
/// `chunk_offset` (offset into its decompressed records), or, when
/// `chunk_offset` is kNoChunk, in the file itself.
struct McapMessageRef {
  static constexpr uint64_t kNoChunk = ~uint64_t{0};
  uint64_t chunk_offset = kNoChunk;
  uint64_t offset = 0;
  uint64_t size = 0;
};

struct McapMessageInfo {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time_ns = 0;
  uint64_t publish_time_ns = 0;
  McapMessageRef ref;
};

class McapReader {
 public:
  /// Opens `path` and checks the magic and the Header record. Throws IoError
  /// when it cannot be read, FormatError when it is not MCAP.
  explicit McapReader(const std::filesystem::path& path);

  const std::filesystem::path& path() const { return path_; }
  /// The Header record's profile ("ros2" for rosbag2) and library.
  const std::string& profile() const { return profile_; }
  const std::string& library() const { return library_; }

  /// Visits every message of the data section in file order, after the
  /// Schema and Channel records before it were seen (schemas(), channels()
  /// are then complete for the messages visited so far). `data` is valid
  /// only during the call. Throws FormatError naming the file and the byte
  /// offset for a broken record, an unknown compression or a CRC mismatch.
  using Visitor = std::function<void(const McapMessageInfo& info,
                                     const uint8_t* data, size_t size)>;
  void Scan(const Visitor& visit);

  /// The bytes of one message Scan() reported.
  std::vector<uint8_t> Read(const McapMessageRef& ref);

  const std::map<uint16_t, McapSchema>& schemas() const { return schemas_; }
  const std::map<uint16_t, McapChannel>& channels() const { return channels_; }
  /// Metadata records (rosbag2 writes two named "rosbag2": use the last).
  const std::vector<McapMetadata>& metadata() const { return metadata_; }
  /// Chunks seen by compression ("" = none, "zstd", "lz4").
  const std::map<std::string, size_t>& chunk_compressions() const {
    return compressions_;
  }
  /// Whether the last Scan() went by the summary's chunk index.
  bool used_chunk_index() const { return used_chunk_index_; }

 private:
  // The decompressed records of the chunk at `offset` (cached; valid until
  // the next call).
  const std::vector<uint8_t>& Chunk(uint64_t offset);
  void ReadExact(uint64_t offset, uint8_t* out, size_t size);
  // The chunks' offsets in log-time order from the summary's ChunkIndex
  // records (empty when the file has no summary or no chunk index).
  std::vector<uint64_t> IndexedChunks();
  // Schemas, channels and metadata outside chunks, up to `data_end`; false
  // when a message lies outside chunks (the chunk index does not list it).
  bool TopLevelRecords(uint64_t data_end);
  // The records of the chunk at `offset`, visited.
  void VisitChunk(uint64_t offset, const Visitor& visit);
  // One record of the data section (top level or inside a chunk).
  void Record(uint8_t opcode, const uint8_t* body, uint64_t size,
              uint64_t chunk_offset, uint64_t body_offset,
              const Visitor& visit);

  std::filesystem::path path_;
  std::ifstream file_;
  uint64_t file_size_ = 0;
  std::string profile_, library_;
  std::map<uint16_t, McapSchema> schemas_;
  std::map<uint16_t, McapChannel> channels_;
  std::vector<McapMetadata> metadata_;
  std::map<std::string, size_t> compressions_;
  bool used_chunk_index_ = false;
  // The last few decompressed chunks, most recent first: a frame's colour
  // and depth messages often lie in different chunks, read in turn.
  std::deque<std::pair<uint64_t, std::vector<uint8_t>>> cache_;
};

/// True when `path` starts with the MCAP magic.
bool IsMcapFile(const std::filesystem::path& path);

}  // namespace semrec::io
