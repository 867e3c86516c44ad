#include "semrec/fuse/map_objects.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <set>

#include <spdlog/spdlog.h>

#include "semrec/core/error.h"
#include "semrec/core/union_find.h"

namespace semrec::fuse {

void MapObjectOptions::Check() const {
  planes.Check();
  CheckArgument(min_seen_ratio >= 0.0 && min_seen_ratio <= 1.0,
                "map objects: min_seen_ratio must be in [0, 1]");
  CheckArgument(touch_voxels >= 1 && touch_voxels <= 3,
                "map objects: touch_voxels must be 1, 2 or 3");
}

namespace {

constexpr uint16_t kNoClass = 0xFFFF;

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

// The id with the most votes (ties: the smaller id) among `votes` passing
// `accept`; 0 when none.
template <typename Accept>
uint32_t MostVoted(const std::map<uint32_t, float>& votes,
                   const Accept& accept) {
  uint32_t best = 0;
  float best_views = 0.0f;
  for (const auto& [id, views] : votes) {
    if (views > best_views && accept(id)) best = id, best_views = views;
  }
  return best;
}

class Resolver {
 public:
  Resolver(const VoxelEvidenceMap& map, const MapContext& context,
           const MapObjectOptions& options,
           const std::function<uint32_t(uint32_t)>& resolve, uint32_t* next_id)
      : map_(map),
        context_(context),
        options_(options),
        resolve_(resolve),
        next_id_(next_id) {}

  MapResolution Run() {
    CollectCells();
    if (options_.structure_planes) GateStructure();
    AssignOwners();
    SplitDisconnected();
    AttachOrphans();
    MergeByMasks();
    JudgeFragments();
    return Build();
  }

 private:
  struct Cell {
    uint64_t key = 0;
    Eigen::Vector3f p;
    const VoxelEvidence* evidence = nullptr;
    uint16_t class_id = kNoClass;
    uint32_t owner = 0;
    uint32_t source = 0;
    /// Structure classes set aside here (off their planes).
    std::vector<uint16_t> excluded;
  };

  bool IsStuff(uint16_t class_id) const {
    const auto it = context_.kinds.find(class_id);
    return it != context_.kinds.end() && it->second == ClassKind::kStuff;
  }
  bool IsThingCell(const Cell& c) const {
    return c.class_id != kNoClass && !IsStuff(c.class_id);
  }

  // Labelled voxels in key order (deterministic), with their winners.
  void CollectCells() {
    for (const auto& [key, v] : map_.voxels()) {
      if (v.classes.empty() || v.points == 0) continue;
      cells_.push_back({key, v.Centroid(), &v, Winner(v, {}), 0, 0, {}});
    }
    std::sort(cells_.begin(), cells_.end(),
              [](const Cell& a, const Cell& b) { return a.key < b.key; });
    for (size_t i = 0; i < cells_.size(); ++i) index_[cells_[i].key] = i;
  }

  // Structure evidence off its planes is set aside; the next class wins.
  void GateStructure() {
    std::map<uint16_t, std::vector<StructurePlane>> planes;
    std::set<uint16_t> stuff_classes;
    for (const Cell& c : cells_) {
      if (c.class_id != kNoClass && IsStuff(c.class_id)) {
        stuff_classes.insert(c.class_id);
      }
    }
    const double area = map_.voxel_size_m() * map_.voxel_size_m();
    for (uint16_t cls : stuff_classes) {
      const auto g = context_.geometry.find(cls);
      if (g == context_.geometry.end() ||
          g->second == StructureGeometry::kNone) {
        continue;
      }
      Cloud points;
      for (const Cell& c : cells_) {
        if (c.class_id == cls) points.push_back(c.p);
      }
      auto found = FindStructurePlanes(points, g->second, context_.up_world,
                                       area, options_.planes);
      spdlog::debug("structure class {}: {} voxels, {} planes", cls,
                    points.size(), found.size());
      if (found.empty()) continue;  // too little seen to tell: not gated
      for (StructurePlane& p : found) p.class_id = cls;
      result_.planes.insert(result_.planes.end(), found.begin(), found.end());
      planes[cls] = std::move(found);
    }
    for (Cell& c : cells_) {
      for (;;) {
        const auto it = planes.find(c.class_id);
        if (it == planes.end() ||
            OnAnyPlane(c.p, it->second, options_.planes.tolerance_m)) {
          break;
        }
        // With no other class in view, the structure class stays: nothing
        // says otherwise (a patch of wall too small to fit a plane to).
        std::vector<uint16_t> excluded = c.excluded;
        excluded.push_back(c.class_id);
        const uint16_t next = Winner(*c.evidence, excluded);
        if (!CanTakeOver(*c.evidence, next)) break;
        c.excluded = std::move(excluded);
        c.class_id = next;
      }
      if (!c.excluded.empty()) ++result_.gated_voxels;
    }
  }

