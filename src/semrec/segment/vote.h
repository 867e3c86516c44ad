// The vote that fuses the two branches (the paper's Fig. 4): inside each
// class-agnostic mask the majority semantic class wins and the whole mask
// takes it; pixels in no mask keep the semantic branch's label.
#pragma once

#include <cstdint>
#include <map>
#include <vector>

#include "semrec/core/label_map.h"
#include "semrec/segment/detector_votes.h"
#include "semrec/segment/mask.h"

namespace semrec::segment {

struct VoteResult {
  /// Final classes: each mask's pixels carry its winning class; pixels in no
  /// mask keep the semantic label. One "mask per class" is the set of pixels
  /// with that label.
  LabelMap semantic;
  /// Instance ids: mask i (in the given order) is instance i + 1; pixels in
  /// no mask form one instance per class, ids masks + 1, masks + 2, ... in
  /// the order of `unmasked_classes`.
  LabelMap instance;
  /// Winning class per mask and the share of the mask's pixels that voted for
  /// it (in [0, 1]).
  std::vector<uint16_t> mask_labels;
  std::vector<float> mask_agreement;
  /// The winner's part of all the mask's class scores (pixel shares after
  /// stuff scaling + evidence weights), in [0, 1]: the vote's probability
  /// for the class it chose (= mask_agreement without evidence).
  std::vector<float> mask_confidence;
  /// Classes of the pixels in no mask, ascending.
  std::vector<uint16_t> unmasked_classes;
};

/// Votes each mask's class from `semantic` over all of the mask's pixels
/// (ties: the smaller class id), then paints the masks in the given order so
/// later masks own overlapping pixels. Pass masks sorted large to small (as
/// MaskGenerator returns them): a small mask lying on a large one (a cup on a
/// table) keeps its own class. Cost: one pass over each mask's box plus one
/// pass over the image; no per-mask full-image scans. Throws InvalidArgument
/// when a mask belongs to an image of another size or there are more than
/// 65535 masks.
///
/// With `evidence` (one per mask, e.g. from object detections), a mask's
/// class is the argmax of its classes' pixel shares (those of stuff classes
/// in `classes` scaled by stuff_scale) plus their extra weights;
/// `mask_agreement` stays the semantic share of the winner. Throws
/// InvalidArgument when its size differs from the masks'.
VoteResult Vote(const LabelMap& semantic, const std::vector<Mask>& masks,
                const std::vector<MaskEvidence>* evidence = nullptr,
                const LabelSet* classes = nullptr);

/// Confidence per instance id of `vote` (fuse::FrameLabels::confidence):
/// masks their mask_confidence; the pixels in no mask (one instance per
/// class) the mean of `semantic_confidence` (the semantic branch's
/// probability of its class) over them, 1 where that image is empty. Throws
/// InvalidArgument when a non-empty image's size differs from the vote's.
std::map<uint16_t, float> InstanceConfidence(
    const VoteResult& vote, const Image<float>& semantic_confidence);

}  // namespace semrec::segment
