#include "semrec/fuse/voxel_votes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>
#include <utility>

#include <Eigen/Eigenvalues>

#include "semrec/core/error.h"

namespace semrec::fuse {

void VoxelEvidenceOptions::Check() const {
  CheckArgument(full_weight_distance_m > 0.0,
                "voxel evidence: full_weight_distance_m must be > 0");
  CheckArgument(view_class_share > 0.0 && view_class_share <= 1.0,
                "voxel evidence: view_class_share must be in (0, 1]");
}

ClassEvidence* FindOrAddClass(std::vector<ClassEvidence>* classes,
                              uint16_t class_id) {
  for (ClassEvidence& c : *classes) {
    if (c.class_id == class_id) return &c;
  }
  classes->push_back({class_id, 0, 0.0f});
  return &classes->back();
}

const ClassEvidence* VoxelEvidence::Find(uint16_t class_id) const {
  for (const ClassEvidence& c : classes) {
    if (c.class_id == class_id) return &c;
  }
  return nullptr;
}

bool VoxelEvidence::SurfaceAxis(float min_share, float min_points,
                                Eigen::Vector3f* axis) const {
  // Each unit normal adds 1 to the trace.
  const float trace = normal_scatter.trace();
  if (!(trace > 0.0f) || trace < min_points) return false;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eig(normal_scatter);
  // Eigenvalues ascending: the last is the dominant axis.
  if (eig.eigenvalues()(2) < min_share * trace) return false;
  *axis = eig.eigenvectors().col(2).normalized();
  return true;
}

VoxelEvidenceMap::VoxelEvidenceMap(double voxel_size_m,
                                   const VoxelEvidenceOptions& options)
    : voxel_size_m_(voxel_size_m),
      inv_voxel_(static_cast<float>(1.0 / voxel_size_m)),
      options_((options.Check(), options)) {
  CheckArgument(voxel_size_m > 0.0, "voxel evidence: voxel size must be > 0");
}

size_t VoxelEvidenceMap::labelled_voxels() const {
  return static_cast<size_t>(
      std::count_if(voxels_.begin(), voxels_.end(),
                    [](const auto& kv) { return !kv.second.classes.empty(); }));
}

namespace {

// One labelled pixel of the frame: its voxel, class and object.
struct Vote {
  uint64_t key;
  uint32_t object;
  uint16_t class_id;
  /// The mask's label in the frame; 0 for structure (not kept).
  uint16_t label;
  Eigen::Vector3f p;
  float confidence;
  Eigen::Vector3f normal;  // zero: none
};

ObjectVote* FindOrAddObject(std::vector<ObjectVote>* objects, uint32_t id) {
  for (ObjectVote& o : *objects) {
    if (o.id == id) return &o;
  }
  objects->push_back({id, 0.0f});
  return &objects->back();
}

// The object mask holding most of the pixels in votes[begin, end) (one
// voxel's); 0 when none does (ties: the smaller label). Only the dominant mask
// is kept per view: where two touching objects' depths mix in a voxel, it
// stays with the object most of its pixels show, so the two do not look like
// one mask's.
// `counts`: scratch (label, pixels), reused across voxels: this runs for
// every voxel of every frame.
uint16_t DominantMask(const std::vector<Vote>& votes, size_t begin, size_t end,
                      std::vector<std::pair<uint16_t, uint32_t>>* scratch) {
  std::vector<std::pair<uint16_t, uint32_t>>& counts = *scratch;
  counts.clear();
  for (size_t k = begin; k < end; ++k) {
    if (votes[k].label == 0) continue;
    auto it = std::find_if(counts.begin(), counts.end(), [&](const auto& c) {
      return c.first == votes[k].label;
    });
    if (it == counts.end()) {
      counts.emplace_back(votes[k].label, 1);
    } else {
      ++it->second;
    }
  }
  uint16_t best = 0;
  uint32_t best_count = 0;
  for (const auto& [label, count] : counts) {
    if (count > best_count || (count == best_count && label < best)) {
      best = label, best_count = count;
    }
  }
  return best;
}

}  // namespace

void VoxelEvidenceMap::AddFrame(const std::vector<FrameSegment>& segments,
                                const std::vector<uint32_t>& object_ids,
                                const FrameObservation* observation,
                                size_t frame_index) {
  CheckArgument(object_ids.size() == segments.size(),
                "voxel evidence: one object id per segment");
  std::vector<Vote> votes;
  size_t total = 0;
  for (const FrameSegment& s : segments) total += s.points_world.size();
  votes.reserve(total);
  for (size_t f = 0; f < segments.size(); ++f) {
    const FrameSegment& s = segments[f];
    if (s.map_object != 0) continue;
    if (s.kind != ClassKind::kStuff && s.source_label != 0) {
      mask_classes_[MaskId(frame_index, s.source_label)] = s.class_id;
    }
    const bool has_normals = s.normals_world.size() == s.points_world.size();
    for (size_t i = 0; i < s.points_world.size(); ++i) {
      const Eigen::Vector3f& p = s.points_world[i];
      votes.push_back(
          {VoxelKey(p, inv_voxel_), object_ids[f], s.class_id,
           s.kind == ClassKind::kStuff ? uint16_t{0} : s.source_label, p,
           s.confidence,
           has_normals ? s.normals_world[i] : Eigen::Vector3f::Zero()});
    }
  }
  // Grouped by voxel, then class and object: one pass casts each voxel's vote.
  std::sort(votes.begin(), votes.end(), [](const Vote& a, const Vote& b) {
    return a.key != b.key             ? a.key < b.key
           : a.class_id != b.class_id ? a.class_id < b.class_id
                                      : a.object < b.object;
  });
  const Eigen::Vector3f eye = observation ? observation->camera_position_world
                                          : Eigen::Vector3f::Zero();
  std::unordered_set<uint64_t> seen_this_frame;
  std::vector<std::pair<uint16_t, uint32_t>> mask_counts;
  for (size_t i = 0; i < votes.size();) {
    size_t end = i;
    while (end < votes.size() && votes[end].key == votes[i].key) ++end;
    VoxelEvidence& v = voxels_[votes[i].key];
    const auto n = static_cast<float>(end - i);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3f scatter = Eigen::Matrix3f::Zero();
    for (size_t k = i; k < end; ++k) {
      sum += votes[k].p.cast<double>();
      scatter.noalias() += votes[k].normal * votes[k].normal.transpose();
    }
    v.point_sum += sum;
    v.normal_scatter += scatter;
    v.points += static_cast<uint32_t>(end - i);
    float weight = 1.0f;
    if (observation != nullptr) {
      const Eigen::Vector3f to_eye = eye - (sum / n).cast<float>();
      const float d = to_eye.norm();
      const auto full = static_cast<float>(options_.full_weight_distance_m);
      if (d > full) weight = full / d;
      if (d > 0.0f) v.towards_camera_sum += to_eye / d;
    }
    for (size_t k = i; k < end;) {  // per class
      size_t class_end = k;
      while (class_end < end &&
             votes[class_end].class_id == votes[k].class_id) {
        ++class_end;
      }
      const float share = static_cast<float>(class_end - k) / n;
      // The class's share of the view's vote, each pixel counted by how sure
      // the segmenter was of it: an unsure view casts less than one vote.
      float sure = 0.0f;
      for (size_t q = k; q < class_end; ++q) sure += votes[q].confidence;
      ClassEvidence* c = FindOrAddClass(&v.classes, votes[k].class_id);
      c->weight += weight * sure / n;
      if (share >= options_.view_class_share) ++c->views;
      for (size_t o = k; o < class_end;) {  // per object within the class
        size_t object_end = o;
        while (object_end < class_end &&
               votes[object_end].object == votes[o].object) {
          ++object_end;
        }
        if (votes[o].object != 0) {
          FindOrAddObject(&v.objects, votes[o].object)->views +=
              static_cast<float>(object_end - o) / n;
        }
        o = object_end;
      }
      k = class_end;
    }
    if (const uint16_t label = DominantMask(votes, i, end, &mask_counts);
        label != 0) {
      v.masks.push_back(MaskId(frame_index, label));
    }
    ++v.views;
    seen_this_frame.insert(votes[i].key);
    i = end;
  }
  if (observation == nullptr) return;
  if (options_.far_views && !observation->far.cells.empty()) {
    far_views_.push_back(observation->far);
  }
  for (const Eigen::Vector3f& p : observation->observed_world) {
    const uint64_t key = VoxelKey(p, inv_voxel_);
    if (!seen_this_frame.insert(key).second) continue;
    ++voxels_[key].views;
  }
}

namespace {

using VoxelCentres = std::vector<std::pair<uint64_t, Eigen::Vector3d>>;
using ClassVotes = std::unordered_map<uint64_t, VoxelEvidenceMap::FarEvidence>;

// Per grid cell of `view`: its class (0: none) and whether its 4-neighbours
// carry the same class (a 2D model's borders blur, the more so far away).
void LabelGrid(const FarView& view, std::vector<uint16_t>* cell_class,
               std::vector<float>* cell_confidence,
               std::vector<uint8_t>* interior) {
  const int cols = view.columns(), rows = view.rows();
  const size_t n_cells = static_cast<size_t>(cols) * rows;
  cell_class->assign(n_cells, 0);
  cell_confidence->assign(n_cells, 0.0f);
  for (size_t c = 0; c < view.cells.size(); ++c) {
    if (view.cells[c] >= n_cells) continue;
    (*cell_class)[view.cells[c]] = view.class_ids[c];
    (*cell_confidence)[view.cells[c]] = view.confidence[c];
  }
  constexpr std::pair<int, int> kNeighbours[] = {
      {1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  interior->assign(n_cells, 0);
  for (size_t cell = 0; cell < n_cells; ++cell) {
    const uint16_t cls = (*cell_class)[cell];
    if (cls == 0) continue;
    const int col = static_cast<int>(cell % cols);
    const int row = static_cast<int>(cell / cols);
    bool alike = true;
    for (const auto& [dc, dr] : kNeighbours) {
      const int c2 = col + dc, r2 = row + dr;
      if (c2 < 0 || r2 < 0 || c2 >= cols || r2 >= rows) continue;
      alike &= (*cell_class)[static_cast<size_t>(r2) * cols + c2] == cls;
    }
    (*interior)[cell] = alike;
  }
}

// One far view's votes (VoxelEvidenceMap::FarVotes) added to `out`.
void VoteFromFarView(const FarView& view, const VoxelCentres& voxels,
                     double voxel_size_m, double view_class_share,
                     ClassVotes* out) {
  constexpr int kStride = FarView::kStride;
  const int cols = view.columns(), rows = view.rows();
  std::vector<uint16_t> cell_class;
  std::vector<float> cell_confidence;
  std::vector<uint8_t> interior;
  LabelGrid(view, &cell_class, &cell_confidence, &interior);
  const Transform T_camera_world = view.T_world_camera.Inverse();
  const CameraIntrinsics& k = view.intrinsics;
  // Each voxel covers the cells its square (side: a voxel) spans, projected
  // once for both passes below (empty when behind the camera or outside).
  struct Footprint {
    int c0 = 0, c1 = -1, r0 = 0, r1 = -1;
    float z = 0.0f;
  };
  std::vector<Footprint> footprints(voxels.size());
  const auto cell_of = [](double x) {
    return static_cast<int>(std::floor(x / kStride));
  };
  for (size_t i = 0; i < voxels.size(); ++i) {
    const Eigen::Vector3d p = T_camera_world * voxels[i].second;
    if (p.z() <= voxel_size_m) continue;
    const Eigen::Vector2d uv = k.Project(p);
    const double r = k.fx * voxel_size_m / 2 / p.z();
    footprints[i] = {std::max(0, cell_of(uv.x() - r)),
                     std::min(cols - 1, cell_of(uv.x() + r)),
                     std::max(0, cell_of(uv.y() - r)),
                     std::min(rows - 1, cell_of(uv.y() + r)),
                     static_cast<float>(p.z())};
  }
  // Calls f(cell, depth) for each cell voxel i covers.
  const auto visit = [&](size_t i, const auto& f) {
    const Footprint& fp = footprints[i];
    for (int row = fp.r0; row <= fp.r1; ++row) {
      for (int col = fp.c0; col <= fp.c1; ++col) {
        f(static_cast<size_t>(row) * cols + col, fp.z);
      }
    }
  };
  std::vector<float> nearest(cell_class.size(),
                             std::numeric_limits<float>::infinity());
  for (size_t i = 0; i < voxels.size(); ++i) {
    visit(i, [&](size_t cell, float z) {
      nearest[cell] = std::min(nearest[cell], z);
    });
  }
  // The voxels of the nearest surface (within two voxels of it: a surface's
  // thickness in the map) in each interior labelled cell beyond reach.
  const auto thickness = static_cast<float>(2 * voxel_size_m);
  struct CellVote {
    uint32_t voxel;
    uint16_t class_id;
    float confidence;
  };
  std::vector<CellVote> votes;
  for (size_t i = 0; i < voxels.size(); ++i) {
    visit(i, [&](size_t cell, float z) {
      if (!interior[cell] || nearest[cell] < view.max_ranged_depth_m ||
          z > nearest[cell] + thickness) {
        return;
      }
      votes.push_back(
          {static_cast<uint32_t>(i), cell_class[cell], cell_confidence[cell]});
    });
  }
  std::sort(
      votes.begin(), votes.end(), [](const CellVote& a, const CellVote& b) {
        return a.voxel != b.voxel ? a.voxel < b.voxel : a.class_id < b.class_id;
      });
  // One vote per voxel, split over its cells' classes.
  for (size_t i = 0; i < votes.size();) {
    size_t end = i;
    while (end < votes.size() && votes[end].voxel == votes[i].voxel) ++end;
    const auto n = static_cast<float>(end - i);
    VoxelEvidenceMap::FarEvidence& far = (*out)[voxels[votes[i].voxel].first];
    ++far.views;
    std::vector<ClassEvidence>& classes = far.classes;
    for (size_t q = i; q < end;) {  // per class
      size_t class_end = q;
      float sure = 0.0f;
      for (; class_end < end && votes[class_end].class_id == votes[q].class_id;
           ++class_end) {
        sure += votes[class_end].confidence;
      }
      ClassEvidence* c = FindOrAddClass(&classes, votes[q].class_id);
      c->weight += sure / n;
      if (static_cast<double>(class_end - q) >= view_class_share * n) {
        ++c->views;
      }
      q = class_end;
    }
    i = end;
  }
}

}  // namespace

std::unordered_map<uint64_t, VoxelEvidenceMap::FarEvidence>
VoxelEvidenceMap::FarVotes() const {
  ClassVotes out;
  if (far_views_.empty()) return out;
  VoxelCentres voxels;
  for (const auto& [key, v] : voxels_) {
    if (v.points > 0 && !v.classes.empty()) {
      voxels.emplace_back(key, v.Centroid().cast<double>());
    }
  }
  std::sort(voxels.begin(), voxels.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const FarView& view : far_views_) {
    VoteFromFarView(view, voxels, voxel_size_m_, options_.view_class_share,
                    &out);
  }
  return out;
}

}  // namespace semrec::fuse
