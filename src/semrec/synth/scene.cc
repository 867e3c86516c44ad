#include "semrec/synth/scene.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

#include <fmt/format.h>

#include "semrec/core/error.h"
#include "semrec/core/random.h"

namespace semrec::synth {
namespace {

struct ClassSpec {
  uint16_t id;
  const char* name;
  Rgb color;
  StructureGeometry geometry = StructureGeometry::kNone;
  double max_length_m = 0.0, max_width_m = 0.0;  // LabelClass
  bool furniture_front = false;                  // LabelClass
};

// Colours are the flat albedo of each class (people get their own clothing
// colours). Footprints as the shipped label sets give them (data/labels).
constexpr ClassSpec kClasses[] = {
    {1, "floor", {150, 120, 90}, StructureGeometry::kFloor},
    {2, "wall", {210, 205, 195}, StructureGeometry::kVertical},
    {3, "ceiling", {235, 235, 235}, StructureGeometry::kCeiling},
    {4, "table", {140, 90, 50}, StructureGeometry::kNone, 2.6, 1.3},
    {5, "chair", {60, 110, 160}, StructureGeometry::kNone, 0.75, 0.75},
    {6, "sofa", {120, 60, 120}, StructureGeometry::kNone, 3.0, 1.2},
    {7, "shelf", {170, 140, 100}},
    {8, "box", {190, 160, 60}},
    {9, "lamp", {230, 210, 120}, StructureGeometry::kNone, 0.7, 0.7},
    {10, "bed", {90, 140, 90}, StructureGeometry::kNone, 2.4, 2.2},
    {11, "cabinet", {110, 110, 120}, StructureGeometry::kNone, 0.0, 0.0, true},
    {12, "monitor", {30, 30, 35}, StructureGeometry::kNone, 1.0, 0.5},
    {13, "plant", {50, 150, 60}, StructureGeometry::kNone, 1.2, 1.2},
    {14, "person", {200, 40, 40}},
    {15, "counter", {150, 45, 50}, StructureGeometry::kNone, 0.0, 0.0, true},
};

Eigen::Matrix3d Yaw(double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

Primitive Transformed(const Primitive& p, const Eigen::Matrix3d& R,
                      const Eigen::Vector3d& t) {
  if (const auto* b = std::get_if<Box>(&p)) {
    return Box{R * b->center + t, b->half, R * b->R_world_box};
  }
  if (const auto* c = std::get_if<Cylinder>(&p)) {
    return Cylinder{R * c->a + t, R * c->b + t, c->radius};
  }
  if (const auto* c = std::get_if<Capsule>(&p)) {
    return Capsule{R * c->a + t, R * c->b + t, c->radius};
  }
  const auto& s = std::get<Sphere>(p);
  return Sphere{R * s.center + t, s.radius};
}

Box MakeBox(double cx, double cy, double cz, double hx, double hy, double hz) {
  return Box{{cx, cy, cz}, {hx, hy, hz}, Eigen::Matrix3d::Identity()};
}
Cylinder Vertical(double x, double y, double z0, double z1, double r) {
  return Cylinder{{x, y, z0}, {x, y, z1}, r};
}

// An object in its local frame: origin at the footprint centre on the floor,
// facing +x.
struct Blueprint {
  std::vector<Primitive> parts;
  double hx = 0.25;  // footprint half extents
  double hy = 0.25;
  double height = 0.5;
  bool against_wall = false;
};

Blueprint Build(const std::string& cls, Rng& rng) {
  const double s = rng.Uniform(0.9, 1.1);
  Blueprint bp;
  if (cls == "table") {
    const double hx = 0.6 * s, hy = 0.4 * s, h = 0.74;
    bp.parts.push_back(MakeBox(0, 0, h - 0.02, hx, hy, 0.02));
    for (int sx : {-1, 1}) {
      for (int sy : {-1, 1}) {
        bp.parts.push_back(
            Vertical(sx * (hx - 0.06), sy * (hy - 0.06), 0, h - 0.04, 0.03));
      }
    }
    bp.hx = hx, bp.hy = hy, bp.height = h;
  } else if (cls == "chair") {
    const double h = 0.22 * s;
    bp.parts.push_back(MakeBox(0, 0, 0.45, h, h, 0.02));
    bp.parts.push_back(MakeBox(-h + 0.02, 0, 0.47 + 0.22, 0.02, h, 0.22));
    for (int sx : {-1, 1}) {
      for (int sy : {-1, 1}) {
        bp.parts.push_back(
            Vertical(sx * (h - 0.03), sy * (h - 0.03), 0, 0.43, 0.02));
      }
    }
    bp.hx = bp.hy = h, bp.height = 0.91;
  } else if (cls == "sofa") {
    const double hy = 0.95 * s, hx = 0.45;
    bp.parts.push_back(MakeBox(0, 0, 0.21, hx, hy, 0.21));
    bp.parts.push_back(MakeBox(-hx + 0.1, 0, 0.62, 0.1, hy, 0.2));
    for (int sy : {-1, 1}) {
      bp.parts.push_back(
          MakeBox(0.05, sy * (hy - 0.1), 0.55, hx - 0.05, 0.1, 0.13));
    }
    bp.hx = hx, bp.hy = hy, bp.height = 0.82, bp.against_wall = true;
  } else if (cls == "shelf") {
    const double hy = 0.45 * s, hx = 0.18, h = 1.8;
    for (int sy : {-1, 1}) {
      bp.parts.push_back(
          MakeBox(0, sy * (hy - 0.015), h / 2, hx, 0.015, h / 2));
    }
    bp.parts.push_back(MakeBox(-hx + 0.01, 0, h / 2, 0.01, hy - 0.03, h / 2));
    for (double z : {0.03, 0.45, 0.9, 1.35, 1.77}) {
      bp.parts.push_back(MakeBox(0, 0, z, hx, hy - 0.03, 0.015));
    }
    bp.hx = hx, bp.hy = hy, bp.height = h, bp.against_wall = true;
  } else if (cls == "box") {
    const double hx = rng.Uniform(0.15, 0.3), hy = rng.Uniform(0.15, 0.3),
                 hz = rng.Uniform(0.15, 0.3);
    bp.parts.push_back(MakeBox(0, 0, hz, hx, hy, hz));
    bp.hx = hx, bp.hy = hy, bp.height = 2 * hz;
  } else if (cls == "lamp") {
    bp.parts.push_back(Vertical(0, 0, 0, 0.03, 0.15));
    bp.parts.push_back(Vertical(0, 0, 0.03, 1.45 * s, 0.015));
    bp.parts.push_back(Vertical(0, 0, 1.45 * s, 1.45 * s + 0.25, 0.2));
    bp.hx = bp.hy = 0.2, bp.height = 1.45 * s + 0.25;
  } else if (cls == "bed") {
    const double hx = 1.0 * s, hy = 0.75 * s;
    bp.parts.push_back(MakeBox(0, 0, 0.15, hx, hy, 0.15));
    bp.parts.push_back(MakeBox(0.02, 0, 0.4, hx - 0.03, hy - 0.03, 0.1));
    bp.parts.push_back(MakeBox(-hx + 0.03, 0, 0.5, 0.03, hy, 0.5));
    bp.parts.push_back(MakeBox(-hx + 0.3, 0, 0.55, 0.2, hy * 0.6, 0.05));
    bp.hx = hx, bp.hy = hy, bp.height = 1.0, bp.against_wall = true;
  } else if (cls == "cabinet") {
    const double hx = 0.3, hy = 0.4 * s, hz = 0.45 * s;
    bp.parts.push_back(MakeBox(0, 0, hz, hx, hy, hz));
    bp.parts.push_back(
        MakeBox(hx + 0.01, hy * 0.6, hz * 1.4, 0.01, 0.015, 0.12));
    bp.hx = hx + 0.02, bp.hy = hy, bp.height = 2 * hz, bp.against_wall = true;
  } else if (cls == "counter") {
    // A row of kitchen base cabinets under a worktop that overhangs the front
    // by 2 cm (7-Scenes chess: red cabinets, a dark top).
    const double hx = 0.32, hy = 1.2 * s, body_hz = 0.43;
    bp.parts.push_back(MakeBox(-0.02, 0, body_hz, hx - 0.02, hy, body_hz));
    bp.parts.push_back(MakeBox(0, 0, 2 * body_hz + 0.02, hx, hy, 0.02));
    bp.hx = hx, bp.hy = hy, bp.height = 2 * body_hz + 0.04;
    bp.against_wall = true;
  } else if (cls == "monitor") {
    bp.parts.push_back(MakeBox(0, 0, 0.01, 0.1, 0.12, 0.01));
    bp.parts.push_back(Vertical(-0.02, 0, 0.02, 0.2, 0.02));
    bp.parts.push_back(MakeBox(0, 0, 0.36 * s, 0.02, 0.3 * s, 0.18 * s));
    bp.hx = 0.1, bp.hy = 0.3 * s, bp.height = 0.54 * s;
  } else if (cls == "plant") {
    bp.parts.push_back(Vertical(0, 0, 0, 0.3, 0.15 * s));
    bp.parts.push_back(Sphere{{0, 0, 0.3 + 0.28 * s}, 0.3 * s});
    bp.hx = bp.hy = 0.3 * s, bp.height = 0.3 + 0.58 * s;
  } else {
    throw InvalidArgument("synth: no blueprint for class '" + cls + "'");
  }
  return bp;
}

// A placed footprint: an oriented rectangle on the floor.
struct Footprint {
  Eigen::Vector2d center;
  double yaw;
  double hx, hy;
};

// Separating-axis test for two oriented rectangles grown by `margin`.
bool Overlap(const Footprint& a, const Footprint& b, double margin) {
  auto axes = [](const Footprint& f) {
    return std::array<Eigen::Vector2d, 2>{
        Eigen::Vector2d(std::cos(f.yaw), std::sin(f.yaw)),
        Eigen::Vector2d(-std::sin(f.yaw), std::cos(f.yaw))};
  };
  const auto aa = axes(a), ba = axes(b);
  const Eigen::Vector2d d = b.center - a.center;
  for (const auto& axis : {aa[0], aa[1], ba[0], ba[1]}) {
    const double ra = (a.hx + margin) * std::abs(aa[0].dot(axis)) +
                      (a.hy + margin) * std::abs(aa[1].dot(axis));
    const double rb = (b.hx + margin) * std::abs(ba[0].dot(axis)) +
                      (b.hy + margin) * std::abs(ba[1].dot(axis));
    if (std::abs(d.dot(axis)) > ra + rb) return false;
  }
  return true;
}

bool InsideRoom(const Footprint& f, const Eigen::Vector2d& lo,
                const Eigen::Vector2d& hi) {
  const double ex =
      f.hx * std::abs(std::cos(f.yaw)) + f.hy * std::abs(std::sin(f.yaw));
  const double ey =
      f.hx * std::abs(std::sin(f.yaw)) + f.hy * std::abs(std::cos(f.yaw));
  return f.center.x() - ex >= lo.x() - 1e-9 &&
         f.center.x() + ex <= hi.x() + 1e-9 &&
         f.center.y() - ey >= lo.y() - 1e-9 &&
         f.center.y() + ey <= hi.y() + 1e-9;
}

constexpr Rgb kShirts[] = {{200, 40, 40},  {40, 160, 60},  {230, 200, 40},
                           {40, 90, 210},  {230, 120, 30}, {150, 50, 180},
                           {30, 180, 180}, {240, 240, 240}};
constexpr Rgb kPants[] = {
    {40, 40, 120}, {30, 30, 30}, {90, 70, 50}, {100, 100, 100}};

}  // namespace

const LabelSet& SynthClasses() {
  static const LabelSet classes = [] {
    LabelSet set("semrec-synth");
    for (const ClassSpec& c : kClasses) {
      // The room's shell is structure; everything placed in it is an object.
      const bool shell = c.id == 1 || c.id == 2 || c.id == 3;
      LabelClass label{c.id, c.name, c.color,
                       shell ? ClassKind::kStuff : ClassKind::kThing};
      label.geometry = c.geometry;
      label.max_length_m = c.max_length_m;
      label.max_width_m = c.max_width_m;
      label.furniture_front = c.furniture_front;
      set.Add(label);
    }
    return set;
  }();
  return classes;
}

Eigen::AlignedBox3d SceneObject::Bounds() const {
  Eigen::AlignedBox3d box;
  for (const Primitive& p : parts) box.extend(synth::Bounds(p));
  return box;
}

double SceneObject::DistanceToSurface(const Eigen::Vector3d& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (const Primitive& part : parts) {
    best = std::min(best, std::abs(SignedDistance(part, p)));
  }
  return best;
}

const SceneObject* Scene::FindObject(uint16_t instance_id) const {
  for (const SceneObject& o : objects) {
    if (o.instance_id == instance_id) return &o;
  }
  return nullptr;
}

bool Scene::IsObject(uint16_t instance_id) const {
  if (instance_id == 0 || instance_id >= kPersonInstanceBase) return false;
  const SceneObject* o = FindObject(instance_id);
  return o != nullptr && !o->structure;
}

void SceneOptions::Check() const {
  CheckArgument(
      room_width_m >= 2.0 && room_depth_m >= 2.0 && room_height_m >= 2.0,
      "synth: the room must be at least 2 x 2 x 2 m");
  CheckArgument(room_width_m <= 50 && room_depth_m <= 50 && room_height_m <= 10,
                "synth: the room must be at most 50 x 50 x 10 m");
  CheckArgument(touching_probability >= 0.0 && touching_probability <= 1.0,
                "synth: touching_probability must be in [0, 1]");
  CheckArgument(num_people >= 0 && num_people <= 8,
                "synth: num_people must be in [0, 8]");
  CheckArgument(object_classes.size() <= 900, "synth: at most 900 objects");
  if (!partitions_x_m.empty()) {
    CheckArgument(door_width_m >= 0.6 && door_width_m <= room_depth_m - 1.0,
                  "synth: door_width_m must be in [0.6, room depth - 1 m]");
    CheckArgument(door_height_m >= 1.8 && door_height_m < room_height_m,
                  "synth: door_height_m must be in [1.8, room height)");
  }
  std::vector<double> xs = partitions_x_m;
  std::sort(xs.begin(), xs.end());
  for (size_t i = 0; i < xs.size(); ++i) {
    const double before = i == 0 ? 0.0 : xs[i - 1];
    CheckArgument(xs[i] - before >= 1.5 && room_width_m - xs[i] >= 1.5,
                  "synth: interior walls must leave rooms at least 1.5 m wide");
  }
  for (const std::string& cls : object_classes) {
    const auto id = SynthClasses().FindByName(cls);
    CheckArgument(id.has_value() && *id != kClassFloor && *id != kClassWall &&
                      *id != kClassCeiling && *id != kClassPerson,
                  fmt::format("synth: '{}' is not a placeable object class "
                              "(use table, chair, sofa, "
                              "shelf, box, lamp, bed, cabinet, monitor, plant)",
                              cls));
  }
}

namespace {

// Walls objects may stand against: a point on the face, the normal into the
// room and the free stretch along it.
struct WallFace {
  Eigen::Vector2d origin, normal, along;
  double length;
};

// The floor plan while objects are placed: footprints on the floor (objects
// and interior wall segments), the faces objects may stand against, doorways.
struct FloorPlan {
  Eigen::Vector2d lo, hi;  // where objects may stand
  std::vector<Footprint> footprints;
  std::vector<size_t> footprint_object;
  std::vector<bool> footprint_is_wall;
  std::set<size_t> tables_with_monitor;  // footprint indices
  std::vector<WallFace> faces;
  std::vector<Footprint> doorways;
};

// Floor, walls (and the ceiling) as 10 cm slabs just outside the interior, so
// inner faces are at the room bounds.
void AddRoomShell(const SceneOptions& options, uint16_t* next_id,
                  Scene* scene) {
  const double W = options.room_width_m, D = options.room_depth_m,
               H = options.room_height_m;
  const LabelSet& classes = SynthClasses();
  // Returns the new instance id.
  auto add_structure = [&](uint16_t cls, const Box& box) -> uint16_t {
    SceneObject o;
    o.instance_id = (*next_id)++;
    o.class_id = cls;
    o.name = fmt::format("{}_{}", classes.Get(cls).name, o.instance_id);
    o.parts.push_back(box);
    o.color = classes.Get(cls).color;
    o.structure = true;
    o.room_face = true;
    scene->objects.push_back(std::move(o));
    return scene->objects.back().instance_id;
  };
  const double t = 0.05;
  scene->room_faces[4] = add_structure(
      kClassFloor, MakeBox(W / 2, D / 2, -t, W / 2 + 2 * t, D / 2 + 2 * t, t));
  scene->room_faces[0] =
      add_structure(kClassWall, MakeBox(-t, D / 2, H / 2, t, D / 2, H / 2));
  scene->room_faces[1] =
      add_structure(kClassWall, MakeBox(W + t, D / 2, H / 2, t, D / 2, H / 2));
  scene->room_faces[2] = add_structure(
      kClassWall, MakeBox(W / 2, -t, H / 2, W / 2 + 2 * t, t, H / 2));
  scene->room_faces[3] = add_structure(
      kClassWall, MakeBox(W / 2, D + t, H / 2, W / 2 + 2 * t, t, H / 2));
  if (options.ceiling) {
    scene->room_faces[5] = add_structure(
        kClassCeiling,
        MakeBox(W / 2, D / 2, H + t, W / 2 + 2 * t, D / 2 + 2 * t, t));
  }
}

// Interior walls: anchors that objects may touch, never overlap; doorways
// (and a walking space either side) stay free.
void AddInteriorWalls(const SceneOptions& options, uint16_t* next_id,
                      FloorPlan* plan, Scene* scene) {
  const double D = options.room_depth_m, H = options.room_height_m;
  for (const double x : options.partitions_x_m) {
    SceneObject wall;
    wall.instance_id = (*next_id)++;
    wall.class_id = kClassWall;
    wall.name = fmt::format("wall_{}", wall.instance_id);
    wall.color = SynthClasses().Get(kClassWall).color;
    wall.structure = true;
    const double door = options.door_width_m, ht = 0.05;
    const double y0 = D / 2 - door / 2, y1 = D / 2 + door / 2;
    for (const auto& [a, b] : {std::pair{0.0, y0}, std::pair{y1, D}}) {
      wall.parts.push_back(
          MakeBox(x, (a + b) / 2, H / 2, ht, (b - a) / 2, H / 2));
      plan->footprints.push_back({{x, (a + b) / 2}, 0.0, ht, (b - a) / 2});
      plan->footprint_object.push_back(scene->objects.size());
      plan->footprint_is_wall.push_back(true);
      plan->faces.push_back({{x - ht, a}, {-1, 0}, {0, 1}, b - a});
      plan->faces.push_back({{x + ht, a}, {1, 0}, {0, 1}, b - a});
    }
    const double lintel = H - options.door_height_m;
    wall.parts.push_back(
        MakeBox(x, D / 2, H - lintel / 2, ht, door / 2, lintel / 2));
    plan->doorways.push_back({{x, D / 2}, 0.0, ht + 0.6, door / 2});
    scene->objects.push_back(std::move(wall));
  }
}

// A monitor stands on a table top when there is a table without one
// (stacked, touching); one per table, not three in one place.
bool PlaceOnTable(const Scene& scene, FloorPlan* plan, Footprint* fp,
                  double* base_z) {
  for (size_t k = 0; k < plan->footprints.size(); ++k) {
    const SceneObject& other = scene.objects[plan->footprint_object[k]];
    if (SynthClasses().Get(other.class_id).name != "table" ||
        !plan->tables_with_monitor.insert(k).second) {
      continue;
    }
    fp->center = plan->footprints[k].center;
    fp->yaw = plan->footprints[k].yaw;
    *base_z = other.Bounds().max().z();
    return true;
  }
  return false;
}

// One placement attempt on the floor: touching an existing footprint, against
// a wall, or anywhere; true when it overlaps nothing.
bool TryFloorPlacement(const SceneOptions& options, const Blueprint& bp,
                       int attempt, const FloorPlan& plan, Rng* rng,
                       Footprint* fp) {
  const bool touch = !plan.footprints.empty() && attempt < 100 &&
                     rng->Uniform() < options.touching_probability;
  size_t anchor = 0;
  if (touch) {
    anchor = static_cast<size_t>(
        rng->UniformInt(0, static_cast<int64_t>(plan.footprints.size()) - 1));
    const Footprint& a = plan.footprints[anchor];
    const int side = static_cast<int>(rng->UniformInt(0, 3));
    const Eigen::Vector2d ax(std::cos(a.yaw), std::sin(a.yaw)),
        ay(-std::sin(a.yaw), std::cos(a.yaw));
    fp->yaw = a.yaw + (side == 0   ? M_PI
                       : side == 1 ? 0.0
                       : side == 2 ? -M_PI / 2
                                   : M_PI / 2);
    // The new object's +x faces the anchor; 2 mm gap.
    const Eigen::Vector2d dir = side == 0   ? ax
                                : side == 1 ? -ax
                                : side == 2 ? ay
                                            : -ay;
    const double reach = (side < 2 ? a.hx : a.hy) + bp.hx + 0.002;
    const double slide = rng->Uniform(-0.3, 0.3);
    const Eigen::Vector2d along = side < 2 ? ay : ax;
    fp->center = a.center + reach * dir + slide * along;
    // Against an interior wall its back is to the wall (a sofa, a shelf
    // facing the room); the footprint is symmetric, so only the yaw turns.
    if (plan.footprint_is_wall[anchor]) fp->yaw += M_PI;
  } else if (bp.against_wall && rng->Uniform() < 0.8) {
    const WallFace& f = plan.faces[static_cast<size_t>(
        rng->UniformInt(0, static_cast<int64_t>(plan.faces.size()) - 1))];
    const double gap = 0.01;
    // The object's +x (its front) faces into the room.
    fp->yaw = std::atan2(f.normal.y(), f.normal.x());
    // Summed in the order the four-wall code did (identical bytes).
    fp->center = f.origin + bp.hx * f.normal + gap * f.normal +
                 rng->Uniform() * f.length * f.along;
  } else {
    fp->yaw = rng->Uniform() * 2 * M_PI;
    fp->center = {plan.lo.x() + rng->Uniform() * (plan.hi.x() - plan.lo.x()),
                  plan.lo.y() + rng->Uniform() * (plan.hi.y() - plan.lo.y())};
  }
  if (!InsideRoom(*fp, plan.lo, plan.hi)) return false;
  bool free = true;
  for (size_t k = 0; k < plan.footprints.size() && free; ++k) {
    // Touching the anchor or a wall is intended: only forbid actual
    // overlap with them.
    const double margin =
        ((touch && k == anchor) || plan.footprint_is_wall[k]) ? -0.0005 : 0.05;
    free = !Overlap(*fp, plan.footprints[k], margin);
  }
  for (const Footprint& door : plan.doorways) {
    free = free && !Overlap(*fp, door, 0.0);
  }
  return free;
}

void PlaceObject(const SceneOptions& options, const std::string& cls,
                 uint16_t* next_id, Rng* rng, FloorPlan* plan, Scene* scene) {
  Blueprint bp = Build(cls, *rng);
  const LabelSet& classes = SynthClasses();
  const uint16_t class_id = *classes.FindByName(cls);
  SceneObject object;
  object.instance_id = (*next_id)++;
  object.class_id = class_id;
  object.name = fmt::format("{}_{}", cls, object.instance_id);
  object.color = classes.Get(class_id).color;
  Footprint fp{{0, 0}, 0, bp.hx, bp.hy};
  double base_z = 0.0;
  bool placed = cls == "monitor" && PlaceOnTable(*scene, plan, &fp, &base_z);
  for (int attempt = 0; attempt < 400 && !placed; ++attempt) {
    placed = TryFloorPlacement(options, bp, attempt, *plan, rng, &fp);
  }
  if (!placed) {
    throw Error(fmt::format(
        "synth: cannot place object {} ('{}') in a {:.1f} x {:.1f} m room "
        "without overlaps; use a bigger room or fewer objects",
        object.instance_id, cls, options.room_width_m, options.room_depth_m));
  }
  const Eigen::Matrix3d R = Yaw(fp.yaw);
  const Eigen::Vector3d offset(fp.center.x(), fp.center.y(), base_z);
  for (const Primitive& p : bp.parts) {
    object.parts.push_back(Transformed(p, R, offset));
  }
  if (base_z == 0.0) {
    plan->footprints.push_back(fp);
    plan->footprint_object.push_back(scene->objects.size());
    plan->footprint_is_wall.push_back(false);
  }
  scene->objects.push_back(std::move(object));
}

// People walk rectangular loops in the front part of the room, long enough to
// leave the view.
void AddPeople(const SceneOptions& options, Rng* rng, Scene* scene) {
  const double W = options.room_width_m, D = options.room_depth_m;
  for (int i = 0; i < options.num_people; ++i) {
    Person person;
    person.person_id = static_cast<uint16_t>(i + 1);
    person.height_m = rng->Uniform(1.6, 1.9);
    person.shirt = kShirts[i % std::size(kShirts)];
    person.pants = kPants[i % std::size(kPants)];
    const double y0 = 0.6 + 0.15 * (i % 3), y1 = D * 0.5 - 0.1 * (i % 2);
    const double x0 = 0.5 + 0.1 * i, x1 = W - 0.5 - 0.1 * i;
    person.path = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    if (i % 2 == 1) std::reverse(person.path.begin(), person.path.end());
    person.speed_mps = rng->Uniform(0.9, 1.4);
    person.start_offset_m = rng->Uniform(0.0, 2 * (x1 - x0 + y1 - y0));
    scene->people.push_back(std::move(person));
  }
}

}  // namespace

Scene GenerateScene(const SceneOptions& options) {
  options.Check();
  Rng rng(options.seed * 0x9E3779B97F4A7C15ULL + 17);
  Scene scene;
  const double W = options.room_width_m, D = options.room_depth_m,
               H = options.room_height_m;
  scene.room_size = {W, D, H};
  uint16_t next_id = 1;
  AddRoomShell(options, &next_id, &scene);
  // Objects stay out of a walkway when people are present (the front third of
  // the room).
  FloorPlan plan;
  plan.lo = {0.0, options.num_people > 0 ? D * 0.55 : 0.0};
  plan.hi = {W, D};
  // The outer walls first, in the order the draws have always had.
  const Eigen::Vector2d lo = plan.lo, hi = plan.hi;
  plan.faces = {{{lo.x(), lo.y()}, {1, 0}, {0, 1}, hi.y() - lo.y()},
                {{hi.x(), lo.y()}, {-1, 0}, {0, 1}, hi.y() - lo.y()},
                {{lo.x(), lo.y()}, {0, 1}, {1, 0}, hi.x() - lo.x()},
                {{lo.x(), hi.y()}, {0, -1}, {1, 0}, hi.x() - lo.x()}};
  AddInteriorWalls(options, &next_id, &plan, &scene);
  for (const std::string& cls : options.object_classes) {
    PlaceObject(options, cls, &next_id, &rng, &plan, &scene);
  }
  AddPeople(options, &rng, &scene);
  return scene;
}

PersonBody PoseAt(const Person& person, double time_s) {
  // Position along the closed loop.
  std::vector<double> lengths;
  double total = 0.0;
  for (size_t i = 0; i < person.path.size(); ++i) {
    lengths.push_back(
        (person.path[(i + 1) % person.path.size()] - person.path[i]).norm());
    total += lengths.back();
  }
  const double walked = person.start_offset_m + person.speed_mps * time_s;
  double s = std::fmod(walked, total);
  if (s < 0) s += total;
  size_t seg = 0;
  while (seg + 1 < lengths.size() && s > lengths[seg]) s -= lengths[seg++];
  const Eigen::Vector2d a = person.path[seg],
                        b = person.path[(seg + 1) % person.path.size()];
  const Eigen::Vector2d dir = (b - a).normalized();
  PersonBody body;
  body.position = a + s * dir;
  body.heading_rad = std::atan2(dir.y(), dir.x());

  const double H = person.height_m;
  const double phase = 2 * M_PI * walked / 1.3;  // one gait cycle per 1.3 m
  const double swing = 0.45 * std::sin(phase);
  const Eigen::Vector3d fwd(dir.x(), dir.y(), 0), side(-dir.y(), dir.x(), 0);
  const Eigen::Vector3d base(body.position.x(), body.position.y(), 0);
  const double hip_z = 0.5 * H, shoulder_z = 0.8 * H;
  const double limb_r = 0.055 * H / 1.75, arm_r = 0.04 * H / 1.75;
  auto add = [&](const Primitive& p, const Rgb& c) {
    body.parts.push_back(p);
    body.colors.push_back(c);
  };
  for (int k : {-1, 1}) {
    const double a_leg = k * swing;
    const Eigen::Vector3d hip =
        base + k * 0.1 * H / 1.75 * side + Eigen::Vector3d(0, 0, hip_z);
    const Eigen::Vector3d foot =
        hip + (hip_z - limb_r) * (std::sin(a_leg) * fwd -
                                  std::cos(a_leg) * Eigen::Vector3d::UnitZ());
    add(Capsule{hip, foot, limb_r}, person.pants);
    const double a_arm = -k * swing * 0.8;
    const Eigen::Vector3d shoulder =
        base + k * 0.22 * H / 1.75 * side + Eigen::Vector3d(0, 0, shoulder_z);
    const Eigen::Vector3d hand =
        shoulder + 0.33 * H *
                       (std::sin(a_arm) * fwd -
                        std::cos(a_arm) * Eigen::Vector3d::UnitZ());
    add(Capsule{shoulder, hand, arm_r}, person.shirt);
  }
  add(Capsule{base + Eigen::Vector3d(0, 0, hip_z + 0.05 * H),
              base + Eigen::Vector3d(0, 0, shoulder_z - 0.02 * H),
              0.15 * H / 1.75},
      person.shirt);
  add(Sphere{base + Eigen::Vector3d(0, 0, 0.92 * H), 0.075 * H}, person.skin);
  return body;
}

}  // namespace semrec::synth
