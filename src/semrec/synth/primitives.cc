#include "semrec/synth/primitives.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace semrec::synth {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Two unit vectors orthogonal to `axis` (unit) and to each other.
void Basis(const Eigen::Vector3d& axis, Eigen::Vector3d* u,
           Eigen::Vector3d* v) {
  const Eigen::Vector3d helper = std::abs(axis.z()) < 0.9
                                     ? Eigen::Vector3d::UnitZ()
                                     : Eigen::Vector3d::UnitX();
  *u = axis.cross(helper).normalized();
  *v = axis.cross(*u);
}

std::optional<Hit> IntersectBox(const Box& box, const Eigen::Vector3d& origin,
                                const Eigen::Vector3d& dir, double t_min,
                                double t_max) {
  // Slab test in the box frame.
  const Eigen::Vector3d o = box.R_world_box.transpose() * (origin - box.center);
  const Eigen::Vector3d d = box.R_world_box.transpose() * dir;
  double t_near = -kInf, t_far = kInf;
  int axis_near = -1, axis_far = -1;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      if (std::abs(o[i]) > box.half[i]) return std::nullopt;
      continue;
    }
    double t0 = (-box.half[i] - o[i]) / d[i];
    double t1 = (box.half[i] - o[i]) / d[i];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) t_near = t0, axis_near = i;
    if (t1 < t_far) t_far = t1, axis_far = i;
    // Missed, or the entry (hence any hit) lies beyond t_max.
    if (t_near > t_far || t_near >= t_max) return std::nullopt;
  }
  // Entering hit, or the exit when the origin is inside (rooms are seen from
  // inside).
  double t = t_near;
  int axis = axis_near;
  if (t <= t_min) t = t_far, axis = axis_far;
  if (t <= t_min || t >= t_max || axis < 0) return std::nullopt;
  const Eigen::Vector3d p = o + t * d;
  Eigen::Vector3d n_local = Eigen::Vector3d::Zero();
  n_local[axis] = p[axis] > 0 ? 1.0 : -1.0;
  return Hit{t, box.R_world_box * n_local};
}

std::optional<Hit> IntersectSphere(const Eigen::Vector3d& c, double r,
                                   const Eigen::Vector3d& origin,
                                   const Eigen::Vector3d& dir, double t_min,
                                   double t_max) {
  const Eigen::Vector3d oc = origin - c;
  const double a = dir.squaredNorm();
  const double half_b = oc.dot(dir);
  const double cc = oc.squaredNorm() - r * r;
  const double disc = half_b * half_b - a * cc;
  if (disc < 0) return std::nullopt;
  const double sq = std::sqrt(disc);
  for (double t : {(-half_b - sq) / a, (-half_b + sq) / a}) {
    if (t > t_min && t < t_max) return Hit{t, (origin + t * dir - c) / r};
  }
  return std::nullopt;
}

// Lateral surface of the infinite cylinder around a-b clipped to the segment
// (no caps).
std::optional<Hit> IntersectTube(const Eigen::Vector3d& a,
                                 const Eigen::Vector3d& b, double r,
                                 const Eigen::Vector3d& origin,
                                 const Eigen::Vector3d& dir, double t_min,
                                 double t_max) {
  const Eigen::Vector3d axis = b - a;
  const double len = axis.norm();
  const Eigen::Vector3d w = axis / len;
  const Eigen::Vector3d oc = origin - a;
  const Eigen::Vector3d d_perp = dir - dir.dot(w) * w;
  const Eigen::Vector3d o_perp = oc - oc.dot(w) * w;
  const double qa = d_perp.squaredNorm();
  if (qa < 1e-18) return std::nullopt;
  const double half_b = o_perp.dot(d_perp);
  const double qc = o_perp.squaredNorm() - r * r;
  const double disc = half_b * half_b - qa * qc;
  if (disc < 0) return std::nullopt;
  const double sq = std::sqrt(disc);
  for (double t : {(-half_b - sq) / qa, (-half_b + sq) / qa}) {
    if (t <= t_min || t >= t_max) continue;
    const Eigen::Vector3d p = origin + t * dir;
    const double s = (p - a).dot(w);
    if (s < 0 || s > len) continue;
    return Hit{t, (p - a - s * w) / r};
  }
  return std::nullopt;
}

