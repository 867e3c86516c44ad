#include "semrec/fuse/gravity.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <Eigen/Eigenvalues>

#include "semrec/core/error.h"
#include "semrec/core/random.h"

namespace semrec::fuse {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
// RANSAC works on a sample: a room holds ~10^5 points at 5 cm.
constexpr size_t kMaxPoints = 60000;
constexpr int kIterations = 600;
constexpr int kMaxPlanes = 6;

struct Plane {
  Eigen::Vector3d normal;  // unit, oriented along the cameras' up
  double offset = 0.0;     // normal . p for points on the plane
  std::vector<size_t> inliers;
};

// Least-squares plane through `idx` (normal = smallest principal axis),
// oriented along `up`.
Plane FitPlane(const std::vector<Eigen::Vector3d>& pts,
               const std::vector<size_t>& idx, const Eigen::Vector3d& up) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (size_t i : idx) mean += pts[i];
  mean /= static_cast<double>(idx.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t i : idx) cov += (pts[i] - mean) * (pts[i] - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Plane p;
  p.normal = eig.eigenvectors().col(0).normalized();
  if (p.normal.dot(up) < 0) p.normal = -p.normal;
  p.offset = p.normal.dot(mean);
  p.inliers = idx;
  return p;
}

// Horizontal planes (normal within max_tilt of `up`), largest first, found by
// sequential RANSAC on the points not yet explained.
//
// A camera that barely turns gives a prior with its mean pitch in it
// (six-objects orbits 16 degrees in 8 frames looking down by 48), so the cone
// is wide; a wall inside it is told apart by the cameras looking *up* at it: a
// plane counts only if the mean viewing direction does not rise above it by
// more than max_look_up (people film floors and tables from above, not from
// below).
std::vector<Plane> HorizontalPlanes(const std::vector<Eigen::Vector3d>& pts,
                                    const Eigen::Vector3d& up,
                                    const Eigen::Vector3d& mean_view,
                                    const GravityOptions& options) {
  const double max_rise = std::sin(options.max_look_up_deg * kDegToRad);
  std::vector<Plane> planes;
  std::vector<size_t> remaining(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) remaining[i] = i;
  const double cos_tilt = std::cos(options.max_tilt_deg * kDegToRad);
  const double tol = options.plane_tolerance_m;
  const size_t min_inliers = std::max<size_t>(50, pts.size() / 100);
  Rng rng(options.seed);
  // Candidate planes from three points of one neighbourhood (a cell of
  // kCellM): drawn from the whole cloud, three points rarely share a small
  // plane (a floor patch between furniture), from one cell they mostly do.
  constexpr double kCellM = 0.3;
  const auto cell_key = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d c = (p / kCellM).array().floor();
    return (static_cast<int64_t>(c.x()) * 73856093) ^
           (static_cast<int64_t>(c.y()) * 19349663) ^
           (static_cast<int64_t>(c.z()) * 83492791);
  };
  for (int round = 0; round < kMaxPlanes && remaining.size() >= min_inliers;
       ++round) {
    std::unordered_map<int64_t, std::vector<size_t>> cells;
    for (size_t i : remaining) cells[cell_key(pts[i])].push_back(i);
    size_t best_count = 0;
    Eigen::Vector3d best_n = Eigen::Vector3d::Zero();
    double best_d = 0.0;
    for (int it = 0; it < kIterations; ++it) {
      const auto pick = [&](const std::vector<size_t>& from) {
        return pts[from[static_cast<size_t>(
            rng.UniformInt(0, static_cast<int64_t>(from.size()) - 1))]];
      };
      const Eigen::Vector3d a = pick(remaining);
      const std::vector<size_t>& near = cells[cell_key(a)];
      if (near.size() < 3) continue;
      const Eigen::Vector3d b = pick(near), c = pick(near);
      Eigen::Vector3d n = (b - a).cross(c - a);
      if (n.norm() < 1e-9) continue;
      n.normalize();
      if (std::abs(n.dot(up)) < cos_tilt) continue;  // not horizontal
      if (n.dot(up) < 0) n = -n;
      if (mean_view.dot(n) > max_rise) continue;  // the cameras look up at it
      const double d = n.dot(a);
      size_t count = 0;
      for (size_t i : remaining) count += std::abs(n.dot(pts[i]) - d) < tol;
      if (count > best_count) best_count = count, best_n = n, best_d = d;
    }
    if (best_count < min_inliers) break;
    std::vector<size_t> in, out;
    for (size_t i : remaining) {
      (std::abs(best_n.dot(pts[i]) - best_d) < tol ? in : out).push_back(i);
    }
    Plane plane = FitPlane(pts, in, up);
    if (plane.normal.dot(up) < cos_tilt ||
        mean_view.dot(plane.normal) > max_rise) {
      break;  // the refit tilted away
    }
    planes.push_back(std::move(plane));
    remaining = std::move(out);
  }
  std::sort(planes.begin(), planes.end(), [](const Plane& a, const Plane& b) {
    return a.inliers.size() > b.inliers.size();
  });
  return planes;
}

