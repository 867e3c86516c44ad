#include "semrec/io/label_set_io.h"

#include <map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/json_file.h"

namespace semrec::io {

LabelSet ReadLabelSetJson(const std::filesystem::path& path) {
  const nlohmann::json j = ReadJsonFile(path);
  if (!j.is_array()) throw FormatError(path, "expected a JSON list of classes");
  LabelSet labels(path.stem().string());
  for (size_t i = 0; i < j.size(); ++i) {
    try {
      LabelClass c;
      c.id = j[i].at("id").get<uint16_t>();
      c.name = j[i].at("name").get<std::string>();
      if (j[i].contains("color")) {
        c.color = j[i]["color"].get<std::array<uint8_t, 3>>();
      }
      // Fusion treats structure and objects differently, so every class must
      // say which it is: a missing mark is an error, not a guess.
      if (!j[i].contains("kind")) {
        throw FormatError(
            path, fmt::format("class {} ('{}') has no \"kind\": mark every "
                              "class \"thing\" (objects), \"stuff\" (wall, "
                              "floor, sky...) or \"other\" (the catch-all)",
                              c.id, c.name));
      }
      const auto kind = ParseClassKind(j[i]["kind"].get<std::string>());
      if (!kind) {
        throw FormatError(
            path, fmt::format("class {} ('{}'): kind '{}' is not thing, stuff "
                              "or other",
                              c.id, c.name, j[i]["kind"].get<std::string>()));
      }
      c.kind = *kind;
      labels.Add(c);
    } catch (const nlohmann::json::exception& e) {
      throw FormatError(path, "class " + std::to_string(i) + ": " + e.what());
    } catch (const InvalidArgument& e) {
      throw FormatError(path, e.what());
    }
  }
  return labels;
}

LabelSet LoadLabelSet(const std::string& name_or_path) {
  static const std::map<std::string, std::string> kAliases = {
      {"voc", "voc21"},
      {"voc21", "voc21"},
      {"ade20k", "ade20k150"},
      {"ade20k150", "ade20k150"},
      {"ade20k-top31", "ade20k_top31"},
      {"ade20k_top31", "ade20k_top31"},
      {"coco", "coco80"},
      {"coco80", "coco80"},
      {"cityscapes", "cityscapes19"},
      {"cityscapes19", "cityscapes19"},
      {"nyu40", "nyu40"}};
  if (auto it = kAliases.find(name_or_path); it != kAliases.end()) {
    return ReadLabelSetJson(ProjectDataDir() / "labels" /
                            (it->second + ".json"));
  }
  if (std::filesystem::is_regular_file(name_or_path)) {
    return ReadLabelSetJson(name_or_path);
  }
  throw InvalidArgument(
      "unknown label set '" + name_or_path +
      "': use voc, ade20k, ade20k-top31, coco, cityscapes or the path of "
      "a JSON class list");
}

void WriteLabelSetJson(const std::filesystem::path& path,
                       const LabelSet& labels) {
  nlohmann::json j = nlohmann::json::array();
  for (const LabelClass& c : labels.Classes()) {
    j.push_back({{"id", c.id},
                 {"name", c.name},
                 {"kind", ClassKindName(c.kind)},
                 {"color", c.color}});
  }
  WriteTextFileAtomic(path, j.dump(2) + "\n");
}

}  // namespace semrec::io
