// Our own USDA (USD text) writer for reconstructed scenes, following the USD
// file format: a `#usda 1.0` header with defaultPrim / metersPerUnit / upAxis,
// `/World` (Xform) holding `Objects/<class>_<id>` Mesh prims. Every mesh
// carries its class the ways robotics simulators read it: the UsdSemantics
// labels API (`semantics:labels:class`, token array) and Isaac Sim's legacy
// `Semantics` schema (`semantic:Semantics:params:semanticType/semanticData`),
// plus `semrec:*` custom attributes (instance id, original label, point count,
// frames, confidence).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace semrec::usd {

struct MeshPrim {
  /// Class label as the segmentation named it (any characters; sanitised for
  /// the prim name).
  std::string label;
  uint32_t instance_id = 0;
  /// Structure (one prim per stuff class under /World/Structure, named by the
  /// class) rather than an object under /World/Objects.
  bool structure = false;
  std::vector<Eigen::Vector3f> points;
  std::vector<std::array<uint32_t, 3>> triangles;
  /// Optional per-vertex normals and colours (0-255); without colours, `color`
  /// is constant.
  std::vector<Eigen::Vector3f> normals;
  std::vector<std::array<uint8_t, 3>> vertex_colors;
  std::array<uint8_t, 3> color = {200, 200, 200};
  /// Provenance, written as custom attributes.
  size_t point_count = 0;
  size_t first_seen_frame = 0;
  size_t last_seen_frame = 0;
  /// Share of the winning class among the class votes, and the votes as text
  /// ("chair 0.72, table 0.28"; empty: not written).
  double confidence = 1.0;
  std::string class_votes;
};

struct StageOptions {
  /// "Z" (robotics) or "Y".
  std::string up_axis = "Z";
  double meters_per_unit = 1.0;
  /// Free-form provenance stored in the layer's customLayerData (options,
  /// inputs).
  std::map<std::string, std::string> custom_layer_data;
  /// Time codes are frame indices; > 0 writes startTimeCode, endTimeCode and
  /// timeCodesPerSecond (the sequence's frame rate) so viewers play people's
  /// motion at the recorded speed. 0: a static stage.
  double time_codes_per_second = 0.0;
  double start_time_code = 0.0;
  double end_time_code = 0.0;
  void Check() const;
};

/// One observation of a tracked person: where their points were in one frame.
struct PersonSample {
  size_t frame = 0;
  /// Centroid of the person's points (world frame): the prim's translation.
  Eigen::Vector3f centroid_world = Eigen::Vector3f::Zero();
  /// The person's points in the world frame (downsampled); may be empty when
  /// only the position is known.
  std::vector<Eigen::Vector3f> points_world;
};

/// A tracked person over time (one prim in dynamic.usda).
struct PersonTrack {
  uint32_t track_id = 0;
  std::string label = "person";
  std::array<uint8_t, 3> color = {220, 40, 40};
  /// Observations in increasing frame order; frames without one are "out of
  /// view" (the prim is invisible there).
  std::vector<PersonSample> samples;
};

/// A valid USD prim name for `label`: [A-Za-z_][A-Za-z0-9_]*, other characters
/// become '_', a leading digit gets a '_' prefix. Deterministic; the original
/// stays in `semrec:label`.
std::string SanitizeName(const std::string& label);

/// Text of a USDA layer with /World/Objects/<sanitised label>_<id> meshes and,
/// when there is structure, /World/Structure/<sanitised label> meshes.
std::string StaticLayerText(const std::vector<MeshPrim>& meshes,
                            const StageOptions& options);

/// Text of a USDA layer with /World/People/<label>_<track id> Xforms: a
/// time-sampled translation (the centroid), visibility ("invisible" at frames
/// without an observation) and a child Points prim "Cloud" with time-sampled
/// points relative to the centroid and extent. Needs
/// options.time_codes_per_second > 0 when there are people.
std::string DynamicLayerText(const std::vector<PersonTrack>& people,
                             const StageOptions& options);

/// One self-contained layer with both scopes (objects and people): what the
/// USDZ package holds, for viewers that do not compose sublayers.
std::string FlatLayerText(const std::vector<MeshPrim>& meshes,
                          const std::vector<PersonTrack>& people,
                          const StageOptions& options);

/// Text of a root layer that sublayers the given files (relative paths).
std::string RootLayerText(const std::vector<std::string>& sublayers,
                          const StageOptions& options);

/// Writes `dir`/scene.usda (root, sublayering dynamic.usda and static.usda),
/// `dir`/static.usda (objects) and `dir`/dynamic.usda (people; an empty
/// People scope when there are none), each atomically. Throws IoError for an
/// unwritable folder.
void WriteScene(const std::filesystem::path& dir,
                const std::vector<MeshPrim>& meshes,
                const StageOptions& options,
                const std::vector<PersonTrack>& people = {});

/// Writes FlatLayerText as `path` (a .usdz package holding scene.usda),
/// atomically.
void WriteSceneUsdz(const std::filesystem::path& path,
                    const std::vector<MeshPrim>& meshes,
                    const StageOptions& options,
                    const std::vector<PersonTrack>& people = {});

}  // namespace semrec::usd
