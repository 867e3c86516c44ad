#include "semrec/io/label_set_io.h"

#include <map>
#include <set>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/json_file.h"

namespace semrec::io {

namespace {

// The label sets in ProjectDataDir()/labels (file stems) by the names
// LoadLabelSet accepts.
const std::map<std::string, std::string>& ShippedAliases() {
  static const std::map<std::string, std::string> aliases = {
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
  return aliases;
}

LabelSet ParseLabelSet(const std::filesystem::path& path,
                       bool fill_from_shipped);

// Structure planes and footprints by class name, as the shipped sets give
// them.
const std::map<std::string, LabelClass>& ShippedClassData() {
  static const std::map<std::string, LabelClass> data = [] {
    std::map<std::string, LabelClass> by_name;
    std::set<std::string> stems;
    for (const auto& [alias, stem] : ShippedAliases()) stems.insert(stem);
    for (const std::string& stem : stems) {
      const LabelSet set =
          ParseLabelSet(ProjectDataDir() / "labels" / (stem + ".json"), false);
      for (const LabelClass& c : set.Classes()) {
        if (c.geometry != StructureGeometry::kNone || c.max_length_m > 0.0 ||
            c.furniture_front) {
          by_name.emplace(c.name, c);
        }
      }
    }
    return by_name;
  }();
  return data;
}

// A class list that says nothing of structure planes and footprints (written
// before they were data, or by hand) takes them from the shipped sets by
// class name, so that a chair is still a chair's size.
void FillFromShipped(std::vector<LabelClass>* classes) {
  const auto& shipped = ShippedClassData();
  for (LabelClass& c : *classes) {
    const auto it = shipped.find(c.name);
    if (it == shipped.end() || it->second.kind != c.kind) continue;
    c.geometry = it->second.geometry;
    c.max_length_m = it->second.max_length_m;
    c.max_width_m = it->second.max_width_m;
    c.furniture_front = it->second.furniture_front;
  }
}

LabelSet ParseLabelSet(const std::filesystem::path& path,
                       bool fill_from_shipped) {
  const nlohmann::json j = ReadJsonFile(path);
  if (!j.is_array()) throw FormatError(path, "expected a JSON list of classes");
  std::vector<LabelClass> classes;
  bool has_class_data = false;
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
      if (j[i].contains("structure")) {
        const auto text = j[i]["structure"].get<std::string>();
        const auto geometry = ParseStructureGeometry(text);
        if (!geometry) {
          throw FormatError(
              path, fmt::format("class {} ('{}'): structure '{}' is not "
                                "vertical, floor, ceiling or none",
                                c.id, c.name, text));
        }
        c.geometry = *geometry;
      }
      if (j[i].contains("footprint_m")) {
        const auto size = j[i]["footprint_m"].get<std::array<double, 2>>();
        c.max_length_m = size[0];
        c.max_width_m = size[1];
      }
      if (j[i].contains("front")) c.furniture_front = j[i]["front"].get<bool>();
      has_class_data |= j[i].contains("structure") ||
                        j[i].contains("footprint_m") || j[i].contains("front");
      classes.push_back(c);
    } catch (const nlohmann::json::exception& e) {
      throw FormatError(path, "class " + std::to_string(i) + ": " + e.what());
    }
  }
  if (fill_from_shipped && !has_class_data) FillFromShipped(&classes);
  LabelSet labels(path.stem().string());
  try {
    for (const LabelClass& c : classes) labels.Add(c);
  } catch (const InvalidArgument& e) {
    throw FormatError(path, e.what());
  }
  return labels;
}

}  // namespace

LabelSet ReadLabelSetJson(const std::filesystem::path& path) {
  return ParseLabelSet(path, true);
}

LabelSet LoadLabelSet(const std::string& name_or_path) {
  const auto& aliases = ShippedAliases();
  if (auto it = aliases.find(name_or_path); it != aliases.end()) {
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
    nlohmann::json entry = {{"id", c.id},
                            {"name", c.name},
                            {"kind", ClassKindName(c.kind)},
                            {"color", c.color}};
    if (c.geometry != StructureGeometry::kNone) {
      entry["structure"] = StructureGeometryName(c.geometry);
    }
    if (c.max_length_m > 0.0) {
      entry["footprint_m"] = {c.max_length_m, c.max_width_m};
    }
    if (c.furniture_front) entry["front"] = true;
    j.push_back(std::move(entry));
  }
  WriteTextFileAtomic(path, j.dump(2) + "\n");
}

}  // namespace semrec::io
