#include "semrec/usd/usdz.h"

#include <array>
#include <set>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace semrec::usd {
namespace {

constexpr size_t kAlignment = 64;
// Extra-field id for the alignment padding (private ids are allowed by the zip
// format; readers skip unknown ones).
constexpr uint16_t kPaddingFieldId = 0x1986;

void Put16(std::string* out, uint16_t v) {
  out->push_back(static_cast<char>(v & 0xff));
  out->push_back(static_cast<char>(v >> 8));
}

void Put32(std::string* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) {
    out->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  }
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

uint32_t Crc32(const std::string& data) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char byte : data) crc = table[(crc ^ byte) & 0xff] ^ (crc >> 8);
  return crc ^ 0xFFFFFFFFu;
}

std::string UsdzBytes(
    const std::vector<std::pair<std::string, std::string>>& files) {
  CheckArgument(!files.empty(), "usdz: no files to package");
  const std::string& first = files.front().first;
  CheckArgument(
      EndsWith(first, ".usda") || EndsWith(first, ".usdc") ||
          EndsWith(first, ".usd"),
      "usdz: the first file must be a USD layer, got '" + first + "'");
  std::set<std::string> names;
  std::string out, central;
  for (const auto& [name, content] : files) {
    CheckArgument(!name.empty() && name.front() != '/' &&
                      name.find("..") == std::string::npos &&
                      name.find('\\') == std::string::npos,
                  "usdz: bad file name '" + name + "'");
    CheckArgument(names.insert(name).second,
                  "usdz: duplicate file name '" + name + "'");
    CheckArgument(name.size() < 0xffff && content.size() < 0xffffffffu &&
                      out.size() + content.size() < 0xffffffffu,
                  "usdz: archive over 4 GiB (zip64 is not supported)");
    const uint32_t crc = Crc32(content);
    const uint32_t offset = static_cast<uint32_t>(out.size());
    // Padding so the data starts on a 64-byte boundary: an extra field of at
    // least its 4-byte header.
    const size_t base = out.size() + 30 + name.size();
    size_t extra = (kAlignment - base % kAlignment) % kAlignment;
    if (extra > 0 && extra < 4) extra += kAlignment;
    Put32(&out, 0x04034b50);  // local file header
    Put16(&out, 20);          // version needed
    Put16(&out, 0);           // flags
    Put16(&out, 0);           // stored, no compression
    Put16(&out, 0);           // time
    Put16(&out, 0x21);        // date: 1980-01-01 (fixed: reproducible files)
    Put32(&out, crc);
    Put32(&out, static_cast<uint32_t>(content.size()));
    Put32(&out, static_cast<uint32_t>(content.size()));
    Put16(&out, static_cast<uint16_t>(name.size()));
    Put16(&out, static_cast<uint16_t>(extra));
    out += name;
    if (extra > 0) {
      Put16(&out, kPaddingFieldId);
      Put16(&out, static_cast<uint16_t>(extra - 4));
      out.append(extra - 4, '\0');
    }
    out += content;

    Put32(&central, 0x02014b50);  // central directory header
    Put16(&central, 20);          // version made by
    Put16(&central, 20);          // version needed
    Put16(&central, 0);
    Put16(&central, 0);
    Put16(&central, 0);
    Put16(&central, 0x21);
    Put32(&central, crc);
    Put32(&central, static_cast<uint32_t>(content.size()));
    Put32(&central, static_cast<uint32_t>(content.size()));
    Put16(&central, static_cast<uint16_t>(name.size()));
    Put16(&central, 0);  // no extra field here
    Put16(&central, 0);  // no comment
    Put16(&central, 0);  // disk
    Put16(&central, 0);  // internal attributes
    Put32(&central, 0);  // external attributes
    Put32(&central, offset);
    central += name;
  }
  const uint32_t central_offset = static_cast<uint32_t>(out.size());
  out += central;
  Put32(&out, 0x06054b50);  // end of central directory
  Put16(&out, 0);
  Put16(&out, 0);
  Put16(&out, static_cast<uint16_t>(files.size()));
  Put16(&out, static_cast<uint16_t>(files.size()));
  Put32(&out, static_cast<uint32_t>(central.size()));
  Put32(&out, central_offset);
  Put16(&out, 0);
  return out;
}

void WriteUsdz(const std::filesystem::path& path,
               const std::vector<std::pair<std::string, std::string>>& files) {
  WriteTextFileAtomic(path, UsdzBytes(files));
}

}  // namespace semrec::usd
