#include "semrec/core/label_map.h"

#include <cmath>

#include <fmt/format.h>

namespace semrec {

const char* ClassKindName(ClassKind kind) {
  switch (kind) {
    case ClassKind::kStuff:
      return "stuff";
    case ClassKind::kOther:
      return "other";
    case ClassKind::kThing:
      break;
  }
  return "thing";
}

std::optional<ClassKind> ParseClassKind(const std::string& text) {
  for (const ClassKind kind :
       {ClassKind::kThing, ClassKind::kStuff, ClassKind::kOther}) {
    if (text == ClassKindName(kind)) return kind;
  }
  return std::nullopt;
}

const char* StructureGeometryName(StructureGeometry geometry) {
  switch (geometry) {
    case StructureGeometry::kVertical:
      return "vertical";
    case StructureGeometry::kFloor:
      return "floor";
    case StructureGeometry::kCeiling:
      return "ceiling";
    case StructureGeometry::kNone:
      break;
  }
  return "none";
}

std::optional<StructureGeometry> ParseStructureGeometry(
    const std::string& text) {
  if (text == "none") return StructureGeometry::kNone;
  if (text == "vertical") return StructureGeometry::kVertical;
  if (text == "floor") return StructureGeometry::kFloor;
  if (text == "ceiling") return StructureGeometry::kCeiling;
  return std::nullopt;
}

void LabelSet::Add(const LabelClass& label_class) {
  CheckArgument(!label_class.name.empty(),
                fmt::format("label set '{}': class {} has an empty name", name_,
                            label_class.id));
  CheckArgument(!Contains(label_class.id),
                fmt::format("label set '{}': duplicate class id {}", name_,
                            label_class.id));
  CheckArgument(by_name_.count(label_class.name) == 0,
                fmt::format("label set '{}': duplicate class name '{}'", name_,
                            label_class.name));
  const LabelClass& c = label_class;
  CheckArgument(
      c.geometry == StructureGeometry::kNone || c.kind == ClassKind::kStuff,
      fmt::format("label set '{}': class '{}' has a structure plane ({}) but "
                  "is not stuff",
                  name_, c.name, StructureGeometryName(c.geometry)));
  const bool no_footprint = c.max_length_m == 0.0 && c.max_width_m == 0.0;
  CheckArgument(
      no_footprint || (c.kind == ClassKind::kThing && c.max_width_m > 0.0 &&
                       c.max_length_m >= c.max_width_m),
      fmt::format("label set '{}': class '{}': a footprint needs a thing and "
                  "length >= width > 0 (got {} x {} m)",
                  name_, c.name, c.max_length_m, c.max_width_m));
  CheckArgument(!c.furniture_front || c.kind == ClassKind::kThing,
                fmt::format("label set '{}': class '{}' is a furniture front "
                            "but not a thing",
                            name_, c.name));
  by_id_[label_class.id] = classes_.size();
  by_name_[label_class.name] = label_class.id;
  classes_.push_back(label_class);
}

const LabelClass& LabelSet::Get(uint16_t id) const {
  auto it = by_id_.find(id);
  CheckArgument(it != by_id_.end(),
                fmt::format("label set '{}': unknown class id {}", name_, id));
  return classes_[it->second];
}

std::optional<uint16_t> LabelSet::FindByName(const std::string& name) const {
  auto it = by_name_.find(name);
  if (it == by_name_.end()) return std::nullopt;
  return it->second;
}

std::vector<LabelClass> LabelSet::Classes() const {
  std::vector<LabelClass> out;
  out.reserve(classes_.size());
  for (const auto& [id, index] : by_id_) out.push_back(classes_[index]);
  return out;
}

std::map<uint16_t, size_t> LabelHistogram(const LabelMap& labels) {
  std::vector<size_t> counts(65536, 0);
  for (uint16_t v : labels.values()) ++counts[v];
  std::map<uint16_t, size_t> out;
  for (size_t i = 0; i < counts.size(); ++i) {
    if (counts[i] > 0) out.emplace(static_cast<uint16_t>(i), counts[i]);
  }
  return out;
}

std::array<uint8_t, 3> LabelColor(uint32_t id) {
  if (id == 0) return {0, 0, 0};
  // HSV with a golden-ratio hue walk: neighbouring ids get clearly different
  // colours.
  const double h = std::fmod(id * 0.618033988749895, 1.0) * 6.0;
  const double s = 0.65 + 0.35 * ((id / 7) % 2);
  const double v = 0.95 - 0.25 * ((id / 3) % 2);
  const int sector = static_cast<int>(h);
  const double f = h - sector;
  const double p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  double r = 0, g = 0, b = 0;
  switch (sector % 6) {
    case 0:
      r = v, g = t, b = p;
      break;
    case 1:
      r = q, g = v, b = p;
      break;
    case 2:
      r = p, g = v, b = t;
      break;
    case 3:
      r = p, g = q, b = v;
      break;
    case 4:
      r = t, g = p, b = v;
      break;
    default:
      r = v, g = p, b = q;
      break;
  }
  auto to8 = [](double x) {
    return static_cast<uint8_t>(std::lround(x * 255.0));
  };
  return {to8(r), to8(g), to8(b)};
}

}  // namespace semrec