// Mean height of the points `idx` along `up`.
double MeanHeight(const std::vector<Eigen::Vector3d>& pts,
                  const std::vector<size_t>& idx, const Eigen::Vector3d& up) {
  double sum = 0.0;
  for (size_t i : idx) sum += up.dot(pts[i]);
  return sum / static_cast<double>(idx.size());
}

// Rotation taking `up` to +Z (the smallest one: no spin about the up axis).
Eigen::Matrix3d RotationToZ(const Eigen::Vector3d& up) {
  return Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitZ())
      .toRotationMatrix();
}

// Which way the cameras say is up. People hold RGB-D cameras with little roll
// but any pitch (an orbit looking down at furniture, a walk looking ahead), so
// the camera x axes are nearly horizontal: when they turn enough to span the
// horizontal plane, up is the direction perpendicular to all of them
// (smallest eigenvector of their scatter). Otherwise (a camera that barely
// turns) the mean -y (image up) with the mean x direction removed: it keeps
// the pitch error but not the roll. Oriented along the mean -y.
Eigen::Vector3d CameraUpPrior(const std::vector<Transform>& T_world_cameras) {
  Eigen::Vector3d image_up = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Transform& T : T_world_cameras) {
    image_up -= T.rotation().col(1);
    scatter += T.rotation().col(0) * T.rotation().col(0).transpose();
  }
  if (image_up.norm() < 1e-6) return Eigen::Vector3d::UnitZ();
  image_up.normalize();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const Eigen::Vector3d& l = eig.eigenvalues();  // ascending
  Eigen::Vector3d up;
  if (l(1) > 0.1 * l(2) && l(0) < 0.1 * l(1)) {
    up = eig.eigenvectors().col(0);
  } else {
    const Eigen::Vector3d x = eig.eigenvectors().col(2);
    up = image_up - image_up.dot(x) * x;
    if (up.norm() < 1e-6) return image_up;
  }
  up.normalize();
  return up.dot(image_up) < 0 ? -up : up;
}

GravityEstimate Finish(GravityEstimate e, const GravityOptions& options) {
  const double angle = std::acos(
      std::clamp(e.up_world.dot(Eigen::Vector3d::UnitZ()), -1.0, 1.0));
  if (options.mode == GravityOptions::Mode::kAuto &&
      angle < options.snap_angle_deg * kDegToRad &&
      std::abs(e.floor_height_m) < options.snap_height_m) {
    e.method = "already upright";
    e.up_world = Eigen::Vector3d::UnitZ();
    e.floor_height_m = 0.0;
    e.T_upright_world = Transform();
    return e;
  }
  const Eigen::Matrix3d R = RotationToZ(e.up_world);
  e.T_upright_world =
      Transform(R, Eigen::Vector3d(0.0, 0.0, -e.floor_height_m));
  return e;
}

}  // namespace

void GravityOptions::Check() const {
  CheckArgument(std::abs(up.norm() - 1.0) < 1e-6 && up.allFinite(),
                "gravity: up must be a unit vector");
  CheckArgument(max_tilt_deg > 0.0 && max_tilt_deg < 90.0,
                "gravity: max_tilt_deg must be in (0, 90)");
  CheckArgument(max_look_up_deg >= 0.0 && max_look_up_deg < 90.0,
                "gravity: max_look_up_deg must be in [0, 90)");
  CheckArgument(plane_tolerance_m > 0.0,
                "gravity: plane_tolerance_m must be > 0");
  CheckArgument(min_floor_share > 0.0 && min_floor_share <= 1.0,
                "gravity: min_floor_share must be in (0, 1]");
  CheckArgument(snap_angle_deg >= 0.0 && snap_height_m >= 0.0,
                "gravity: snap thresholds must be >= 0");
}

