#include "semrec/usd/usda_reader.h"

#include <regex>
#include <sstream>

#include <fmt/format.h>

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

std::string Unquote(const std::string& s) {
  std::string out;
  for (size_t i = 1; i + 1 < s.size(); ++i) {
    if (s[i] == '\\' && i + 2 < s.size()) ++i;
    out += s[i];
  }
  return out;
}

void ReadLayer(const fs::path& path, std::vector<MeshPrim>* meshes, int depth) {
  if (depth > 8) {
    throw FormatError(path, "subLayers nested too deeply (a cycle?)");
  }
  std::istringstream in(ReadTextFile(path));
  std::string line;
  if (!std::getline(in, line) || line.rfind("#usda 1.0", 0) != 0) {
    throw FormatError(path, "not a USDA file (missing '#usda 1.0' header)");
  }
  static const std::regex sublayer(R"re(@([^@]+)@)re");
  static const std::regex mesh(R"re(^\s*def Mesh "([^"]+)")re");
  bool in_sublayers = false;
  int line_number = 1;
  MeshPrim* current = nullptr;
  while (std::getline(in, line)) {
    ++line_number;
    std::smatch m;
    if (line.find("subLayers") != std::string::npos) in_sublayers = true;
    if (in_sublayers) {
      for (auto it = std::sregex_iterator(line.begin(), line.end(), sublayer);
           it != std::sregex_iterator(); ++it) {
        ReadLayer(path.parent_path() / (*it)[1].str(), meshes, depth + 1);
      }
      if (line.find(']') != std::string::npos) in_sublayers = false;
      continue;
    }
    if (line.find("def Mesh") != std::string::npos &&
        std::regex_search(line, m, mesh)) {
      meshes->emplace_back();
      current = &meshes->back();
      continue;
    }
    // "[custom|uniform] <type> <name> = <value>"; parsed by hand: value lines
    // of big meshes are megabytes long, too long for std::regex.
    const size_t eq = line.find(" = ");
    if (current == nullptr || eq == std::string::npos) continue;
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
        current->points.emplace_back(static_cast<float>(v[i]),
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
        current->triangles.push_back({static_cast<uint32_t>(v[i]),
                                      static_cast<uint32_t>(v[i + 1]),
                                      static_cast<uint32_t>(v[i + 2])});
      }
    } else if (name == "semrec:label") {
      current->label = Unquote(value);
    } else if (name == "semrec:kind") {
      current->structure = Unquote(value) == "stuff";
    } else if (name == "semrec:instanceId") {
      current->instance_id = static_cast<uint32_t>(std::stoul(value));
    } else if (name == "semrec:pointCount") {
      current->point_count = std::stoul(value);
    } else if (name == "semrec:firstSeenFrame") {
      current->first_seen_frame = std::stoul(value);
    } else if (name == "semrec:lastSeenFrame") {
      current->last_seen_frame = std::stoul(value);
    } else if (name == "semrec:confidence") {
      current->confidence = std::stod(value);
    }
  }
}

}  // namespace

std::vector<MeshPrim> ReadScene(const fs::path& path) {
  std::vector<MeshPrim> meshes;
  ReadLayer(path, &meshes, 0);
  return meshes;
}

}  // namespace semrec::usd
