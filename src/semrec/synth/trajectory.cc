#include "semrec/synth/trajectory.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "semrec/core/error.h"
#include "semrec/core/random.h"
#include "semrec/synth/seed.h"

namespace semrec::synth {
namespace {

// People's body radius, for the clearance of sparse cameras.
constexpr double kPersonRadiusM = 0.3;
constexpr int kSparseTries = 400;

// Distance along the unit ray from `origin` (inside the room) to the first
// static surface; `far` where it leaves through an open ceiling. Sets
// *object when the surface belongs to an object, not to the room.
double CastRay(const Scene& scene, const Eigen::Vector3d& origin,
               const Eigen::Vector3d& dir, double far, bool* object) {
  double best = far;
  for (int axis = 0; axis < 3; ++axis) {
    if (dir[axis] == 0.0) continue;
    const bool positive = dir[axis] > 0.0;
    const double t =
        ((positive ? scene.room_size[axis] : 0.0) - origin[axis]) / dir[axis];
    const int face = 2 * axis + (positive ? 1 : 0);
    if (t < best && scene.room_faces[face] != 0) best = t;
  }
  *object = false;
  for (const SceneObject& o : scene.objects) {
    if (o.room_face) continue;
    for (const Primitive& part : o.parts) {
      if (const auto hit = Intersect(part, origin, dir, 1e-4, best)) {
        best = hit->t;
        *object = !o.structure;  // an interior wall is no object
      }
    }
  }
  return best;
}

// Whether a camera at `eye` keeps the clearance from walls, objects and the
// people where they are at `time_s`.
bool IsFree(const Scene& scene, const Eigen::Vector3d& eye, double time_s,
            double clearance) {
  const Eigen::Vector3d& size = scene.room_size;
  if (eye.x() < clearance || eye.y() < clearance ||
      eye.x() > size.x() - clearance || eye.y() > size.y() - clearance) {
    return false;
  }
  for (const SceneObject& o : scene.objects) {
    if (o.room_face) continue;
    // Interior walls part by part: their doorways are free.
    const bool near =
        o.structure ? std::any_of(o.parts.begin(), o.parts.end(),
                                  [&](const Primitive& part) {
                                    return Bounds(part).exteriorDistance(eye) <
                                           clearance;
                                  })
                    : o.Bounds().exteriorDistance(eye) < clearance;
    if (near) return false;
  }
  for (const Person& person : scene.people) {
    const Eigen::Vector2d at = PoseAt(person, time_s).position;
    if ((at - eye.head<2>()).norm() < clearance + kPersonRadiusM) return false;
  }
  return true;
}

// How far a view is from the depth and object conditions (0: it meets them),
// from a 9 x 7 grid of probe rays over the central 48 x 36 degrees.
double ViewPenalty(const Scene& scene, const Transform& pose,
                   const TrajectoryOptions& options) {
  std::vector<double> depths;
  int objects = 0;
  for (int row = -3; row <= 3; ++row) {
    for (int col = -4; col <= 4; ++col) {
      const Eigen::Vector3d d_camera(std::tan(col * 6.0 * M_PI / 180.0),
                                     std::tan(row * 6.0 * M_PI / 180.0), 1.0);
      bool object = false;
      depths.push_back(CastRay(scene, pose.translation(),
                               pose.rotation() * d_camera.normalized(), 100.0,
                               &object));
      objects += object;
    }
  }
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2,
                   depths.end());
  const double median = depths[depths.size() / 2];
  const double share = static_cast<double>(objects) / depths.size();
  return std::max(0.0, options.sparse_min_median_depth_m - median) +
         std::max(0.0, median - options.sparse_max_median_depth_m) +
         std::max(0.0, options.sparse_min_object_share - share);
}

// One sparse view: random tries from the frame's own stream, so the view
// depends on (seed, frame) only.
Transform SparseView(const Scene& scene, const TrajectoryOptions& options,
                     double time_s, uint64_t seed, int frame) {
  Rng rng(seed);
  const Eigen::Vector3d& size = scene.room_size;
  Transform best;
  double best_penalty = std::numeric_limits<double>::infinity();
  for (int attempt = 0; attempt < kSparseTries; ++attempt) {
    const Eigen::Vector3d eye(
        rng.Uniform(0.0, size.x()), rng.Uniform(0.0, size.y()),
        rng.Uniform(options.sparse_min_height_m, options.sparse_max_height_m));
    const double yaw = rng.Uniform(0.0, 2 * M_PI);
    const double pitch =
        rng.Uniform(0.0, options.sparse_max_pitch_deg * M_PI / 180.0);
    if (!IsFree(scene, eye, time_s, options.sparse_clearance_m)) continue;
    const Eigen::Vector3d forward(std::cos(pitch) * std::cos(yaw),
                                  std::cos(pitch) * std::sin(yaw),
                                  -std::sin(pitch));
    const Transform pose = LookAt(eye, eye + forward);
    const double penalty = ViewPenalty(scene, pose, options);
    if (penalty < best_penalty) best = pose, best_penalty = penalty;
    if (penalty == 0.0) break;
  }
  if (!std::isfinite(best_penalty)) {
    throw Error(fmt::format(
        "synth: no free spot for sparse view {} ({} m from walls, objects and "
        "people); use a bigger room or fewer objects",
        frame, options.sparse_clearance_m));
  }
  return best;
}

}  // namespace