std::optional<Hit> IntersectDisc(const Eigen::Vector3d& c,
                                 const Eigen::Vector3d& n, double r,
                                 const Eigen::Vector3d& origin,
                                 const Eigen::Vector3d& dir, double t_min,
                                 double t_max) {
  const double denom = n.dot(dir);
  if (std::abs(denom) < 1e-15) return std::nullopt;
  const double t = n.dot(c - origin) / denom;
  if (t <= t_min || t >= t_max) return std::nullopt;
  if ((origin + t * dir - c).squaredNorm() > r * r) return std::nullopt;
  return Hit{t, n};
}

void Closer(const std::optional<Hit>& candidate, std::optional<Hit>* best,
            double* t_max) {
  if (candidate && candidate->t < *t_max) {
    *best = candidate;
    *t_max = candidate->t;
  }
}

double SegmentDistance(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                       const Eigen::Vector3d& p) {
  const Eigen::Vector3d ab = b - a;
  const double s = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + s * ab)).norm();
}

// Grid samples on a parallelogram corner + s u + t v, s in [0, |u|], t in [0,
// |v|].
void SampleRect(const Eigen::Vector3d& corner, const Eigen::Vector3d& u,
                const Eigen::Vector3d& v, double spacing,
                std::vector<Eigen::Vector3d>* points) {
  const int nu = std::max(1, static_cast<int>(std::ceil(u.norm() / spacing)));
  const int nv = std::max(1, static_cast<int>(std::ceil(v.norm() / spacing)));
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      points->push_back(corner + (i + 0.5) / nu * u + (j + 0.5) / nv * v);
    }
  }
}

void SampleSphereCap(const Eigen::Vector3d& c, double r,
                     const Eigen::Vector3d& pole, bool hemisphere,
                     double spacing, std::vector<Eigen::Vector3d>* points) {
  // Fibonacci lattice: near-uniform and deterministic.
  const double area = (hemisphere ? 2.0 : 4.0) * M_PI * r * r;
  const int n =
      std::max(1, static_cast<int>(std::ceil(area / (spacing * spacing))));
  Eigen::Vector3d u, v;
  Basis(pole, &u, &v);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    // z from 1 down to -1 (sphere) or 0 (hemisphere), equal-area bands.
    const double z =
        hemisphere ? 1.0 - (i + 0.5) / n : 1.0 - 2.0 * (i + 0.5) / n;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * i;
    points->push_back(
        c + r * (z * pole + rho * std::cos(phi) * u + rho * std::sin(phi) * v));
  }
}

void SampleTube(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
                double spacing, std::vector<Eigen::Vector3d>* points) {
  const Eigen::Vector3d axis = b - a;
  Eigen::Vector3d u, v;
  Basis(axis.normalized(), &u, &v);
  const int na =
      std::max(3, static_cast<int>(std::ceil(2 * M_PI * r / spacing)));
  const int nh =
      std::max(1, static_cast<int>(std::ceil(axis.norm() / spacing)));
  for (int i = 0; i < na; ++i) {
    const double phi = 2 * M_PI * (i + 0.5) / na;
    const Eigen::Vector3d radial = r * (std::cos(phi) * u + std::sin(phi) * v);
    for (int j = 0; j < nh; ++j) {
      points->push_back(a + (j + 0.5) / nh * axis + radial);
    }
  }
}

