// Where per-frame segmentations come from (files, for now: ground-truth layers
// or label PNGs) and how a frame's segments become world-frame point clouds.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "semrec/core/frame.h"
#include "semrec/core/label_map.h"
#include "semrec/fuse/voxel.h"
#include "semrec/io/sequence_reader.h"

namespace semrec::fuse {

/// A frame's segmentation: pixels with the same non-zero instance id form one
/// segment; its class is the semantic label its pixels carry (majority).
struct FrameLabels {
  FrameLabels() = default;
  FrameLabels(LabelMap instance_map, LabelMap semantic_map,
              std::string source_name,
              std::map<uint16_t, uint32_t> projected_objects = {})
      : instance(std::move(instance_map)),
        semantic(std::move(semantic_map)),
        source(std::move(source_name)),
        map_objects(std::move(projected_objects)) {}

  LabelMap instance;
  LabelMap semantic;
  /// Where the labels came from, for messages.
  std::string source;
  /// Map-guided labels: the instances the map's projection labelled, with the
  /// map object each one is (fusion attaches them to it without counting
  /// them as a new view: the map seeing itself is no evidence).
  std::map<uint16_t, uint32_t> map_objects;
  /// Per instance: how sure the segmenter was of its class, in [0, 1] (the
  /// vote's mass on the winning class, detector evidence included; the
  /// semantic model's mean probability for pixels in no mask). Missing = 1
  /// (given labels). Scales the instance's votes in the voxel evidence.
  std::map<uint16_t, float> confidence;
};

/// Where a run's labels come from, as `--labels` names it.
struct LabelSpec {
  enum class Kind {
    /// "models": the segmentation models label the frames (no source).
    kModels,
    /// "gt": the sequence's own `instance` and `semantic` layers.
    kSequence,
    /// A label folder (`semrec segment`'s output, `synth`'s labels_noisy).
    kFolder,
    /// "single:<class>": every pixel with depth is one segment of the class.
    kSingleClass,
  };
  Kind kind = Kind::kSequence;
  /// kFolder: the folder; kSingleClass: the class name.
  std::string value;
  /// "models", "gt", "single:<class>", anything else a folder. Throws
  /// InvalidArgument for an empty text or "single:" without a class.
  static LabelSpec Parse(const std::string& text);
  /// The text Parse reads back.
  std::string Text() const;
  bool given() const { return kind != Kind::kModels; }
};

class SegmentationSource {
 public:
  virtual ~SegmentationSource() = default;

  /// Labels for frame `i` of `reader`; throws FormatError (naming the file) for
  /// label maps of the wrong size or type.
  virtual FrameLabels Get(const io::SequenceReader& reader, size_t i) const = 0;

  /// The class table: from the source's data (e.g. gt/classes.json) or the one
  /// given.
  virtual const LabelSet& classes() const = 0;

  /// `spec`:
  ///  - "gt": the sequence's own `instance` and `semantic` layers (generic
  ///  layout, e.g. from
  ///    `semrec synth`), classes from <sequence>/gt/classes.json;
  ///  - a folder: <folder>/instance/<depth file name> and
  ///  <folder>/semantic/<depth file name>
  ///    (single-channel 8- or 16-bit PNGs), classes from <folder>/classes.json;
  ///  - "single:<class name>": every pixel with depth is one segment of that
  ///  class (class table
  ///    with that single class, id 1).
  /// Throws InvalidArgument for LabelSpec::Kind::kModels, IoError for a
  /// folder that does not exist.
  static std::unique_ptr<SegmentationSource> Create(
      const LabelSpec& spec, const io::SequenceReader& reader);
  /// Create(LabelSpec::Parse(spec), reader).
  static std::unique_ptr<SegmentationSource> Create(
      const std::string& spec, const io::SequenceReader& reader);
};

/// One segment of one frame, back-projected into the world frame.
struct FrameSegment {
  uint16_t class_id = 0;
  /// The instance id in the frame's label map.
  uint16_t source_label = 0;
  Cloud points_world;
  /// Structure (wall, floor...) or an object; from the class table.
  ClassKind kind = ClassKind::kThing;
  /// The map object these pixels were labelled as by projection
  /// (FrameLabels::map_objects; 0: found in the frame itself).
  uint32_t map_object = 0;
  /// FrameLabels::confidence of the instance (1 when not given).
  float confidence = 1.0f;
  /// Parallel to points_world (or empty: unknown): the surface normal at each
  /// point from the depth around it (world frame, unit, facing the camera;
  /// zero where depth jumps or is missing there). SurfaceNormalAt.
  Cloud normals_world = {};
};

struct SegmentExtractionOptions {
  /// Back-project every n-th pixel in u and v (1 = all).
  int pixel_stride = 1;
  /// Segments with fewer back-projected points are skipped (mask fringes,
  /// specks).
  size_t min_points = 50;
  /// Classes left out of static fusion (people are tracked, not fused).
  std::set<std::string> excluded_classes = {"person"};

