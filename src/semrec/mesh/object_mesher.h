// Per-object TSDF meshing: one Open3D ScalableTSDFVolume per object, each
// integrating only that object's pixels (depth masked by the object's mask) at
// the frame's pose.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include <open3d/geometry/TriangleMesh.h>

#include "semrec/core/frame.h"
#include "semrec/core/label_map.h"
#include "semrec/mesh/tsdf_integrator.h"

namespace semrec::mesh {

struct ObjectMeshingOptions {
  /// Voxel size of each object's volume: 2 cm keeps furniture detail at a
  /// fraction of the memory of 1 cm.
  TsdfOptions tsdf = {0.02, 0.08, 4.0, true};
  /// Objects integrated in fewer frames are not meshed (spurious segments).
  size_t min_observations = 1;
  /// Mask pixels within this many pixels of another label are not integrated:
  /// depth at mask borders often belongs to the neighbour (mixed pixels,
  /// lateral noise, imprecise masks) and would add stray surfaces to the
  /// object. -1 (auto): 1, or 0 where the meshes are cut by the map's voxel
  /// owners (SceneBuilder with fusion merge "voxel": a border triangle lands
  /// in the neighbour's voxel and goes to it), since erosion also eats thin
  /// and far objects (a lamp's pole, a split mask's jittered rim).
  int mask_erosion_px = -1;
  /// The erosion used (auto resolved as without the voxel cut).
  int ErosionPx() const { return mask_erosion_px < 0 ? 1 : mask_erosion_px; }
  void Check() const;
};

/// 1 for pixels whose (2r+1) x (2r+1) neighbourhood lies in the image and
/// has one label only, 0 elsewhere (all 1 for r = 0): the mask erosion that
/// keeps depth from object boundaries out of the objects' volumes.
std::vector<uint8_t> InteriorMask(const LabelMap& labels, int r);

class ObjectMesher {
 public:
  explicit ObjectMesher(const ObjectMeshingOptions& options = {});
  ~ObjectMesher();

  /// Integrates, for every (label, object id) pair, the pixels of `frame` whose
  /// `labels` value is `label` into object `object_id`'s volume. Marks those
  /// objects as changed.
  void Integrate(
      const Frame& frame, const LabelMap& labels,
      const std::vector<std::pair<uint16_t, uint32_t>>& label_to_object);

  /// Meshes of the objects changed since the last call (all objects with enough
  /// observations on the first call); unchanged objects keep their previous
  /// mesh, so only changed objects are re-meshed.
  std::map<uint32_t, std::shared_ptr<open3d::geometry::TriangleMesh>>
  UpdateMeshes();

  /// Object `from`'s volume goes into `into`'s (TsdfIntegrator::Absorb):
  /// what a streaming pipeline does when fusion merges two objects after both
  /// were integrated. `into` is marked as changed; `from` is gone.
  void Merge(uint32_t from, uint32_t into);
  /// Forgets an object (fusion dropped it).
  void Erase(uint32_t id);
  /// Brings the volumes in line with fusion's ids: every object whose
  /// `resolve(id)` differs is merged into that object, or erased when it is 0.
  /// Returns the number of volumes merged or erased.
  template <typename Resolve>
  size_t Reconcile(const Resolve& resolve) {
    std::vector<std::pair<uint32_t, uint32_t>> moves;
    for (const auto& entry : objects_) {
      const uint32_t to = resolve(entry.first);
      if (to != entry.first) moves.emplace_back(entry.first, to);
    }
    for (const auto& [from, to] : moves) {
      if (to == 0) {
        Erase(from);
      } else {
        Merge(from, to);
      }
    }
    return moves.size();
  }

  size_t remeshed_last_update() const { return remeshed_last_update_; }
  size_t num_objects() const { return objects_.size(); }

 private:
  struct Object {
    std::unique_ptr<TsdfIntegrator> volume;
    size_t observations = 0;
    bool changed = false;
    std::shared_ptr<open3d::geometry::TriangleMesh> mesh;
  };
  ObjectMeshingOptions options_;
  std::map<uint32_t, Object> objects_;
  size_t remeshed_last_update_ = 0;
};

}  // namespace semrec::mesh
