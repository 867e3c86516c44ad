// The scene as frames stream in: labelled frames go through semantics-guided
// fusion (which segments are which object) and, in the same step, each
// object's pixels into that object's own TSDF volume; tracked people are
// collected as time-sampled 3-D tracks. At any point the scene can be written
// as USD (scene.usda -> static.usda + dynamic.usda) and PLY per object; only
// the objects that changed since the last write are re-meshed.
//
// When fusion merges two objects after both were integrated, their volumes are
// combined voxel by voxel (weights add, TSDF and colour are weight-averaged:
// exactly what integrating the frames into one volume gives, up to rounding).
// `stream_volumes = false` instead records which frame label went into which
// object and integrates the volumes afterwards with the final ids
// (RebuildVolumes): the two-pass reference the streaming result is tested
// against.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "semrec/core/frame.h"
#include "semrec/core/label_map.h"
#include "semrec/fuse/fusion.h"
#include "semrec/fuse/gravity.h"
#include "semrec/fuse/segments.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/mesh/object_mesher.h"
#include "semrec/pipeline/people_3d.h"
#include "semrec/usd/usda_writer.h"

namespace semrec::pipeline {

struct SceneBuilderOptions {
  fuse::FusionOptions fusion;
  fuse::SegmentExtractionOptions extraction;
  mesh::ObjectMeshingOptions meshing;
  People3dOptions people_3d;
  usd::StageOptions stage;
  /// The scene is written upright (Z up, floor at z = 0) by this transform of
  /// the sequence's world frame (see fuse/gravity.h).
  fuse::GravityOptions gravity;
  /// Integrate each object's volume as its frames arrive (true), or only
  /// after Finish() with the final ids (RebuildVolumes; the reference).
  bool stream_volumes = true;
  /// With the voxel merge rule: owned map voxels the volumes gave no surface
  /// (something thin seen once, a 2 cm TSDF's blind spot) get a patch of
  /// their own (CoverOwnedVoxels), when they hold at least
  /// cover_min_points labelled points (2: not a lone stray depth pixel).
  bool cover_owned_voxels = true;
  uint32_t cover_min_points = 2;
  void Check() const;
};

/// What one Add() did.
struct SceneFrameStats {
  /// Static segments fused (0 for a frame without labels).
  size_t segments = 0;
  /// Object volumes merged or dropped because fusion merged or dropped their
  /// objects.
  size_t volumes_merged = 0;
  double fusion_seconds = 0.0;
  double volume_seconds = 0.0;
  /// The same stages' CPU time on the calling thread.
  double fusion_cpu_seconds = 0.0;
  double volume_cpu_seconds = 0.0;
};

/// What Write() wrote.
struct SceneWriteResult {
  size_t objects = 0;
  /// Structure prims (one per stuff class) among `objects`.
  size_t structure = 0;
  size_t skipped_empty_objects = 0;
  /// Map voxels covered by a patch (SceneBuilderOptions::cover_owned_voxels).
  size_t patches = 0;
  size_t triangles = 0;
  size_t people = 0;
  /// Objects re-meshed for this write (the others kept their mesh).
  size_t remeshed = 0;
  fuse::GravityEstimate gravity;
  /// Per object: id, class, kind, sizes, votes, frames, ply (summary.json).
  nlohmann::json objects_json = nlohmann::json::array();
  /// The effective options as one line (also in the USD layer metadata).
  std::string options_text;
  /// T_upright_world as 16 numbers, row-major.
  std::string upright_matrix;
};

struct SceneWriteOptions {
  /// Also write objects/<id>_<class>.ply.
  bool write_ply = true;
  /// Also package the scene as scene.usdz (one flattened layer).
  bool usdz = false;
  /// Also write scene.glb (glTF 2.0 binary, Y-up) for tools without USD.
  bool glb = false;
  /// Provenance for the USD layer metadata (customLayerData), e.g. "input".
  std::map<std::string, std::string> custom_layer_data;
  /// These options with "input" naming `reader`'s sequence.
  static SceneWriteOptions For(const io::SequenceReader& reader, bool write_ply,
                               bool usdz);
};

class SceneBuilder {
 public:
  /// `classes`: the label set the frames' semantic labels refer to.
  SceneBuilder(const LabelSet& classes, const SceneBuilderOptions& options);
  ~SceneBuilder();
  SceneBuilder(const SceneBuilder&) = delete;
  SceneBuilder& operator=(const SceneBuilder&) = delete;

