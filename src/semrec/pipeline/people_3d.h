// Tracked people in 3-D: per-frame person id maps (from `semrec track`'s
// persons/ folder or a synthetic sequence's person layer) back-projected with
// depth and pose into world-frame clouds, one time-sampled track per id for
// dynamic.usda.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "semrec/core/frame.h"
#include "semrec/core/label_map.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/usd/usda_writer.h"

namespace semrec::pipeline {

/// Where per-frame person id maps (16-bit PNG, 0 = nobody, else track id) come
/// from.
class PersonMapSource {
 public:
  /// `spec`: "gt" = the sequence's own `person` layer (generic layout, e.g.
  /// `semrec synth --preset people`); a folder = <folder>/<colour image file
  /// name> (what `semrec track <sequence> --out DIR` writes in DIR/persons),
  /// falling back to the depth image's name. Throws IoError when the folder
  /// does not exist or holds no map for any frame.
  PersonMapSource(const std::string& spec, const io::SequenceReader& reader);

  /// Frame `i`'s map, or nothing when the folder has none for it (nobody
  /// tracked there). Throws FormatError (naming the file) for a map of the
  /// wrong size.
  std::optional<LabelMap> Get(size_t i) const;

 private:
  const io::SequenceReader& reader_;
  std::vector<std::filesystem::path> paths_;  // empty path: none
};

struct People3dOptions {
  /// Points further than this are left out (noise grows with depth).
  double max_depth_m = 4.0;
  /// Each person's per-frame cloud is voxel-downsampled at this size.
  double voxel_size_m = 0.05;
  /// Observations with fewer points (after downsampling) are dropped: a hand
  /// at the image border is no position estimate.
  size_t min_points = 10;
  void Check() const;
};

/// Collects person observations frame by frame.
class People3d {
 public:
  explicit People3d(const People3dOptions& options = {});

  /// Back-projects every id of `person_ids` in `frame`.
  void Add(const Frame& frame, const LabelMap& person_ids);

  /// One track per id, samples in frame order (frame = Frame::index).
  std::vector<usd::PersonTrack> Tracks() const;

 private:
  People3dOptions options_;
  std::map<uint32_t, std::vector<usd::PersonSample>> samples_;
};

}  // namespace semrec::pipeline
