// Sizes and boxes of the map's objects: footprints (without specks), the
// fit of one object of a class, nesting, and objects too large for their
// class (see map_resolver.h).
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "semrec/fuse/map_resolver.h"

namespace semrec::fuse::internal {
std::vector<Eigen::Vector3d> MapResolver::SpecklessPoints(
    const std::vector<size_t>& cells) const {
  std::vector<bool> member(cells_.size(), false), done(cells_.size(), false);
  for (size_t i : cells) member[i] = true;
  std::vector<std::vector<size_t>> parts;
  size_t largest = 0;
  for (size_t i : cells) {
    if (done[i]) continue;
    parts.push_back(Component(i, &done, [&](size_t n) { return member[n]; }));
    largest = std::max(largest, parts.back().size());
  }
  std::vector<Eigen::Vector3d> points;
  points.reserve(cells.size());
  for (const std::vector<size_t>& part : parts) {
    if (part.size() == largest ||
        static_cast<double>(part.size()) >=
            kSpeckShare * static_cast<double>(cells.size())) {
      for (size_t i : part) points.push_back(cells_[i].p.cast<double>());
    }
  }
  return points;
}

namespace {

// A box around voxel centres: upright, turned about the vertical to the
// smallest footprint (main axes of a near-square footprint, a chair's, point
// anywhere: a box on them can be twice the chair's area).
struct UprightBox {
  Eigen::Vector3d up, axis1, axis2;  // axis1: the footprint's longer side
  Eigen::Vector3d lo, hi;            // along axis1, axis2, up
  Eigen::Vector3d Coordinates(const Eigen::Vector3d& p) const {
    return {p.dot(axis1), p.dot(axis2), p.dot(up)};
  }
  double Volume() const { return (hi - lo).prod(); }
};

UprightBox BoxOf(const std::vector<Eigen::Vector3d>& points,
                 const Eigen::Vector3d& up_world, double voxel_size_m) {
  UprightBox box;
  box.up = up_world.normalized();
  const Eigen::Vector3d e1 = box.up.unitOrthogonal(), e2 = box.up.cross(e1);
  constexpr int kTurns = 45;  // 2 degree steps over a quarter turn
  double best_area = std::numeric_limits<double>::max();
  for (int k = 0; k < kTurns; ++k) {
    const double angle = M_PI / 2 * k / kTurns;
    const Eigen::Vector3d u = std::cos(angle) * e1 + std::sin(angle) * e2;
    const Eigen::Vector3d v = box.up.cross(u);
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(
                        std::numeric_limits<double>::max()),
                    hi = -lo;
    for (const Eigen::Vector3d& p : points) {
      const Eigen::Vector2d c(p.dot(u), p.dot(v));
      lo = lo.cwiseMin(c), hi = hi.cwiseMax(c);
    }
    const Eigen::Vector2d size = hi - lo;
    if (size.prod() < best_area) {
      best_area = size.prod();
      const bool u_longer = size.x() >= size.y();
      box.axis1 = u_longer ? u : v;
      box.axis2 = u_longer ? v : -u;
    }
  }
  box.lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
  box.hi = -box.lo;
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d c = box.Coordinates(p);
    box.lo = box.lo.cwiseMin(c), box.hi = box.hi.cwiseMax(c);
  }
  // Voxel centres: the surfaces reach half a voxel further.
  box.lo.array() -= voxel_size_m / 2, box.hi.array() += voxel_size_m / 2;
  return box;
}

// The sides of the smallest upright box around `points` (zero when none).
Eigen::Vector2d BoxSides(const std::vector<Eigen::Vector3d>& points,
                         const Eigen::Vector3d& up_world, double voxel_size_m) {
  if (points.empty()) return Eigen::Vector2d::Zero();
  const UprightBox box = BoxOf(points, up_world, voxel_size_m);
  return (box.hi - box.lo).head<2>();
}

}  // namespace

Eigen::Vector2d MapResolver::FootprintSize(
    const std::vector<size_t>& cells) const {
  return BoxSides(SpecklessPoints(cells), context_.up_world,
                  map_.voxel_size_m());
}

Eigen::Vector2d MapResolver::FootprintWithSpecks(
    const std::vector<size_t>& cells) const {
  std::vector<Eigen::Vector3d> points;
  points.reserve(cells.size());
  for (size_t i : cells) points.push_back(cells_[i].p.cast<double>());
  return BoxSides(points, context_.up_world, map_.voxel_size_m());
}

Eigen::Vector2d MapResolver::CoreFootprintSize(const std::vector<size_t>& cells,
                                               double trim_share) const {
  const std::vector<Eigen::Vector3d> points = SpecklessPoints(cells);
  if (points.empty()) return Eigen::Vector2d::Zero();
  const UprightBox box = BoxOf(points, context_.up_world, map_.voxel_size_m());
  Eigen::Vector2d size_m;
  for (int axis = 0; axis < 2; ++axis) {
    const Eigen::Vector3d& along = axis == 0 ? box.axis1 : box.axis2;
    std::vector<double> t;
    t.reserve(points.size());
    for (const Eigen::Vector3d& p : points) t.push_back(p.dot(along));
    std::sort(t.begin(), t.end());
    const auto k = static_cast<size_t>(trim_share * (t.size() - 1));
    size_m[axis] = t[t.size() - 1 - k] - t[k] + map_.voxel_size_m();
  }
  if (size_m.y() > size_m.x()) std::swap(size_m.x(), size_m.y());
  return size_m;
}