  void Check() const;
};

/// The surface normal at pixel (u, v) of `depth` (camera frame, unit, facing
/// the camera) from the points `step_px` pixels to each side (central
/// differences, one-sided where a neighbour is missing or lies across a depth
/// jump of more than 10 % of the depth); zero when no pair is left. A
/// per-pixel normal from Kinect-like depth is noisy (~20 degrees at 2 m with
/// a 3-pixel step); its use is summed over the many pixels of a map voxel.
Eigen::Vector3f SurfaceNormalAt(const DepthImage& depth,
                                const CameraIntrinsics& k, int u, int v,
                                int step_px);

/// Segments of `frame` per its labels. Pixels without depth are ignored;
/// instance 0 is "unlabelled", and so is semantic 0 unless `classes` has an
/// entry for it (VOC's "background"). Throws FormatError when a
/// semantic label is not in `classes`, or when label and depth sizes differ.
std::vector<FrameSegment> ExtractFrameSegments(
    const Frame& frame, const FrameLabels& labels, const LabelSet& classes,
    const SegmentExtractionOptions& options);

/// What a frame's labels say where its sensor gave no depth: a coarse grid
/// (every kStride-th pixel) of the labelled pixels there. Depth sensors stop
/// at 4-5 m, but the colour camera still sees the sofa across the room: such
/// views vote on the map voxels that other views ranged, when those lie
/// beyond anything this frame ranged (VoxelEvidenceMap, far views). In a
/// walk-through most views of a far object are of this kind.
struct FarView {
  static constexpr int kStride = 8;
  Transform T_world_camera;
  CameraIntrinsics intrinsics;  // of the full frame
  /// The frame's reach: the 99th percentile of its sampled valid depths (m).
  float max_ranged_depth_m = 0.0f;
  /// Grid cells (row-major over ceil(width / kStride) columns) with a label
  /// and no depth, with the label's class and confidence.
  std::vector<uint32_t> cells;
  std::vector<uint16_t> class_ids;
  std::vector<float> confidence;
  int columns() const { return (intrinsics.width + kStride - 1) / kStride; }
  int rows() const { return (intrinsics.height + kStride - 1) / kStride; }
};

/// What one frame shows: where the camera was and every surface point it
/// measured (world frame), labelled or not, and its labels where it measured
/// none. Pixels the map's projection labelled are left out: the map seeing
/// itself is no view.
struct FrameObservation {
  Eigen::Vector3f camera_position_world = Eigen::Vector3f::Zero();
  Cloud observed_world;
  FarView far;
};

/// What the frame observed, labelled or not (fusion's visibility): the
/// camera's position and every `pixel_stride`-th pixel with depth,
/// back-projected into the world frame, and its labels where it has no depth
/// (`far`). Left out: pixels of tracked people (`person_ids` != 0, may be
/// null) and pixels the map's projection labelled (labels.map_objects).
FrameObservation ObserveFrame(const Frame& frame, const FrameLabels& labels,
                              const LabelMap* person_ids, int pixel_stride);

}  // namespace semrec::fuse
