#include "semrec/segment/vote.h"

#include <algorithm>
#include <unordered_map>

#include "semrec/core/error.h"

namespace semrec::segment {

VoteResult Vote(const LabelMap& semantic, const std::vector<Mask>& masks,
                const std::vector<MaskEvidence>* evidence,
                const LabelSet* classes) {
  const int w = semantic.width(), h = semantic.height();
  CheckArgument(masks.size() <= 65535, "vote: more than 65535 masks");
  CheckArgument(!evidence || evidence->size() == masks.size(),
                "vote: one evidence list per mask expected");
  VoteResult result;
  result.semantic = semantic;
  result.instance = LabelMap(w, h);
  result.mask_labels.resize(masks.size());
  result.mask_agreement.resize(masks.size());
  result.mask_confidence.resize(masks.size());
  std::unordered_map<uint16_t, int64_t> counts;
  for (size_t m = 0; m < masks.size(); ++m) {
    const Mask& mask = masks[m];
    CheckArgument(mask.image_width == w && mask.image_height == h,
                  "vote: mask " + std::to_string(m) +
                      " belongs to an image of another size");
    counts.clear();
    const Box& b = mask.box;
    for (int y = b.y0; y < b.y1; ++y) {
      const uint8_t* bits =
          &mask.bits[static_cast<size_t>(y - b.y0) * b.width()];
      const uint16_t* labels = &semantic(0, y);
      for (int x = b.x0; x < b.x1; ++x) {
        if (bits[x - b.x0]) ++counts[labels[x]];
      }
    }
    int64_t total = 0;
    for (const auto& [label, count] : counts) total += count;
    // Score = share of the mask's pixels (+ extra evidence); ties: the
    // smaller class id.
    const MaskEvidence* extra = evidence ? &(*evidence)[m] : nullptr;
    std::unordered_map<uint16_t, double> score;
    for (const auto& [label, count] : counts) {
      double share = total > 0 ? static_cast<double>(count) / total : 0.0;
      if (extra && classes && classes->Contains(label) &&
          classes->Get(label).kind == ClassKind::kStuff) {
        share *= extra->stuff_scale;
      }
      score[label] = share;
    }
    if (extra) {
      for (const ClassWeight& e : extra->weights) score[e.class_id] += e.weight;
    }
    uint16_t best = 0;
    double best_score = -1, score_sum = 0;
    for (const auto& [label, value] : score) {
      score_sum += value;
      if (value > best_score || (value == best_score && label < best)) {
        best = label;
        best_score = value;
      }
    }
    const auto it = counts.find(best);
    const int64_t best_count = it == counts.end() ? 0 : it->second;
    result.mask_labels[m] = best;
    result.mask_confidence[m] =
        score_sum > 0 ? static_cast<float>(best_score / score_sum) : 0.0f;
    result.mask_agreement[m] =
        total > 0 ? static_cast<float>(best_count) / static_cast<float>(total)
                  : 0;
    // Painting in order: later masks own the overlap.
    const uint16_t id = static_cast<uint16_t>(m + 1);
    for (int y = b.y0; y < b.y1; ++y) {
      const uint8_t* bits =
          &mask.bits[static_cast<size_t>(y - b.y0) * b.width()];
      uint16_t* inst = &result.instance(0, y);
      for (int x = b.x0; x < b.x1; ++x) {
        if (bits[x - b.x0]) inst[x] = id;
      }
    }
  }
  // One pass: each owned pixel takes its owner's class; pixels in no mask
  // keep their class and note which classes occur there.
  uint16_t* inst = result.instance.data();
  uint16_t* out = result.semantic.data();
  std::vector<uint8_t> unmasked_class(65536, 0);
  for (size_t i = 0; i < result.semantic.NumPixels(); ++i) {
    if (inst[i]) {
      out[i] = result.mask_labels[inst[i] - 1];
    } else {
      unmasked_class[out[i]] = 1;
    }
  }
  // Pixels in no mask form one instance per class (ids after the masks', in
  // class order), so downstream fusion still sees them.
  std::vector<uint16_t> extra_id(65536, 0);
  size_t next = masks.size() + 1;
  for (size_t c = 0; c < extra_id.size(); ++c) {
    if (unmasked_class[c]) {
      CheckArgument(next <= 65535, "vote: more than 65535 instances");
      extra_id[c] = static_cast<uint16_t>(next++);
      result.unmasked_classes.push_back(static_cast<uint16_t>(c));
    }
  }
  for (size_t i = 0; i < result.semantic.NumPixels(); ++i) {
    if (!inst[i]) inst[i] = extra_id[out[i]];
  }
  return result;
}

std::map<uint16_t, float> InstanceConfidence(
    const VoteResult& vote, const Image<float>& semantic_confidence) {
  std::map<uint16_t, float> out;
  for (size_t m = 0; m < vote.mask_confidence.size(); ++m) {
    out[static_cast<uint16_t>(m + 1)] = vote.mask_confidence[m];
  }
  const size_t masks = vote.mask_confidence.size();
  const size_t extra = vote.unmasked_classes.size();
  if (extra == 0) return out;
  std::vector<double> sum(extra, 0.0);
  std::vector<size_t> count(extra, 0);
  const bool have = semantic_confidence.NumPixels() > 0;
  CheckArgument(!have || semantic_confidence.SameSize(vote.instance.width(),
                                                      vote.instance.height()),
                "vote: the confidence image's size differs from the labels'");
  if (have) {
    const uint16_t* inst = vote.instance.data();
    const float* conf = semantic_confidence.data();
    for (size_t i = 0; i < vote.instance.NumPixels(); ++i) {
      if (inst[i] > masks) {
        const size_t k = inst[i] - masks - 1;
        sum[k] += conf[i];
        ++count[k];
      }
    }
  }
  for (size_t k = 0; k < extra; ++k) {
    out[static_cast<uint16_t>(masks + k + 1)] =
        count[k] > 0 ? static_cast<float>(sum[k] / count[k]) : 1.0f;
  }
  return out;
}

}  // namespace semrec::segment