void SampleDisc(const Eigen::Vector3d& c, const Eigen::Vector3d& n, double r,
                double spacing, std::vector<Eigen::Vector3d>* points) {
  Eigen::Vector3d u, v;
  Basis(n, &u, &v);
  const int rings = std::max(1, static_cast<int>(std::ceil(r / spacing)));
  for (int k = 0; k < rings; ++k) {
    const double rho = r * (k + 0.5) / rings;
    const int na =
        std::max(3, static_cast<int>(std::ceil(2 * M_PI * rho / spacing)));
    for (int i = 0; i < na; ++i) {
      const double phi = 2 * M_PI * (i + 0.5 * (k % 2)) / na;
      points->push_back(c + rho * (std::cos(phi) * u + std::sin(phi) * v));
    }
  }
}

uint32_t AddVertex(TriangleMesh* mesh, const Eigen::Vector3d& v) {
  mesh->vertices.push_back(v);
  return static_cast<uint32_t>(mesh->vertices.size() - 1);
}

void MeshTube(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
              int segments, bool caps, TriangleMesh* mesh) {
  Eigen::Vector3d u, v;
  const Eigen::Vector3d w = (b - a).normalized();
  Basis(w, &u, &v);
  const uint32_t base = static_cast<uint32_t>(mesh->vertices.size());
  for (int i = 0; i < segments; ++i) {
    const double phi = 2 * M_PI * i / segments;
    const Eigen::Vector3d radial = r * (std::cos(phi) * u + std::sin(phi) * v);
    AddVertex(mesh, a + radial);
    AddVertex(mesh, b + radial);
  }
  for (int i = 0; i < segments; ++i) {
    const uint32_t a0 = base + 2 * i, b0 = a0 + 1;
    const uint32_t a1 = base + 2 * ((i + 1) % segments), b1 = a1 + 1;
    mesh->triangles.push_back({a0, a1, b1});
    mesh->triangles.push_back({a0, b1, b0});
  }
  if (caps) {
    const uint32_t ca = AddVertex(mesh, a), cb = AddVertex(mesh, b);
    for (int i = 0; i < segments; ++i) {
      const uint32_t a0 = base + 2 * i, a1 = base + 2 * ((i + 1) % segments);
      mesh->triangles.push_back({ca, a1, a0});
      mesh->triangles.push_back({cb, a0 + 1, a1 + 1});
    }
  }
}

void MeshSphere(const Eigen::Vector3d& c, double r, int segments,
                TriangleMesh* mesh) {
  const int rings = std::max(2, segments / 2);
  const uint32_t base = static_cast<uint32_t>(mesh->vertices.size());
  for (int i = 0; i <= rings; ++i) {
    const double theta = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * M_PI * j / segments;
      AddVertex(mesh, c + r * Eigen::Vector3d(std::sin(theta) * std::cos(phi),
                                              std::sin(theta) * std::sin(phi),
                                              std::cos(theta)));
    }
  }
  for (int i = 0; i < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      const uint32_t p00 = base + i * segments + j,
                     p01 = base + i * segments + (j + 1) % segments;
      const uint32_t p10 = p00 + segments, p11 = p01 + segments;
      if (i > 0) mesh->triangles.push_back({p00, p10, p01});
      if (i < rings - 1) mesh->triangles.push_back({p01, p10, p11});
    }
  }
}

}  // namespace

