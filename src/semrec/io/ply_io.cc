#include "semrec/io/ply_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include <fmt/format.h>

#include "semrec/core/checked_cast.h"
#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace fs = std::filesystem;

namespace semrec::io {

void WritePly(const fs::path& path, const PlyData& data) {
  const size_t n = data.points.size();
  CheckArgument(data.colors.empty() || data.colors.size() == n,
                path.string() + ": colours must be empty or one per point");
  CheckArgument(data.labels.empty() || data.labels.size() == n,
                path.string() + ": labels must be empty or one per point");
  for (const auto& t : data.triangles) {
    CheckArgument(t[0] < n && t[1] < n && t[2] < n,
                  path.string() + ": triangle index out of range");
  }
  for (const auto& [name, values] : data.int_properties) {
    CheckArgument(values.size() == n && !name.empty() &&
                      name.find_first_of(" \n") == std::string::npos,
                  path.string() + ": property '" + name +
                      "' must be a name without spaces with one value per "
                      "point");
  }
  std::string header = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment written by "
      "semrec\nelement vertex {}\n"
      "property float x\nproperty float y\nproperty float z\n",
      n);
  if (!data.colors.empty()) {
    header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  }
  if (!data.labels.empty()) header += "property uint label\n";
  for (const auto& property : data.int_properties) {
    header += "property int " + property.first + "\n";
  }
  if (!data.triangles.empty()) {
    header += fmt::format(
        "element face {}\nproperty list uchar uint vertex_indices\n",
        data.triangles.size());
  }
  header += "end_header\n";
  const size_t vertex_bytes = 12 + (data.colors.empty() ? 0 : 3) +
                              (data.labels.empty() ? 0 : 4) +
                              4 * data.int_properties.size();
  std::string body(n * vertex_bytes + data.triangles.size() * 13, '\0');
  char* p = body.data();
  for (size_t i = 0; i < n; ++i) {
    std::memcpy(p, data.points[i].data(), 12);
    p += 12;
    if (!data.colors.empty()) {
      std::memcpy(p, data.colors[i].data(), 3);
      p += 3;
    }
    if (!data.labels.empty()) {
      std::memcpy(p, &data.labels[i], 4);
      p += 4;
    }
    for (const auto& property : data.int_properties) {
      std::memcpy(p, &property.second[i], 4);
      p += 4;
    }
  }
  for (const auto& t : data.triangles) {
    *p++ = 3;
    std::memcpy(p, t.data(), 12);
    p += 12;
  }
  WriteTextFileAtomic(path, header + body);
}

namespace {

struct Property {
  std::string name;
  std::string type;
  bool is_list = false;
  std::string count_type;
};

size_t TypeSize(const fs::path& path, const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") {
    return 1;
  }
  if (type == "short" || type == "ushort" || type == "int16" ||
      type == "uint16") {
    return 2;
  }
  if (type == "int" || type == "uint" || type == "float" || type == "int32" ||
      type == "uint32" || type == "float32") {
    return 4;
  }
  if (type == "double" || type == "float64") return 8;
  throw FormatError(path, "unknown PLY property type '" + type + "'");
}

double ReadBinaryValue(const char* p, const std::string& type) {
  auto get = [p](auto v) {
    std::memcpy(&v, p, sizeof(v));
    return static_cast<double>(v);
  };
  if (type == "char" || type == "int8") return get(int8_t{});
  if (type == "uchar" || type == "uint8") return get(uint8_t{});
  if (type == "short" || type == "int16") return get(int16_t{});
  if (type == "ushort" || type == "uint16") return get(uint16_t{});
  if (type == "int" || type == "int32") return get(int32_t{});
  if (type == "uint" || type == "uint32") return get(uint32_t{});
  if (type == "float" || type == "float32") return get(float{});
  return get(double{});
}

// A value of the file as T, or a FormatError naming the property.
template <typename T>
T As(double v, const fs::path& path, const std::string& property,
     bool round = false) {
  const std::optional<T> out = CheckedCast<T>(v, round);
  if (!out) {
    throw FormatError(path, fmt::format("property '{}': value {} is out of "
                                        "range",
                                        property, v));
  }
  return *out;
}

}  // namespace

namespace {

struct Element {
  std::string name;
  size_t count = 0;
  std::vector<Property> properties;
};

struct Header {
  bool binary = false;
  std::vector<Element> elements;
  size_t body_offset = 0;  // bytes
};

Header ParseHeader(const std::string& text, const fs::path& path) {
  const size_t end = text.find("end_header\n");
  if (text.rfind("ply", 0) != 0 || end == std::string::npos) {
    throw FormatError(path,
                      "not a PLY file (missing 'ply' magic or 'end_header')");
  }
  std::istringstream lines(text.substr(0, end));
  std::string line, format;
  Header header;
  while (std::getline(lines, line)) {
    std::istringstream tokens(line);
    std::string keyword;
    tokens >> keyword;
    if (keyword == "format") {
      tokens >> format;
    } else if (keyword == "element") {
      Element e;
      tokens >> e.name >> e.count;
      header.elements.push_back(e);
    } else if (keyword == "property") {
      if (header.elements.empty()) {
        throw FormatError(path, "property before any element");
      }
      Property prop;
      tokens >> prop.type;
      if (prop.type == "list") {
        prop.is_list = true;
        tokens >> prop.count_type >> prop.type;
      }
      tokens >> prop.name;
      header.elements.back().properties.push_back(prop);
    }
  }
  if (format != "binary_little_endian" && format != "ascii") {
    throw FormatError(path, "unsupported PLY format '" + format + "'");
  }
  header.binary = format == "binary_little_endian";
  header.body_offset = end + std::string("end_header\n").size();
  return header;
}

// The body's values one after the other, binary or ASCII.
class ValueReader {
 public:
  ValueReader(const std::string& text, const Header& header,
              const fs::path& path)
      : text_(text),
        path_(path),
        binary_(header.binary),
        offset_(header.body_offset),
        ascii_(binary_ ? std::string() : text.substr(header.body_offset)) {}

