#include "semrec/mesh/object_mesher.h"

#include <algorithm>
#include <limits>

#include "semrec/core/error.h"

namespace semrec::mesh {

void ObjectMeshingOptions::Check() const {
  tsdf.Check();
  CheckArgument(mask_erosion_px >= 0 && mask_erosion_px <= 20,
                "object meshing: mask_erosion_px must be in [0, 20]");
}

namespace {

// Pixels whose (2r+1)^2 neighbourhood has one label only (separable: rows, then
// columns).
std::vector<uint8_t> InteriorMask(const LabelMap& labels, int r) {
  const int w = labels.width(), h = labels.height();
  std::vector<uint8_t> rows(labels.NumPixels(), 1), out(labels.NumPixels(), 1);
  if (r == 0) return out;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint16_t l = labels(x, y);
      for (int d = -r; d <= r && rows[y * w + x]; ++d) {
        const int xx = x + d;
        if (xx < 0 || xx >= w || labels(xx, y) != l) {
          rows[static_cast<size_t>(y) * w + x] = 0;
        }
      }
    }
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint16_t l = labels(x, y);
      uint8_t keep = rows[static_cast<size_t>(y) * w + x];
      for (int d = -r; d <= r && keep; ++d) {
        const int yy = y + d;
        keep = yy >= 0 && yy < h && labels(x, yy) == l &&
               rows[static_cast<size_t>(yy) * w + x];
      }
      out[static_cast<size_t>(y) * w + x] = keep;
    }
  }
  return out;
}

}  // namespace

ObjectMesher::ObjectMesher(const ObjectMeshingOptions& options)
    : options_(options) {
  options_.Check();
}

ObjectMesher::~ObjectMesher() = default;

void ObjectMesher::Integrate(
    const Frame& frame, const LabelMap& labels,
    const std::vector<std::pair<uint16_t, uint32_t>>& label_to_object) {
  CheckArgument(labels.SameSize(frame.depth),
                "ObjectMesher: labels and depth sizes differ");
  const std::vector<uint8_t> interior =
      InteriorMask(labels, options_.mask_erosion_px);
  // Each object's volume sees only the bounding box of its pixels (the
  // principal point shifted accordingly): integration then costs in proportion
  // to the object's image area, not the whole frame per object. Voxels that
  // project outside the crop are skipped exactly like masked-out pixels.
  struct PixelBox {
    int x0 = std::numeric_limits<int>::max(), y0 = x0, x1 = -1, y1 = -1;
  };
  std::map<uint16_t, PixelBox> boxes;
  const int w = labels.width(), h = labels.height();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!interior[static_cast<size_t>(y) * w + x]) continue;
      PixelBox& b = boxes[labels(x, y)];
      b.x0 = std::min(b.x0, x);
      b.y0 = std::min(b.y0, y);
      b.x1 = std::max(b.x1, x);
      b.y1 = std::max(b.y1, y);
    }
  }
  for (const auto& [label, object_id] : label_to_object) {
    Object& object = objects_[object_id];
    if (!object.volume) {
      object.volume = std::make_unique<TsdfIntegrator>(options_.tsdf);
    }
    ++object.observations;
    object.changed = true;
    const auto it = boxes.find(label);
    if (it == boxes.end()) continue;  // no interior pixel: nothing to add
    const PixelBox& b = it->second;
    const int cw = b.x1 - b.x0 + 1, ch = b.y1 - b.y0 + 1;
    Frame crop;
    crop.index = frame.index;
    crop.timestamp_s = frame.timestamp_s;
    crop.T_world_camera = frame.T_world_camera;
    crop.intrinsics = frame.intrinsics;
    crop.intrinsics.width = cw;
    crop.intrinsics.height = ch;
    crop.intrinsics.cx -= b.x0;
    crop.intrinsics.cy -= b.y0;
    crop.depth = DepthImage(cw, ch);
    crop.color = ColorImage(cw, ch, 3);
    for (int y = 0; y < ch; ++y) {
      for (int x = 0; x < cw; ++x) {
        const int u = b.x0 + x, v = b.y0 + y;
        const size_t i = static_cast<size_t>(v) * w + u;
        if (labels(u, v) == label && interior[i]) {
          crop.depth(x, y) = frame.depth(u, v);
        }
        for (int c = 0; c < 3; ++c) crop.color(x, y, c) = frame.color(u, v, c);
      }
    }
    object.volume->Integrate(crop);
  }
}

std::map<uint32_t, std::shared_ptr<open3d::geometry::TriangleMesh>>
ObjectMesher::UpdateMeshes() {
  remeshed_last_update_ = 0;
  std::map<uint32_t, std::shared_ptr<open3d::geometry::TriangleMesh>> out;
  for (auto& [id, object] : objects_) {
    if (object.observations < options_.min_observations) continue;
    if (object.changed || !object.mesh) {
      object.mesh = object.volume->ExtractMesh();
      object.mesh->ComputeVertexNormals();
      object.changed = false;
      ++remeshed_last_update_;
    }
    out.emplace(id, object.mesh);
  }
  return out;
}

}  // namespace semrec::mesh
