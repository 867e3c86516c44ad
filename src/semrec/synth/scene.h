// Synthetic indoor scenes: a room, furniture-like objects of named classes
// built from primitives, and walking people. Everything is deterministic given
// the options (seed included).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "semrec/core/label_map.h"
#include "semrec/synth/primitives.h"

namespace semrec::synth {

/// The generator's class table (ids are stable; written to gt/classes.json).
const LabelSet& SynthClasses();
constexpr uint16_t kClassFloor = 1;
constexpr uint16_t kClassWall = 2;
constexpr uint16_t kClassCeiling = 3;
constexpr uint16_t kClassPerson = 14;
/// Instance ids of people are kPersonInstanceBase + person id (objects
/// use 1..999).
constexpr uint16_t kPersonInstanceBase = 1000;

using Rgb = std::array<uint8_t, 3>;

/// A static object: a union of primitives with one class and one instance id.
struct SceneObject {
  uint16_t instance_id = 0;
  uint16_t class_id = 0;
  /// "<class>_<instance id>", e.g. "chair_5".
  std::string name;
  std::vector<Primitive> parts;
  Rgb color = {128, 128, 128};
  /// Floor, walls and ceiling.
  bool structure = false;
  /// One of the room box's faces (Scene::room_faces): drawn by the room test,
  /// not as primitives. Interior walls are structure but not room faces.
  bool room_face = false;

  Eigen::AlignedBox3d Bounds() const;
  /// Unsigned distance from p to the object's surface (min over its parts'
  /// surfaces).
  double DistanceToSurface(const Eigen::Vector3d& p) const;
};

/// A person walking a closed loop at constant speed.
struct Person {
  uint16_t person_id = 0;
  double height_m = 1.75;
  Rgb shirt = {200, 40, 40};
  Rgb pants = {40, 40, 120};
  Rgb skin = {224, 172, 140};
  /// Closed loop of floor positions (x, y), walked in order.
  std::vector<Eigen::Vector2d> path;
  double speed_mps = 1.0;
  /// Distance along the loop at time 0.
  double start_offset_m = 0.0;
};

/// A person's body at one instant: capsules and a sphere, with a colour per
/// part.
struct PersonBody {
  std::vector<Primitive> parts;
  std::vector<Rgb> colors;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double heading_rad = 0.0;
};
PersonBody PoseAt(const Person& person, double time_s);

struct Scene {
  /// Room interior: [0, size.x] x [0, size.y] x [0, size.z], z up.
  Eigen::Vector3d room_size = Eigen::Vector3d(5, 4, 2.6);
  /// Instance id of the structure object forming each interior face, in the
  /// order -x, +x, -y, +y, -z (floor), +z (ceiling); 0 = open (no ceiling). The
  /// renderer casts rays against the room as one box seen from inside instead
  /// of six slabs.
  std::array<uint16_t, 6> room_faces = {0, 0, 0, 0, 0, 0};
  std::vector<SceneObject> objects;
  std::vector<Person> people;

  const SceneObject* FindObject(uint16_t instance_id) const;
  /// A thing of the scene (not structure, not a person, not 0).
  bool IsObject(uint16_t instance_id) const;
};

struct SceneOptions {
  double room_width_m = 5.0;
  double room_depth_m = 4.0;
  double room_height_m = 2.6;
  /// Render a ceiling (off lets a top-down camera see in).
  bool ceiling = true;
  /// Classes of the objects to place, in order (must be in SynthClasses(), not
  /// structure/person). "monitor" goes on a table when one exists.
  std::vector<std::string> object_classes = {"table", "chair",   "sofa",
                                             "shelf", "cabinet", "plant"};
  /// Interior walls across the room (perpendicular to x) at these x (m), 10 cm
  /// thick, each with a door centred in y: a flat of rooms in a row. Objects
  /// may stand against them; doorways stay free.
  std::vector<double> partitions_x_m;
  double door_width_m = 1.0;
  double door_height_m = 2.1;
  /// Probability that an object is placed touching an earlier one (different
  /// classes touching is the interesting case for label-gated fusion).
  double touching_probability = 0.4;
  int num_people = 0;
  uint64_t seed = 1;

  /// Throws InvalidArgument for impossible values or unknown classes.
  void Check() const;
};

/// Throws Error when the objects do not fit into the room.
Scene GenerateScene(const SceneOptions& options);

}  // namespace semrec::synth
