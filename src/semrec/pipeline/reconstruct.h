// The reconstruction pipeline from labelled RGB-D frames to a USD scene:
// semantics-guided fusion decides which frame segments belong to which object,
// then each object's pixels are integrated into its own TSDF volume and meshed,
// and the scene is written as USD (+ PLY per object).
//
// One pass: a SceneBuilder fuses each frame and integrates its objects'
// volumes as it goes (volumes of objects that fusion merges are combined).
// `scene.stream_volumes = false` builds the volumes in a second pass with the
// final ids instead:
// the reference the streaming result is tested against.
#pragma once

#include <filesystem>
#include <string>

#include "semrec/core/progress.h"
#include "semrec/fuse/segments.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/pipeline/scene_builder.h"

namespace semrec::pipeline {

struct ReconstructOptions {
  /// Fusion, volumes, people in 3-D, stage, gravity; `scene.stream_volumes =
  /// false` integrates the volumes in a second pass over the frames with
  /// fusion's final ids (reads every frame twice; the reference for
  /// streaming).
  SceneBuilderOptions scene;
  /// Tracked people for dynamic.usda: "" (none), "gt" (the sequence's person
  /// layer) or a folder of person id maps (semrec track's persons/).
  std::string people;
  /// Also write objects/<id>_<class>.ply for tools that do not read USD.
  bool write_ply = true;
  /// Also package the scene as scene.usdz (one flattened layer).
  bool usdz = false;
  /// Also write scene.glb (glTF 2.0 binary).
  bool glb = false;
  /// Write into a non-empty output folder.
  bool overwrite = false;
  void Check() const;
};

struct ReconstructResult {
  size_t frames = 0;
  /// Objects, structure, triangles, people, gravity (what was written).
  SceneWriteResult scene;
  double seconds = 0.0;
};

/// Writes `out_dir`/scene.usda, static.usda, dynamic.usda, objects/*.ply and
/// summary.json. Objects of a set's catch-all class ("other", VOC
/// "background") are named "object"; stuff classes become structure prims.
ReconstructResult Reconstruct(const io::SequenceReader& reader,
                              const fuse::SegmentationSource& source,
                              const ReconstructOptions& options,
                              const std::filesystem::path& out_dir,
                              const ProgressOptions& progress = {});

}  // namespace semrec::pipeline