void TrajectoryOptions::Check() const {
  CheckArgument(height_m > 0.2, "synth trajectory: height_m must be > 0.2");
  CheckArgument(std::isfinite(orbit_deg_per_s),
                "synth trajectory: orbit_deg_per_s must be finite");
  CheckArgument(walking_speed_mps > 0.0 && walking_speed_mps < 10.0,
                "synth trajectory: walking_speed_mps must be in (0, 10)");
  CheckArgument(jitter_m >= 0.0 && jitter_deg >= 0.0,
                "synth trajectory: jitter amplitudes must be >= 0");
  CheckArgument(
      sparse_min_height_m > 0.1 && sparse_min_height_m <= sparse_max_height_m,
      "synth trajectory: sparse heights must satisfy 0.1 < min <= "
      "max");
  CheckArgument(sparse_max_pitch_deg >= 0.0 && sparse_max_pitch_deg < 80.0,
                "synth trajectory: sparse_max_pitch_deg must be in [0, 80)");
  CheckArgument(sparse_clearance_m >= 0.0 && sparse_clearance_m < 1.0,
                "synth trajectory: sparse_clearance_m must be in [0, 1)");
  CheckArgument(sparse_min_median_depth_m >= 0.0 &&
                    sparse_min_median_depth_m <= sparse_max_median_depth_m,
                "synth trajectory: sparse median depths must satisfy 0 <= min "
                "<= max");
  CheckArgument(sparse_min_object_share >= 0.0 && sparse_min_object_share <= 1,
                "synth trajectory: sparse_min_object_share must be in [0, 1]");
}

std::vector<Transform> MakeTrajectory(const Scene& scene,
                                      const TrajectoryOptions& options,
                                      int frames, double fps, uint64_t seed) {
  CheckArgument(fps > 0.0, "synth trajectory: fps must be > 0");
  options.Check();
  std::vector<Transform> poses;
  if (options.kind == TrajectoryOptions::Kind::kSparse) {
    for (int i = 0; i < frames; ++i) {
      poses.push_back(SparseView(scene, options, i / fps,
                                 MixSeed(MixSeed(seed, 0x5BA25E), i), i));
    }
    return poses;
  }
  const Eigen::Vector3d size = scene.room_size;
  const Eigen::Vector3d center(size.x() / 2, size.y() / 2, 0.0);
  // Smooth hand-held jitter: a few sinusoids per axis with seeded phases and
  // frequencies.
  Rng rng(MixSeed(seed, 0x7A11));
  std::array<std::array<double, 4>, 6> waves;
  for (auto& axis : waves) {
    axis = {rng.Uniform(0.0, 2 * M_PI), rng.Uniform(0.3, 1.3),
            rng.Uniform(0.0, 2 * M_PI), 2.3 * rng.Uniform(0.3, 1.3)};
  }
  auto wave = [&](int axis, double t) {
    const auto& p = waves[axis];
    return 0.7 * std::sin(p[0] + 2 * M_PI * p[1] * t) +
           0.3 * std::sin(p[2] + 2 * M_PI * p[3] * t);
  };
  for (int i = 0; i < frames; ++i) {
    // Poses depend on time only, so a shorter sequence is a prefix of a longer
    // one.
    const double t = i / fps;
    Transform pose;
    switch (options.kind) {
      case TrajectoryOptions::Kind::kOrbit: {
        const double radius =
            std::max(0.5, std::min(size.x(), size.y()) / 2 - 0.5);
        const double angle =
            -M_PI / 2 + t * options.orbit_deg_per_s * M_PI / 180.0;
        const Eigen::Vector3d eye =
            center + Eigen::Vector3d(radius * std::cos(angle),
                                     radius * std::sin(angle),
                                     options.height_m);
        pose = LookAt(eye, center + Eigen::Vector3d(0, 0, 0.4));
        break;
      }
      case TrajectoryOptions::Kind::kWalkthrough: {
        // Along the long axis and back at walking_speed_mps, panning +-40
        // degrees every 6 s, looking 35 degrees down.
        const double length = size.x() - 1.6;
        const double lap = std::fmod(t * options.walking_speed_mps, 2 * length);
        const bool forward = lap < length;
        const double x = forward ? lap : 2 * length - lap;
        const Eigen::Vector3d eye(0.8 + x, size.y() / 2, options.height_m);
        const double heading =
            0.7 * std::sin(2 * M_PI * t / 6.0) + (forward ? 0.0 : M_PI);
        const Eigen::Vector3d look(std::cos(heading), std::sin(heading), -0.7);
        pose = LookAt(eye, eye + look);
        break;
      }
      case TrajectoryOptions::Kind::kStatic: {
        const Eigen::Vector3d eye(size.x() / 2, 0.15, options.height_m);
        pose = LookAt(eye, Eigen::Vector3d(size.x() / 2, size.y(), 0.8));
        break;
      }
      case TrajectoryOptions::Kind::kSparse:  // returned above
        break;
    }
    const Eigen::Vector3d dp(wave(0, t), wave(1, t), wave(2, t));
    const double deg = options.jitter_deg * M_PI / 180.0;
    const Eigen::Matrix3d dR =
        (Eigen::AngleAxisd(deg * wave(3, t), Eigen::Vector3d::UnitX()) *
         Eigen::AngleAxisd(deg * wave(4, t), Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(deg * wave(5, t), Eigen::Vector3d::UnitZ()))
            .toRotationMatrix();
    poses.emplace_back(pose.rotation() * dR,
                       pose.translation() + options.jitter_m * dp);
  }
  return poses;
}

}  // namespace semrec::synth
