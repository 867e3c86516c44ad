// A small MCAP writer (https://mcap.dev/spec): the data section only
// (Header, Schema, Channel, Metadata, Chunk records with their messages,
// DataEnd, Footer without a summary), as a recorder cut short would leave a
// file readable. semrec writes test bags with it; it is cross-checked against
// the reference implementation (@mcap/core) in the tests.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace semrec::io {

struct McapWriterOptions {
  /// "" (none), "zstd" or "lz4".
  std::string compression = "zstd";
  /// A chunk is closed when its records reach this size.
  size_t chunk_bytes = 1 << 20;
  /// Write each chunk's CRC (0 = "not computed" otherwise).
  bool crc = true;
  /// Messages outside chunks (no chunking at all).
  bool chunked = true;
  std::string profile = "ros2";
};

class McapWriter {
 public:
  McapWriter(const std::filesystem::path& path,
             const McapWriterOptions& options = {});
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Returns the schema id.
  uint16_t AddSchema(const std::string& name, const std::string& encoding,
                     const std::string& data);
  /// Returns the channel id.
  uint16_t AddChannel(uint16_t schema_id, const std::string& topic,
                      const std::string& message_encoding = "cdr");
  void AddMetadata(const std::string& name,
                   const std::map<std::string, std::string>& values);
  void Write(uint16_t channel_id, uint64_t log_time_ns,
             const std::vector<uint8_t>& data);
  /// Writes the last chunk, DataEnd, Footer and the closing magic. Throws
  /// IoError when the file cannot be written.
  void Close();

 private:
  void FlushChunk();

  std::filesystem::path path_;
  McapWriterOptions options_;
  std::vector<uint8_t> out_;    // the whole file (tests write small bags)
  std::vector<uint8_t> chunk_;  // records of the open chunk
  uint64_t chunk_start_ = 0, chunk_end_ = 0;
  uint16_t next_schema_ = 1, next_channel_ = 0;
  std::map<uint16_t, uint32_t> sequence_;
  bool closed_ = false;
};

}  // namespace semrec::io
