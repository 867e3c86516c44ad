#include "semrec/mesh/object_mesher.h"

#include <algorithm>
#include <limits>

#include "semrec/core/error.h"

namespace semrec::mesh {

void ObjectMeshingOptions::Check() const {
  tsdf.Check();
  CheckArgument(mask_erosion_px >= -1 && mask_erosion_px <= 20,
                "object meshing: mask_erosion_px must be in [0, 20] (or -1: "
                "auto)");
}

// Separable: rows, then columns; the offset loops outside so that the inner
// loops vectorise.
std::vector<uint8_t> InteriorMask(const LabelMap& labels, int r) {
  const int w = labels.width(), h = labels.height();
  std::vector<uint8_t> rows(labels.NumPixels(), 0), out(labels.NumPixels(), 0);
  if (r == 0) {
    std::fill(out.begin(), out.end(), 1);
    return out;
  }
  if (w <= 2 * r || h <= 2 * r) return out;
  const uint16_t* l = labels.data();
  for (int y = 0; y < h; ++y) {
    const uint16_t* row = l + static_cast<size_t>(y) * w;
    uint8_t* keep = rows.data() + static_cast<size_t>(y) * w;
    std::fill(keep + r, keep + w - r, 1);
    for (int d = -r; d <= r; ++d) {
      for (int x = r; x < w - r; ++x) keep[x] &= row[x + d] == row[x];
    }
  }
  for (int y = r; y < h - r; ++y) {
    const size_t at = static_cast<size_t>(y) * w;
    uint8_t* keep = out.data() + at;
    std::copy_n(rows.data() + at, w, keep);
    for (int d = -r; d <= r; ++d) {
      const size_t other = static_cast<size_t>(y + d) * w;
      for (int x = 0; x < w; ++x) {
        keep[x] &=
            static_cast<uint8_t>(l[other + x] == l[at + x]) & rows[other + x];
      }
    }
  }
  return out;
}

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
      InteriorMask(labels, options_.ErosionPx());
  // Each object's volume sees only the bounding box of its pixels (the
  // principal point shifted accordingly): integration then costs in proportion
  // to the object's image area, not the whole frame per object. Voxels that
  // project outside the crop are skipped exactly like masked-out pixels.
  struct PixelBox {
    int x0 = std::numeric_limits<int>::max(), y0 = x0, x1 = -1, y1 = -1;
  };
  // Indexed by label (a flat table: a map lookup per pixel cost as much as
  // the integration of a small object).
  uint16_t max_label = 0;
  for (const auto& entry : label_to_object) {
    max_label = std::max(max_label, entry.first);
  }
  std::vector<PixelBox> boxes(static_cast<size_t>(max_label) + 1);
  const int w = labels.width(), h = labels.height();
  const uint16_t* label_data = labels.data();
  for (int y = 0; y < h; ++y) {
    const size_t row = static_cast<size_t>(y) * w;
    for (int x = 0; x < w; ++x) {
      const uint16_t l = label_data[row + x];
      if (l > max_label || !interior[row + x]) continue;
      PixelBox& b = boxes[l];
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
    const PixelBox& b = boxes[label];
    if (b.x1 < 0) continue;  // no interior pixel: nothing to add
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
      const size_t row = static_cast<size_t>(b.y0 + y) * w + b.x0;
      const float* depth_in = frame.depth.data() + row;
      float* depth_out = crop.depth.data() + static_cast<size_t>(y) * cw;
      for (int x = 0; x < cw; ++x) {
        if (label_data[row + x] == label && interior[row + x]) {
          depth_out[x] = depth_in[x];
        }
      }
      std::copy_n(frame.color.data() + row * 3, static_cast<size_t>(cw) * 3,
                  crop.color.data() + static_cast<size_t>(y) * cw * 3);
    }
    object.volume->Integrate(crop);
  }
}

void ObjectMesher::Merge(uint32_t from, uint32_t into) {
  CheckArgument(from != into, "ObjectMesher::Merge: an object into itself");
  auto it = objects_.find(from);
  if (it == objects_.end()) return;  // never integrated: nothing to carry
  Object& target = objects_[into];
  if (!target.volume) {
    target.volume = std::move(it->second.volume);
  } else {
    target.volume->Absorb(it->second.volume.get());
  }
  target.observations += it->second.observations;
  target.changed = true;
  objects_.erase(it);
}

void ObjectMesher::Erase(uint32_t id) { objects_.erase(id); }

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