std::optional<Hit> Intersect(const Primitive& shape,
                             const Eigen::Vector3d& origin,
                             const Eigen::Vector3d& dir, double t_min,
                             double t_max) {
  if (const auto* box = std::get_if<Box>(&shape)) {
    return IntersectBox(*box, origin, dir, t_min, t_max);
  }
  if (const auto* s = std::get_if<Sphere>(&shape)) {
    return IntersectSphere(s->center, s->radius, origin, dir, t_min, t_max);
  }
  std::optional<Hit> best;
  if (const auto* c = std::get_if<Cylinder>(&shape)) {
    const Eigen::Vector3d w = (c->b - c->a).normalized();
    Closer(IntersectTube(c->a, c->b, c->radius, origin, dir, t_min, t_max),
           &best, &t_max);
    Closer(IntersectDisc(c->a, -w, c->radius, origin, dir, t_min, t_max), &best,
           &t_max);
    Closer(IntersectDisc(c->b, w, c->radius, origin, dir, t_min, t_max), &best,
           &t_max);
    return best;
  }
  const auto& cap = std::get<Capsule>(shape);
  Closer(IntersectTube(cap.a, cap.b, cap.radius, origin, dir, t_min, t_max),
         &best, &t_max);
  Closer(IntersectSphere(cap.a, cap.radius, origin, dir, t_min, t_max), &best,
         &t_max);
  Closer(IntersectSphere(cap.b, cap.radius, origin, dir, t_min, t_max), &best,
         &t_max);
  return best;
}

double SignedDistance(const Primitive& shape, const Eigen::Vector3d& p) {
  if (const auto* box = std::get_if<Box>(&shape)) {
    const Eigen::Vector3d q =
        (box->R_world_box.transpose() * (p - box->center)).cwiseAbs() -
        box->half;
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
  }
  if (const auto* s = std::get_if<Sphere>(&shape)) {
    return (p - s->center).norm() - s->radius;
  }
  if (const auto* c = std::get_if<Cylinder>(&shape)) {
    const Eigen::Vector3d axis = c->b - c->a;
    const double len = axis.norm();
    const Eigen::Vector3d w = axis / len;
    const double h = (p - c->a).dot(w);
    const double radial = (p - c->a - h * w).norm();
    // 2-D box SDF in (radial, axial) coordinates.
    const Eigen::Vector2d q(radial - c->radius,
                            std::abs(h - len / 2) - len / 2);
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
  }
  const auto& cap = std::get<Capsule>(shape);
  return SegmentDistance(cap.a, cap.b, p) - cap.radius;
}

Eigen::AlignedBox3d Bounds(const Primitive& shape) {
  Eigen::AlignedBox3d box;
  if (const auto* b = std::get_if<Box>(&shape)) {
    const Eigen::Vector3d extent = b->R_world_box.cwiseAbs() * b->half;
    box.extend(b->center - extent);
    box.extend(b->center + extent);
  } else if (const auto* s = std::get_if<Sphere>(&shape)) {
    box.extend(s->center - Eigen::Vector3d::Constant(s->radius));
    box.extend(s->center + Eigen::Vector3d::Constant(s->radius));
  } else {
    const auto [a, b, r] =
        std::holds_alternative<Cylinder>(shape)
            ? std::tuple(std::get<Cylinder>(shape).a,
                         std::get<Cylinder>(shape).b,
                         std::get<Cylinder>(shape).radius)
            : std::tuple(std::get<Capsule>(shape).a, std::get<Capsule>(shape).b,
                         std::get<Capsule>(shape).radius);
    for (const Eigen::Vector3d& e : {a, b}) {
      box.extend(e - Eigen::Vector3d::Constant(r));
      box.extend(e + Eigen::Vector3d::Constant(r));
    }
  }
  return box;
}

double SurfaceArea(const Primitive& shape) {
  if (const auto* b = std::get_if<Box>(&shape)) {
    const Eigen::Vector3d e = 2 * b->half;
    return 2 * (e.x() * e.y() + e.y() * e.z() + e.x() * e.z());
  }
  if (const auto* s = std::get_if<Sphere>(&shape)) {
    return 4 * M_PI * s->radius * s->radius;
  }
  if (const auto* c = std::get_if<Cylinder>(&shape)) {
    return 2 * M_PI * c->radius * ((c->b - c->a).norm() + c->radius);
  }
  const auto& cap = std::get<Capsule>(shape);
  return 2 * M_PI * cap.radius * (cap.b - cap.a).norm() +
         4 * M_PI * cap.radius * cap.radius;
}

