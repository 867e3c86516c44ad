#include "semrec/pipeline/reconstruct.h"

#include <chrono>
#include <cmath>
#include <map>
#include <optional>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/fuse/fuse_sequence.h"
#include "semrec/io/ply_io.h"

namespace fs = std::filesystem;

namespace semrec::pipeline {

void ReconstructOptions::Check() const {
  people_3d.Check();
  fusion.Check();
  extraction.Check();
  meshing.Check();
  stage.Check();
  gravity.Check();
}

ReconstructResult Reconstruct(const io::SequenceReader& reader,
                              const fuse::SegmentationSource& source,
                              const ReconstructOptions& options,
                              const fs::path& out_dir,
                              const ProgressOptions& progress_options) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  RequireEmptyOrOverwrite(out_dir, options.overwrite);
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) {
    throw IoError(out_dir, "cannot create output folder: " + ec.message());
  }

  // Pass 1: fusion; remember which frame label went into which segment.
  fuse::SceneFusion fusion(options.fusion);
  std::optional<PersonMapSource> person_maps;
  if (!options.people.empty()) person_maps.emplace(options.people, reader);
  People3d people(options.people_3d);
  std::vector<std::vector<std::pair<uint16_t, uint32_t>>> assignments(
      reader.size());
  {
    Progress progress("fusing", reader.size(), progress_options);
    for (size_t i = 0; i < reader.size(); ++i) {
      const Frame frame = reader.Read(i);
      const auto segments = fuse::ExtractFrameSegments(
          frame, source.Get(reader, i), source.classes(), options.extraction);
      if (person_maps) {
        if (const auto ids = person_maps->Get(i)) people.Add(frame, *ids);
      }
      const fuse::FrameFusionStats stats = fusion.Integrate(segments, i);
      for (size_t k = 0; k < segments.size(); ++k) {
        assignments[i].emplace_back(segments[k].source_label,
                                    stats.assigned_ids[k]);
      }
      progress.Tick();
    }
  }
  if (const size_t cleaned = fusion.Finish(); cleaned > 0) {
    spdlog::info(
        "end of sequence: {} objects merged or dropped (evidence, "
        "fragments; see summary.json events)",
        cleaned);
  }
  // Pass 2: per-object volumes with the final ids.
  mesh::ObjectMesher mesher(options.meshing);
  {
    Progress progress("meshing", reader.size(), progress_options);
    for (size_t i = 0; i < reader.size(); ++i) {
      for (auto& [label, id] : assignments[i]) id = fusion.ResolveId(id);
      std::erase_if(assignments[i],
                    [](const auto& a) { return a.second == 0; });  // dropped
      if (!assignments[i].empty()) {
        mesher.Integrate(reader.Read(i), source.Get(reader, i).instance,
                         assignments[i]);
      }
      progress.Tick();
    }
  }
  const auto meshes = mesher.UpdateMeshes();

  // Upright: the scene's points and the cameras decide which way is up.
  ReconstructResult result;
  {
    std::vector<const fuse::Cloud*> clouds;
    std::vector<bool> is_floor;
    for (const fuse::SceneSegment& s : fusion.segments()) {
      clouds.push_back(&s.points);
      is_floor.push_back(source.classes().Get(s.class_id).name == "floor");
    }
    std::vector<Transform> cameras;
    for (size_t i = 0; i < reader.size(); ++i) {
      cameras.push_back(reader.T_world_camera(i));
    }
    result.gravity =
        fuse::EstimateGravity(clouds, is_floor, cameras, options.gravity);
    const auto& g = result.gravity;
    spdlog::info("gravity: {} (up {:.3f} {:.3f} {:.3f}, floor at {:.3f} m)",
                 g.method, g.up_world.x(), g.up_world.y(), g.up_world.z(),
                 g.floor_height_m);
  }
  // An upright scene declared Y-up gets its axes turned: (x, y, z) -> (x, z,
  // -y). With gravity "none" the stage only declares the user's own axis.
  if (options.stage.up_axis == "Y" &&
      options.gravity.mode != fuse::GravityOptions::Mode::kNone) {
    Eigen::Matrix3d z_to_y;
    z_to_y << 1, 0, 0, 0, 0, 1, 0, -1, 0;
    result.gravity.T_upright_world =
        Transform(z_to_y, Eigen::Vector3d::Zero()) *
        result.gravity.T_upright_world;
  }
  const Transform& T_up = result.gravity.T_upright_world;
  const Eigen::Matrix3f R_up = T_up.rotation().cast<float>();
  const Eigen::Vector3f t_up = T_up.translation().cast<float>();

  result.frames = reader.size();
  std::vector<usd::MeshPrim> prims;
  nlohmann::json objects = nlohmann::json::array();
  for (const fuse::SceneSegment& s : fusion.segments()) {
    const auto it = meshes.find(s.id);
    if (it == meshes.end() || it->second->triangles_.empty()) {
      ++result.skipped_empty_objects;
      spdlog::warn("object {} ({}) has no surface to mesh; skipped", s.id,
                   source.classes().Get(s.class_id).name);
      continue;
    }
    const open3d::geometry::TriangleMesh& m = *it->second;
    const LabelClass& cls = source.classes().Get(s.class_id);
    // The set's catch-all ("other") names no class: the segment is still a
    // thing, a generic object.
    const std::string name =
        cls.kind == ClassKind::kOther ? kGenericObjectName : cls.name;
    usd::MeshPrim prim;
    prim.label = name;
    prim.structure =
        cls.kind == ClassKind::kStuff && options.fusion.stuff_per_class;
    prim.instance_id = s.id;
    prim.color = cls.color;
    prim.point_count = s.points.size();
    prim.first_seen_frame = s.first_seen_frame;
    prim.last_seen_frame = s.last_seen_frame;
    prim.confidence = fuse::ClassConfidence(s);
    prim.class_votes = fuse::ClassVotesText(s, source.classes());
    for (size_t v = 0; v < m.vertices_.size(); ++v) {
      prim.points.push_back(R_up * m.vertices_[v].cast<float>() + t_up);
      if (m.HasVertexNormals()) {
        prim.normals.push_back(R_up * m.vertex_normals_[v].cast<float>());
      }
      if (m.HasVertexColors()) {
        const Eigen::Vector3d c =
            (m.vertex_colors_[v] * 255.0).cwiseMax(0.0).cwiseMin(255.0);
        prim.vertex_colors.push_back(
            {static_cast<uint8_t>(std::lround(c.x())),
             static_cast<uint8_t>(std::lround(c.y())),
             static_cast<uint8_t>(std::lround(c.z()))});
      }
    }
    for (const auto& t : m.triangles_) {
      prim.triangles.push_back({static_cast<uint32_t>(t.x()),
                                static_cast<uint32_t>(t.y()),
                                static_cast<uint32_t>(t.z())});
    }
    result.triangles += prim.triangles.size();
    const std::string ply =
        fmt::format("objects/{:04}_{}.ply", s.id, usd::SanitizeName(name));
    if (options.write_ply) {
      io::PlyData data;
      data.points = prim.points;
      data.colors = prim.vertex_colors;
      data.triangles = prim.triangles;
      io::WritePly(out_dir / ply, data);
    }
    result.structure += prim.structure ? 1 : 0;
    objects.push_back(
        {{"id", s.id},
         {"class", name},
         {"kind", prim.structure ? "structure" : "object"},
         {"vertices", prim.points.size()},
         {"triangles", prim.triangles.size()},
         {"fused_points", s.points.size()},
         {"observations", s.observations},
         {"frames_seen", s.frames_seen.size()},
         {"class_votes", fuse::ClassVotesJson(s, source.classes())},
         {"first_seen_frame", s.first_seen_frame},
         {"last_seen_frame", s.last_seen_frame},
         {"ply", options.write_ply ? ply : ""}});
    prims.push_back(std::move(prim));
  }
  result.objects = prims.size();
  usd::StageOptions stage = options.stage;
  stage.custom_layer_data["input"] =
      fmt::format("{} ({} layout, {} frames)", reader.root().string(),
                  reader.layout(), reader.size());
  const auto& f = options.fusion;
  const auto& t = options.meshing.tsdf;
  stage.custom_layer_data["options"] = fmt::format(
      "fusion: alpha {} corr_voxel_size_m {} store_voxel_size_m {} "
      "max_corr_dist_m {} "
      "label_gating {} merge {}; tsdf: voxel_size_m {} sdf_trunc_m {} "
      "max_depth_m {}",
      f.alpha, f.corr_voxel_size_m, f.store_voxel_size_m, f.max_corr_dist_m,
      f.label_gating, fuse::MergeName(f.merge), t.voxel_size_m, t.sdf_trunc_m,
      t.max_depth_m);
  const auto& gm = T_up.Matrix();
  std::string matrix;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      matrix += fmt::format("{}{:.6g}", r + c ? " " : "", gm(r, c));
    }
  }
  stage.custom_layer_data["T_upright_world"] = matrix;
  stage.custom_layer_data["gravity"] = result.gravity.method;
  std::vector<usd::PersonTrack> tracks = people.Tracks();
  for (usd::PersonTrack& track : tracks) {
    for (usd::PersonSample& sample : track.samples) {
      sample.centroid_world = R_up * sample.centroid_world + t_up;
      for (auto& p : sample.points_world) p = R_up * p + t_up;
    }
  }
  result.people = tracks.size();
  if (person_maps) {
    // Time codes are frame indices, played at the sequence's frame rate.
    const auto& frames = reader.index().frames;
    const double span = frames.back().timestamp_s - frames.front().timestamp_s;
    stage.time_codes_per_second =
        frames.size() > 1 && span > 0
            ? static_cast<double>(frames.size() - 1) / span
            : 30.0;
    stage.start_time_code = 0;
    stage.end_time_code = static_cast<double>(frames.size() - 1);
    stage.custom_layer_data["people"] = options.people;
  }
  usd::WriteScene(out_dir, prims, stage, tracks);
  if (options.usdz) {
    usd::WriteSceneUsdz(out_dir / "scene.usdz", prims, stage, tracks);
  }
  result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  WriteTextFileAtomic(
      out_dir / "summary.json",
      nlohmann::json(
          {{"input", stage.custom_layer_data["input"]},
           {"options", stage.custom_layer_data["options"]},
           {"objects", objects},
           {"structure", result.structure},
           {"gravity",
            {{"method", result.gravity.method},
             {"up_world",
              {result.gravity.up_world.x(), result.gravity.up_world.y(),
               result.gravity.up_world.z()}},
             {"floor_height_m", result.gravity.floor_height_m},
             {"floor_points", result.gravity.floor_points},
             {"T_upright_world", matrix}}},
           {"people", result.people},
           {"fusion_events", fuse::FusionEventsJson(fusion, source.classes())},
           {"skipped_empty_objects", result.skipped_empty_objects},
           {"seconds", result.seconds}})
              .dump(2) +
          "\n");
  return result;
}

}  // namespace semrec::pipeline
