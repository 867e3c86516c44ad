// Segmenting a list of images to label files (the `semrec segment` command):
// the hybrid segmenter on each image, its label PNGs, overlay and mask JSON
// written per image, classes.json and summary.json at the end.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "semrec/core/progress.h"
#include "semrec/infer/model_registry.h"
#include "semrec/segment/hybrid_segmenter.h"
#include "semrec/segment/segment_io.h"

namespace semrec::segment {

struct SegmentImagesResult {
  size_t images = 0;
  size_t masks = 0;
  double seconds_per_image = 0.0;
};

/// Segments `inputs` into `out_dir` (a label folder `semrec fuse|mesh|run
/// --labels DIR` reads): semantic/, instance/, overlay/, masks/,
/// classes.json, summary.json. `description` names the input in the summary.
/// Throws FormatError naming the image for one the models cannot take.
SegmentImagesResult SegmentImages(const infer::ModelRegistry& registry,
                                  const HybridSegmenterOptions& options,
                                  const std::vector<SegmentInput>& inputs,
                                  const std::filesystem::path& out_dir,
                                  const std::string& description,
                                  const ProgressOptions& progress = {});

}  // namespace semrec::segment