void AppendMesh(const Primitive& shape, int segments, TriangleMesh* mesh) {
  if (const auto* b = std::get_if<Box>(&shape)) {
    // 4 vertices per face so that each face is flat.
    for (int axis = 0; axis < 3; ++axis) {
      for (int sign : {-1, 1}) {
        const int u_axis = (axis + 1) % 3, v_axis = (axis + 2) % 3;
        Eigen::Vector3d n = Eigen::Vector3d::Zero(), u = n, v = n;
        n[axis] = sign * b->half[axis];
        u[u_axis] = b->half[u_axis];
        v[v_axis] = b->half[v_axis];
        const uint32_t i0 =
            AddVertex(mesh, b->center + b->R_world_box * (n - u - v));
        const uint32_t i1 =
            AddVertex(mesh, b->center + b->R_world_box * (n + u - v));
        const uint32_t i2 =
            AddVertex(mesh, b->center + b->R_world_box * (n + u + v));
        const uint32_t i3 =
            AddVertex(mesh, b->center + b->R_world_box * (n - u + v));
        // Counter-clockwise seen from outside.
        if (sign > 0) {
          mesh->triangles.push_back({i0, i1, i2});
          mesh->triangles.push_back({i0, i2, i3});
        } else {
          mesh->triangles.push_back({i0, i2, i1});
          mesh->triangles.push_back({i0, i3, i2});
        }
      }
    }
  } else if (const auto* s = std::get_if<Sphere>(&shape)) {
    MeshSphere(s->center, s->radius, segments, mesh);
  } else if (const auto* c = std::get_if<Cylinder>(&shape)) {
    MeshTube(c->a, c->b, c->radius, segments, /*caps=*/true, mesh);
  } else {
    const auto& cap = std::get<Capsule>(shape);
    MeshTube(cap.a, cap.b, cap.radius, segments, /*caps=*/false, mesh);
    MeshSphere(cap.a, cap.radius, segments, mesh);
    MeshSphere(cap.b, cap.radius, segments, mesh);
  }
}

void AppendSurfaceSamples(const Primitive& shape, double spacing,
                          std::vector<Eigen::Vector3d>* points) {
  if (const auto* b = std::get_if<Box>(&shape)) {
    for (int axis = 0; axis < 3; ++axis) {
      for (int sign : {-1, 1}) {
        const int u_axis = (axis + 1) % 3, v_axis = (axis + 2) % 3;
        Eigen::Vector3d n = Eigen::Vector3d::Zero(), u = n, v = n;
        n[axis] = sign * b->half[axis];
        u[u_axis] = 2 * b->half[u_axis];
        v[v_axis] = 2 * b->half[v_axis];
        SampleRect(b->center + b->R_world_box * (n - u / 2 - v / 2),
                   b->R_world_box * u, b->R_world_box * v, spacing, points);
      }
    }
  } else if (const auto* s = std::get_if<Sphere>(&shape)) {
    SampleSphereCap(s->center, s->radius, Eigen::Vector3d::UnitZ(), false,
                    spacing, points);
  } else if (const auto* c = std::get_if<Cylinder>(&shape)) {
    const Eigen::Vector3d w = (c->b - c->a).normalized();
    SampleTube(c->a, c->b, c->radius, spacing, points);
    SampleDisc(c->a, -w, c->radius, spacing, points);
    SampleDisc(c->b, w, c->radius, spacing, points);
  } else {
    const auto& cap = std::get<Capsule>(shape);
    const Eigen::Vector3d w = (cap.b - cap.a).normalized();
    SampleTube(cap.a, cap.b, cap.radius, spacing, points);
    SampleSphereCap(cap.b, cap.radius, w, true, spacing, points);
    SampleSphereCap(cap.a, cap.radius, -w, true, spacing, points);
  }
}

}  // namespace semrec::synth
