// Analytic shapes of the synthetic scenes: ray intersection, exact distance to
// the surface, triangulation and area-uniform surface sampling. World frame: z
// up, metres.
#pragma once

#include <array>
#include <optional>
#include <variant>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace semrec::synth {

/// An oriented box: centre, half extents along its local axes, rotation local
/// -> world.
struct Box {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5);
  Eigen::Matrix3d R_world_box = Eigen::Matrix3d::Identity();
};

/// A solid cylinder between the centres of its two flat caps.
struct Cylinder {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::UnitZ();
  double radius = 0.1;
};

/// A capsule: all points within `radius` of the segment a-b (limbs of people).
struct Capsule {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::UnitZ();
  double radius = 0.1;
};

struct Sphere {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.1;
};

using Primitive = std::variant<Box, Cylinder, Capsule, Sphere>;

struct Hit {
  /// Ray parameter (distance along the ray direction, in units of its length).
  double t = 0.0;
  /// Outward unit surface normal.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

/// Nearest intersection with t in (t_min, t_max); `dir` need not be unit
/// length.
std::optional<Hit> Intersect(const Primitive& shape,
                             const Eigen::Vector3d& origin,
                             const Eigen::Vector3d& dir, double t_min,
                             double t_max);

/// Signed distance (negative inside) from `p` to the shape's surface.
double SignedDistance(const Primitive& shape, const Eigen::Vector3d& p);

/// Axis-aligned bounds in the world frame.
Eigen::AlignedBox3d Bounds(const Primitive& shape);

/// Surface area (m^2).
double SurfaceArea(const Primitive& shape);

/// A closed triangle mesh of the surface (flat-shaded boxes and caps,
/// `segments` around round shapes).
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;
};
void AppendMesh(const Primitive& shape, int segments, TriangleMesh* mesh);

/// Deterministic, roughly area-uniform points on the surface, about `spacing_m`
/// apart.
void AppendSurfaceSamples(const Primitive& shape, double spacing_m,
                          std::vector<Eigen::Vector3d>* points);

}  // namespace semrec::synth
