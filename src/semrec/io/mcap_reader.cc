#include "semrec/io/mcap_reader.h"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <iterator>
#include <memory>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "semrec/core/error.h"

namespace fs = std::filesystem;

namespace semrec::io {
namespace {

constexpr std::array<uint8_t, 8> kMagic = {0x89, 'M', 'C',  'A',
                                           'P',  '0', '\r', '\n'};
constexpr uint8_t kHeader = 0x01, kFooter = 0x02, kSchema = 0x03,
                  kChannel = 0x04, kMessage = 0x05, kChunk = 0x06,
                  kChunkIndex = 0x08, kMetadata = 0x0C, kDataEnd = 0x0F;
// Message record: channel id, sequence, log time, publish time, then data.
constexpr uint64_t kMessageHead = 2 + 4 + 8 + 8;
// Chunks kept decompressed (count, bytes).
constexpr size_t kCachedChunks = 4;
constexpr size_t kCachedBytes = size_t{256} << 20;
// A chunk larger than this decompressed is refused (rosbag2 writes ~1 MB).
constexpr uint64_t kMaxChunkBytes = uint64_t{1} << 30;
// A summary larger than this is not trusted (a damaged footer): scan instead.
constexpr uint64_t kMaxSummaryBytes = uint64_t{256} << 20;

// Bounds-checked little-endian reads of one record's body.
class Cursor {
 public:
  Cursor(const uint8_t* data, uint64_t size, const fs::path& path,
         uint64_t file_offset)
      : data_(data), size_(size), path_(path), file_offset_(file_offset) {}

