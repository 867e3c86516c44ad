#include "semrec/fuse/map_projection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "semrec/core/error.h"

namespace semrec::fuse {
namespace {

// True when the 4-neighbours of (x, y) show the same object (not on its
// silhouette).
bool Interior(const Image<uint32_t>& ids, int x, int y) {
  const uint32_t id = ids(x, y);
  return x > 0 && y > 0 && x + 1 < ids.width() && y + 1 < ids.height() &&
         ids(x - 1, y) == id && ids(x + 1, y) == id && ids(x, y - 1) == id &&
         ids(x, y + 1) == id;
}

}  // namespace

void MapProjectionOptions::Check() const {
  CheckArgument(splat_radius_m > 0 && std::isfinite(splat_radius_m),
                "map projection: splat_radius_m must be > 0");
  CheckArgument(max_splat_px >= 0, "map projection: max_splat_px must be >= 0");
  CheckArgument(min_depth_m > 0, "map projection: min_depth_m must be > 0");
  CheckArgument(depth_tolerance_m >= 0 && depth_tolerance_ratio >= 0,
                "map projection: depth tolerances must be >= 0");
  CheckArgument(ambiguity_ratio >= 0 && ambiguity_ratio <= 1,
                "map projection: ambiguity_ratio must be in [0, 1]");
  CheckArgument(ambiguity_window_px >= 0,
                "map projection: ambiguity_window_px must be >= 0");
}

double ProjectedMap::UnexplainedShare() const {
  if (valid_depth_pixels == 0) return 1.0;
  return 1.0 - static_cast<double>(explained_pixels) /
                   static_cast<double>(valid_depth_pixels);
}

namespace {

constexpr float kFar = std::numeric_limits<float>::infinity();

// A splat that explains a pixel's measured depth.
struct Match {
  float diff = kFar;
  uint32_t id = 0;
  uint16_t class_id = 0;
  float z = 0.0f;
};

// Per pixel the nearest splat (what the map would show: z-buffer, object and
// class in *out) and, apart, the splats whose depth is closest to the
// measured depth within the tolerance (what explains the measurement): near a
// silhouette a nearer object's splat spills over the background, which the
// map explains all the same. The best and the second-best object (distinct)
// per pixel.
struct Splats {
  std::vector<float> zbuf;
  std::vector<Match> best, second;
};

class DepthTolerance {
 public:
  explicit DepthTolerance(const MapProjectionOptions& options)
      : options_(options) {}
  float operator()(float z) const {
    return options_.depth_tolerance_m + options_.depth_tolerance_ratio * z;
  }

 private:
  const MapProjectionOptions& options_;
};

// Keeps m as the pixel's best or second-best match (distinct objects).
void Offer(const Match& m, Match* best, Match* second) {
  if (m.id == best->id) {
    if (m.diff < best->diff) *best = m;
  } else if (m.diff < best->diff) {
    *second = *best;
    *best = m;
  } else if (m.id == second->id) {
    if (m.diff < second->diff) *second = m;
  } else if (m.diff < second->diff) {
    *second = m;
  }
}

Splats SplatObjects(const std::vector<SceneSegment>& objects,
                    const CameraIntrinsics& intrinsics,
                    const Transform& T_world_camera, const DepthImage& depth_m,
                    const MapProjectionOptions& options, ProjectedMap* out) {
  const int w = intrinsics.width;
  const int h = intrinsics.height;
  const size_t pixels = static_cast<size_t>(w) * h;
  Splats splats{std::vector<float>(pixels, kFar), std::vector<Match>(pixels),
                std::vector<Match>(pixels)};
  const Eigen::Matrix3f R = T_world_camera.rotation().transpose().cast<float>();
  const Eigen::Vector3f t =
      (-T_world_camera.rotation().transpose() * T_world_camera.translation())
          .cast<float>();
  const auto fx = static_cast<float>(intrinsics.fx);
  const auto fy = static_cast<float>(intrinsics.fy);
  const auto cx = static_cast<float>(intrinsics.cx);
  const auto cy = static_cast<float>(intrinsics.cy);
  const DepthTolerance tolerance(options);
  for (const SceneSegment& object : objects) {
    for (const Eigen::Vector3f& p_world : object.points) {
      const Eigen::Vector3f p = R * p_world + t;
      if (!(p.z() >= options.min_depth_m)) continue;
      const float u = fx * p.x() / p.z() + cx;
      const float v = fy * p.y() / p.z() + cy;
      const int r = std::min(
          options.max_splat_px,
          static_cast<int>(std::lround(fx * options.splat_radius_m / p.z())));
      const int u0 = static_cast<int>(std::floor(u));
      const int v0 = static_cast<int>(std::floor(v));
      if (u0 + r < 0 || v0 + r < 0 || u0 - r >= w || v0 - r >= h) continue;
      for (int y = std::max(0, v0 - r); y <= std::min(h - 1, v0 + r); ++y) {
        for (int x = std::max(0, u0 - r); x <= std::min(w - 1, u0 + r); ++x) {
          const size_t i = static_cast<size_t>(y) * w + x;
          if (p.z() < splats.zbuf[i]) {
            splats.zbuf[i] = p.z();
            out->object_id(x, y) = object.id;
            out->class_id(x, y) = object.class_id;
          }
          const float z = depth_m(x, y);
          const float diff = std::abs(z - p.z());
          if (!(z > 0) || diff > tolerance(z)) continue;
          Offer({diff, object.id, object.class_id, p.z()}, &splats.best[i],
                &splats.second[i]);
        }
      }
    }
  }
  return splats;
}

// Where two objects explain a pixel about equally well they are one surface
// to the camera (a surface fused twice under two classes): the pixel goes to
// the one that explains more of its neighbourhood, so that the frame's labels
// do not speckle between them (the whole frame would favour the largest
// object, a structure class gathering every mislabelled pixel).
void ResolveAmbiguous(const DepthImage& depth_m,
                      const MapProjectionOptions& options, Splats* splats) {
  const int w = depth_m.width(), h = depth_m.height();
  std::vector<Match>& best = splats->best;
  const std::vector<Match>& second = splats->second;
  const DepthTolerance tolerance(options);
  const auto ambiguous = [&](size_t i) {
    return second[i].id != 0 &&
           second[i].diff - best[i].diff <=
               options.ambiguity_ratio * tolerance(depth_m.data()[i]);
  };
  std::vector<uint32_t> best_id(best.size());
  for (size_t i = 0; i < best.size(); ++i) best_id[i] = best[i].id;
  const int radius = options.ambiguity_window_px;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (best[i].id == 0 || !ambiguous(i)) continue;
      int votes_best = 0, votes_second = 0;
      for (int v = std::max(0, y - radius); v <= std::min(h - 1, y + radius);
           v += 2) {
        for (int u = std::max(0, x - radius); u <= std::min(w - 1, x + radius);
             u += 2) {
          const uint32_t id = best_id[static_cast<size_t>(v) * w + u];
          votes_best += id == best[i].id ? 1 : 0;
          votes_second += id == second[i].id ? 1 : 0;
        }
      }
      if (votes_second > votes_best) best[i] = second[i];
    }
  }
}

