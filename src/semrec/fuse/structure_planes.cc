#include "semrec/fuse/structure_planes.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <random>
#include <set>

#include <Eigen/Eigenvalues>

#include <spdlog/spdlog.h>

#include "semrec/core/error.h"

namespace semrec::fuse {

void StructurePlaneOptions::Check() const {
  CheckArgument(tolerance_m > 0.0, "structure planes: tolerance_m must be > 0");
  CheckArgument(min_area_m2 > 0.0, "structure planes: min_area_m2 must be > 0");
  CheckArgument(tolerance_sigmas > 0.0,
                "structure planes: tolerance_sigmas must be > 0");
  CheckArgument(
      min_tolerance_m > 0.0 && min_tolerance_m <= tolerance_m,
      "structure planes: min_tolerance_m must be in (0, tolerance_m]");
  CheckArgument(min_wall_height_m >= 0.0,
                "structure planes: min_wall_height_m must be >= 0");
  CheckArgument(max_wall_tilt_deg >= 0.0 && max_wall_tilt_deg < 90.0,
                "structure planes: max_wall_tilt_deg must be in [0, 90)");
  CheckArgument(min_top_surface_share >= 0.0,
                "structure planes: min_top_surface_share must be >= 0");
  CheckArgument(max_front_distance_m >= 0.0,
                "structure planes: max_front_distance_m must be >= 0");
  CheckArgument(max_furniture_depth_m >= 0.0,
                "structure planes: max_furniture_depth_m must be >= 0");
  CheckArgument(max_surface_tilt_deg >= 0.0,
                "structure planes: max_surface_tilt_deg must be >= 0");
  CheckArgument(min_normal_agreement > 1.0 / 3.0 && min_normal_agreement <= 1.0,
                "structure planes: min_normal_agreement must be in (1/3, 1]");
  CheckArgument(min_normal_points >= 1,
                "structure planes: min_normal_points must be >= 1");
  CheckArgument(max_planes > 0, "structure planes: max_planes must be > 0");
  CheckArgument(ransac_iterations > 0,
                "structure planes: ransac_iterations must be > 0");
}

double StructurePlaneOptions::MinSurfaceFacing() const {
  return max_surface_tilt_deg >= 90.0
             ? 0.0
             : std::cos(max_surface_tilt_deg * std::numbers::pi / 180.0);
}

bool OnAnyPlane(const Eigen::Vector3f& p,
                const std::vector<StructurePlane>& planes, double tolerance_m) {
  const Eigen::Vector3d q = p.cast<double>();
  return std::any_of(planes.begin(), planes.end(), [&](const auto& plane) {
    return std::abs(plane.normal.dot(q) - plane.offset) <= tolerance_m;
  });
}

namespace {

constexpr double kAlongBinM = 0.1;

int64_t AlongBin(const Eigen::Vector3d& along, const Eigen::Vector3d& p) {
  return static_cast<int64_t>(std::floor(along.dot(p) / kAlongBinM));
}

// Cosine of the largest angle at which two walls still count as parallel.
double ParallelCos(const StructurePlaneOptions& options) {
  return std::cos(options.max_wall_tilt_deg * std::numbers::pi / 180.0);
}

}  // namespace

bool StructurePlane::Covers(const Eigen::Vector3d& p) const {
  return std::binary_search(along_bins.begin(), along_bins.end(),
                            AlongBin(along, p));
}

void OrientToInterior(const Cloud& scene, double tolerance_m,
                      std::vector<StructurePlane>* planes) {
  // Only what lies along the wall and near it: in an L-shaped room or a
  // scan of two rooms most of the scene may lie behind a wall's plane.
  constexpr double kNearM = 3.0;
  for (StructurePlane& plane : *planes) {
    if (plane.geometry != StructureGeometry::kVertical || plane.oriented) {
      continue;
    }
    size_t front = 0, back = 0;
    for (const Eigen::Vector3f& p : scene) {
      const Eigen::Vector3d q = p.cast<double>();
      const double d = plane.normal.dot(q) - plane.offset;
      if (std::abs(d) > kNearM || !plane.Covers(q)) continue;
      if (d > tolerance_m) ++front;
      if (d < -tolerance_m) ++back;
    }
    if (back > front) {
      plane.normal = -plane.normal;
      plane.offset = -plane.offset;
    }
  }
}

std::vector<StructurePlane> TakeFurnitureFronts(
    const Cloud& scene, const Eigen::Vector3d& up_world,
    const StructurePlaneOptions& options, std::vector<StructurePlane>* planes,
    const std::vector<Eigen::Vector3f>& towards_camera) {
  CheckArgument(towards_camera.empty() || towards_camera.size() == scene.size(),
                "TakeFurnitureFronts: one view direction per scene point");
  std::vector<StructurePlane> fronts;
  if (options.min_top_surface_share <= 0.0 ||
      options.min_top_surface_share > 1.0) {
    return fronts;
  }
  constexpr double kDepthBinM = 0.1;
  constexpr double kMinFromAboveCos = 0.0;
  constexpr double kAboveLowM = 0.25, kAboveHighM = 0.45;
  constexpr int64_t kWallBehindBin = 5;  // 50 cm
  // Behind the plane by more than a wall's other face and the tolerance.
  const double min_behind_m = 2.0 * options.tolerance_m;
  std::erase_if(*planes, [&](const StructurePlane& plane) {
    if (plane.geometry != StructureGeometry::kVertical ||
        plane.along_bins.empty()) {
      return false;
    }
    std::set<std::pair<int64_t, int64_t>> cells;  // (along bin, depth bin)
    // Surface a little above the top band, behind the plane (a wall's
    // continuation; over a worktop there is air up to the wall cabinets).
    std::set<std::pair<int64_t, int64_t>> above;
    for (const Eigen::Vector3f& p : scene) {
      const Eigen::Vector3d q = p.cast<double>();
      const double behind = plane.offset - plane.normal.dot(q);
      const double h = up_world.dot(q) - plane.top_m;
      if (behind < min_behind_m ||
          behind > options.max_front_distance_m + 0.2 || h < kAboveLowM ||
          h > kAboveHighM || !plane.Covers(q)) {
        continue;
      }
      above.emplace(AlongBin(plane.along, q),
                    static_cast<int64_t>(std::floor(behind / kDepthBinM)));
    }
    const auto goes_up = [&](int64_t along, int64_t depth) {
      return above.count({along, depth - 1}) > 0 ||
             above.count({along, depth}) > 0 ||
             above.count({along, depth + 1}) > 0;
    };
    size_t wall_cells = 0;  // voxels left out as the wall itself
    for (size_t i = 0; i < scene.size(); ++i) {
      const Eigen::Vector3d q = scene[i].cast<double>();
      const double behind = plane.offset - plane.normal.dot(q);
      if (behind < min_behind_m ||
          !OnTopOfFront(scene[i], plane, up_world, options)) {
        continue;
      }
      // Seen from above, over the top edge (a worktop), not through a
      // doorway (the top of a shelf in the next room, level with the
      // wall's highest seen part).
      if (!towards_camera.empty() && !towards_camera[i].isZero() &&
          up_world.dot(towards_camera[i].cast<double>().normalized()) <
              kMinFromAboveCos) {
        continue;
      }
      const int64_t along = AlongBin(plane.along, q);
      const auto depth = static_cast<int64_t>(std::floor(behind / kDepthBinM));
      // A surface close behind the top that goes on above it is the wall
      // itself (a wall far from the camera lies in depth-quantization layers
      // 47 cm deep on Bonn crowd; each layer's lower band passed for a
      // front); one further back is the wall behind a counter top.
      if (depth < kWallBehindBin && goes_up(along, depth)) {
        ++wall_cells;
        continue;
      }
      cells.emplace(along, depth);
    }
    // Stretches along the plane with a surface at least two bins deep, and
    // some reaching 35 cm or more behind it: a worktop is 60 cm deep (seen
    // in part from a walk-through); a deep window sill (25 cm, in a wall
    // under a window reaching the ceiling, so that the wall's top is the
    // sill) is not.
    constexpr int64_t kDeepBin = 3;  // 35 cm at the voxel centres
    std::map<int64_t, std::pair<int, int64_t>> stretch;  // bins, deepest
    for (const auto& [along, depth] : cells) {
      auto& [bins, deepest] = stretch[along];
      ++bins;
      deepest = std::max(deepest, depth);
    }
    size_t topped = 0, deep = 0;
    for (const auto& [along, s] : stretch) {
      if (s.first < 2) continue;
      ++topped;
      deep += s.second >= kDeepBin ? 1 : 0;
    }
    const auto stretches = static_cast<double>(plane.along_bins.size());
    const double share = static_cast<double>(topped) / stretches;
    const bool front = share >= options.min_top_surface_share &&
                       static_cast<double>(deep) >= 0.5 * topped;
    spdlog::debug(
        "vertical plane ({} points, top {:.2f} along up): surface behind its "
        "top along {:.0f}% of it ({} of {} stretches 35 cm deep; {} voxels "
        "left out, the wall going on above them){}",
        plane.support, plane.top_m, 100.0 * share, deep, topped, wall_cells,
        front ? ": the front of furniture, not a wall" : "");
    if (front) fronts.push_back(plane);
    return front;
  });
  return fronts;
}

bool OnStructure(const Eigen::Vector3f& p,
                 const std::vector<StructurePlane>& planes,
                 const StructurePlaneOptions& options, double near_scale,
                 const Eigen::Vector3f* surface_axis) {
  const Eigen::Vector3d q = p.cast<double>();
  const double parallel = ParallelCos(options);
  const double min_facing = options.MinSurfaceFacing();
  auto in_front_of_larger = [&](const StructurePlane& plane) {
    return std::any_of(planes.begin(), planes.end(), [&](const auto& wall) {
      if (wall.geometry != StructureGeometry::kVertical ||
          wall.support <= plane.support ||
          std::abs(wall.normal.dot(plane.normal)) < parallel) {
        return false;
      }
      const double d = wall.normal.dot(q) - wall.offset;
      return d > 1.5 * options.tolerance_m &&
             d <= options.max_furniture_depth_m && wall.Covers(q);
    });
  };
  return std::any_of(planes.begin(), planes.end(), [&](const auto& plane) {
    const double near_m = near_scale * plane.Tolerance(options);
    if (std::abs(plane.normal.dot(q) - plane.offset) > near_m) return false;
    if (surface_axis != nullptr &&
        std::abs(plane.normal.dot(surface_axis->cast<double>())) < min_facing) {
      return false;
    }
    return plane.geometry != StructureGeometry::kVertical ||
           !in_front_of_larger(plane);
  });
}

bool BehindWall(const Eigen::Vector3f& p,
                const std::vector<StructurePlane>& planes,
                const StructurePlaneOptions& options) {
  const Eigen::Vector3d q = p.cast<double>();
  const double parallel = ParallelCos(options);
  auto in_front_of_opposite = [&](const StructurePlane& a) {
    return std::any_of(planes.begin(), planes.end(), [&](const auto& b) {
      return b.geometry == StructureGeometry::kVertical &&
             b.normal.dot(a.normal) < -parallel &&
             b.normal.dot(q) - b.offset > b.Tolerance(options) && b.Covers(q);
    });
  };
  return std::any_of(planes.begin(), planes.end(), [&](const auto& wall) {
    if (wall.geometry != StructureGeometry::kVertical) return false;
    const double d = wall.normal.dot(q) - wall.offset;
    // In front of the other face of the same wall: the next room.
    return d < -wall.Tolerance(options) && d >= -options.max_front_distance_m &&
           wall.Covers(q) && !in_front_of_opposite(wall);
  });
}

bool OnTopOfFront(const Eigen::Vector3f& p, const StructurePlane& front,
                  const Eigen::Vector3d& up_world,
                  const StructurePlaneOptions& options) {
  // The top band: a counter top lies at the front's top edge, within a voxel
  // or two (the 95th percentile of the front's heights).
  constexpr double kBelowTopM = 0.1, kAboveTopM = 0.15;
  const Eigen::Vector3d q = p.cast<double>();
  const double behind = front.offset - front.normal.dot(q);
  const double h = up_world.dot(q) - front.top_m;
  return behind > 0.0 && behind <= options.max_front_distance_m + 0.2 &&
         h >= -kBelowTopM && h <= kAboveTopM && front.Covers(q);
}

namespace {

// A plane's own tolerance from its points' signed distances to it:
// tolerance_sigmas x their robust spread (1.4826 x MAD), clamped.
double OwnTolerance(std::vector<double> r, const StructurePlaneOptions& o) {
  const auto mid = r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2);
  std::nth_element(r.begin(), mid, r.end());
  const double median = *mid;
  for (double& d : r) d = std::abs(d - median);
  std::nth_element(r.begin(), mid, r.end());
  return std::clamp(o.tolerance_sigmas * 1.4826 * *mid, o.min_tolerance_m,
                    o.tolerance_m);
}

// Floor or ceiling: heights along `up` in bins of the tolerance; the lowest
// (highest) run of three bins holding enough points is the plane, at their
// mean height.
std::vector<StructurePlane> HorizontalPlane(const Cloud& points, bool lowest,
                                            const Eigen::Vector3d& up,
                                            size_t min_support,
                                            const StructurePlaneOptions& o) {
  std::map<int64_t, std::pair<size_t, double>> bins;  // count, height sum
  for (const Eigen::Vector3f& p : points) {
    const double h = up.dot(p.cast<double>());
    auto& bin = bins[static_cast<int64_t>(std::floor(h / o.tolerance_m))];
    ++bin.first;
    bin.second += h;
  }
  auto window = [&](int64_t b) {
    std::pair<size_t, double> sum{0, 0.0};
    for (int64_t d = -1; d <= 1; ++d) {
      if (const auto it = bins.find(b + d); it != bins.end()) {
        sum.first += it->second.first;
        sum.second += it->second.second;
      }
    }
    return sum;
  };
  std::vector<int64_t> order;
  order.reserve(bins.size());
  for (const auto& [b, unused] : bins) order.push_back(b);
  if (!lowest) std::reverse(order.begin(), order.end());
  for (int64_t b : order) {
    // The window's centre must be its densest bin: the run's middle, not its
    // edge.
    const auto [count, height_sum] = window(b);
    if (count < min_support) continue;
    int64_t best = b;
    for (int64_t c = b - 1; c <= b + 1; ++c) {
      if (window(c).first > window(best).first) best = c;
    }
    const auto [n, sum] = window(best);
    StructurePlane plane;
    plane.geometry =
        lowest ? StructureGeometry::kFloor : StructureGeometry::kCeiling;
    plane.normal = up;
    plane.offset = sum / static_cast<double>(n);
    plane.support = n;
    // Its own tolerance from the spread of the heights near it.
    std::vector<double> r;
    for (const Eigen::Vector3f& p : points) {
      const double d = up.dot(p.cast<double>()) - plane.offset;
      if (std::abs(d) <= o.tolerance_m) r.push_back(d);
    }
    // (the window's middle bin may be empty)
    plane.tolerance_m =
        r.empty() ? o.tolerance_m : OwnTolerance(std::move(r), o);
    spdlog::debug("{} at {:.3f} m: {} points, tolerance {:.3f} m",
                  lowest ? "floor" : "ceiling", plane.offset, n,
                  plane.tolerance_m);
    return {plane};
  }
  return {};
}

// Whether a point seen from `towards_camera` (zero: unknown) can lie on the
// face of (n, side): a wall's two faces are seen from opposite sides.
bool FacesSide(const Eigen::Vector3d& n, int side,
               const Eigen::Vector3f& towards_camera) {
  return side * n.dot(towards_camera.cast<double>()) >= 0.0;
}

// The best of o.ransac_iterations vertical planes through two random points,
// scored on a sample (rooms have tens of thousands of wall voxels) by the
// points within the tolerance seen from one side; *side: that side.
StructurePlane VerticalHypothesis(
    const Cloud& points, const std::vector<Eigen::Vector3f>& towards_camera,
    const Eigen::Vector3d& up, const StructurePlaneOptions& o,
    std::mt19937_64* rng, int* side) {
  std::uniform_int_distribution<size_t> pick(0, points.size() - 1);
  constexpr size_t kSample = 4000;
  std::vector<size_t> scored;
  if (points.size() > kSample) {
    for (size_t i = 0; i < kSample; ++i) scored.push_back(pick(*rng));
  } else {
    scored.resize(points.size());
    std::iota(scored.begin(), scored.end(), size_t{0});
  }
  StructurePlane best;
  *side = 1;
  for (int it = 0; it < o.ransac_iterations; ++it) {
    const Eigen::Vector3d a = points[pick(*rng)].cast<double>();
    const Eigen::Vector3d b = points[pick(*rng)].cast<double>();
    Eigen::Vector3d n = (b - a).cross(up);
    if (n.norm() < 0.1) continue;  // too close, or one above the other
    n.normalize();
    const double offset = n.dot(a);
    size_t front = 0, back = 0;
    for (size_t i : scored) {
      if (std::abs(n.dot(points[i].cast<double>()) - offset) > o.tolerance_m) {
        continue;
      }
      front += FacesSide(n, 1, towards_camera[i]);
      back += FacesSide(n, -1, towards_camera[i]);
    }
    if (std::max(front, back) > best.support) {
      best.normal = n, best.offset = offset;
      best.support = std::max(front, back);
      *side = front >= back ? 1 : -1;
    }
  }
  return best;
}

// Heights along up of a plane's inliers, sorted: the 5% and 95% quantiles.
struct HeightSpan {
  double low = 0.0, high = 0.0;
  double height() const { return high - low; }
};

// Least squares over the inliers (normal kept horizontal within the tilt
// allowed): centroid and the smallest principal direction; oriented towards
// the cameras that saw it (the room's side) where view directions are known;
// its own tolerance and the bins along it it covers.
HeightSpan RefineVerticalPlane(
    const Cloud& points, const std::vector<Eigen::Vector3f>& towards_camera,
    const std::vector<size_t>& inliers, int side, const Eigen::Vector3d& up,
    const StructurePlaneOptions& o, StructurePlane* plane) {
  const double max_dot =
      std::sin(o.max_wall_tilt_deg * std::numbers::pi / 180.0);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::vector<double> heights;
  bool sided = false;
  for (size_t i : inliers) {
    const Eigen::Vector3d q = points[i].cast<double>();
    heights.push_back(up.dot(q));
    mean += q;
    sided = sided || !towards_camera[i].isZero();
  }
  std::sort(heights.begin(), heights.end());
  const HeightSpan span{heights[heights.size() * 5 / 100],
                        heights[heights.size() * 95 / 100]};
  mean /= static_cast<double>(inliers.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t i : inliers) {
    const Eigen::Vector3d d = points[i].cast<double>() - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d n = eig.eigenvectors().col(0);
  const Eigen::Vector3d seen_from = side * plane->normal;
  if (std::abs(n.dot(up)) <= max_dot) {
    plane->normal = n.normalized();
    plane->offset = plane->normal.dot(mean);
  }
  if (sided) {  // towards the cameras that saw it: the room's side
    if (plane->normal.dot(seen_from) < 0.0) {
      plane->normal = -plane->normal, plane->offset = -plane->offset;
    }
    plane->oriented = true;
  }
  plane->geometry = StructureGeometry::kVertical;
  // Its own tolerance, like the floor's: a flat wall measured well is thin,
  // and a headboard 5 cm in front of it is not wall.
  std::vector<double> r;
  r.reserve(inliers.size());
  for (size_t i : inliers) {
    r.push_back(plane->normal.dot(points[i].cast<double>()) - plane->offset);
  }
  plane->tolerance_m = OwnTolerance(std::move(r), o);
  plane->top_m = span.high;
  plane->along = up.cross(plane->normal).normalized();
  for (size_t i : inliers) {
    plane->along_bins.push_back(
        AlongBin(plane->along, points[i].cast<double>()));
  }
  std::sort(plane->along_bins.begin(), plane->along_bins.end());
  plane->along_bins.erase(
      std::unique(plane->along_bins.begin(), plane->along_bins.end()),
      plane->along_bins.end());
  return span;
}

// The inliers leave (the other face's points stay for the next plane).
void RemovePoints(const std::vector<size_t>& inliers, Cloud* points,
                  std::vector<Eigen::Vector3f>* towards_camera) {
  std::vector<bool> gone(points->size(), false);
  for (size_t i : inliers) gone[i] = true;
  size_t kept = 0;
  for (size_t i = 0; i < points->size(); ++i) {
    if (gone[i]) continue;
    (*points)[kept] = (*points)[i];
    (*towards_camera)[kept] = (*towards_camera)[i];
    ++kept;
  }
  points->resize(kept);
  towards_camera->resize(kept);
}

// Sequential RANSAC over planes containing `up`: two points fix one. With
// `towards_camera` (parallel to points, or empty), a plane holds only the
// points seen from one side of it: the two faces of an interior wall 10 cm
// thick are two planes, not one plane tilted through both.
std::vector<StructurePlane> VerticalPlanes(
    Cloud points, std::vector<Eigen::Vector3f> towards_camera,
    const Eigen::Vector3d& up, size_t min_support,
    const StructurePlaneOptions& o, std::vector<StructurePlane>* low) {
  if (towards_camera.empty()) {
    towards_camera.assign(points.size(), Eigen::Vector3f::Zero());
  }
  std::vector<StructurePlane> planes;
  std::mt19937_64 rng(o.seed);
  // Rejected candidates (too low for a wall) count as attempts too.
  for (int attempt = 0; attempt < 2 * o.max_planes &&
                        static_cast<int>(planes.size()) < o.max_planes &&
                        points.size() >= min_support;
       ++attempt) {
    int side = 1;
    StructurePlane best =
        VerticalHypothesis(points, towards_camera, up, o, &rng, &side);
    std::vector<size_t> inliers;
    for (size_t i = 0; i < points.size(); ++i) {
      if (std::abs(best.normal.dot(points[i].cast<double>()) - best.offset) <=
              o.tolerance_m &&
          FacesSide(best.normal, side, towards_camera[i])) {
        inliers.push_back(i);
      }
    }
    best.support = inliers.size();
    if (best.support < min_support) break;
    const HeightSpan span = RefineVerticalPlane(points, towards_camera, inliers,
                                                side, up, o, &best);
    RemovePoints(inliers, &points, &towards_camera);
    spdlog::debug(
        "vertical plane candidate: {} points, {:.2f} m tall ({:.2f} "
        "to {:.2f} along up), tolerance {:.3f} m{}",
        best.support, span.height(), span.low, span.high, best.tolerance_m,
        span.height() >= o.min_wall_height_m ? "" : " (too low for a wall)");
    if (span.height() >= o.min_wall_height_m) {
      planes.push_back(best);
    } else if (low != nullptr) {
      low->push_back(best);
    }
  }
  return planes;
}

}  // namespace

std::vector<StructurePlane> FindStructurePlanes(
    const Cloud& points, StructureGeometry geometry,
    const Eigen::Vector3d& up_world, double voxel_area_m2,
    const StructurePlaneOptions& options,
    const std::vector<Eigen::Vector3f>& towards_camera,
    std::vector<StructurePlane>* low_planes) {
  options.Check();
  CheckArgument(voxel_area_m2 > 0.0,
                "structure planes: voxel area must be > 0");
  CheckArgument(
      towards_camera.empty() || towards_camera.size() == points.size(),
      "structure planes: one view direction per point");
  const Eigen::Vector3d up = up_world.normalized();
  const auto min_support =
      static_cast<size_t>(std::ceil(options.min_area_m2 / voxel_area_m2));
  switch (geometry) {
    case StructureGeometry::kVertical:
      return VerticalPlanes(points, towards_camera, up, min_support, options,
                            low_planes);
    case StructureGeometry::kFloor:
      return HorizontalPlane(points, true, up, min_support, options);
    case StructureGeometry::kCeiling:
      return HorizontalPlane(points, false, up, min_support, options);
    case StructureGeometry::kNone:
      break;
  }
  return {};
}

}  // namespace semrec::fuse
