// Inputs and outputs of `semrec segment`: images from a file, a folder or an
// RGB-D sequence; label PNGs (readable by `semrec fuse --labels DIR` and
// `semrec eval seg`), a colour overlay and per-image JSON.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "semrec/core/image.h"
#include "semrec/core/label_map.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/segment/hybrid_segmenter.h"

namespace semrec::segment {

struct SegmentInput {
  /// Output file name ("<stem>.png"; for sequences the depth file's name, so
  /// fusion's folder source finds the labels).
  std::string name;
  /// The image file (for sequences: the frame's colour name, for messages).
  std::filesystem::path image;
  /// Set for sequences: frames are read through the reader (bags, .sens
  /// have no image files).
  std::shared_ptr<const io::SequenceReader> sequence = nullptr;
  size_t frame = 0;

  /// The colour image (RGB8).
  ColorImage Load() const;
};

/// An image file; a sequence (any layout SequenceReader reads: a folder, a
/// bag, a .sens file); or a
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
