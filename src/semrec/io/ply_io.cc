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

PlyData ReadPly(const fs::path& path) {
  const std::vector<unsigned char> bytes = ReadFileBytes(path);
  const std::string text(bytes.begin(), bytes.end());
  const size_t end = text.find("end_header\n");
  if (text.rfind("ply", 0) != 0 || end == std::string::npos) {
    throw FormatError(path,
                      "not a PLY file (missing 'ply' magic or 'end_header')");
  }
  std::istringstream header(text.substr(0, end));
  std::string line, format;
  struct Element {
    std::string name;
    size_t count = 0;
    std::vector<Property> properties;
  };
  std::vector<Element> elements;
  while (std::getline(header, line)) {
    std::istringstream tokens(line);
    std::string keyword;
    tokens >> keyword;
    if (keyword == "format") {
      tokens >> format;
    } else if (keyword == "element") {
      Element e;
      tokens >> e.name >> e.count;
      elements.push_back(e);
    } else if (keyword == "property") {
      if (elements.empty()) {
        throw FormatError(path, "property before any element");
      }
      Property prop;
      tokens >> prop.type;
      if (prop.type == "list") {
        prop.is_list = true;
        tokens >> prop.count_type >> prop.type;
      }
      tokens >> prop.name;
      elements.back().properties.push_back(prop);
    }
  }
  if (format != "binary_little_endian" && format != "ascii") {
    throw FormatError(path, "unsupported PLY format '" + format + "'");
  }
  const bool binary = format == "binary_little_endian";
  PlyData out;
  size_t offset = end + std::string("end_header\n").size();
  std::istringstream ascii(binary ? std::string() : text.substr(offset));
  auto next_value = [&](const std::string& type) -> double {
    if (binary) {
      const size_t size = TypeSize(path, type);
      if (offset + size > bytes.size()) {
        throw FormatError(path, "file is truncated");
      }
      const double v = ReadBinaryValue(text.data() + offset, type);
      offset += size;
      return v;
    }
    double v = 0;
    if (!(ascii >> v)) {
      throw FormatError(path, "file is truncated or has a non-number");
    }
    return v;
  };
  static const std::set<std::string> kKnown = {"x",     "y",    "z",    "red",
                                               "green", "blue", "label"};
  for (const Element& e : elements) {
    const bool vertex = e.name == "vertex", face = e.name == "face";
    // Every item takes at least a byte (binary) or a character (ASCII), so a
    // header count beyond the file's size is a lie: refuse it before looping
    // or allocating.
    const size_t remaining = bytes.size() - std::min(offset, bytes.size());
    if (e.count > 0 && (e.properties.empty() || e.count > remaining)) {
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
        if (!prop.is_list && kKnown.count(prop.name) == 0 &&
            extra.count(prop.name) == 0) {
          extra[prop.name] = out.int_properties.size();
          out.int_properties.emplace_back(prop.name, std::vector<int32_t>());
        }
      }
    }
    for (size_t i = 0; i < e.count; ++i) {
      Eigen::Vector3f p = Eigen::Vector3f::Zero();
      std::array<uint8_t, 3> c{};
      bool has_color = false, has_label = false;
      uint32_t label = 0;
      for (const Property& prop : e.properties) {
        if (prop.is_list) {
          const auto k = As<size_t>(next_value(prop.count_type), path,
                                    prop.name);
          if (k > bytes.size()) {
            throw FormatError(path, fmt::format("a '{}' list claims {} items, "
                                                "more than the file holds",
                                                prop.name, k));
          }
          std::vector<uint32_t> idx(k);
          for (auto& v : idx) {
            v = As<uint32_t>(next_value(prop.type), path, prop.name);
          }
          if (face) {
            // Fan-triangulate polygons.
            for (size_t j = 2; j < k; ++j) {
              out.triangles.push_back({idx[0], idx[j - 1], idx[j]});
            }
          }
          continue;
        }
        const double v = next_value(prop.type);
        if (!vertex) continue;
        if (prop.name == "x") {
          p.x() = As<float>(v, path, prop.name);
        } else if (prop.name == "y") {
          p.y() = As<float>(v, path, prop.name);
        } else if (prop.name == "z") {
          p.z() = As<float>(v, path, prop.name);
        } else if (prop.name == "red") {
          c[0] = As<uint8_t>(v, path, prop.name, true), has_color = true;
        } else if (prop.name == "green") {
          c[1] = As<uint8_t>(v, path, prop.name, true);
        } else if (prop.name == "blue") {
          c[2] = As<uint8_t>(v, path, prop.name, true);
        } else if (prop.name == "label") {
          label = As<uint32_t>(v, path, prop.name), has_label = true;
        } else if (const auto it = extra.find(prop.name); it != extra.end()) {
          out.int_properties[it->second].second.push_back(
              As<int32_t>(v, path, prop.name, true));
        }
      }
      if (vertex) {
        out.points.push_back(p);
        if (has_color) out.colors.push_back(c);
        if (has_label) out.labels.push_back(label);
      }
    }
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
