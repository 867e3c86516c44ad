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
  constexpr float kFar = std::numeric_limits<float>::infinity();
  std::vector<float> zbuf(static_cast<size_t>(w) * h, kFar);

  const Eigen::Matrix3f R = T_world_camera.rotation().transpose().cast<float>();
  const Eigen::Vector3f t =
      (-T_world_camera.rotation().transpose() * T_world_camera.translation())
          .cast<float>();
  const auto fx = static_cast<float>(intrinsics.fx);
  const auto fy = static_cast<float>(intrinsics.fy);
  const auto cx = static_cast<float>(intrinsics.cx);
  const auto cy = static_cast<float>(intrinsics.cy);
  // Per pixel the nearest splat (what the map would show) and, apart, the
  // splat whose depth is closest to the measured depth within the tolerance
  // (what explains the measurement): near a silhouette a nearer object's
  // splat spills over the background, which the map explains all the same.
  // The best and the second-best object (distinct) per pixel.
  struct Match {
    float diff = kFar;
    uint32_t id = 0;
    uint16_t class_id = 0;
    float z = 0.0f;
  };
  std::vector<Match> best(static_cast<size_t>(w) * h);
  std::vector<Match> second(static_cast<size_t>(w) * h);
  const auto tolerance = [&](float z) {
    return options.depth_tolerance_m + options.depth_tolerance_ratio * z;
  };
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
          if (p.z() < zbuf[i]) {
            zbuf[i] = p.z();
            out.object_id(x, y) = object.id;
            out.class_id(x, y) = object.class_id;
          }
          const float z = depth_m(x, y);
          const float diff = std::abs(z - p.z());
          if (!(z > 0) || diff > tolerance(z)) continue;
          const Match m{diff, object.id, object.class_id, p.z()};
          if (object.id == best[i].id) {
            if (diff < best[i].diff) best[i] = m;
          } else if (diff < best[i].diff) {
            second[i] = best[i];
            best[i] = m;
          } else if (object.id == second[i].id) {
            if (diff < second[i].diff) second[i] = m;
          } else if (diff < second[i].diff) {
            second[i] = m;
          }
        }
      }
    }
  }

  // Where two objects explain a pixel about equally well they are one surface
  // to the camera (a surface fused twice under two classes): the pixel goes
  // to the one that explains more of its neighbourhood, so that the frame's
  // labels do not speckle between them (the whole frame would favour the
  // largest object, a structure class gathering every mislabelled pixel).
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

  const Image<uint32_t> nearest_id = out.object_id;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const float z_map = zbuf[i];
      if (z_map != kFar) out.depth_m(x, y) = z_map;
      const float z = depth_m(x, y);
      if (!(z > 0) || !std::isfinite(z)) {
        out.state(x, y) = ProjectedMap::kNoDepth;
        continue;
      }
      ++out.valid_depth_pixels;
      if (best[i].id != 0) {
        out.state(x, y) = ProjectedMap::kExplained;
        out.object_id(x, y) = best[i].id;
        out.class_id(x, y) = best[i].class_id;
        out.depth_m(x, y) = best[i].z;
        ++out.explained_pixels;
      } else if (z_map != kFar && z > z_map + tolerance(z) &&
                 Interior(nearest_id, x, y)) {
        // The camera sees past where the map has a surface and nothing of
        // the map lies at the measured depth: it moved or is gone.
        out.state(x, y) = ProjectedMap::kContradicted;
        ++out.contradicted_pixels;
      }
    }
  }
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