// Per pixel: no depth, explained (the explaining object, class and depth), or
// contradicted (the camera sees past where the map has a surface and nothing
// of the map lies at the measured depth: it moved or is gone).
void ClassifyPixels(const Splats& splats, const DepthImage& depth_m,
                    const MapProjectionOptions& options, ProjectedMap* out) {
  const int w = depth_m.width(), h = depth_m.height();
  const DepthTolerance tolerance(options);
  const Image<uint32_t> nearest_id = out->object_id;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const float z_map = splats.zbuf[i];
      if (z_map != kFar) out->depth_m(x, y) = z_map;
      const float z = depth_m(x, y);
      if (!(z > 0) || !std::isfinite(z)) {
        out->state(x, y) = ProjectedMap::kNoDepth;
        continue;
      }
      ++out->valid_depth_pixels;
      const Match& best = splats.best[i];
      if (best.id != 0) {
        out->state(x, y) = ProjectedMap::kExplained;
        out->object_id(x, y) = best.id;
        out->class_id(x, y) = best.class_id;
        out->depth_m(x, y) = best.z;
        ++out->explained_pixels;
      } else if (z_map != kFar && z > z_map + tolerance(z) &&
                 Interior(nearest_id, x, y)) {
        out->state(x, y) = ProjectedMap::kContradicted;
        ++out->contradicted_pixels;
      }
    }
  }
}

}  // namespace

ProjectedMap ProjectMap(const std::vector<SceneSegment>& objects,
                        const CameraIntrinsics& intrinsics,
                        const Transform& T_world_camera,
                        const DepthImage& depth_m,
                        const MapProjectionOptions& options) {
  options.Check();
  intrinsics.Check();
  CheckArgument(
      depth_m.SameSize(intrinsics.width, intrinsics.height),
      "map projection: the depth image size differs from the intrinsics'");
  const int w = intrinsics.width;
  const int h = intrinsics.height;
  ProjectedMap out;
  out.object_id = Image<uint32_t>(w, h);
  out.class_id = LabelMap(w, h);
  out.depth_m = DepthImage(w, h);
  out.state = Image<uint8_t>(w, h);
  Splats splats =
      SplatObjects(objects, intrinsics, T_world_camera, depth_m, options, &out);
  ResolveAmbiguous(depth_m, options, &splats);
  ClassifyPixels(splats, depth_m, options, &out);
  return out;
}

std::vector<SceneSegment> DecidedMapForProjection(
    const std::vector<SceneSegment>& segments, const MapResolution& resolution,
    const VoxelEvidenceMap& evidence) {
  std::map<std::pair<uint32_t, uint16_t>, SceneSegment> split;
  const auto segment_for = [&](uint32_t id, uint16_t class_id,
                               ClassKind kind) -> SceneSegment& {
    SceneSegment& s = split[{id, class_id}];
    s.id = id;
    s.class_id = class_id;
    s.kind = kind;
    return s;
  };
  // Decided voxels, in key order within each object (deterministic).
  for (const MapObject& o : resolution.objects) {
    for (const uint64_t key : o.voxels) {
      const auto owner = resolution.owners.find(key);
      const auto voxel = evidence.voxels().find(key);
      if (owner == resolution.owners.end() || owner->second.source == 0 ||
          voxel == evidence.voxels().end()) {
        continue;
      }
      segment_for(owner->second.source, o.class_id, o.kind)
          .points.push_back(voxel->second.Centroid());
    }
  }
  const float inv_voxel = evidence.inv_voxel_size();
  for (const SceneSegment& s : segments) {
    for (const Eigen::Vector3f& p : s.points) {
      if (resolution.owners.count(VoxelKey(p, inv_voxel)) != 0) continue;
      segment_for(s.id, s.class_id, s.kind).points.push_back(p);
    }
  }
  std::vector<SceneSegment> out;
  out.reserve(split.size());
  for (auto& [key, s] : split) {
    if (!s.points.empty()) out.push_back(std::move(s));
  }
  return out;
}

}  // namespace semrec::fuse
