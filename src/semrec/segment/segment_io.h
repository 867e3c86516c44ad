// Inputs and outputs of `semrec segment`: images from a file, a folder or an
// RGB-D sequence; label PNGs (readable by `semrec fuse --labels DIR` and
// `semrec eval seg`), a colour overlay and per-image JSON.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "semrec/core/image.h"
#include "semrec/core/label_map.h"
#include "semrec/segment/hybrid_segmenter.h"

namespace semrec::segment {

struct SegmentInput {
  /// Output file name ("<stem>.png"; for sequences the depth file's name, so
  /// fusion's folder source finds the labels).
  std::string name;
  std::filesystem::path image;
};

/// An image file; a sequence folder (any layout SequenceReader reads); or a
/// folder of .png/.jpg/.jpeg images (sorted by name). Throws IoError /
/// FormatError naming the path when it is none of these.
std::vector<SegmentInput> ListSegmentInputs(const std::filesystem::path& path,
                                            int stride = 1,
                                            size_t max_frames = 0);

/// The colour overlay: image blended with class colours, instance outlines,
/// each instance's class name (majority of its pixels) at its centroid.
ColorImage RenderLabelOverlay(const ColorImage& rgb, const LabelMap& semantic,
                              const LabelMap& instance, const LabelSet& labels);
/// RenderLabelOverlay of the vote's maps.
ColorImage RenderOverlay(const ColorImage& rgb, const HybridResult& result,
                         const LabelSet& labels);

/// Writes semantic/<name>, instance/<name> (16-bit PNG), overlay/<name> and
/// masks/<stem>.json under `out_dir`, each atomically.
void WriteSegmentation(const std::filesystem::path& out_dir,
                       const SegmentInput& input, const ColorImage& rgb,
                       const HybridResult& result, const LabelSet& labels);

}  // namespace semrec::segment