GravityOptions ParseGravity(const std::string& text) {
  GravityOptions options;
  if (text == "auto") return options;
  if (text == "none") {
    options.mode = GravityOptions::Mode::kNone;
    return options;
  }
  Eigen::Vector3d v;
  std::istringstream in(text);
  char c1 = 0, c2 = 0;
  if (!(in >> v.x() >> c1 >> v.y() >> c2 >> v.z()) || c1 != ',' || c2 != ',' ||
      !(in >> std::ws).eof() || !v.allFinite() || v.norm() < 1e-9) {
    throw InvalidArgument(fmt::format(
        "--gravity '{}': use auto, none or the world's up direction as x,y,z "
        "(e.g. 0,-1,0 for a y-down world)",
        text));
  }
  options.mode = GravityOptions::Mode::kGiven;
  options.up = v.normalized();
  return options;
}

GravityEstimate EstimateGravity(const std::vector<const Cloud*>& clouds,
                                const std::vector<bool>& is_floor,
                                const std::vector<Transform>& T_world_cameras,
                                const GravityOptions& options) {
  options.Check();
  GravityEstimate e;
  if (options.mode == GravityOptions::Mode::kNone) return e;

  const bool given = options.mode == GravityOptions::Mode::kGiven;
  const Eigen::Vector3d up =
      given ? options.up : CameraUpPrior(T_world_cameras);
  Eigen::Vector3d mean_view = Eigen::Vector3d::Zero();
  for (const Transform& T : T_world_cameras) mean_view += T.rotation().col(2);
  if (!T_world_cameras.empty()) {
    mean_view /= static_cast<double>(T_world_cameras.size());
  }
  spdlog::debug("gravity: cameras' up {:.3f} {:.3f} {:.3f}", up.x(), up.y(),
                up.z());

  // An even sample of all points, and the floor class's points.
  size_t total = 0;
  for (const Cloud* c : clouds) total += c->size();
  const size_t step = std::max<size_t>(1, total / kMaxPoints);
  std::vector<Eigen::Vector3d> pts, floor_pts;
  size_t k = 0;
  for (size_t i = 0; i < clouds.size(); ++i) {
    const bool floor = i < is_floor.size() && is_floor[i];
    for (const auto& p : *clouds[i]) {
      if (floor) floor_pts.push_back(p.cast<double>());
      if (k++ % step == 0) pts.push_back(p.cast<double>());
    }
  }
  if (pts.empty()) {
    e.method = "none";
    return e;
  }
  // A floor class makes the floor explicit.
  if (floor_pts.size() >= 200) {
    const std::vector<Plane> floor_planes =
        HorizontalPlanes(floor_pts, up, mean_view, options);
    if (!floor_planes.empty()) {
      const Plane& f = floor_planes.front();
      e.up_world = given ? up : f.normal;
      e.floor_height_m = MeanHeight(floor_pts, f.inliers, e.up_world);
      e.floor_points = f.inliers.size();
      e.method = given ? "given" : "floor class";
      return Finish(e, options);
    }
  }
  // Otherwise the horizontal planes of the whole scene (only searched now:
  // the floor class, when it has a plane, decides alone).
  const std::vector<Plane> planes =
      HorizontalPlanes(pts, up, mean_view, options);
  for (const Plane& p : planes) {
    spdlog::debug(
        "gravity: horizontal plane, {} points, normal {:.3f} {:.3f} "
        "{:.3f}, height {:.3f} m",
        p.inliers.size(), p.normal.x(), p.normal.y(), p.normal.z(), p.offset);
  }
  if (!planes.empty()) {
    // Up from the largest horizontal plane; the floor is the lowest plane with
    // a fair share of points (tables and seats are above it).
    e.up_world = given ? up : planes.front().normal;
    const size_t needed =
        static_cast<size_t>(options.min_floor_share *
                            static_cast<double>(planes.front().inliers.size()));
    const Plane* floor = nullptr;
    double floor_h = 0.0;
    for (const Plane& p : planes) {
      if (p.inliers.size() < needed) continue;
      const double h = MeanHeight(pts, p.inliers, e.up_world);
      if (floor == nullptr || h < floor_h) floor = &p, floor_h = h;
    }
    e.floor_height_m = floor_h;
    e.floor_points = floor->inliers.size();
    e.method = given ? "given" : "planes";
    return Finish(e, options);
  }
  // No horizontal plane: trust the cameras (or the given up); the floor is
  // the lowest percentile of the points.
  e.up_world = up;
  std::vector<double> h(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) h[i] = up.dot(pts[i]);
  std::nth_element(h.begin(),
                   h.begin() + static_cast<std::ptrdiff_t>(h.size() / 100),
                   h.end());
  e.floor_height_m = h[h.size() / 100];
  e.method = given ? "given" : "cameras";
  return Finish(e, options);
}

}  // namespace semrec::fuse