  double Next(const std::string& type) {
    if (binary_) {
      const size_t size = TypeSize(path_, type);
      if (offset_ + size > text_.size()) {
        throw FormatError(path_, "file is truncated");
      }
      const double v = ReadBinaryValue(text_.data() + offset_, type);
      offset_ += size;
      return v;
    }
    double v = 0;
    if (!(ascii_ >> v)) {
      throw FormatError(path_, "file is truncated or has a non-number");
    }
    return v;
  }

  // Bytes after the binary read position (an upper bound for ASCII).
  size_t Remaining() const {
    return text_.size() - std::min(offset_, text_.size());
  }

 private:
  const std::string& text_;
  const fs::path& path_;
  bool binary_;
  size_t offset_;
  std::istringstream ascii_;
};

const std::set<std::string>& KnownVertexProperties() {
  static const std::set<std::string> kKnown = {"x",     "y",    "z",    "red",
                                               "green", "blue", "label"};
  return kKnown;
}

// One list property's items; a face's polygon is fan-triangulated into out.
void ReadList(const Property& prop, bool face, size_t file_bytes,
              ValueReader* values, const fs::path& path, PlyData* out) {
  const auto k = As<size_t>(values->Next(prop.count_type), path, prop.name);
  if (k > file_bytes) {
    throw FormatError(path, fmt::format("a '{}' list claims {} items, more "
                                        "than the file holds",
                                        prop.name, k));
  }
  std::vector<uint32_t> idx(k);
  for (auto& v : idx) {
    v = As<uint32_t>(values->Next(prop.type), path, prop.name);
  }
  if (!face) return;
  for (size_t j = 2; j < k; ++j) {
    out->triangles.push_back({idx[0], idx[j - 1], idx[j]});
  }
}

// One vertex's scalar property into the vertex being read.
struct Vertex {
  Eigen::Vector3f p = Eigen::Vector3f::Zero();
  std::array<uint8_t, 3> c{};
  bool has_color = false, has_label = false;
  uint32_t label = 0;
};

void SetVertexProperty(const std::string& name, double v,
                       const std::map<std::string, size_t>& extra,
                       const fs::path& path, Vertex* vertex, PlyData* out) {
  if (name == "x") {
    vertex->p.x() = As<float>(v, path, name);
  } else if (name == "y") {
    vertex->p.y() = As<float>(v, path, name);
  } else if (name == "z") {
    vertex->p.z() = As<float>(v, path, name);
  } else if (name == "red") {
    vertex->c[0] = As<uint8_t>(v, path, name, true), vertex->has_color = true;
  } else if (name == "green") {
    vertex->c[1] = As<uint8_t>(v, path, name, true);
  } else if (name == "blue") {
    vertex->c[2] = As<uint8_t>(v, path, name, true);
  } else if (name == "label") {
    vertex->label = As<uint32_t>(v, path, name), vertex->has_label = true;
  } else if (const auto it = extra.find(name); it != extra.end()) {
    out->int_properties[it->second].second.push_back(
        As<int32_t>(v, path, name, true));
  }
}

void ReadElement(const Element& e, size_t file_bytes, ValueReader* values,
                 const fs::path& path, PlyData* out) {
  const bool vertex = e.name == "vertex", face = e.name == "face";
  // Every item takes at least a byte (binary) or a character (ASCII), so a
  // header count beyond the file's size is a lie: refuse it before looping
  // or allocating.
  if (e.count > 0 && (e.properties.empty() || e.count > values->Remaining())) {
    throw FormatError(
        path, fmt::format("element '{}' claims {} items{}, more than the "
                          "file holds",
                          e.name, e.count,
                          e.properties.empty() ? " without properties" : ""));
  }
  // Columns for the other scalar vertex properties.
  std::map<std::string, size_t> extra;
  if (vertex) {
    for (const Property& prop : e.properties) {
      if (!prop.is_list && KnownVertexProperties().count(prop.name) == 0 &&
          extra.count(prop.name) == 0) {
        extra[prop.name] = out->int_properties.size();
        out->int_properties.emplace_back(prop.name, std::vector<int32_t>());
      }
    }
  }
  for (size_t i = 0; i < e.count; ++i) {
    Vertex v;
    for (const Property& prop : e.properties) {
      if (prop.is_list) {
        ReadList(prop, face, file_bytes, values, path, out);
        continue;
      }
      const double value = values->Next(prop.type);
      if (vertex) SetVertexProperty(prop.name, value, extra, path, &v, out);
    }
    if (vertex) {
      out->points.push_back(v.p);
      if (v.has_color) out->colors.push_back(v.c);
      if (v.has_label) out->labels.push_back(v.label);
    }
  }
}

}  // namespace

PlyData ReadPly(const fs::path& path) {
  const std::vector<unsigned char> bytes = ReadFileBytes(path);
  const std::string text(bytes.begin(), bytes.end());
  const Header header = ParseHeader(text, path);
  ValueReader values(text, header, path);
  PlyData out;
  for (const Element& e : header.elements) {
    ReadElement(e, bytes.size(), &values, path, &out);
  }
  for (const auto& t : out.triangles) {
    if (t[0] >= out.points.size() || t[1] >= out.points.size() ||
        t[2] >= out.points.size()) {
      throw FormatError(path, "face index out of range");
    }
  }
  return out;
}

}  // namespace semrec::io
