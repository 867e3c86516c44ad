#include "semrec/synth/render.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace semrec::synth {
namespace {

struct Drawable {
  const Primitive* shape;
  uint16_t instance;
  uint16_t semantic;
  uint16_t person;
  Rgb color;
};

struct Rect {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive; empty when x1 < x0
};

// Screen rectangle that contains the projection of `bounds` (conservative).
Rect ScreenRect(const Eigen::AlignedBox3d& bounds,
                const Transform& T_camera_world, const CameraIntrinsics& k) {
  constexpr double kNear = 0.01;
  double u0 = 1e18, v0 = 1e18, u1 = -1e18, v1 = -1e18;
  int in_front = 0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner =
        bounds.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
    const Eigen::Vector3d p = T_camera_world * corner;
    if (p.z() < kNear) continue;
    ++in_front;
    const Eigen::Vector2d uv = k.Project(p);
    u0 = std::min(u0, uv.x()), u1 = std::max(u1, uv.x());
    v0 = std::min(v0, uv.y()), v1 = std::max(v1, uv.y());
  }
  if (in_front == 0) return {};
  if (in_front < 8)
    return {0, 0, k.width - 1, k.height - 1};  // straddles the camera plane
  Rect r;
  r.x0 = std::max(0, static_cast<int>(std::floor(u0)) - 1);
  r.y0 = std::max(0, static_cast<int>(std::floor(v0)) - 1);
  r.x1 = std::min(k.width - 1, static_cast<int>(std::ceil(u1)) + 1);
  r.y1 = std::min(k.height - 1, static_cast<int>(std::ceil(v1)) + 1);
  return r;
}

// Deterministic value noise in [-1, 1] from a world position (2 cm cells): a
// texture that sticks to surfaces, so appearance is consistent across frames.
double Texture(const Eigen::Vector3d& p) {
  const auto q = (p / 0.02).array().floor().cast<int64_t>();
  uint64_t h = static_cast<uint64_t>(q.x()) * 0x9E3779B185EBCA87ULL ^
               static_cast<uint64_t>(q.y()) * 0xC2B2AE3D27D4EB4FULL ^
               static_cast<uint64_t>(q.z()) * 0x165667B19E3779F9ULL;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 32;
  return static_cast<double>(h & 0xFFFF) / 32767.5 - 1.0;
}

std::vector<Drawable> CollectDrawables(const Scene& scene,
                                       const std::vector<PersonBody>& bodies) {
  std::vector<Drawable> out;
  for (const SceneObject& o : scene.objects) {
    for (const Primitive& p : o.parts)
      out.push_back({&p, o.instance_id, o.class_id, 0, o.color});
  }
  for (size_t i = 0; i < bodies.size(); ++i) {
    const uint16_t pid = scene.people[i].person_id;
    for (size_t j = 0; j < bodies[i].parts.size(); ++j) {
      out.push_back({&bodies[i].parts[j],
                     static_cast<uint16_t>(kPersonInstanceBase + pid),
                     kClassPerson, pid, bodies[i].colors[j]});
    }
  }
  return out;
}

}  // namespace

