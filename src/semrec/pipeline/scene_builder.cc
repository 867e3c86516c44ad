#include "semrec/pipeline/scene_builder.h"

#include <cmath>
#include <optional>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "semrec/core/error.h"
#include "semrec/core/stopwatch.h"
#include "semrec/fuse/fuse_sequence.h"
#include "semrec/fuse/map_projection.h"
#include "semrec/io/ply_io.h"
#include "semrec/pipeline/object_surfaces.h"
#include "semrec/usd/glb_writer.h"

namespace fs = std::filesystem;

namespace semrec::pipeline {
namespace {

std::vector<std::pair<uint16_t, uint32_t>> Assignments(
    const std::vector<fuse::FrameSegment>& segments,
    const fuse::FrameFusionStats& stats) {
  std::vector<std::pair<uint16_t, uint32_t>> out;
  for (size_t k = 0; k < segments.size(); ++k) {
    out.emplace_back(segments[k].source_label, stats.assigned_ids[k]);
  }
  return out;
}

usd::MeshPrim ToPrim(const open3d::geometry::TriangleMesh& m,
                     const Eigen::Matrix3f& R_up, const Eigen::Vector3f& t_up) {
  usd::MeshPrim prim;
  for (size_t v = 0; v < m.vertices_.size(); ++v) {
    prim.points.push_back(R_up * m.vertices_[v].cast<float>() + t_up);
    if (m.HasVertexNormals()) {
      prim.normals.push_back(R_up * m.vertex_normals_[v].cast<float>());
    }
    if (m.HasVertexColors()) {
      const Eigen::Vector3d c =
          (m.vertex_colors_[v] * 255.0).cwiseMax(0.0).cwiseMin(255.0);
      prim.vertex_colors.push_back({static_cast<uint8_t>(std::lround(c.x())),
                                    static_cast<uint8_t>(std::lround(c.y())),
                                    static_cast<uint8_t>(std::lround(c.z()))});
    }
  }
  for (const auto& t : m.triangles_) {
    prim.triangles.push_back({static_cast<uint32_t>(t.x()),
                              static_cast<uint32_t>(t.y()),
                              static_cast<uint32_t>(t.z())});
  }
  return prim;
}

// Mask erosion "auto": none where the meshes are cut by the voxel owners.
mesh::ObjectMeshingOptions ResolvedMeshing(const SceneBuilderOptions& o) {
  mesh::ObjectMeshingOptions meshing = o.meshing;
  if (meshing.mask_erosion_px < 0) {
    meshing.mask_erosion_px =
        o.fusion.merge == fuse::FusionOptions::Merge::kVoxel ? 0 : 1;
  }
  return meshing;
}

}  // namespace

SceneWriteOptions SceneWriteOptions::For(const io::SequenceReader& reader,
                                         bool write_ply, bool usdz) {
  SceneWriteOptions o;
  o.write_ply = write_ply;
  o.usdz = usdz;
  o.custom_layer_data["input"] =
      fmt::format("{} ({} layout, {} frames)", reader.root().string(),
                  reader.layout(), reader.size());
  return o;
}

void SceneBuilderOptions::Check() const {
  fusion.Check();
  extraction.Check();
  meshing.Check();
  people_3d.Check();
  stage.Check();
  gravity.Check();
}

nlohmann::json GravityJson(const fuse::GravityEstimate& gravity,
                           const std::string& upright_matrix) {
  return {{"method", gravity.method},
          {"up_world",
           {gravity.up_world.x(), gravity.up_world.y(), gravity.up_world.z()}},
          {"floor_height_m", gravity.floor_height_m},
          {"floor_points", gravity.floor_points},
          {"T_upright_world", upright_matrix}};
}

std::vector<usd::PersonTrack> FollowTracks(
    std::vector<usd::PersonTrack> tracks,
    const std::map<uint32_t, std::set<size_t>>& frames) {
  std::vector<usd::PersonTrack> out;
  for (usd::PersonTrack& track : tracks) {
    const auto listed = frames.find(track.track_id);
    if (listed == frames.end()) continue;
    const std::vector<usd::PersonSample> observed = std::move(track.samples);
    track.samples.clear();
    size_t next = 0;  // first observation at or after the frame
    for (const size_t frame : listed->second) {
      while (next < observed.size() && observed[next].frame < frame) ++next;
      if (next < observed.size() && observed[next].frame == frame) {
        track.samples.push_back(observed[next]);
      } else if (next > 0 && next < observed.size()) {
        const usd::PersonSample& a = observed[next - 1];
        const usd::PersonSample& b = observed[next];
        const float t = static_cast<float>(frame - a.frame) /
                        static_cast<float>(b.frame - a.frame);
        usd::PersonSample filled;
        filled.frame = frame;
        filled.centroid_world =
            (1.0f - t) * a.centroid_world + t * b.centroid_world;
        track.samples.push_back(std::move(filled));
      }
    }
    if (!track.samples.empty()) out.push_back(std::move(track));
  }
  return out;
}

fuse::FrameLabels WithoutPeople(const fuse::FrameLabels& labels,
                                const LabelMap& person_ids) {
  CheckArgument(labels.instance.SameSize(person_ids),
                "person map and labels differ in size (" + labels.source + ")");
  fuse::FrameLabels out = labels;
  const uint16_t* person = person_ids.data();
  uint16_t* instance = out.instance.data();
  for (size_t p = 0; p < person_ids.NumPixels(); ++p) {
    if (person[p] != 0) instance[p] = 0;
  }
  return out;
}

SceneBuilder::SceneBuilder(const LabelSet& classes,
                           const SceneBuilderOptions& options)
    : classes_(classes),
      options_((options.Check(), options)),
      fusion_(options.fusion),
      mesher_(ResolvedMeshing(options)),
      people_(options.people_3d) {}

SceneBuilder::~SceneBuilder() = default;

SceneFrameStats SceneBuilder::Add(const Frame& frame,
                                  const fuse::FrameLabels* labels,
                                  const LabelMap* person_ids) {
  CheckArgument(!finished_, "SceneBuilder: Add() after Finish()");
  if (cameras_.empty()) first_timestamp_s_ = frame.timestamp_s;
  last_timestamp_s_ = frame.timestamp_s;
  cameras_.push_back(frame.T_world_camera);
  if (person_ids != nullptr) people_.Add(frame, *person_ids);
  SceneFrameStats stats;
  if (labels == nullptr) return stats;
  ++labelled_frames_;
  // A copy only where people must be cleared from the labels.
  std::optional<fuse::FrameLabels> cleared;
  if (person_ids != nullptr) cleared = WithoutPeople(*labels, *person_ids);
  const fuse::FrameLabels& static_labels = cleared ? *cleared : *labels;
  StageWatch watch;
  const auto segments = fuse::ExtractFrameSegments(
      frame, static_labels, classes_, options_.extraction);
  // Voxel evidence: what the frame saw, labelled or not (visibility).
  std::optional<fuse::FrameObservation> observation;
  if (fusion_.voxel_evidence() != nullptr) {
    observation = fuse::ObserveFrame(frame, static_labels, person_ids,
                                     options_.extraction.pixel_stride);
  }
  const fuse::FrameFusionStats fused = fusion_.Integrate(
      segments, frame.index, observation ? &*observation : nullptr);
  stats.segments = segments.size();
  const StageWatch::Lap fusion = watch.Next();
  stats.fusion_seconds = fusion.wall;
  stats.fusion_cpu_seconds = fusion.cpu;
  auto pairs = Assignments(segments, fused);
  if (options_.stream_volumes) {
    if (!pairs.empty()) {
      mesher_.Integrate(frame, static_labels.instance, pairs);
    }
    stats.volumes_merged =
        mesher_.Reconcile([&](uint32_t id) { return fusion_.ResolveId(id); });
  } else {
    assignments_.push_back(std::move(pairs));
  }
  const StageWatch::Lap volumes = watch.Next();
  stats.volume_seconds = volumes.wall;
  stats.volume_cpu_seconds = volumes.cpu;
  return stats;
}

void SceneBuilder::Finish() {
  if (finished_) return;
  finished_ = true;
  if (const size_t cleaned = fusion_.Finish(); cleaned > 0) {
    spdlog::debug(
        "end of sequence: {} objects merged or dropped (evidence, "
        "fragments; report.json: fusion_events)",
        cleaned);
  }
  mesher_.Reconcile([&](uint32_t id) { return fusion_.ResolveId(id); });
  if (fusion_.voxel_evidence() != nullptr) {
    const fuse::GravityEstimate gravity = fuse::EstimateSceneGravity(
        fusion_, classes_, cameras_, options_.gravity);
    const fuse::MapResolution& r =
        fusion_.ResolveMap(fuse::MakeMapContext(classes_, gravity.up_world));
    spdlog::info(
        "the map's objects: {} (walls, floor and ceiling on {} planes); {} "
        "fragments folded into objects, {} dropped",
        r.objects.size(), r.planes.size(), r.fragments_folded,
        r.fragments_dropped);
    spdlog::debug(
        "objects decided per map voxel: {} objects, {} structure planes, {} "
        "voxels moved off structure, {} split, {} merged by masks, {} new, "
        "fragments {} folded / {} dropped, {} stranded structure voxels "
        "joined things, {} wall voxels closed in by things joined them, {} "
        "things on furniture fronts took the front's class, {} furniture "
        "fronts no view "
        "named became objects, {} far specks left their objects",
        r.objects.size(), r.planes.size(), r.gated_voxels, r.split_objects,
        r.merged_objects, r.new_objects, r.fragments_folded,
        r.fragments_dropped, r.stranded_voxels_claimed,
        r.enclosed_voxels_claimed, r.reclassed_on_fronts, r.objects_from_fronts,
        r.far_specks_moved);
  }
}

std::vector<fuse::SceneSegment> SceneBuilder::MapForGuidance(
    bool decided, bool decide_again) {
  const fuse::VoxelEvidenceMap* evidence =
      decided ? fusion_.voxel_evidence() : nullptr;
  if (decide_again && evidence != nullptr && evidence->labelled_voxels() > 0) {
    Stopwatch watch;
    const fuse::GravityEstimate gravity = fuse::EstimateSceneGravity(
        fusion_, classes_, cameras_, options_.gravity);
    const double gravity_s = watch.Elapsed();
    guidance_resolution_ = fusion_.PreviewResolution(
        fuse::MakeMapContext(classes_, gravity.up_world));
    spdlog::debug(
        "map guidance: objects decided again ({} voxels, {} objects) in "
        "{:.3f} s (gravity {:.3f} s)",
        evidence->labelled_voxels(), guidance_resolution_->objects.size(),
        watch.Elapsed(), gravity_s);
  }
  if (guidance_resolution_ && evidence != nullptr) {
    return fuse::DecidedMapForProjection(fusion_.segments(),
                                         *guidance_resolution_, *evidence);
  }
  std::vector<fuse::SceneSegment> map;
  for (const fuse::SceneSegment& s : fusion_.segments()) {
    fuse::SceneSegment copy;
    copy.id = s.id;
    copy.class_id = s.class_id;
    copy.kind = s.kind;
    copy.points = s.points;
    map.push_back(std::move(copy));
  }
  return map;
}

void SceneBuilder::RebuildVolumes(
    const std::function<Frame(size_t)>& frame,
    const std::function<fuse::FrameLabels(size_t)>& labels) {
  CheckArgument(finished_ && !options_.stream_volumes,
                "SceneBuilder::RebuildVolumes: only after Finish() with "
                "stream_volumes off");
  for (size_t i = 0; i < assignments_.size(); ++i) {
    auto& pairs = assignments_[i];
    for (auto& [label, id] : pairs) id = fusion_.ResolveId(id);
    std::erase_if(pairs, [](const auto& a) { return a.second == 0; });
    if (pairs.empty()) continue;
    mesher_.Integrate(frame(i), labels(i).instance, pairs);
  }
  assignments_.clear();
}

std::vector<usd::MeshPrim> SceneBuilder::Meshes(SceneWriteResult* out) {
  SceneWriteResult local;
  SceneWriteResult& result = out != nullptr ? *out : local;
  MeshMap meshes = mesher_.UpdateMeshes();
  result.remeshed = mesher_.remeshed_last_update();
  // Upright: the scene's points and the cameras decide which way is up.
  result.gravity =
      fuse::EstimateSceneGravity(fusion_, classes_, cameras_, options_.gravity);
  // Objects decided per voxel: each takes the surface of its own voxels.
  // While frames still come (a snapshot), what the evidence decides so far.
  std::optional<fuse::SceneFusion::MapPreview> preview;
  if (!finished_ && fusion_.voxel_evidence() != nullptr &&
      fusion_.voxel_evidence()->labelled_voxels() > 0) {
    preview = fusion_.PreviewMap(
        fuse::MakeMapContext(classes_, result.gravity.up_world));
  }
  const fuse::MapResolution* resolution =
      preview ? &preview->resolution : fusion_.map_resolution();
  if (resolution != nullptr) {
    meshes = CutMeshesByOwner(meshes, *resolution,
                              options_.fusion.store_voxel_size_m);
    if (options_.cover_owned_voxels) {
      const fuse::VoxelEvidenceMap& evidence = *fusion_.voxel_evidence();
      result.patches = CoverOwnedVoxels(*resolution, evidence.voxels(),
                                        evidence.voxel_size_m(),
                                        options_.cover_min_points, &meshes);
      if (result.patches > 0 && !preview) {
        spdlog::info(
            "{} map voxels of things no volume meshed (thin, or seen once) "
            "got a surface patch",
            result.patches);
      }
    }
  }
  const std::vector<fuse::SceneSegment>& segments =
      preview ? preview->segments : fusion_.segments();
  // An upright scene declared Y-up gets its axes turned: (x, y, z) -> (x, z,
  // -y). With gravity "none" the stage only declares the user's own axis.
  if (options_.stage.up_axis == "Y" &&
      options_.gravity.mode != fuse::GravityOptions::Mode::kNone) {
    Eigen::Matrix3d z_to_y;
    z_to_y << 1, 0, 0, 0, 0, 1, 0, -1, 0;
    result.gravity.T_upright_world =
        Transform(z_to_y, Eigen::Vector3d::Zero()) *
        result.gravity.T_upright_world;
  }
  const Transform& T_up = result.gravity.T_upright_world;
  const Eigen::Matrix3f R_up = T_up.rotation().cast<float>();
  const Eigen::Vector3f t_up = T_up.translation().cast<float>();

  std::vector<usd::MeshPrim> prims;
  for (const fuse::SceneSegment& s : segments) {
    const auto it = meshes.find(s.id);
    const LabelClass& cls = classes_.Get(s.class_id);
    if (it == meshes.end() || it->second->triangles_.empty()) {
      ++result.skipped_empty_objects;
      spdlog::debug("object {} ({}) has no surface to mesh; skipped", s.id,
                    cls.name);
      continue;
    }
    // The set's catch-all ("other") names no class: the segment is still a
    // thing, a generic object.
    const std::string name =
        cls.kind == ClassKind::kOther ? kGenericObjectName : cls.name;
    usd::MeshPrim prim = ToPrim(*it->second, R_up, t_up);
    prim.label = name;
    prim.structure =
        cls.kind == ClassKind::kStuff && options_.fusion.stuff_per_class;
    prim.instance_id = s.id;
    prim.color = cls.color;
    prim.point_count = s.points.size();
    prim.first_seen_frame = s.first_seen_frame;
    prim.last_seen_frame = s.last_seen_frame;
    prim.confidence = fuse::ClassConfidence(s);
    prim.class_votes = fuse::ClassVotesText(s, classes_);
    result.triangles += prim.triangles.size();
    result.structure += prim.structure ? 1 : 0;
    result.objects_json.push_back(
        {{"id", s.id},
         {"class", name},
         {"kind", prim.structure ? "structure" : "object"},
         {"vertices", prim.points.size()},
         {"triangles", prim.triangles.size()},
         {"fused_points", s.points.size()},
         {"observations", s.observations},
         {"frames_seen", s.frames_seen.size()},
         {"class_votes", fuse::ClassVotesJson(s, classes_)},
         {"first_seen_frame", s.first_seen_frame},
         {"last_seen_frame", s.last_seen_frame},
         {"ply", ""}});
    prims.push_back(std::move(prim));
  }
  result.objects = prims.size();
  const auto& gm = result.gravity.T_upright_world.Matrix();
  result.upright_matrix.clear();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      result.upright_matrix +=
          fmt::format("{}{:.6g}", r + c ? " " : "", gm(r, c));
    }
  }
  return prims;
}

