// Per-pixel label maps (semantic classes or instance ids) and class tables.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "semrec/core/image.h"

namespace semrec {

/// One label per pixel; 0 conventionally means "unlabelled / background".
using LabelMap = Image<uint16_t>;

/// What a class is in a scene: countable objects (chair, table) or amorphous
/// structure (wall, floor, sky), as in panoptic segmentation; `kOther` is a
/// set's catch-all ("other", VOC "background"): something the set cannot
/// name, reconstructed as a generic object.
enum class ClassKind { kThing, kStuff, kOther };

/// "thing", "stuff", "other".
const char* ClassKindName(ClassKind kind);
/// Inverse of ClassKindName; nullopt for anything else.
std::optional<ClassKind> ParseClassKind(const std::string& text);

/// Which of the room's large planes a structure class lives on: fusion
/// counts a wall vote only on a large vertical plane, a floor vote only on the
/// floor, a ceiling vote only on the top plane (fuse/structure_planes.h).
/// kNone: not gated (sky, fence, ...), and every thing.
enum class StructureGeometry { kNone, kVertical, kFloor, kCeiling };

/// "none", "vertical", "floor", "ceiling".
const char* StructureGeometryName(StructureGeometry geometry);
/// Inverse of StructureGeometryName; nullopt for anything else.
std::optional<StructureGeometry> ParseStructureGeometry(
    const std::string& text);

/// One class of a label set.
struct LabelClass {
  uint16_t id = 0;
  std::string name;
  std::array<uint8_t, 3> color = {0, 0, 0};
  ClassKind kind = ClassKind::kThing;
  /// Structure classes only: the plane they lie on (label files:
  /// "structure": "vertical" | "floor" | "ceiling").
  StructureGeometry geometry = StructureGeometry::kNone;
  /// Things only: the footprint one object of the class has at most, its
  /// longest and shortest side (m, generous: a three-seat sofa 3.0 x 1.2, a
  /// king-size bed 2.4 x 2.2; label files: "footprint_m": [length, width]).
  /// Fusion joins pieces the views cut apart when together they fit one
  /// object, and keeps two touching chairs two. 0 = unknown (classes whose
  /// objects vary too much: a cabinet, a shelf, a box).
  double max_length_m = 0.0;
  double max_width_m = 0.0;
  /// Things only: furniture with a vertical front and a top behind it (a
  /// cabinet, a counter, a chest of drawers). Fusion finds such fronts by
  /// their geometry; one that views called wall and no thing holds becomes
  /// an object of such a class (label files: "front": true).
  bool furniture_front = false;
};

/// Name of the objects made from a set's catch-all class.
inline constexpr const char* kGenericObjectName = "object";

/// A class table (ADE20K-150, VOC-21, ...). Label sets are data: build them
/// from files, not code.
class LabelSet {
 public:
  LabelSet() = default;
  explicit LabelSet(std::string name) : name_(std::move(name)) {}

  /// Adds a class. Throws InvalidArgument on a duplicate id or name, or an
  /// empty name.
  void Add(const LabelClass& label_class);

  const std::string& name() const { return name_; }
  size_t size() const { return classes_.size(); }
  bool Contains(uint16_t id) const { return by_id_.count(id) != 0; }
  /// Throws InvalidArgument for an unknown id.
  const LabelClass& Get(uint16_t id) const;
  std::optional<uint16_t> FindByName(const std::string& name) const;
  /// Classes sorted by id.
  std::vector<LabelClass> Classes() const;

 private:
  std::string name_;
  std::vector<LabelClass> classes_;
  std::map<uint16_t, size_t> by_id_;
  std::map<std::string, uint16_t> by_name_;
};

/// Sorted distinct labels of a map, with their pixel counts.
std::map<uint16_t, size_t> LabelHistogram(const LabelMap& labels);

/// A deterministic, well-spread colour for label `id` (golden-ratio hue walk);
/// id 0 is black.
std::array<uint8_t, 3> LabelColor(uint32_t id);

}  // namespace semrec