  /// Adds one frame. `labels`: its static segmentation (nullptr: a frame that
  /// was not segmented; it still counts for the camera path). `person_ids`:
  /// tracked people (track id per pixel, 0 = nobody), or nullptr. Person pixels
  /// never go into the static map: the labels are cleared under them.
  SceneFrameStats Add(const Frame& frame, const fuse::FrameLabels* labels,
                      const LabelMap* person_ids = nullptr);

  /// Ends the stream: fusion's end-of-sequence clean-up (evidence, fragments),
  /// volumes follow. Further Add() calls are refused.
  void Finish();

  /// Two-pass reference (stream_volumes = false), after Finish(): integrates
  /// every labelled frame again with the final object ids. `frame(i)` and
  /// `labels(i)` give back what Add() got for the i-th labelled frame.
  void RebuildVolumes(const std::function<Frame(size_t)>& frame,
                      const std::function<fuse::FrameLabels(size_t)>& labels);

  /// The object and structure meshes Write() writes (upright frame, empty
  /// ones left out), without writing; `result` (optional) gets the counts,
  /// gravity, per-object summary (no "ply") and upright matrix. Re-meshes
  /// the objects that changed, as Write() does.
  std::vector<usd::MeshPrim> Meshes(SceneWriteResult* result = nullptr);

  /// Writes `out_dir`/scene.usda, static.usda, dynamic.usda (people) and
  /// objects/*.ply (each atomically). Callable mid-stream for a snapshot.
  /// Objects of a set's catch-all class ("other", VOC "background") are named
  /// "object"; stuff classes become structure prims.
  SceneWriteResult Write(const std::filesystem::path& out_dir,
                         const SceneWriteOptions& write_options);

  const fuse::SceneFusion& fusion() const { return fusion_; }
  const LabelSet& classes() const { return classes_; }
  /// What map guidance projects (ids, classes and clouds only). `decided`
  /// with objects decided per voxel: the decision
  /// (fuse::DecidedMapForProjection), made again when `decide_again` (after a
  /// frame that voted: nothing else changes a class) and kept for the frames
  /// between; else the fusion objects as they are.
  std::vector<fuse::SceneSegment> MapForGuidance(bool decided,
                                                 bool decide_again);
  /// People as time-sampled tracks (world frame, not yet upright).
  std::vector<usd::PersonTrack> PeopleTracks() const {
    return people_.Tracks();
  }
  /// The people prims follow these tracks (e.g. the offline-smoothed ones of
  /// tracks.txt): track id -> the frame indices it has a box in. Tracks not
  /// listed are left out, observations in frames not listed dropped, and
  /// listed frames without an observation (gaps the smoothing filled) get a
  /// position interpolated between the observations around them.
  void set_person_frames(std::map<uint32_t, std::set<size_t>> frames) {
    person_frames_ = std::move(frames);
  }
  size_t frames() const { return cameras_.size(); }
  size_t labelled_frames() const { return labelled_frames_; }
  size_t volumes() const { return mesher_.num_objects(); }

 private:
  LabelSet classes_;
  SceneBuilderOptions options_;
  fuse::SceneFusion fusion_;
  mesh::ObjectMesher mesher_;
  People3d people_;
  std::optional<std::map<uint32_t, std::set<size_t>>> person_frames_;
  std::vector<Transform> cameras_;
  /// MapForGuidance's last decision.
  std::optional<fuse::MapResolution> guidance_resolution_;
  double first_timestamp_s_ = 0.0, last_timestamp_s_ = 0.0;
  size_t labelled_frames_ = 0;
  bool finished_ = false;
  /// Two-pass only: per labelled frame, (frame label, object id at the time).
  std::vector<std::vector<std::pair<uint16_t, uint32_t>>> assignments_;
};

/// `tracks` reduced to `frames` (see SceneBuilder::set_person_frames).
std::vector<usd::PersonTrack> FollowTracks(
    std::vector<usd::PersonTrack> tracks,
    const std::map<uint32_t, std::set<size_t>>& frames);

/// The gravity estimate for summary.json / report.json.
nlohmann::json GravityJson(const fuse::GravityEstimate& gravity,
                           const std::string& upright_matrix);

/// The labels with every pixel of a tracked person (person_ids != 0) set to 0.
fuse::FrameLabels WithoutPeople(const fuse::FrameLabels& labels,
                                const LabelMap& person_ids);

}  // namespace semrec::pipeline