  // The next class takes a voxel off structure only on real evidence: a view
  // where it held most of the voxel's pixels and a share of its votes (not
  // the stray vote of a mask's fringe).
  bool CanTakeOver(const VoxelEvidence& v, uint16_t class_id) const {
    if (class_id == kNoClass) return false;
    const ClassEvidence* e = v.Find(class_id);
    float total = 0.0f;
    for (const ClassEvidence& c : v.classes) total += c.weight;
    return e != nullptr && e->views >= 1 &&
           e->weight >= options_.min_takeover_share * total;
  }

  uint32_t StructureId(uint16_t class_id) {
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

  // Thing voxels go to the object of their class most views put them in;
  // unclaimed ones stay 0 (orphans) for now.
  void AssignOwners() {
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

  template <typename Visit>
  void ForNeighbours(size_t i, const Visit& visit) const {
    const Eigen::Vector3i v = UnpackVoxel(cells_[i].key);
    const int r = options_.touch_voxels;
    for (int dx = -r; dx <= r; ++dx) {
      for (int dy = -r; dy <= r; ++dy) {
        for (int dz = -r; dz <= r; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          const auto it =
              index_.find(PackVoxel(v.x() + dx, v.y() + dy, v.z() + dz));
          if (it != index_.end()) visit(it->second);
        }
      }
    }
  }

  // Connected cells (from `seed`) for which `member` holds.
  template <typename Member>
  std::vector<size_t> Component(size_t seed, std::vector<bool>* done,
                                const Member& member) const {
    std::vector<size_t> component{seed};
    (*done)[seed] = true;
    for (size_t k = 0; k < component.size(); ++k) {
      ForNeighbours(component[k], [&](size_t n) {
        if (!(*done)[n] && member(n)) {
          (*done)[n] = true;
          component.push_back(n);
        }
      });
    }
    return component;
  }

  // The thing object of `class_id` (other than `except`) touching `cells`
  // most; 0 when none.
  uint32_t MostTouching(const std::vector<size_t>& cells, uint16_t class_id,
                        uint32_t except,
                        const std::set<uint32_t>& refused = {}) const {
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

  // Views that saw two groups of cells: holding both in one mask, or in
  // different masks.
  struct PairViews {
    size_t one = 0, two = 0;
  };
  // Per frame, the masks holding `cells` (covering enough of them).
  std::map<size_t, std::set<uint64_t>> Holders(
      const std::vector<size_t>& cells) const {
    std::map<uint64_t, size_t> count;
    for (size_t i : cells) {
      for (uint64_t m : cells_[i].evidence->masks) ++count[m];
    }
    // A share of the part, not a few voxels at the contact where the depth
    // of two touching objects mixes.
    const auto need = std::max(
        std::min<size_t>(cells.size(), 5),
        static_cast<size_t>(std::ceil(options_.min_hold_share *
                                      static_cast<double>(cells.size()))));
    std::map<size_t, std::set<uint64_t>> holders;
    for (const auto& [m, n] : count) {
      if (n >= need) holders[MaskFrame(m)].insert(m);
    }
    return holders;
  }
  static PairViews CoViews(const std::map<size_t, std::set<uint64_t>>& a,
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
  bool SaysOne(const PairViews& v, size_t min_one) const {
    return v.one >= min_one &&
           static_cast<double>(v.one) >
               options_.two_weight * static_cast<double>(v.two);
  }

  // Pieces of an object that do not touch: those the views held in one mask
  // stay with the largest; other large groups become objects, small ones
  // orphans (joined below).
  void SplitDisconnected() {
    std::vector<bool> done(cells_.size(), false);
    std::map<uint32_t, std::vector<std::vector<size_t>>> pieces;
    for (size_t i = 0; i < cells_.size(); ++i) {
      if (done[i] || cells_[i].owner == 0 || !IsThingCell(cells_[i])) continue;
      const uint32_t owner = cells_[i].owner;
      pieces[owner].push_back(Component(
          i, &done, [&](size_t n) { return cells_[n].owner == owner; }));
    }
    for (auto& [owner, list] : pieces) {
      if (list.size() < 2) continue;
      std::stable_sort(
          list.begin(), list.end(),
          [](const auto& a, const auto& b) { return a.size() > b.size(); });
      std::vector<std::map<size_t, std::set<uint64_t>>> holders;
      for (const auto& piece : list) holders.push_back(Holders(piece));
      UnionFind groups(list.size());
      for (size_t a = 0; a < list.size(); ++a) {
        for (size_t b = a + 1; b < list.size(); ++b) {
          if (SaysOne(CoViews(holders[a], holders[b]), 1)) groups.Unite(a, b);
        }
      }
      std::map<size_t, uint32_t> group_id{{groups.Find(0), owner}};
      for (size_t k = 1; k < list.size(); ++k) {
        const size_t g = groups.Find(k);
        if (!group_id.count(g)) {
          group_id[g] = 0;
          if (list[k].size() >= options_.min_piece_voxels) {
            group_id[g] = (*next_id_)++;
            owner_class_[group_id[g]] = owner_class_[owner];
            ++result_.split_objects;
          }
        }
        for (size_t i : list[k]) cells_[i].owner = group_id[g];
      }
    }
  }

  // Share of `cells`' class evidence that goes to `class_id`.
  double VoteShare(const std::vector<size_t>& cells, uint16_t class_id) const {
    double total = 0.0, of_class = 0.0;
    for (size_t i : cells) {
      for (const ClassEvidence& e : cells_[i].evidence->classes) {
        total += e.weight;
        if (e.class_id == class_id) of_class += e.weight;
      }
    }
    return total > 0.0 ? of_class / total : 0.0;
  }

  // Whether touching objects a and b are one. One class: unless two views or
  // more held them in different masks and the views holding both in one mask
  // are too few (masks cut one object apart far more often than they join
  // two; sparse views see an object once or twice). Two classes: when views
  // held both in one mask, none said two more often, and one's votes give the
  // other's class at least confusion_share (one object, its class confused).
  bool OneObject(const std::vector<size_t>& a, const std::vector<size_t>& b,
                 uint32_t id_a, uint32_t id_b, const PairViews& views) const {
    const uint16_t ca = owner_class_.at(id_a), cb = owner_class_.at(id_b);
    if (ca == cb) {
      return views.two == 0 || SaysOne(views, options_.min_one_views);
    }
    return SaysOne(views, 1) && std::max(VoteShare(a, cb), VoteShare(b, ca)) >=
                                    options_.confusion_share;
  }

  // Touching objects that are one (OneObject) become one; the larger keeps
  // its id and class.
  void MergeByMasks() {
    std::map<uint32_t, std::vector<size_t>> members;
    for (size_t i = 0; i < cells_.size(); ++i) {
      if (cells_[i].owner != 0 && IsThingCell(cells_[i])) {
        members[cells_[i].owner].push_back(i);
      }
    }
    std::map<uint32_t, std::map<size_t, std::set<uint64_t>>> holders;
    for (const auto& [id, cells] : members) holders[id] = Holders(cells);
    std::set<std::pair<uint32_t, uint32_t>> pairs;
    for (const auto& entry : members) {
      const uint32_t id = entry.first;
      for (size_t i : entry.second) {
        ForNeighbours(i, [&](size_t n) {
          const uint32_t other = cells_[n].owner;
          if (other > id && IsThingCell(cells_[n])) pairs.emplace(id, other);
        });
      }
    }
    // Judged on the objects as they were: a chain of merges does not change
    // the evidence of a pair.
    std::vector<std::pair<uint32_t, uint32_t>> one;
    for (const auto& [a, b] : pairs) {
      if (OneObject(members[a], members[b], a, b,
                    CoViews(holders[a], holders[b]))) {
        one.emplace_back(a, b);
      }
    }
    std::map<uint32_t, uint32_t> into;
    auto find = [&](uint32_t id) {
      while (into.count(id)) id = into[id];
      return id;
    };
    for (const auto& [a, b] : one) {
      const uint32_t x = find(a), y = find(b);
      if (x == y) continue;
      const bool x_keeps = members[x].size() >= members[y].size();
      const uint32_t keep = x_keeps ? x : y, gone = x_keeps ? y : x;
      into[gone] = keep;
      members[keep].insert(members[keep].end(), members[gone].begin(),
                           members[gone].end());
      ++result_.merged_objects;
    }
    for (Cell& c : cells_) {
      if (c.owner == 0 || !IsThingCell(c)) continue;
      c.owner = find(c.owner);
      c.class_id = owner_class_[c.owner];
    }
  }

  // Thing voxels no object of their class claimed: each connected group joins
  // the object of its class it touches most, or becomes a new object.
  void AttachOrphans() {
    std::vector<bool> done(cells_.size(), false);
    for (size_t i = 0; i < cells_.size(); ++i) {
      const Cell& c = cells_[i];
      if (done[i] || c.owner != 0 || !IsThingCell(c)) continue;
      const uint16_t cls = c.class_id;
      const auto group = Component(i, &done, [&](size_t n) {
        return cells_[n].owner == 0 && cells_[n].class_id == cls;
      });
      uint32_t id = MostTouching(group, cls, 0);
      spdlog::debug("orphan voxels: {} of class {} -> object {}", group.size(),
                    cls, id);
      if (id == 0) {
        id = (*next_id_)++;
        owner_class_[id] = cls;
        ++result_.new_objects;
      }
      for (size_t n : group) cells_[n].owner = id;
    }
  }

  // Seen in few of the views that observed it: folded into the touching object
  // of its class, or dropped. A view that called the place structure where no
  // structure can be (set aside by the gate) did see it: it counts as a
  // sighting.
  void JudgeFragments() {
    std::map<uint32_t, std::vector<size_t>> members;
    for (size_t i = 0; i < cells_.size(); ++i) {
      if (cells_[i].owner != 0 && IsThingCell(cells_[i])) {
        members[cells_[i].owner].push_back(i);
      }
    }
    std::vector<std::pair<size_t, uint32_t>> fragments;  // (size, id)
    for (const auto& [id, cells] : members) {
      const auto [ratio, max_views] = Visibility(cells);
      seen_[id] = {ratio, max_views};
      if (cells.size() < options_.min_voxels ||
          ratio < options_.min_seen_ratio) {
        fragments.emplace_back(cells.size(), id);
      }
    }
    std::sort(fragments.begin(), fragments.end());
    std::set<uint32_t> refused;
    for (const auto& [size, id] : fragments) refused.insert(id);
    for (const auto& [size, id] : fragments) {
      const std::vector<size_t>& cells = members[id];
      const uint32_t into = MostTouching(cells, owner_class_[id], id, refused);
      for (size_t i : cells) {
        cells_[i].owner = into;
        if (into == 0) cells_[i].class_id = kNoClass;
      }
      ++(into ? result_.fragments_folded : result_.fragments_dropped);
    }
  }

  std::pair<double, uint32_t> Visibility(
      const std::vector<size_t>& cells) const {
    double labelled = 0.0, observed = 0.0;
    uint32_t max_views = 0;
    for (size_t i : cells) {
      const Cell& c = cells_[i];
      uint32_t views = 0;
      for (const ClassEvidence& e : c.evidence->classes) {
        if (e.class_id == c.class_id ||
            std::find(c.excluded.begin(), c.excluded.end(), e.class_id) !=
                c.excluded.end()) {
          views += e.views;
        }
      }
      labelled += views;
      observed += std::max(c.evidence->views, views);
      max_views = std::max(max_views, views);
    }
    return {observed > 0.0 ? labelled / observed : 0.0, max_views};
  }

  MapResolution Build() {
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

  const VoxelEvidenceMap& map_;
  const MapContext& context_;
  const MapObjectOptions& options_;
  const std::function<uint32_t(uint32_t)>& resolve_;
  uint32_t* next_id_;
  std::vector<Cell> cells_;
  std::unordered_map<uint64_t, size_t> index_;
  std::map<uint16_t, uint32_t> structure_ids_;
  std::map<uint32_t, uint16_t> owner_class_;
  std::map<uint32_t, std::pair<double, uint32_t>> seen_;
  MapResolution result_;
};

}  // namespace

MapContext MakeMapContext(const LabelSet& classes,
                          const Eigen::Vector3d& up_world) {
  MapContext context;
  context.up_world = up_world;
  for (const LabelClass& c : classes.Classes()) {
    context.kinds[c.id] = c.kind;
    context.geometry[c.id] = c.kind == ClassKind::kStuff
                                 ? StructureGeometryOf(c.name)
                                 : StructureGeometry::kNone;
  }
  return context;
}

MapResolution ResolveMapObjects(
    const VoxelEvidenceMap& map, const MapContext& context,
    const MapObjectOptions& options,
    const std::function<uint32_t(uint32_t)>& resolve, uint32_t* next_id) {
  options.Check();
  CheckArgument(next_id != nullptr, "ResolveMapObjects: next_id is null");
  return Resolver(map, context, options, resolve, next_id).Run();
}

}  // namespace semrec::fuse
