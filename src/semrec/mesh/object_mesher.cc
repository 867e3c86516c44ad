#include "semrec/mesh/object_mesher.h"

#include "semrec/core/error.h"

namespace semrec::mesh {

void ObjectMeshingOptions::Check() const { tsdf.Check(); }

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
  for (const auto& [label, object_id] : label_to_object) {
    Frame masked = frame;  // colour, pose, intrinsics; depth masked below
    for (size_t i = 0; i < masked.depth.NumPixels(); ++i) {
      if (labels.values()[i] != label) masked.depth.values()[i] = 0.0f;
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
