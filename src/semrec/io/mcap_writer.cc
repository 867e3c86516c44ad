#include "semrec/io/mcap_writer.h"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <fstream>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace semrec::io {
namespace {

template <typename T>
void Put(std::vector<uint8_t>* out, T v) {
  const size_t at = out->size();
  out->resize(at + sizeof(T));
  std::memcpy(out->data() + at, &v, sizeof(T));
}
void PutString(std::vector<uint8_t>* out, const std::string& s) {
  Put<uint32_t>(out, static_cast<uint32_t>(s.size()));
  out->insert(out->end(), s.begin(), s.end());
}
void PutRecord(std::vector<uint8_t>* out, uint8_t opcode,
               const std::vector<uint8_t>& body) {
  out->push_back(opcode);
  Put<uint64_t>(out, body.size());
  out->insert(out->end(), body.begin(), body.end());
}
void PutMagic(std::vector<uint8_t>* out) {
  const uint8_t magic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
  out->insert(out->end(), magic, magic + 8);
}

}  // namespace

McapWriter::McapWriter(const std::filesystem::path& path,
                       const McapWriterOptions& options)
    : path_(path), options_(options) {
  CheckArgument(options.compression.empty() || options.compression == "zstd" ||
                    options.compression == "lz4",
                "MCAP writer: compression must be '', zstd or lz4");
  PutMagic(&out_);
  std::vector<uint8_t> header;
  PutString(&header, options.profile);
  PutString(&header, "semrec");
  PutRecord(&out_, 0x01, header);
}

McapWriter::~McapWriter() {
  if (!closed_) {
    try {
      Close();
    } catch (
        ...) {  // NOLINT(bugprone-empty-catch): a destructor must not throw
    }
  }
}

uint16_t McapWriter::AddSchema(const std::string& name,
                               const std::string& encoding,
                               const std::string& data) {
  std::vector<uint8_t> body;
  const uint16_t id = next_schema_++;
  Put<uint16_t>(&body, id);
  PutString(&body, name);
  PutString(&body, encoding);
  PutString(&body, data);
  PutRecord(&out_, 0x03, body);
  return id;
}

uint16_t McapWriter::AddChannel(uint16_t schema_id, const std::string& topic,
                                const std::string& message_encoding) {
  std::vector<uint8_t> body;
  const uint16_t id = next_channel_++;
  Put<uint16_t>(&body, id);
  Put<uint16_t>(&body, schema_id);
  PutString(&body, topic);
  PutString(&body, message_encoding);
  Put<uint32_t>(&body, 0);  // no metadata
  PutRecord(&out_, 0x04, body);
  return id;
}

void McapWriter::AddMetadata(const std::string& name,
                             const std::map<std::string, std::string>& values) {
  std::vector<uint8_t> map;
  for (const auto& [k, v] : values) {
    PutString(&map, k);
    PutString(&map, v);
  }
  std::vector<uint8_t> body;
  PutString(&body, name);
  Put<uint32_t>(&body, static_cast<uint32_t>(map.size()));
  body.insert(body.end(), map.begin(), map.end());
  PutRecord(&out_, 0x0C, body);
}

void McapWriter::Write(uint16_t channel_id, uint64_t log_time_ns,
                       const std::vector<uint8_t>& data) {
  CheckArgument(!closed_, "MCAP writer: Write() after Close()");
  std::vector<uint8_t> body;
  Put<uint16_t>(&body, channel_id);
  Put<uint32_t>(&body, sequence_[channel_id]++);
  Put<uint64_t>(&body, log_time_ns);
  Put<uint64_t>(&body, log_time_ns);
  body.insert(body.end(), data.begin(), data.end());
  if (!options_.chunked) {
    PutRecord(&out_, 0x05, body);
    return;
  }
  if (chunk_.empty()) {
    chunk_start_ = log_time_ns;
  } else {
    chunk_start_ = std::min(chunk_start_, log_time_ns);
  }
  chunk_end_ = std::max(chunk_end_, log_time_ns);
  PutRecord(&chunk_, 0x05, body);
  if (chunk_.size() >= options_.chunk_bytes) FlushChunk();
}

void McapWriter::FlushChunk() {
  if (chunk_.empty()) return;
  std::vector<uint8_t> packed;
  if (options_.compression == "zstd") {
    packed.resize(ZSTD_compressBound(chunk_.size()));
    const size_t n = ZSTD_compress(packed.data(), packed.size(), chunk_.data(),
                                   chunk_.size(), 1);
    if (ZSTD_isError(n)) throw Error("zstd compression failed");
    packed.resize(n);
  } else if (options_.compression == "lz4") {
    packed.resize(LZ4F_compressFrameBound(chunk_.size(), nullptr));
    const size_t n = LZ4F_compressFrame(packed.data(), packed.size(),
                                        chunk_.data(), chunk_.size(), nullptr);
    if (LZ4F_isError(n)) throw Error("lz4 compression failed");
    packed.resize(n);
  } else {
    packed = chunk_;
  }
  std::vector<uint8_t> body;
  Put<uint64_t>(&body, chunk_start_);
  Put<uint64_t>(&body, chunk_end_);
  Put<uint64_t>(&body, chunk_.size());
  const uint32_t crc =
      options_.crc
          ? static_cast<uint32_t>(crc32(crc32(0L, Z_NULL, 0), chunk_.data(),
                                        static_cast<uInt>(chunk_.size())))
          : 0;
  Put<uint32_t>(&body, crc);
  PutString(&body, options_.compression);
  Put<uint64_t>(&body, packed.size());
  body.insert(body.end(), packed.begin(), packed.end());
  PutRecord(&out_, 0x06, body);
  chunk_.clear();
  chunk_end_ = 0;
}

void McapWriter::Close() {
  if (closed_) return;
  closed_ = true;
  FlushChunk();
  std::vector<uint8_t> data_end;
  Put<uint32_t>(&data_end, 0);
  PutRecord(&out_, 0x0F, data_end);
  std::vector<uint8_t> footer;
  Put<uint64_t>(&footer, 0);
  Put<uint64_t>(&footer, 0);
  Put<uint32_t>(&footer, 0);
  PutRecord(&out_, 0x02, footer);
  PutMagic(&out_);
  WriteFileAtomic(path_, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f.write(reinterpret_cast<const char*>(out_.data()),
            static_cast<std::streamsize>(out_.size()));
    if (!f) throw IoError(tmp, "cannot write the MCAP file");
  });
}

}  // namespace semrec::io
