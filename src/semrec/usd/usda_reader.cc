#include "semrec/usd/usda_reader.h"

#include <algorithm>
#include <array>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>

#include <fmt/format.h>

#include "semrec/core/checked_cast.h"
#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace fs = std::filesystem;

namespace semrec::usd {
namespace {

// Numbers inside the brackets of an array value.
std::vector<double> Numbers(const std::string& line, const fs::path& path,
                            int line_number) {
  const auto open = line.find('['), close = line.rfind(']');
  if (open == std::string::npos || close == std::string::npos || close < open) {
    throw FormatError(
        path, fmt::format("line {}: expected an array value", line_number));
  }
  std::string body = line.substr(open + 1, close - open - 1);
  for (char& c : body) {
    if (c == '(' || c == ')' || c == ',') c = ' ';
  }
  std::istringstream in(body);
  std::vector<double> out;
  double x;
  while (in >> x) out.push_back(x);
  if (!in.eof()) {
    throw FormatError(path,
                      fmt::format("line {}: bad number in array", line_number));
  }
  return out;
}

// A scalar attribute value as T (an unsigned count or id, or a double).
template <typename T>
T Scalar(const std::string& value, const fs::path& path, int line_number) {
  std::istringstream in(value);
  double v = 0.0;
  std::optional<T> out;
  if (in >> v) out = CheckedCast<T>(v);
  if (!out || (in >> std::ws, !in.eof())) {
    throw FormatError(
        path, fmt::format("line {}: bad value '{}'", line_number, value));
  }
  return *out;
}

std::string Unquote(const std::string& s) {
  std::string out;
  for (size_t i = 1; i + 1 < s.size(); ++i) {
    if (s[i] == '\\' && i + 2 < s.size()) ++i;
    out += s[i];
  }
  return out;
}

// Triangles must index the mesh's points: consumers index with them.
void CheckMesh(const MeshPrim& mesh, const fs::path& path) {
  for (const auto& t : mesh.triangles) {
    for (uint32_t i : t) {
      if (i >= mesh.points.size()) {
        throw FormatError(path, fmt::format("mesh '{}': face index {} is out "
                                            "of range ({} points)",
                                            mesh.label, i, mesh.points.size()));
      }
    }
  }
}

// `open` holds the layers being read, outermost first: a layer that names one
// of them is a cycle.
void ReadLayer(const fs::path& path, std::vector<MeshPrim>* meshes,
               std::vector<fs::path>* open) {
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(path, ec);
  if (std::find(open->begin(), open->end(), canonical) != open->end()) {
    throw FormatError(path, "subLayers form a cycle");
  }
  if (open->size() > 16) throw FormatError(path, "subLayers nested too deeply");
  open->push_back(canonical);
  std::istringstream in(ReadTextFile(path));
  std::string line;
  if (!std::getline(in, line) || line.rfind("#usda 1.0", 0) != 0) {
    throw FormatError(path, "not a USDA file (missing '#usda 1.0' header)");
  }
  static const std::regex sublayer(R"re(@([^@]+)@)re");
  static const std::regex mesh(R"re(^\s*def Mesh "([^"]+)")re");
  bool in_sublayers = false;
  int line_number = 1;
  // An index, not a pointer: sublayers read later append to `meshes`.
  std::optional<size_t> current;
  const size_t first = meshes->size();
  while (std::getline(in, line)) {
    ++line_number;
    std::smatch m;
    if (line.find("subLayers") != std::string::npos) in_sublayers = true;
    if (in_sublayers) {
      for (auto it = std::sregex_iterator(line.begin(), line.end(), sublayer);
           it != std::sregex_iterator(); ++it) {
        ReadLayer(path.parent_path() / (*it)[1].str(), meshes, open);
      }
      if (line.find(']') != std::string::npos) in_sublayers = false;
      continue;
    }
    if (line.find("def Mesh") != std::string::npos &&
        std::regex_search(line, m, mesh)) {
      meshes->emplace_back();
      current = meshes->size() - 1;
      continue;
    }
    // "[custom|uniform] <type> <name> = <value>"; parsed by hand: value lines
    // of big meshes are megabytes long, too long for std::regex.
    const size_t eq = line.find(" = ");
    if (!current || eq == std::string::npos) continue;
    MeshPrim& mesh = (*meshes)[*current];
    std::istringstream head(line.substr(0, eq));
    std::string word, name;
    while (head >> word) name = word;
    const std::string value = line.substr(eq + 3);
    if (name == "points") {
      const auto v = Numbers(value, path, line_number);
      if (v.size() % 3 != 0) {
        throw FormatError(path, fmt::format("line {}: points", line_number));
      }
      for (size_t i = 0; i < v.size(); i += 3) {
        mesh.points.emplace_back(static_cast<float>(v[i]),
                                 static_cast<float>(v[i + 1]),
                                 static_cast<float>(v[i + 2]));
      }
    } else if (name == "faceVertexIndices") {
      const auto v = Numbers(value, path, line_number);
      if (v.size() % 3 != 0) {
        throw FormatError(
            path,
            fmt::format("line {}: only triangles are supported", line_number));
      }
      for (size_t i = 0; i < v.size(); i += 3) {
        std::array<uint32_t, 3> t{};
        for (int k = 0; k < 3; ++k) {
          const auto index = CheckedCast<uint32_t>(v[i + k]);
          if (!index) {
            throw FormatError(path, fmt::format("line {}: bad face index {}",
                                                line_number, v[i + k]));
          }
          t[k] = *index;
        }
        mesh.triangles.push_back(t);
      }
    } else if (name == "semrec:label") {
      mesh.label = Unquote(value);
    } else if (name == "semrec:kind") {
      mesh.structure = Unquote(value) == "stuff";
    } else if (name == "semrec:instanceId") {
      mesh.instance_id = Scalar<uint32_t>(value, path, line_number);
    } else if (name == "semrec:pointCount") {
      mesh.point_count =
          Scalar<decltype(mesh.point_count)>(value, path, line_number);
    } else if (name == "semrec:firstSeenFrame") {
      mesh.first_seen_frame =
          Scalar<decltype(mesh.first_seen_frame)>(value, path, line_number);
    } else if (name == "semrec:lastSeenFrame") {
      mesh.last_seen_frame =
          Scalar<decltype(mesh.last_seen_frame)>(value, path, line_number);
    } else if (name == "semrec:confidence") {
      mesh.confidence = Scalar<double>(value, path, line_number);
    }
  }
  for (size_t i = first; i < meshes->size(); ++i) CheckMesh((*meshes)[i], path);
  open->pop_back();
}

}  // namespace

std::vector<MeshPrim> ReadScene(const fs::path& path) {
  std::vector<MeshPrim> meshes;
  std::vector<fs::path> open;
  ReadLayer(path, &meshes, &open);
  return meshes;
}

std::map<std::string, std::string> ReadCustomLayerData(const fs::path& path) {
  // Line by line: the metadata is at the top, the prims below can be large.
  std::ifstream in(path);
  if (!in) throw IoError(path, "cannot open the layer");
  std::string line;
  int line_number = 0;
  const auto next = [&] {
    if (!std::getline(in, line)) return false;
    ++line_number;
    const size_t b = line.find_first_not_of(" \t\r");
    line = b == std::string::npos
               ? std::string()
               : line.substr(b, line.find_last_not_of(" \t\r") - b + 1);
    return true;
  };
  if (!next() || line.rfind("#usda 1.0", 0) != 0) {
    throw FormatError(path, "not a USDA file (missing '#usda 1.0' header)");
  }
  std::map<std::string, std::string> data;
  // Layer metadata is a "( ... )" block right after the header, if any.
  while (next() && line.empty()) {
  }
  if (line != "(") return data;
  // Depth inside customLayerData's braces; nested dictionaries are skipped.
  int depth = 0;
  while (next()) {
    if (depth == 0) {
      if (line == ")") return data;
      if (line.rfind("customLayerData", 0) == 0 && line.back() == '{')
        depth = 1;
      continue;
    }
    if (line == "}") {
      --depth;
      continue;
    }
    if (!line.empty() && line.back() == '{') ++depth;
    if (depth > 1) continue;  // a nested dictionary or its entries
    // "<type> <name> = <value>"
    const size_t eq = line.find(" = ");
    std::istringstream head(line.substr(0, eq));
    std::string type, name;
    if (eq == std::string::npos || !(head >> type >> name)) {
      throw FormatError(path,
                        fmt::format("line {}: bad customLayerData entry '{}'",
                                    line_number, line));
    }
    const std::string value = line.substr(eq + 3);
    data[name] =
        value.size() >= 2 && value.front() == '"' ? Unquote(value) : value;
  }
  throw FormatError(path, "layer metadata '(' is never closed");
}

}  // namespace semrec::usd