RenderedFrame Render(const Scene& scene, double time_s,
                     const Transform& T_world_camera,
                     const CameraIntrinsics& k) {
  k.Check();
  std::vector<PersonBody> bodies;
  for (const Person& person : scene.people)
    bodies.push_back(PoseAt(person, time_s));
  const std::vector<Drawable> drawables = CollectDrawables(scene, bodies);

  const Transform T_camera_world = T_world_camera.Inverse();
  const Eigen::Matrix3d& R = T_world_camera.rotation();
  const Eigen::Vector3d origin = T_world_camera.translation();
  const int w = k.width, h = k.height;
  std::vector<double> zbuf(static_cast<size_t>(w) * h,
                           std::numeric_limits<double>::infinity());
  std::vector<int> owner(zbuf.size(), -1);
  std::vector<Eigen::Vector3f> normals(zbuf.size());

  for (size_t d = 0; d < drawables.size(); ++d) {
    const Rect r = ScreenRect(Bounds(*drawables[d].shape), T_camera_world, k);
    for (int v = r.y0; v <= r.y1; ++v) {
      for (int u = r.x0; u <= r.x1; ++u) {
        const size_t i = static_cast<size_t>(v) * w + u;
        // Ray direction with unit z in the camera frame, so the hit parameter
        // is the z-depth.
        const Eigen::Vector3d dir =
            R * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
        const auto hit =
            Intersect(*drawables[d].shape, origin, dir, 1e-4, zbuf[i]);
        if (!hit) continue;
        zbuf[i] = hit->t;
        owner[i] = static_cast<int>(d);
        normals[i] = hit->normal.cast<float>();
      }
    }
  }

  RenderedFrame out;
  out.color = ColorImage(w, h, 3);
  out.depth = DepthImage(w, h, 1, 0.0f);
  out.cos_incidence = Image<float>(w, h, 1, 0.0f);
  out.semantic = LabelMap(w, h);
  out.instance = LabelMap(w, h);
  out.person = LabelMap(w, h);
  const Eigen::Vector3d light = Eigen::Vector3d(0.3, -0.5, 1.0).normalized();
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const size_t i = static_cast<size_t>(v) * w + u;
      if (owner[i] < 0) continue;
      const Drawable& dr = drawables[owner[i]];
      const Eigen::Vector3d dir =
          R * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      const Eigen::Vector3d n = normals[i].cast<double>();
      const double cos_view = std::abs(n.dot(dir)) / dir.norm();
      out.depth(u, v) = static_cast<float>(zbuf[i]);
      out.cos_incidence(u, v) = static_cast<float>(cos_view);
      out.semantic(u, v) = dr.semantic;
      out.instance(u, v) = dr.instance;
      out.person(u, v) = dr.person;
      // Lambert from a fixed light plus a head-light term, and a surface-fixed
      // texture.
      const double shade =
          0.35 + 0.4 * std::max(0.0, n.dot(light)) + 0.25 * cos_view;
      const double tex = 1.0 + 0.08 * Texture(origin + zbuf[i] * dir);
      for (int c = 0; c < 3; ++c) {
        out.color(u, v, c) = static_cast<uint8_t>(
            std::clamp(dr.color[c] * shade * tex, 0.0, 255.0) + 0.5);
      }
    }
  }
  return out;
}

Silhouette UnoccludedSilhouette(const Scene& scene, uint16_t person_id,
                                double time_s, const Transform& T_world_camera,
                                const CameraIntrinsics& k) {
  Silhouette s;
  s.x0 = k.width, s.y0 = k.height;
  for (const Person& person : scene.people) {
    if (person.person_id != person_id) continue;
    const PersonBody body = PoseAt(person, time_s);
    Eigen::AlignedBox3d bounds;
    for (const Primitive& p : body.parts) bounds.extend(Bounds(p));
    const Rect r = ScreenRect(bounds, T_world_camera.Inverse(), k);
    const Eigen::Matrix3d& R = T_world_camera.rotation();
    const Eigen::Vector3d origin = T_world_camera.translation();
    for (int v = r.y0; v <= r.y1; ++v) {
      for (int u = r.x0; u <= r.x1; ++u) {
        const Eigen::Vector3d dir =
            R * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
        const bool hit = std::any_of(
            body.parts.begin(), body.parts.end(), [&](const Primitive& p) {
              return Intersect(p, origin, dir, 1e-4, 1e9).has_value();
            });
        if (!hit) continue;
        ++s.pixels;
        s.x0 = std::min(s.x0, u), s.x1 = std::max(s.x1, u);
        s.y0 = std::min(s.y0, v), s.y1 = std::max(s.y1, v);
      }
    }
  }
  if (s.pixels == 0) s = Silhouette{};
  return s;
}

}  // namespace semrec::synth
