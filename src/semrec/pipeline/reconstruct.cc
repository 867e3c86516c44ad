#include "semrec/pipeline/reconstruct.h"

#include <optional>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/stopwatch.h"
#include "semrec/fuse/fuse_sequence.h"
#include "semrec/pipeline/scene_builder.h"

namespace fs = std::filesystem;

namespace semrec::pipeline {

void ReconstructOptions::Check() const { scene.Check(); }

ReconstructResult Reconstruct(const io::SequenceReader& reader,
                              const fuse::SegmentationSource& source,
                              const ReconstructOptions& options,
                              const fs::path& out_dir,
                              const ProgressOptions& progress_options) {
  options.Check();
  const Stopwatch run_time;
  RequireEmptyOrOverwrite(out_dir, options.overwrite);
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) {
    throw IoError(out_dir, "cannot create output folder: " + ec.message());
  }

  SceneBuilder builder(source.classes(), options.scene);
  std::optional<PersonMapSource> person_maps;
  if (!options.people.empty()) person_maps.emplace(options.people, reader);
  {
    Progress progress("reconstructing", reader.size(), progress_options);
    for (size_t i = 0; i < reader.size(); ++i) {
      const Frame frame = reader.Read(i);
      const fuse::FrameLabels labels = source.Get(reader, i);
      std::optional<LabelMap> ids;
      if (person_maps) ids = person_maps->Get(i);
      builder.Add(frame, &labels, ids ? &*ids : nullptr);
      progress.Tick();
    }
  }
  builder.Finish();
  const bool two_pass = !options.scene.stream_volumes;
  if (two_pass) {
    Progress progress("meshing (second pass)", reader.size(), progress_options);
    builder.RebuildVolumes(
        [&](size_t i) {
          progress.Tick();
          return reader.Read(i);
        },
        [&](size_t i) {
          fuse::FrameLabels labels = source.Get(reader, i);
          if (person_maps) {
            if (const auto ids = person_maps->Get(i)) {
              labels = WithoutPeople(labels, *ids);
            }
          }
          return labels;
        });
  }

  SceneWriteOptions write =
      SceneWriteOptions::For(reader, options.write_ply, options.usdz);
  write.glb = options.glb;
  if (person_maps) write.custom_layer_data["people"] = options.people;
  ReconstructResult result;
  result.frames = reader.size();
  result.scene = builder.Write(out_dir, write);
  const SceneWriteResult& written = result.scene;
  if (written.skipped_empty_objects > 0) {
    spdlog::warn("{} objects have no surface to mesh; skipped",
                 written.skipped_empty_objects);
  }
  const auto& g = written.gravity;
  spdlog::info("gravity: {} (up {:.3f} {:.3f} {:.3f}, floor at {:.3f} m)",
               g.method, g.up_world.x(), g.up_world.y(), g.up_world.z(),
               g.floor_height_m);

  result.seconds = run_time.Elapsed();
  WriteTextFileAtomic(
      out_dir / "summary.json",
      nlohmann::json(
          {{"input", write.custom_layer_data["input"]},
           {"options", written.options_text},
           {"volumes", two_pass ? "two-pass" : "streaming"},
           {"objects", written.objects_json},
           {"structure", written.structure},
           {"gravity", GravityJson(written.gravity, written.upright_matrix)},
           {"people", written.people},
           {"fusion_events",
            fuse::FusionEventsJson(builder.fusion(), source.classes())},
           {"map_objects",
            fuse::MapResolutionJson(builder.fusion(), source.classes())},
           {"skipped_empty_objects", written.skipped_empty_objects},
           {"surface_patches", written.patches},
           {"seconds", result.seconds}})
              .dump(2) +
          "\n");
  return result;
}

}  // namespace semrec::pipeline