  template <typename T>
  T Get() {
    Need(sizeof(T));
    T v;
    std::memcpy(&v, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string String() {
    const uint32_t n = Get<uint32_t>();
    Need(n);
    std::string s(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return s;
  }
  std::map<std::string, std::string> Map() {
    const uint32_t n = Get<uint32_t>();
    Need(n);
    Cursor inner(data_ + pos_, n, path_, file_offset_ + pos_);
    pos_ += n;
    std::map<std::string, std::string> out;
    while (inner.pos_ < inner.size_) {
      std::string key = inner.String();
      out[key] = inner.String();
    }
    return out;
  }
  uint64_t pos() const { return pos_; }
  uint64_t left() const { return size_ - pos_; }
  const uint8_t* here() const { return data_ + pos_; }
  void Skip(uint64_t n) {
    Need(n);
    pos_ += n;
  }

 private:
  void Need(uint64_t n) const {
    if (n > size_ - pos_) {
      throw FormatError(
          path_, fmt::format("MCAP record at byte {} ends early (needs {} more "
                             "bytes, has {})",
                             file_offset_, n, size_ - pos_));
    }
  }

  const uint8_t* data_;
  uint64_t size_;
  uint64_t pos_ = 0;
  const fs::path& path_;
  uint64_t file_offset_;
};

std::vector<uint8_t> DecompressZstd(const uint8_t* src, size_t size,
                                    uint64_t out_size, const fs::path& path,
                                    uint64_t offset) {
  std::vector<uint8_t> out(out_size);
  const size_t n = ZSTD_decompress(out.data(), out.size(), src, size);
  if (ZSTD_isError(n) || n != out_size) {
    throw FormatError(
        path,
        fmt::format("MCAP chunk at byte {}: zstd data is corrupt ({})", offset,
                    ZSTD_isError(n)
                        ? ZSTD_getErrorName(n)
                        : fmt::format("{} bytes, not {}", n, out_size)));
  }
  return out;
}

std::vector<uint8_t> DecompressLz4(const uint8_t* src, size_t size,
                                   uint64_t out_size, const fs::path& path,
                                   uint64_t offset) {
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) {
    throw Error("lz4: cannot create a decompression context");
  }
  std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> ctx(
      raw, &LZ4F_freeDecompressionContext);
  std::vector<uint8_t> out(out_size);
  size_t in_pos = 0, out_pos = 0;
  size_t hint = 1;
  while (hint != 0) {
    size_t in_n = size - in_pos, out_n = out.size() - out_pos;
    hint = LZ4F_decompress(ctx.get(), out.data() + out_pos, &out_n,
                           src + in_pos, &in_n, nullptr);
    if (LZ4F_isError(hint)) {
      throw FormatError(
          path, fmt::format("MCAP chunk at byte {}: lz4 data is corrupt ({})",
                            offset, LZ4F_getErrorName(hint)));
    }
    in_pos += in_n;
    out_pos += out_n;
    if (hint != 0 && in_n == 0 && out_n == 0) {
      throw FormatError(path,
                        fmt::format("MCAP chunk at byte {}: lz4 data ends "
                                    "early or is larger than the chunk says",
                                    offset));
    }
  }
  if (out_pos != out_size) {
    throw FormatError(
        path, fmt::format("MCAP chunk at byte {}: lz4 data gives {} bytes, "
                          "the chunk says {}",
                          offset, out_pos, out_size));
  }
  return out;
}

}  // namespace

bool IsMcapFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::array<uint8_t, 8> head{};
  return in.read(reinterpret_cast<char*>(head.data()), head.size()) &&
         head == kMagic;
}

McapReader::McapReader(const fs::path& path) : path_(path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw IoError(path, "MCAP file not found");
  }
  file_.open(path, std::ios::binary);
  if (!file_) throw IoError(path, "cannot open the MCAP file");
  file_size_ = fs::file_size(path, ec);
  std::array<uint8_t, 8> head{};
  if (file_size_ < 8 + 9) {
    throw FormatError(path, "too short for an MCAP file");
  }
  ReadExact(0, head.data(), head.size());
  if (head != kMagic) {
    throw FormatError(path,
                      "not an MCAP file (its first bytes are not the "
                      "MCAP magic)");
  }
  std::array<uint8_t, 9> rec{};
  ReadExact(8, rec.data(), rec.size());
  uint64_t len = 0;
  std::memcpy(&len, rec.data() + 1, 8);
  if (rec[0] != kHeader || len > file_size_ - 17) {
    throw FormatError(path,
                      "MCAP file without a Header record after the "
                      "magic");
  }
  std::vector<uint8_t> body(len);
  ReadExact(17, body.data(), body.size());
  Cursor c(body.data(), body.size(), path_, 17);
  profile_ = c.String();
  library_ = c.String();
}

void McapReader::ReadExact(uint64_t offset, uint8_t* out, size_t size) {
  file_.clear();
  file_.seekg(static_cast<std::streamoff>(offset));
  if (!file_.read(reinterpret_cast<char*>(out),
                  static_cast<std::streamsize>(size))) {
    throw IoError(path_,
                  fmt::format("cannot read {} bytes at byte {}", size, offset));
  }
}

void McapReader::VisitChunk(uint64_t offset, const Visitor& visit) {
  // Our own copy: a visitor may Read() another chunk, which refills the cache.
  const std::vector<uint8_t> records = Chunk(offset);
  uint64_t at = 0;
  while (at < records.size()) {
    if (records.size() - at < 9) {
      throw FormatError(path_, fmt::format("MCAP chunk at byte {}: a record "
                                           "header is cut off",
                                           offset));
    }
    uint64_t n = 0;
    std::memcpy(&n, records.data() + at + 1, 8);
    if (n > records.size() - at - 9) {
      throw FormatError(path_, fmt::format("MCAP chunk at byte {}: a record "
                                           "runs past the chunk's end",
                                           offset));
    }
    Record(records[at], records.data() + at + 9, n, offset, at + 9, visit);
    at += 9 + n;
  }
}

bool McapReader::TopLevelRecords(uint64_t data_end) {
  // Record headers only, seeking past chunks: the schemas, channels and
  // metadata outside chunks; a message outside chunks (which no chunk index
  // lists) means the file needs the linear scan.
  uint64_t pos = 8;
  std::array<uint8_t, 9> head{};
  std::vector<uint8_t> body;
  while (pos < data_end && data_end - pos >= 9) {
    ReadExact(pos, head.data(), head.size());
    uint64_t len = 0;
    std::memcpy(&len, head.data() + 1, 8);
    if (len > data_end - pos - 9) return false;
    const uint8_t opcode = head[0];
    if (opcode == kMessage) return false;
    if (opcode == kDataEnd) break;
    if (opcode == kSchema || opcode == kChannel || opcode == kMetadata) {
      body.resize(len);
      ReadExact(pos + 9, body.data(), body.size());
      Record(opcode, body.data(), len, McapMessageRef::kNoChunk, pos + 9, {});
    }
    pos += 9 + len;
  }
  return true;
}

std::vector<uint64_t> McapReader::IndexedChunks() {
  // Footer: opcode, length, summary start, summary offset start, CRC; then
  // the closing magic.
  constexpr uint64_t kFooterSize = 9 + 8 + 8 + 4;
  if (file_size_ < 8 + kFooterSize + 8 + 17) return {};
  const uint64_t footer_at = file_size_ - 8 - kFooterSize;
  std::array<uint8_t, kFooterSize> footer{};
  ReadExact(footer_at, footer.data(), footer.size());
  uint64_t summary_start = 0;
  std::memcpy(&summary_start, footer.data() + 9, 8);
  if (footer[0] != kFooter || summary_start == 0 ||
      summary_start >= footer_at) {
    return {};
  }
  if (footer_at - summary_start > kMaxSummaryBytes) return {};  // scan instead
  std::vector<uint8_t> summary(footer_at - summary_start);
  ReadExact(summary_start, summary.data(), summary.size());
  std::vector<std::pair<uint64_t, uint64_t>> chunks;  // (start time, offset)
  uint64_t at = 0;
  try {
    while (summary.size() - at >= 9) {
      uint64_t n = 0;
      std::memcpy(&n, summary.data() + at + 1, 8);
      if (n > summary.size() - at - 9) return {};  // damaged: scan instead
      const uint8_t opcode = summary[at];
      Cursor c(summary.data() + at + 9, n, path_, summary_start + at);
      if (opcode == kChunkIndex) {
        const uint64_t start_time = c.Get<uint64_t>();
        c.Skip(8);  // end time
        const uint64_t offset = c.Get<uint64_t>();
        if (offset < 8 || offset >= summary_start) return {};
        chunks.emplace_back(start_time, offset);
      } else if (opcode == kSchema || opcode == kChannel) {
        Record(opcode, summary.data() + at + 9, n, McapMessageRef::kNoChunk,
               summary_start + at + 9, {});
      }
      at += 9 + n;
    }
  } catch (const FormatError&) {
    return {};  // a damaged summary: the linear scan reads the data itself
  }
  if (chunks.empty() || !TopLevelRecords(summary_start)) return {};
  std::sort(chunks.begin(), chunks.end());
  std::vector<uint64_t> offsets;
  offsets.reserve(chunks.size());
  for (const auto& [time, offset] : chunks) offsets.push_back(offset);
  return offsets;
}

void McapReader::Scan(const Visitor& visit) {
  used_chunk_index_ = false;
  if (const std::vector<uint64_t> chunks = IndexedChunks(); !chunks.empty()) {
    used_chunk_index_ = true;
    for (uint64_t offset : chunks) VisitChunk(offset, visit);
    return;
  }
  uint64_t pos = 8;
  std::vector<uint8_t> body;
  while (pos < file_size_) {
    if (file_size_ - pos < 9) {
      spdlog::warn(
          "{}: ends inside a record header at byte {} (a recording "
          "cut short?); read what came before",
          path_.string(), pos);
      return;
    }
    std::array<uint8_t, 9> head{};
    ReadExact(pos, head.data(), head.size());
    const uint8_t opcode = head[0];
    uint64_t len = 0;
    std::memcpy(&len, head.data() + 1, 8);
    const uint64_t body_offset = pos + 9;
    if (len > file_size_ - body_offset) {
      spdlog::warn(
          "{}: the record at byte {} runs past the end of the file "
          "(a recording cut short?); read what came before",
          path_.string(), pos);
      return;
    }
    if (opcode == kDataEnd || opcode == kFooter) return;
    if (opcode == kSchema || opcode == kChannel || opcode == kMessage ||
        opcode == kChunk || opcode == kMetadata) {
      if (opcode == kChunk) {
        VisitChunk(pos, visit);
      } else {
        body.resize(len);
        ReadExact(body_offset, body.data(), body.size());
        Record(opcode, body.data(), len, McapMessageRef::kNoChunk, body_offset,
               visit);
      }
    }
    pos = body_offset + len;
  }
}

void McapReader::Record(uint8_t opcode, const uint8_t* body, uint64_t size,
                        uint64_t chunk_offset, uint64_t body_offset,
                        const Visitor& visit) {
  const uint64_t where =
      chunk_offset == McapMessageRef::kNoChunk ? body_offset : chunk_offset;
  Cursor c(body, size, path_, where);
  if (opcode == kSchema) {
    McapSchema s;
    s.id = c.Get<uint16_t>();
    s.name = c.String();
    s.encoding = c.String();
    s.data = c.String();
    schemas_[s.id] = std::move(s);
  } else if (opcode == kChannel) {
    McapChannel ch;
    ch.id = c.Get<uint16_t>();
    ch.schema_id = c.Get<uint16_t>();
    ch.topic = c.String();
    ch.message_encoding = c.String();
    ch.metadata = c.Map();
    channels_[ch.id] = std::move(ch);
  } else if (opcode == kMetadata) {
    McapMetadata m;
    m.name = c.String();
    m.values = c.Map();
    metadata_.push_back(std::move(m));
  } else if (opcode == kMessage) {
    McapMessageInfo info;
    info.channel_id = c.Get<uint16_t>();
    info.sequence = c.Get<uint32_t>();
    info.log_time_ns = c.Get<uint64_t>();
    info.publish_time_ns = c.Get<uint64_t>();
    info.ref.chunk_offset = chunk_offset;
    info.ref.offset = body_offset + kMessageHead;
    info.ref.size = c.left();
    if (!channels_.count(info.channel_id)) {
      throw FormatError(path_, fmt::format("MCAP message at byte {} names "
                                           "channel {}, which no Channel "
                                           "record before it defines",
                                           where, info.channel_id));
    }
    visit(info, c.here(), c.left());
  }
}

const std::vector<uint8_t>& McapReader::Chunk(uint64_t offset) {
  for (auto it = cache_.begin(); it != cache_.end(); ++it) {
    if (it->first != offset) continue;
    std::rotate(cache_.begin(), it, std::next(it));  // most recent first
    return cache_.front().second;
  }
  std::array<uint8_t, 9> head{};
  ReadExact(offset, head.data(), head.size());
  uint64_t len = 0;
  std::memcpy(&len, head.data() + 1, 8);
  if (head[0] != kChunk || len > file_size_ - offset - 9) {
    throw FormatError(path_, fmt::format("no MCAP chunk at byte {}", offset));
  }
  std::vector<uint8_t> body(len);
  ReadExact(offset + 9, body.data(), body.size());
  Cursor c(body.data(), body.size(), path_, offset);
  c.Skip(16);  // message start and end time
  const uint64_t out_size = c.Get<uint64_t>();
  const uint32_t crc = c.Get<uint32_t>();
  const std::string compression = c.String();
  const uint64_t n = c.Get<uint64_t>();
  if (n > c.left()) {
    throw FormatError(path_, fmt::format("MCAP chunk at byte {}: its records "
                                         "run past the record's end",
                                         offset));
  }
  if (out_size > kMaxChunkBytes) {
    throw FormatError(path_,
                      fmt::format("MCAP chunk at byte {}: {} bytes "
                                  "uncompressed (over the {} MiB "
                                  "semrec accepts)",
                                  offset, out_size, kMaxChunkBytes >> 20));
  }
  std::vector<uint8_t> records;
  if (compression.empty()) {
    if (n != out_size) {
      throw FormatError(path_, fmt::format("MCAP chunk at byte {}: {} bytes "
                                           "of records, the chunk says {}",
                                           offset, n, out_size));
    }
    records.assign(c.here(), c.here() + n);
  } else if (compression == "zstd") {
    records = DecompressZstd(c.here(), n, out_size, path_, offset);
  } else if (compression == "lz4") {
    records = DecompressLz4(c.here(), n, out_size, path_, offset);
  } else {
    throw FormatError(path_, fmt::format("MCAP chunk at byte {}: unknown "
                                         "compression '{}' (semrec reads "
                                         "none, zstd and lz4)",
                                         offset, compression));
  }
  if (crc != 0) {
    const uLong got = crc32(crc32(0L, Z_NULL, 0), records.data(),
                            static_cast<uInt>(records.size()));
    if (got != crc) {
      throw FormatError(path_, fmt::format("MCAP chunk at byte {}: CRC "
                                           "mismatch (file says {:08x}, data "
                                           "gives {:08x}): the file is "
                                           "damaged",
                                           offset, crc, got));
    }
  }
  ++compressions_[compression];
  // Evicted by count, and by size so that large chunks are not all held.
  size_t held = records.size();
  for (const auto& [unused, r] : cache_) held += r.size();
  while (!cache_.empty() &&
         (cache_.size() >= kCachedChunks || held > kCachedBytes)) {
    held -= cache_.back().second.size();
    cache_.pop_back();
  }
  cache_.emplace_front(offset, std::move(records));
  return cache_.front().second;
}

std::vector<uint8_t> McapReader::Read(const McapMessageRef& ref) {
  if (ref.chunk_offset == McapMessageRef::kNoChunk) {
    if (ref.offset > file_size_ || ref.size > file_size_ - ref.offset) {
      throw FormatError(path_,
                        fmt::format("no message at byte {}", ref.offset));
    }
    std::vector<uint8_t> out(ref.size);
    ReadExact(ref.offset, out.data(), out.size());
    return out;
  }
  const std::vector<uint8_t>& records = Chunk(ref.chunk_offset);
  if (ref.offset > records.size() || ref.size > records.size() - ref.offset) {
    throw FormatError(path_, fmt::format("no message at offset {} of the "
                                         "chunk at byte {}",
                                         ref.offset, ref.chunk_offset));
  }
  return {records.begin() + static_cast<std::ptrdiff_t>(ref.offset),
          records.begin() + static_cast<std::ptrdiff_t>(ref.offset + ref.size)};
}

}  // namespace semrec::io
