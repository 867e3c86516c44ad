#include "semrec/segment/segment_images.h"

#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/stopwatch.h"
#include "semrec/io/image_io.h"
#include "semrec/io/label_set_io.h"

namespace fs = std::filesystem;

namespace semrec::segment {

SegmentImagesResult SegmentImages(const infer::ModelRegistry& registry,
                                  const HybridSegmenterOptions& options,
                                  const std::vector<SegmentInput>& inputs,
                                  const fs::path& out_dir,
                                  const std::string& description,
                                  const ProgressOptions& progress_options) {
  options.Check();
  HybridSegmenter segmenter(registry, options);
  // classes.json first: with semantic/ and instance/ it makes the output a
  // label folder for `semrec fuse --labels`.
  io::WriteLabelSetJson(out_dir / "classes.json", segmenter.label_set());
  Progress progress("segmenting", inputs.size(), progress_options);
  double seconds = 0;
  SegmentImagesResult result;
  for (const auto& input : inputs) {
    const ColorImage rgb = input.Load();
    const Stopwatch start;
    HybridResult segmented;
    try {
      segmented = segmenter.Segment(rgb);
    } catch (const InvalidArgument& e) {
      throw FormatError(input.image, e.what());
    }
    seconds += start.Elapsed();
    result.masks += segmented.masks.size();
    WriteSegmentation(out_dir, input, rgb, segmented, segmenter.label_set());
    progress.Tick();
  }
  progress.Finish();
  result.images = inputs.size();
  result.seconds_per_image = inputs.empty() ? 0.0 : seconds / inputs.size();
  const MaskGeneratorOptions& m = options.masks;
  // The registry prefix (<name>_encoder / <name>_decoder), as given.
  std::string mask_model = "none";
  if (options.use_masks) {
    mask_model = m.model.encoder;
    const std::string suffix = "_encoder";
    if (mask_model.ends_with(suffix)) {
      mask_model.resize(mask_model.size() - suffix.size());
    }
  }
  const nlohmann::json summary = {
      {"input", description},
      {"images", inputs.size()},
      {"semantic_model", options.semantic.model},
      {"mask_model", mask_model},
      {"label_set", segmenter.label_set().name()},
      {"points_per_side", m.points_per_side},
      {"pred_iou_threshold", m.pred_iou_threshold},
      {"stability_threshold", m.stability_threshold},
      {"box_nms_threshold", m.box_nms_threshold},
      {"min_region_area_px", m.min_region_area_px},
      {"crop_layers", m.crop_layers},
      {"skip_covered_points", m.skip_covered_points},
      {"covered_similarity", m.covered_similarity},
      {"rejected_similarity", m.rejected_similarity},
      {"rejected_inside_similarity", m.rejected_inside_similarity},
      {"rejected_inside_logit", m.rejected_inside_logit},
      {"object_detector", options.objects.model},
      {"object_score", options.objects.score_threshold},
      {"object_weight", options.objects.weight},
      {"seconds_per_image", result.seconds_per_image}};
  WriteTextFileAtomic(out_dir / "summary.json", summary.dump(2) + "\n");
  return result;
}

}  // namespace semrec::segment