SceneWriteResult SceneBuilder::Write(const fs::path& out_dir,
                                     const SceneWriteOptions& write_options) {
  SceneWriteResult result;
  const std::vector<usd::MeshPrim> prims = Meshes(&result);
  for (size_t k = 0; write_options.write_ply && k < prims.size(); ++k) {
    const usd::MeshPrim& prim = prims[k];
    const std::string ply =
        fmt::format("objects/{:04}_{}.ply", prim.instance_id,
                    usd::SanitizeName(prim.label));
    io::PlyData data;
    data.points = prim.points;
    data.colors = prim.vertex_colors;
    data.triangles = prim.triangles;
    io::WritePly(out_dir / ply, data);
    result.objects_json[k]["ply"] = ply;
  }
  const Transform& T_up = result.gravity.T_upright_world;
  const Eigen::Matrix3f R_up = T_up.rotation().cast<float>();
  const Eigen::Vector3f t_up = T_up.translation().cast<float>();

  usd::StageOptions stage = options_.stage;
  for (const auto& [key, value] : write_options.custom_layer_data) {
    stage.custom_layer_data[key] = value;
  }
  const auto& f = options_.fusion;
  const auto& t = options_.meshing.tsdf;
  result.options_text = fmt::format(
      "fusion: alpha {} corr_voxel_size_m {} store_voxel_size_m {} "
      "max_corr_dist_m {} "
      "label_gating {} merge {}; tsdf: voxel_size_m {} sdf_trunc_m {} "
      "max_depth_m {}",
      f.alpha, f.corr_voxel_size_m, f.store_voxel_size_m, f.max_corr_dist_m,
      f.label_gating, fuse::MergeName(f.merge), t.voxel_size_m, t.sdf_trunc_m,
      t.max_depth_m);
  if (!stage.custom_layer_data.contains("options")) {
    stage.custom_layer_data["options"] = result.options_text;
  }
  stage.custom_layer_data["T_upright_world"] = result.upright_matrix;
  stage.custom_layer_data["gravity"] = result.gravity.method;

  std::vector<usd::PersonTrack> tracks = people_.Tracks();
  if (person_frames_) tracks = FollowTracks(std::move(tracks), *person_frames_);
  for (usd::PersonTrack& track : tracks) {
    for (usd::PersonSample& sample : track.samples) {
      sample.centroid_world = R_up * sample.centroid_world + t_up;
      for (auto& p : sample.points_world) p = R_up * p + t_up;
    }
  }
  result.people = tracks.size();
  if (!tracks.empty()) {
    // Time codes are frame indices, played at the sequence's frame rate.
    const double span = last_timestamp_s_ - first_timestamp_s_;
    stage.time_codes_per_second =
        cameras_.size() > 1 && span > 0
            ? static_cast<double>(cameras_.size() - 1) / span
            : 30.0;
    stage.start_time_code = 0;
    stage.end_time_code = static_cast<double>(cameras_.size() - 1);
  }
  usd::WriteScene(out_dir, prims, stage, tracks);
  if (write_options.usdz) {
    usd::WriteSceneUsdz(out_dir / "scene.usdz", prims, stage, tracks);
  }
  if (write_options.glb) {
    usd::WriteSceneGlb(out_dir / "scene.glb", prims, stage, tracks);
  }
  return result;
}

}  // namespace semrec::pipeline
