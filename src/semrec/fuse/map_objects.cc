#include "semrec/fuse/map_objects.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "semrec/core/error.h"
#include "semrec/core/stopwatch.h"
#include "semrec/fuse/map_resolver.h"

namespace semrec::fuse {

void MapObjectOptions::Check() const {
  planes.Check();
  CheckArgument(min_seen_ratio >= 0.0 && min_seen_ratio <= 1.0,
                "map objects: min_seen_ratio must be in [0, 1]");
  CheckArgument(min_far_views >= 1, "map objects: min_far_views must be >= 1");
  CheckArgument(
      min_stranded_contact_share >= 0.0 && min_stranded_contact_share <= 1.0,
      "map objects: min_stranded_contact_share must be in [0, 1]");
  CheckArgument(
      min_structure_on_planes >= 0.0 && min_structure_on_planes <= 1.0,
      "map objects: min_structure_on_planes must be in [0, 1]");
  CheckArgument(min_front_share >= 0.0 && min_front_share <= 1.0,
                "map objects: min_front_share must be in [0, 1]");
  CheckArgument(
      min_attached_contact_share > 0.0 && min_attached_contact_share <= 1.0 &&
          max_attached_size_ratio >= 0.0 && max_attached_size_ratio <= 1.0,
      "map objects: attached-piece shares must be in (0, 1]");
  CheckArgument(min_part_contact_share > 0.0 && min_part_contact_share <= 1.0,
                "map objects: min_part_contact_share must be in (0, 1]");
  CheckArgument(min_nested_share >= 0.0 && min_nested_share <= 1.0,
                "map objects: min_nested_share must be in [0, 1]");
  CheckArgument(min_apart_views >= 1,
                "map objects: min_apart_views must be >= 1");
  CheckArgument(max_one_share >= 0.0 && max_one_share <= 1.0,
                "map objects: max_one_share must be in [0, 1]");
  CheckArgument(confusion_share >= 0.0 && confusion_share <= 1.0 &&
                    tie_confusion_share >= 0.0 && tie_confusion_share <= 1.0,
                "map objects: confusion shares must be in [0, 1]");
  CheckArgument(min_flush_share > 0.0 && min_flush_share <= 1.0,
                "map objects: min_flush_share must be in (0, 1]");
  CheckArgument(size_slack == 0.0 || size_slack >= 1.0,
                "map objects: size_slack must be 0 (off) or >= 1");
  CheckArgument(min_size_class_share >= 0.0 && min_size_class_share <= 1.0,
                "map objects: min_size_class_share must be in [0, 1]");
  CheckArgument(max_speck_gap_m >= 0.0,
                "map objects: max_speck_gap_m must be >= 0");
  CheckArgument(touch_voxels >= 1 && touch_voxels <= 3,
                "map objects: touch_voxels must be 1, 2 or 3");
  for (const std::string& pass : skip_passes) {
    const auto& names = MapResolverPassNames();
    std::string known;
    for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
    CheckArgument(
        std::find(names.begin(), names.end(), pass) != names.end(),
        "map objects: no resolver pass '" + pass + "' (passes: " + known + ")");
  }
}

const std::vector<std::string>& MapResolverPassNames() {
  static const std::vector<std::string> kNames = [] {
    std::vector<std::string> names;
    for (const auto& pass : internal::MapResolver::Passes()) {
      names.push_back(pass.name);
    }
    return names;
  }();
  return kNames;
}

namespace internal {
namespace {

// The class with the most evidence, leaving out `excluded` (ties: the smaller
// id); kNoClass when none is left.
uint16_t Winner(const VoxelEvidence& v, const std::vector<uint16_t>& excluded) {
  uint16_t best = kNoClass;
  float best_weight = 0.0f;
  for (const ClassEvidence& c : v.classes) {
    if (c.weight <= 0.0f || std::find(excluded.begin(), excluded.end(),
                                      c.class_id) != excluded.end()) {
      continue;
    }
    if (c.weight > best_weight ||
        (c.weight == best_weight && c.class_id < best)) {
      best = c.class_id, best_weight = c.weight;
    }
  }
  return best;
}

}  // namespace

const std::vector<MapResolver::Pass>& MapResolver::Passes() {
  // The object decision, in the order it runs (docs/fusion.md): structure
  // from planes, objects from the fusion's, splits and merges by the masks'
  // consensus, fragments by visibility, structure that only
  // things can own.
  static const std::vector<Pass> kPasses = {
      {"gate-structure", &MapResolver::GateStructure,
       [](const MapObjectOptions& o) { return o.structure_planes; }},
      {"release-flush-parts", &MapResolver::ReleaseFlushParts,
       [](const MapObjectOptions& o) {
         return o.structure_planes && o.min_flush_share < 1.0;
       }},
      {"assign-owners", &MapResolver::AssignOwners, nullptr},
      {"split-by-masks", &MapResolver::SplitByMasks, nullptr},
      {"split-disconnected", &MapResolver::SplitDisconnected, nullptr},
      {"attach-orphans", &MapResolver::AttachOrphans, nullptr},
      {"merge-by-masks", &MapResolver::MergeByMasks, nullptr},
      {"judge-fragments", &MapResolver::JudgeFragments, nullptr},
      {"claim-fronts", &MapResolver::ClaimFronts,
       [](const MapObjectOptions& o) { return o.claim_stranded; }},
      {"claim-stranded", &MapResolver::ClaimStranded,
       [](const MapObjectOptions& o) { return o.claim_stranded; }},
      {"claim-enclosed", &MapResolver::ClaimEnclosed,
       [](const MapObjectOptions& o) {
         return o.structure_planes && o.claim_enclosed;
       }},
      {"release-far-specks", &MapResolver::ReleaseFarSpecks,
       [](const MapObjectOptions& o) { return o.max_speck_gap_m > 0.0; }},
  };
  return kPasses;
}

MapResolution MapResolver::Run() {
  CollectCells();
  for (const Pass& pass : Passes()) {
    if (pass.enabled != nullptr && !pass.enabled(options_)) continue;
    if (options_.skip_passes.contains(pass.name)) {
      spdlog::debug("resolver pass {} left out", pass.name);
      continue;
    }
    (this->*pass.run)();
  }
  return Build();
}

void MapResolver::CollectCells() {
  // The far views' class weights join the voxel's; their views count for
  // visibility only (Visibility), not as ranged views of a class (which let a
  // class take over gated structure, CanTakeOver).
  const Stopwatch far_start;
  far_ = map_.FarVotes();
  for (const auto& [key, votes] : far_) {
    VoxelEvidence& v = amended_[key] = map_.voxels().at(key);
    for (const ClassEvidence& far : votes.classes) {
      FindOrAddClass(&v.classes, far.class_id)->weight += far.weight;
    }
  }
  spdlog::debug("far views: {}, voxels they voted on: {} ({:.1f} ms)",
                map_.far_view_count(), amended_.size(),
                1000.0 * far_start.Elapsed());
  for (const auto& [key, v] : map_.voxels()) {
    if (v.classes.empty() || v.points == 0) continue;
    const auto amended = amended_.find(key);
    const VoxelEvidence& e = amended == amended_.end() ? v : amended->second;
    cells_.push_back({key, v.Centroid(), &e, Winner(e, {}), 0, 0, {}});
  }
  std::sort(cells_.begin(), cells_.end(),
            [](const Cell& a, const Cell& b) { return a.key < b.key; });
  for (size_t i = 0; i < cells_.size(); ++i) index_[cells_[i].key] = i;
  NeighbourLists();
}

void MapResolver::NeighbourLists() {
  std::vector<uint32_t> start, list;
  start.reserve(cells_.size() + 1);
  start.push_back(0);
  for (size_t i = 0; i < cells_.size(); ++i) {
    ForNeighbours(i,
                  [&](size_t n) { list.push_back(static_cast<uint32_t>(n)); });
    start.push_back(static_cast<uint32_t>(list.size()));
  }
  neighbour_start_ = std::move(start);
  neighbours_ = std::move(list);
}

double MapResolver::ShareOnPlanes(
    const Cloud& points, const std::vector<StructurePlane>& planes,
    const std::vector<StructurePlane>& fronts) const {
  if (points.empty() || (planes.empty() && fronts.empty())) return 1.0;
  size_t on = 0;
  for (const Eigen::Vector3f& p : points) {
    const Eigen::Vector3d q = p.cast<double>();
    const auto near = [&](const StructurePlane& plane) {
      return std::abs(plane.normal.dot(q) - plane.offset) <=
             1.5 * plane.Tolerance(options_.planes);
    };
    on += std::any_of(planes.begin(), planes.end(), near) ||
          std::any_of(fronts.begin(), fronts.end(), near);
  }
  return static_cast<double>(on) / static_cast<double>(points.size());
}

void MapResolver::GateStructure() {
  std::set<uint16_t> stuff_classes;
  for (const Cell& c : cells_) {
    if (c.class_id != kNoClass && IsStuff(c.class_id)) {
      stuff_classes.insert(c.class_id);
    }
  }
  const double area = map_.voxel_size_m() * map_.voxel_size_m();
  Cloud scene;
  std::vector<Eigen::Vector3f> scene_seen_from;
  scene.reserve(cells_.size());
  scene_seen_from.reserve(cells_.size());
  for (const Cell& c : cells_) {
    scene.push_back(c.p);
    scene_seen_from.push_back(c.evidence->towards_camera_sum);
  }
  for (uint16_t cls : stuff_classes) {
    const auto g = context_.geometry.find(cls);
    if (g == context_.geometry.end() || g->second == StructureGeometry::kNone) {
      continue;
    }
    Cloud points;
    std::vector<Eigen::Vector3f> towards_camera;
    for (const Cell& c : cells_) {
      if (c.class_id != cls) continue;
      points.push_back(c.p);
      towards_camera.push_back(c.evidence->towards_camera_sum);
    }
    // Low vertical planes are no walls, but may be the front of furniture
    // the views called wall (a row of base cabinets): tested too.
    std::vector<StructurePlane> low;
    auto found = FindStructurePlanes(points, g->second, context_.up_world, area,
                                     options_.planes, towards_camera, &low);
    OrientToInterior(scene, options_.planes.tolerance_m, &found);
    OrientToInterior(scene, options_.planes.tolerance_m, &low);
    std::vector<StructurePlane> fronts = TakeFurnitureFronts(
        scene, context_.up_world, options_.planes, &found, scene_seen_from);
    for (StructurePlane& p :
         TakeFurnitureFronts(scene, context_.up_world, options_.planes, &low,
                             scene_seen_from)) {
      fronts.push_back(std::move(p));
    }
    const double on_planes = ShareOnPlanes(points, found, fronts);
    spdlog::debug(
        "structure class {}: {} voxels, {} planes, {} furniture fronts, "
        "{:.0f}% of the voxels on them",
        cls, points.size(), found.size(), fronts.size(), 100.0 * on_planes);
    if (on_planes < options_.min_structure_on_planes) {
      spdlog::info(
          "structure class {}: its planes hold only {:.0f}% of its {} voxels "
          "(depth too noisy or bent for planes): not gated",
          cls, 100.0 * on_planes, points.size());
      continue;
    }
    for (StructurePlane& p : fronts) p.class_id = cls;
    fronts_.insert(fronts_.end(), fronts.begin(), fronts.end());
    // Too little seen to tell: not gated; where every plane was a front,
    // nothing of the class is structure.
    if (found.empty() && fronts.empty()) continue;
    for (StructurePlane& p : found) p.class_id = cls;
    result_.planes.insert(result_.planes.end(), found.begin(), found.end());
    planes_[cls] = std::move(found);
  }
  for (Cell& c : cells_) {
    // The surface's own orientation, where its normals agree: a board running
    // into the wall lies within the wall plane's tolerance but is no wall.
    Eigen::Vector3f axis;
    const Eigen::Vector3f* surface =
        c.evidence->SurfaceAxis(
            static_cast<float>(options_.planes.min_normal_agreement),
            static_cast<float>(options_.planes.min_normal_points), &axis)
            ? &axis
            : nullptr;
    // On its class's planes and turned along them; or in the corner where
    // such a plane meets another structure plane it is turned along (a wall
    // voxel holding the ceiling's edge holds both).
    auto on_own = [&](const std::vector<StructurePlane>& own) {
      return OnStructure(c.p, own, options_.planes, 1.0, surface) ||
             (surface != nullptr && OnStructure(c.p, own, options_.planes) &&
              OnStructure(c.p, result_.planes, options_.planes, 1.0, surface));
    };
    for (;;) {
      const auto it = planes_.find(c.class_id);
      if (it == planes_.end() || on_own(it->second)) break;
      // With no other class in view, the structure class stays: nothing
      // says otherwise (a patch of wall too small to fit a plane to).
      std::vector<uint16_t> excluded = c.excluded;
      excluded.push_back(c.class_id);
      uint16_t next = Winner(*c.evidence, excluded);
      // Nor a structure class no plane was found for (little ceiling seen)
      // when the surface is not turned as that class's are: the end of a
      // partition, off its faces' planes, had a few votes for the ceiling.
      while (next != kNoClass && IsStuff(next) &&
             UnplacedAndTurnedAway(next, surface)) {
        excluded.push_back(next);
        next = Winner(*c.evidence, excluded);
      }
      if (!CanTakeOver(*c.evidence, next)) {
        // Stranded only clearly off the planes (a bumpy wall's noise band,
        // just beyond the tolerance, stays structure), and not where it lies
        // on another structure plane it is turned along: structure still.
        c.stranded =
            !OnStructure(c.p, it->second, options_.planes, 1.5, surface) &&
            (surface == nullptr ||
             !OnStructure(c.p, result_.planes, options_.planes, 1.5, surface));
        break;
      }
      c.excluded = std::move(excluded);
      c.class_id = next;
    }
    if (!c.excluded.empty()) ++result_.gated_voxels;
  }
}

bool MapResolver::UnplacedAndTurnedAway(
    uint16_t class_id, const Eigen::Vector3f* surface_axis) const {
  const auto g = context_.geometry.find(class_id);
  if (surface_axis == nullptr || g == context_.geometry.end() ||
      g->second == StructureGeometry::kNone || planes_.count(class_id) != 0) {
    return false;
  }
  const double up =
      std::abs(context_.up_world.dot(surface_axis->cast<double>()));
  // A wall's normal is horizontal, a floor's or a ceiling's vertical: the
  // best |cos| the axis can have with such a normal.
  const double facing = g->second == StructureGeometry::kVertical
                            ? std::sqrt(std::max(0.0, 1.0 - up * up))
                            : up;
  return facing < options_.planes.MinSurfaceFacing();
}

void MapResolver::ReleaseFlushParts() {
  // Candidates: structure voxels whose best thing class holds a large share.
  std::vector<uint16_t> thing(cells_.size(), kNoClass);
  for (size_t i = 0; i < cells_.size(); ++i) {
    const Cell& c = cells_[i];
    if (c.class_id == kNoClass || !IsStuff(c.class_id) || c.stranded) continue;
    // Only structure that lives on planes (wall, floor, ceiling; also where
    // too little of it was seen to fit one: a small scan's wall).
    const auto g = context_.geometry.find(c.class_id);
    if (g == context_.geometry.end() || g->second == StructureGeometry::kNone) {
      continue;
    }
    float total = 0.0f, best = 0.0f;
    uint16_t best_class = kNoClass;
    for (const ClassEvidence& e : c.evidence->classes) {
      total += e.weight;
      if (!IsStuff(e.class_id) && e.weight > best) {
        best = e.weight, best_class = e.class_id;
      }
    }
    if (best_class != kNoClass && best >= options_.min_flush_share * total) {
      thing[i] = best_class;
    }
  }
  // Grown ring by ring from the things' voxels that stand off every
  // structure plane and not just behind a wall (the bed in front of the wall;
  // not the top of a partition some views called cabinet, which grew over
  // the partition's face: 7-Scenes chess), through the thing's own voxels on
  // the planes and the candidates.
  std::vector<bool> reached(cells_.size(), false);
  std::vector<size_t> front;
  for (size_t i = 0; i < cells_.size(); ++i) {
    const Cell& c = cells_[i];
    if (c.class_id != kNoClass && !IsStuff(c.class_id) &&
        !OnStructure(c.p, result_.planes, options_.planes) &&
        !BehindWall(c.p, result_.planes, options_.planes)) {
      front.push_back(i);
      reached[i] = true;
    }
  }
  size_t released = 0;
  while (!front.empty()) {
    std::vector<size_t> next;
    for (size_t i : front) {
      const uint16_t cls = cells_[i].class_id;
      ForNeighbours(
          i,
          [&](size_t n) {
            if (reached[n]) return;
            if (thing[n] == cls) {
              // Counted once with the gated ones (a voxel gated wall -> floor
              // already was).
              released += cells_[n].excluded.empty() ? 1 : 0;
              cells_[n].excluded.push_back(cells_[n].class_id);
              cells_[n].class_id = cls;
            } else if (cells_[n].class_id != cls) {
              return;
            }
            reached[n] = true;
            next.push_back(n);
          },
          1);
    }
    front = std::move(next);
  }
  spdlog::debug("{} structure voxels released to things flush with them",
                released);
  result_.gated_voxels += released;
}

bool MapResolver::CanTakeOver(const VoxelEvidence& v, uint16_t class_id) const {
  if (class_id == kNoClass) return false;
  const ClassEvidence* e = v.Find(class_id);
  float total = 0.0f;
  for (const ClassEvidence& c : v.classes) total += c.weight;
  return e != nullptr && e->views >= 1 &&
         e->weight >= options_.min_takeover_share * total;
}

uint32_t MapResolver::StructureId(uint16_t class_id) {
  if (const auto it = structure_ids_.find(class_id);
      it != structure_ids_.end()) {
    return it->second;
  }
  uint32_t id = 0;
  for (const auto& [object_id, o] : context_.objects) {
    if (o.kind == ClassKind::kStuff && o.class_id == class_id) {
      id = object_id;
      break;
    }
  }
  if (id == 0) id = (*next_id_)++;
  owner_class_[id] = class_id;
  return structure_ids_[class_id] = id;
}

void MapResolver::AssignOwners() {
  for (Cell& c : cells_) {
    if (c.class_id == kNoClass) continue;
    std::map<uint32_t, float> votes;
    for (const ObjectVote& v : c.evidence->objects) {
      if (const uint32_t id = resolve_(v.id); id != 0) votes[id] += v.views;
    }
    c.source = MostVoted(votes, [](uint32_t) { return true; });
    if (IsStuff(c.class_id)) {
      c.owner = StructureId(c.class_id);
      continue;
    }
    c.owner = MostVoted(votes, [&](uint32_t id) {
      const auto it = context_.objects.find(id);
      return it != context_.objects.end() &&
             it->second.kind != ClassKind::kStuff &&
             it->second.class_id == c.class_id;
    });
    if (c.owner != 0) owner_class_[c.owner] = c.class_id;
  }
}

uint32_t MapResolver::MostTouching(const std::vector<size_t>& cells,
                                   uint16_t class_id, uint32_t except,
                                   const std::set<uint32_t>& refused) const {
  std::map<uint32_t, float> contacts;
  for (size_t i : cells) {
    ForNeighbours(i, [&](size_t n) {
      const Cell& c = cells_[n];
      if (c.owner != 0 && c.owner != except && c.class_id == class_id &&
          !IsStuff(c.class_id) && refused.count(c.owner) == 0) {
        contacts[c.owner] += 1.0f;
      }
    });
  }
  return MostVoted(contacts, [](uint32_t) { return true; });
}

std::map<size_t, std::set<uint64_t>> MapResolver::Holders(
    const std::vector<size_t>& cells) const {
  std::map<uint64_t, size_t> count;
  std::map<size_t, size_t> in_view;  // frame -> cells it labelled
  for (size_t i : cells) {
    for (uint64_t m : cells_[i].evidence->masks) {
      ++count[m];
      ++in_view[MaskFrame(m)];
    }
  }
  const size_t floor = std::min(cells.size(), kContactVoxels);
  std::map<size_t, std::set<uint64_t>> holders;
  for (const auto& [m, n] : count) {
    const size_t seen = in_view[MaskFrame(m)];
    const auto need = std::max(
        floor, static_cast<size_t>(std::ceil(options_.min_hold_share *
                                             static_cast<double>(seen))));
    if (n >= need) holders[MaskFrame(m)].insert(m);
  }
  return holders;
}

MapResolver::PairViews MapResolver::CoViews(
    const std::map<size_t, std::set<uint64_t>>& a,
    const std::map<size_t, std::set<uint64_t>>& b) {
  PairViews v;
  for (const auto& [frame, masks] : a) {
    const auto it = b.find(frame);
    if (it == b.end()) continue;
    const bool shared = std::any_of(masks.begin(), masks.end(), [&](auto m) {
      return it->second.count(m) != 0;
    });
    ++(shared ? v.one : v.two);
  }
  return v;
}

bool MapResolver::SaysApart(const PairViews& v) const {
  return v.two >= 1 && static_cast<double>(v.one) <=
                           options_.max_one_share * static_cast<double>(v.two);
}

bool MapResolver::SaysOne(const PairViews& v, size_t min_one) const {
  return v.one >= min_one &&
         static_cast<double>(v.one) >
             options_.two_weight * static_cast<double>(v.two);
}

double MapResolver::VoteShare(const std::vector<size_t>& cells,
                              uint16_t class_id) const {
  double total = 0.0, of_class = 0.0;
  for (size_t i : cells) {
    for (const ClassEvidence& e : cells_[i].evidence->classes) {
      total += e.weight;
      if (e.class_id == class_id) of_class += e.weight;
    }
  }
  return total > 0.0 ? of_class / total : 0.0;
}

std::map<uint16_t, double> MapResolver::ViewVotes(
    const std::vector<size_t>& cells) const {
  std::map<size_t, std::map<uint16_t, size_t>> per_view;
  std::map<uint16_t, uint16_t> far_views;
  for (size_t i : cells) {
    for (uint64_t m : cells_[i].evidence->masks) {
      if (const uint16_t cls = map_.MaskClass(m); cls != 0) {
        ++per_view[MaskFrame(m)][cls];
      }
    }
    if (const auto far = far_.find(cells_[i].key); far != far_.end()) {
      for (const ClassEvidence& e : far->second.classes) {
        far_views[e.class_id] = std::max(far_views[e.class_id], e.views);
      }
    }
  }
  std::map<uint16_t, double> votes;
  const size_t floor = std::min(cells.size(), kContactVoxels);
  for (const auto& [frame, counts] : per_view) {
    size_t total = 0;
    for (const auto& [cls, n] : counts) total += n;
    if (total < floor) continue;
    for (const auto& [cls, n] : counts) {
      votes[cls] += static_cast<double>(n) / static_cast<double>(total);
    }
  }
  for (const auto& [cls, n] : far_views) votes[cls] += n;
  return votes;
}

double MapResolver::ShareOf(const std::map<uint16_t, double>& votes,
                            uint16_t class_id) {
  double total = 0.0;
  for (const auto& [cls, n] : votes) total += n;
  const auto it = votes.find(class_id);
  return total > 0.0 && it != votes.end() ? it->second / total : 0.0;
}

MapResolution MapResolver::Build() {
  std::map<uint32_t, MapObject> objects;
  std::map<uint32_t, std::set<uint32_t>> sources;
  for (const Cell& c : cells_) {
    if (c.owner == 0 || c.class_id == kNoClass) continue;
    MapObject& o = objects[c.owner];
    o.id = c.owner;
    o.class_id = owner_class_[c.owner];
    o.kind = IsStuff(o.class_id) ? ClassKind::kStuff : ClassKind::kThing;
    if (const auto k = context_.kinds.find(o.class_id);
        k != context_.kinds.end()) {
      o.kind = k->second;
    }
    o.voxels.push_back(c.key);
    for (const ClassEvidence& e : c.evidence->classes) {
      o.class_votes[e.class_id] +=
          static_cast<uint64_t>(std::lround(e.weight * 100.0f));
    }
    if (c.source != 0) sources[c.owner].insert(c.source);
    result_.owners[c.key] = {c.owner, c.source};
  }
  for (auto& [id, o] : objects) {
    o.sources.assign(sources[id].begin(), sources[id].end());
    if (const auto it = seen_.find(id); it != seen_.end()) {
      o.seen_ratio = it->second.first;
      o.max_views = it->second.second;
    }
    result_.objects.push_back(std::move(o));
  }
  return std::move(result_);
}

}  // namespace internal

MapContext MakeMapContext(const LabelSet& classes,
                          const Eigen::Vector3d& up_world) {
  MapContext context;
  context.up_world = up_world;
  for (const LabelClass& c : classes.Classes()) {
    context.kinds[c.id] = c.kind;
    if (c.kind == ClassKind::kThing && c.max_length_m > 0.0) {
      context.max_length_m[c.id] = c.max_length_m;
      context.max_width_m[c.id] = c.max_width_m;
    }
    context.geometry[c.id] =
        c.kind == ClassKind::kStuff ? c.geometry : StructureGeometry::kNone;
    if (c.kind == ClassKind::kThing && c.furniture_front) {
      context.front_classes.push_back(c.id);
    }
  }
  return context;
}

MapResolution ResolveMapObjects(
    const VoxelEvidenceMap& map, const MapContext& context,
    const MapObjectOptions& options,
    const std::function<uint32_t(uint32_t)>& resolve, uint32_t* next_id) {
  options.Check();
  CheckArgument(next_id != nullptr, "ResolveMapObjects: next_id is null");
  return internal::MapResolver(map, context, options, resolve, next_id).Run();
}

}  // namespace semrec::fuse