double MapResolver::ShareInside(const std::vector<size_t>& a,
                                const std::vector<size_t>& b) const {
  if (a.empty() || b.empty()) return 0.0;
  const std::vector<Eigen::Vector3d> pa = SpecklessPoints(a),
                                     pb = SpecklessPoints(b);
  const UprightBox ba = BoxOf(pa, context_.up_world, map_.voxel_size_m());
  const UprightBox bb = BoxOf(pb, context_.up_world, map_.voxel_size_m());
  const bool a_holds = ba.Volume() >= bb.Volume();
  const UprightBox& outer = a_holds ? ba : bb;
  const std::vector<Eigen::Vector3d>& inner = a_holds ? pb : pa;
  size_t inside = 0;
  for (const Eigen::Vector3d& p : inner) {
    const Eigen::Vector3d c = outer.Coordinates(p);
    inside += (c.array() >= outer.lo.array()).all() &&
              (c.array() <= outer.hi.array()).all();
  }
  return static_cast<double>(inside) / static_cast<double>(inner.size());
}

bool MapResolver::Nested(const std::vector<size_t>& a,
                         const std::vector<size_t>& b) const {
  if (options_.min_nested_share <= 0.0) return false;
  const double share = ShareInside(a, b);
  spdlog::debug("  {} and {} voxels: {:.2f} of one inside the other's box",
                a.size(), b.size(), share);
  return share >= options_.min_nested_share;
}

bool MapResolver::FitsOne(const std::vector<size_t>& a,
                          const std::vector<size_t>& b,
                          uint16_t class_id) const {
  const Eigen::Vector2d max_m = MaxFootprint(class_id);
  if (max_m.x() <= 0.0) return false;
  std::vector<size_t> both = a;
  both.insert(both.end(), b.begin(), b.end());
  const Eigen::Vector2d size_m = FootprintSize(both);
  spdlog::debug(
      "  {} and {} voxels of class {}: {:.2f} x {:.2f} m together ({:.2f} x "
      "{:.2f} fit one)",
      a.size(), b.size(), class_id, size_m.x(), size_m.y(), max_m.x(),
      max_m.y());
  return FitsSize(size_m, class_id, 1.0);
}

bool MapResolver::FitsTogether(const std::vector<size_t>& a,
                               const std::vector<size_t>& b,
                               uint16_t class_id) const {
  if (MaxFootprint(class_id).x() <= 0.0 || options_.size_slack <= 0.0) {
    return true;
  }
  std::vector<size_t> both = a;
  both.insert(both.end(), b.begin(), b.end());
  return FitsSize(FootprintSize(both), class_id, options_.size_slack);
}

bool MapResolver::PartsOfOne(const std::vector<size_t>& a,
                             const std::vector<size_t>& b, uint16_t class_id,
                             size_t contact_voxels) const {
  const auto smaller = static_cast<double>(std::min(a.size(), b.size()));
  return options_.min_part_contact_share < 1.0 &&
         contact_voxels >= options_.min_tie_contact_voxels &&
         static_cast<double>(contact_voxels) >=
             options_.min_part_contact_share * smaller &&
         FitsOne(a, b, class_id);
}

Eigen::Vector2d MapResolver::MaxFootprint(uint16_t class_id) const {
  const auto length = context_.max_length_m.find(class_id);
  if (length == context_.max_length_m.end() || length->second <= 0.0) {
    return Eigen::Vector2d::Zero();
  }
  const auto width = context_.max_width_m.find(class_id);
  return {length->second, width == context_.max_width_m.end()
                              ? 0.0
                              : std::max(0.0, width->second)};
}

bool MapResolver::FitsSize(const Eigen::Vector2d& size_m, uint16_t class_id,
                           double slack) const {
  const Eigen::Vector2d max_m = MaxFootprint(class_id);
  if (max_m.x() <= 0.0) return true;
  return size_m.x() <= slack * max_m.x() &&
         (max_m.y() <= 0.0 || size_m.y() <= slack * max_m.y());
}

std::map<uint16_t, double> MapResolver::ThingShares(
    const std::vector<size_t>& cells) const {
  std::map<uint16_t, double> shares;
  double total = 0.0;
  for (size_t i : cells) {
    for (const ClassEvidence& e : cells_[i].evidence->classes) {
      if (IsStuff(e.class_id)) continue;
      shares[e.class_id] += e.weight;
      total += e.weight;
    }
  }
  if (total <= 0.0) return {};  // only structure votes (claimed voxels)
  for (auto& [c, share] : shares) share /= total;
  return shares;
}

}  // namespace semrec::fuse::internal
