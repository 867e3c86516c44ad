#include "semrec/mesh/object_mesher.h"

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
        if (xx < 0 || xx >= w || labels(xx, y) != l)
          rows[static_cast<size_t>(y) * w + x] = 0;
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
  for (const auto& [label, object_id] : label_to_object) {
    Frame masked = frame;  // colour, pose, intrinsics; depth masked below
    for (size_t i = 0; i < masked.depth.NumPixels(); ++i) {
      if (labels.values()[i] != label || !interior[i]) {
        masked.depth.values()[i] = 0.0f;
      }
    }
    Object& object = objects_[object_id];
    if (!object.volume)
      object.volume = std::make_unique<TsdfIntegrator>(options_.tsdf);
    object.volume->Integrate(masked);
    ++object.observations;
    object.changed = true;
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
