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
  uint16_t part = 0;
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
  if (in_front < 8) {
    return {0, 0, k.width - 1, k.height - 1};  // straddles the camera plane
  }
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

// Objects, interior walls and people; the room's faces are handled by the
// room test (Scene::room_faces).
std::vector<Drawable> CollectDrawables(const Scene& scene,
                                       const std::vector<PersonBody>& bodies) {
  std::vector<Drawable> out;
  for (const SceneObject& o : scene.objects) {
    if (o.room_face) continue;
    for (size_t j = 0; j < o.parts.size(); ++j) {
      // Parts are numbered for objects only (RenderedFrame::part).
      out.push_back({&o.parts[j], o.instance_id, o.class_id, 0, o.color,
                     static_cast<uint16_t>(o.structure ? 0 : j + 1)});
    }
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

std::pair<Eigen::Vector3d, double> BoundingSphere(const Primitive& shape) {
  if (const auto* b = std::get_if<Box>(&shape)) {
    return {b->center, b->half.norm()};
  }
  if (const auto* s = std::get_if<Sphere>(&shape)) {
    return {s->center, s->radius};
  }
  if (const auto* c = std::get_if<Cylinder>(&shape)) {
    const double half_len = (c->b - c->a).norm() / 2;
    return {(c->a + c->b) / 2, std::hypot(half_len, c->radius)};
  }
  const auto& c = std::get<Capsule>(shape);
  return {(c.a + c.b) / 2, (c.b - c.a).norm() / 2 + c.radius};
}

// Exit face of the room box [0, size] seen from `origin` inside it: t and face
// index
// (-x, +x, -y, +y, -z, +z), or face -1 when the origin is outside.
std::pair<double, int> RoomExit(const Eigen::Vector3d& size,
                                const Eigen::Vector3d& origin,
                                const Eigen::Vector3d& dir) {
  double t_exit = std::numeric_limits<double>::infinity();
  int face = -1;
  for (int axis = 0; axis < 3; ++axis) {
    if (dir[axis] == 0.0) continue;
    const bool positive = dir[axis] > 0.0;
    const double t = ((positive ? size[axis] : 0.0) - origin[axis]) / dir[axis];
    if (t < t_exit) t_exit = t, face = 2 * axis + (positive ? 1 : 0);
  }
  return {t_exit, face};
}

}  // namespace

RenderedFrame Render(const Scene& scene, double time_s,
                     const Transform& T_world_camera,
                     const CameraIntrinsics& k) {
  k.Check();
  std::vector<PersonBody> bodies;
  for (const Person& person : scene.people) {
    bodies.push_back(PoseAt(person, time_s));
  }
  const std::vector<Drawable> drawables = CollectDrawables(scene, bodies);

  const Transform T_camera_world = T_world_camera.Inverse();
  const Eigen::Matrix3d& R = T_world_camera.rotation();
  const Eigen::Vector3d& origin = T_world_camera.translation();
  const int w = k.width, h = k.height;
  const size_t n = static_cast<size_t>(w) * h;
  // World ray direction per pixel, with unit z in the camera frame so that the
  // hit parameter is the z-depth.
  std::vector<Eigen::Vector3d> dirs(n);
  for (int v = 0; v < h; ++v) {
    const Eigen::Vector3d row = R.col(1) * ((v - k.cy) / k.fy) + R.col(2);
    for (int u = 0; u < w; ++u) {
      dirs[static_cast<size_t>(v) * w + u] =
          row + R.col(0) * ((u - k.cx) / k.fx);
    }
  }
  std::vector<double> zbuf(n, std::numeric_limits<double>::infinity());
  // Owner: drawable index, or -(face + 2) for a room face, -1 for nothing.
  std::vector<int> owner(n, -1);
  std::vector<Eigen::Vector3f> normals(n);

  const bool inside_room = (origin.array() > 0.0).all() &&
                           (origin.array() < scene.room_size.array()).all();
  if (inside_room) {
    for (size_t i = 0; i < n; ++i) {
      const auto [t, face] = RoomExit(scene.room_size, origin, dirs[i]);
      if (face < 0 || scene.room_faces[face] == 0) continue;
      zbuf[i] = t;
      owner[i] = -(face + 2);
      Eigen::Vector3f normal = Eigen::Vector3f::Zero();
      normal[face / 2] = face % 2 == 1 ? -1.0f : 1.0f;  // facing into the room
      normals[i] = normal;
    }
  }
  for (size_t d = 0; d < drawables.size(); ++d) {
    const Primitive& shape = *drawables[d].shape;
    const Rect r = ScreenRect(Bounds(shape), T_camera_world, k);
    // Bounding sphere: a ray that misses it (a dozen flops) cannot hit the
    // shape; most pixels of a thin or rotated part's rectangle are rejected so.
    const auto [center, radius] = BoundingSphere(shape);
    const Eigen::Vector3d oc = origin - center;
    const double c_term = oc.squaredNorm() - radius * radius;
    for (int v = r.y0; v <= r.y1; ++v) {
      for (int u = r.x0; u <= r.x1; ++u) {
        const size_t i = static_cast<size_t>(v) * w + u;
        const double half_b = oc.dot(dirs[i]);
        if (c_term > 0.0 &&
            (half_b > 0.0 ||
             half_b * half_b < dirs[i].squaredNorm() * c_term)) {
          continue;
        }
        const auto hit =
            Intersect(*drawables[d].shape, origin, dirs[i], 1e-4, zbuf[i]);
        if (!hit) continue;
        zbuf[i] = hit->t;
        owner[i] = static_cast<int>(d);
        normals[i] = hit->normal.cast<float>();
      }
    }
  }

  // Room faces as drawables for shading and labels.
  std::array<Drawable, 6> faces{};
  for (int f = 0; f < 6; ++f) {
    if (scene.room_faces[f] == 0) continue;
    const SceneObject* o = scene.FindObject(scene.room_faces[f]);
    faces[f] = {nullptr, o->instance_id, o->class_id, 0, o->color};
  }

  RenderedFrame out;
  out.color = ColorImage(w, h, 3);
  out.depth = DepthImage(w, h, 1, 0.0f);
  out.cos_incidence = Image<float>(w, h, 1, 0.0f);
  out.semantic = LabelMap(w, h);
  out.instance = LabelMap(w, h);
  out.person = LabelMap(w, h);
  out.part = LabelMap(w, h);
  const Eigen::Vector3d light = Eigen::Vector3d(0.3, -0.5, 1.0).normalized();
  uint8_t* color = out.color.data();
  for (size_t i = 0; i < n; ++i) {
    if (owner[i] == -1) continue;
    const Drawable& dr =
        owner[i] >= 0 ? drawables[owner[i]] : faces[-owner[i] - 2];
    const Eigen::Vector3d& dir = dirs[i];
    const Eigen::Vector3d n_world = normals[i].cast<double>();
    const double cos_view = std::abs(n_world.dot(dir)) / dir.norm();
    out.depth.data()[i] = static_cast<float>(zbuf[i]);
    out.cos_incidence.data()[i] = static_cast<float>(cos_view);
    out.semantic.data()[i] = dr.semantic;
    out.instance.data()[i] = dr.instance;
    out.person.data()[i] = dr.person;
    out.part.data()[i] = dr.part;
    // Lambert from a fixed light plus a head-light term, and a surface-fixed
    // texture.
    const double shade =
        0.35 + 0.4 * std::max(0.0, n_world.dot(light)) + 0.25 * cos_view;
    const double gain = shade * (1.0 + 0.08 * Texture(origin + zbuf[i] * dir));
    for (int c = 0; c < 3; ++c) {
      color[3 * i + c] = static_cast<uint8_t>(
          std::lround(std::min(dr.color[c] * gain, 255.0)));
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
    const Eigen::Vector3d& origin = T_world_camera.translation();
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
