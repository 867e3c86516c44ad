// Wall inside a thing's outline on the wall: the back panel of a shelf, seen
// between its boards, lies on the wall's plane and looks like wall to a 2D
// model in every view; the boards and sides that meet the wall around it are
// the shelf's (GateStructure, ClaimStranded). See map_resolver.h.
#include <cmath>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "semrec/fuse/map_resolver.h"

namespace semrec::fuse::internal {

namespace {

using Cell2 = std::pair<int, int>;  // along, up (voxel units)

// The cells of [lo, hi] (a box in the plane, one cell wider each way) that
// `walls` (a thing's contact cells) do not close off from the box's border,
// four-connected.
std::set<Cell2> ReachableFromBorder(const Cell2& lo, const Cell2& hi,
                                    const std::set<Cell2>& walls) {
  std::set<Cell2> reached;
  std::vector<Cell2> front;
  auto visit = [&](const Cell2& c) {
    if (c.first < lo.first || c.first > hi.first || c.second < lo.second ||
        c.second > hi.second || walls.count(c) != 0 ||
        !reached.insert(c).second) {
      return;
    }
    front.push_back(c);
  };
  for (int a = lo.first; a <= hi.first; ++a) {
    visit({a, lo.second});
    visit({a, hi.second});
  }
  for (int u = lo.second; u <= hi.second; ++u) {
    visit({lo.first, u});
    visit({hi.first, u});
  }
  while (!front.empty()) {
    const Cell2 c = front.back();
    front.pop_back();
    visit({c.first + 1, c.second});
    visit({c.first - 1, c.second});
    visit({c.first, c.second + 1});
    visit({c.first, c.second - 1});
  }
  return reached;
}

}  // namespace

void MapResolver::ClaimEnclosed() {
  constexpr size_t kMinContactCells = 5;
  const double voxel = map_.voxel_size_m();
  const Eigen::Vector3d up = context_.up_world.normalized();
  size_t claimed = 0;
  for (const StructurePlane& plane : result_.planes) {
    if (plane.geometry != StructureGeometry::kVertical) continue;
    const double tolerance = plane.Tolerance(options_.planes);
    // A thing against the wall: voxels within two voxels in front of it.
    const double contact_m = tolerance + 2.0 * voxel;
    auto cell_of = [&](const Eigen::Vector3d& q) {
      return Cell2{static_cast<int>(std::floor(plane.along.dot(q) / voxel)),
                   static_cast<int>(std::floor(up.dot(q) / voxel))};
    };
    // Per thing: its outline on the wall (where its voxels in front of the
    // wall lie, seen straight on) and how many of them touch it.
    std::map<uint32_t, std::set<Cell2>> outline;
    std::map<uint32_t, size_t> touching;
    std::map<Cell2, std::vector<size_t>> wall;
    for (size_t i = 0; i < cells_.size(); ++i) {
      const Cell& c = cells_[i];
      const Eigen::Vector3d q = c.p.cast<double>();
      const double d = plane.normal.dot(q) - plane.offset;
      if (d < -tolerance || !plane.Covers(q)) continue;
      if (c.owner != 0 && IsThingCell(c)) {
        outline[c.owner].insert(cell_of(q));
        if (d <= contact_m) ++touching[c.owner];
      } else if (c.class_id == plane.class_id && !c.stranded &&
                 d <= tolerance) {
        wall[cell_of(q)].push_back(i);
      }
    }
    auto take = [&](const std::vector<size_t>& members, uint32_t id) {
      for (size_t k : members) JoinThing(k, id);
      claimed += members.size();
    };
    for (const auto& [id, around] : outline) {
      if (touching[id] < kMinContactCells) continue;
      Cell2 lo = *around.begin(), hi = lo;
      for (const Cell2& c : around) {
        lo = {std::min(lo.first, c.first), std::min(lo.second, c.second)};
        hi = {std::max(hi.first, c.first), std::max(hi.second, c.second)};
      }
      // Closed compartments need a cell of room inside: three across.
      if (hi.first - lo.first < 2 || hi.second - lo.second < 2) continue;
      const std::set<Cell2> open = ReachableFromBorder(
          {lo.first - 1, lo.second - 1}, {hi.first + 1, hi.second + 1}, around);
      // The holes in the outline (a shelf's compartments), then the wall
      // under the outline around them (a board's back edge, its voxel shared
      // with the back panel).
      std::set<Cell2> holes;
      for (auto it = wall.lower_bound(lo);
           it != wall.end() && it->first.first <= hi.first; ++it) {
        const Cell2& c = it->first;
        if (c.second < lo.second || c.second > hi.second ||
            open.count(c) != 0 || around.count(c) != 0) {
          continue;
        }
        holes.insert(c);
        take(it->second, id);
      }
      for (const Cell2& h : holes) {
        for (const Cell2& n :
             {Cell2{h.first + 1, h.second}, Cell2{h.first - 1, h.second},
              Cell2{h.first, h.second + 1}, Cell2{h.first, h.second - 1}}) {
          const auto it = wall.find(n);
          if (it == wall.end() || holes.count(n) != 0 || around.count(n) == 0) {
            continue;
          }
          take(it->second, id);
          wall.erase(it);
        }
      }
      for (const Cell2& h : holes) wall.erase(h);
    }
  }
  result_.enclosed_voxels_claimed += claimed;
  spdlog::debug("{} wall voxels enclosed by things joined them", claimed);
}

}  // namespace semrec::fuse::internal
