#include "semrec/segment/mask_generator.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string_view>

#include <tbb/parallel_for.h>

#include "semrec/core/error.h"
#include "semrec/core/stopwatch.h"
#include "semrec/segment/grid_decoder.h"

namespace semrec::segment {

void MaskGeneratorOptions::Check() const {
  model.Check();
  CheckArgument(points_per_side >= 1 && points_per_side <= 256,
                "mask generator: points_per_side must be in 1..256");
  CheckArgument(pred_iou_threshold >= 0 && pred_iou_threshold <= 1,
                "mask generator: pred_iou_threshold must be in [0, 1]");
  CheckArgument(stability_threshold >= 0 && stability_threshold <= 1,
                "mask generator: stability_threshold must be in [0, 1]");
  CheckArgument(stability_offset >= 0,
                "mask generator: stability_offset must be >= 0");
  CheckArgument(box_nms_threshold > 0 && box_nms_threshold <= 1,
                "mask generator: box_nms_threshold must be in (0, 1]");
  CheckArgument(min_region_area_px >= 0,
                "mask generator: min_region_area_px must be >= 0");
  CheckArgument(dense_stride >= 1 && (dense_stride & (dense_stride - 1)) == 0,
                "mask generator: dense_stride must be a power of 2");
  CheckArgument(covered_similarity >= 0 && covered_similarity <= 1,
                "mask generator: covered_similarity must be in [0, 1]");
  CheckArgument(rejected_similarity >= 0 && rejected_similarity <= 1,
                "mask generator: rejected_similarity must be in [0, 1]");
  CheckArgument(
      rejected_inside_similarity >= 0 && rejected_inside_similarity <= 1,
      "mask generator: rejected_inside_similarity must be in [0, 1]");
  CheckArgument(std::isfinite(rejected_inside_logit),
                "mask generator: rejected_inside_logit must be finite");
  CheckArgument(crop_layers >= 0 && crop_layers <= 4,
                "mask generator: crop_layers must be in 0..4");
  CheckArgument(crop_overlap_ratio >= 0 && crop_overlap_ratio < 1,
                "mask generator: crop_overlap_ratio must be in [0, 1)");
  CheckArgument(crop_points_downscale >= 1,
                "mask generator: crop_points_downscale must be >= 1");
  CheckArgument(prompts_per_wave >= 1,
                "mask generator: prompts_per_wave must be >= 1");
}

MaskFilter MaskGeneratorOptions::Filter() const {
  MaskFilter filter;
  filter.min_predicted_iou = pred_iou_threshold;
  filter.min_stability = stability_threshold;
  filter.stability_offset = stability_offset;
  return filter;
}

namespace {

// Grid points, coarse to fine: points on every 16th row/column first, then
// every 8th, ..., so that large objects are found by the first prompts and
// the covered-point skip removes most of the rest.
std::vector<std::array<float, 2>> GridPoints(
    int n, int width, int height, std::vector<int>* levels,
    std::vector<std::array<int, 2>>* cells) {
  struct P {
    int level, i, j;
  };
  std::vector<P> points;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      int level = 0;
      while (level < 16 && ((i | j) & (1 << level)) == 0) ++level;
      points.push_back({level, i, j});
    }
  }
  std::stable_sort(points.begin(), points.end(),
                   [](const P& a, const P& b) { return a.level > b.level; });
  std::vector<std::array<float, 2>> out;
  levels->clear();
  cells->clear();
  for (const P& p : points) {
    levels->push_back(p.level);
    cells->push_back({p.i, p.j});
    out.push_back({static_cast<float>((p.i + 0.5) / n * width),
                   static_cast<float>((p.j + 0.5) / n * height)});
  }
  return out;
}

// SAM's crop boxes: the whole image, then per layer l a 2^l x 2^l grid of
// overlapping crops.
std::vector<Box> CropBoxes(int w, int h, int layers, float overlap_ratio,
                           std::vector<int>* layer_of) {
  std::vector<Box> boxes = {Box{0, 0, w, h}};
  *layer_of = {0};
  for (int l = 1; l <= layers; ++l) {
    const int n = 1 << l;
    const int overlap =
        static_cast<int>(overlap_ratio * std::min(w, h) * (2.0 / n));
    const int cw = static_cast<int>(
        std::ceil(static_cast<double>(overlap * (n - 1) + w) / n));
    const int ch = static_cast<int>(
        std::ceil(static_cast<double>(overlap * (n - 1) + h) / n));
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const int x0 = (cw - overlap) * i, y0 = (ch - overlap) * j;
        boxes.push_back(
            Box{x0, y0, std::min(x0 + cw, w), std::min(y0 + ch, h)});
        layer_of->push_back(l);
      }
    }
  }
  return boxes;
}

ColorImage CropImage(const ColorImage& rgb, const Box& b) {
  if (b.x0 == 0 && b.y0 == 0 && b.width() == rgb.width() &&
      b.height() == rgb.height()) {
    return rgb;
  }
  ColorImage out(b.width(), b.height(), 3);
  for (int y = 0; y < b.height(); ++y) {
    std::copy_n(&rgb(b.x0, b.y0 + y), static_cast<size_t>(b.width()) * 3,
                &out(0, y));
  }
  return out;
}

// SAM's is_box_near_crop_edge (20 px): the mask box (crop coordinates) touches
// a crop edge that is not an image edge.
bool NearCropEdge(const Box& m, const Box& crop, int w, int h) {
  constexpr int kTol = 20;
  const auto near = [](int a, int b) { return std::abs(a - b) <= kTol; };
  const Box g{m.x0 + crop.x0, m.y0 + crop.y0, m.x1 + crop.x0, m.y1 + crop.y0};
  return (near(g.x0, crop.x0) && !near(g.x0, 0)) ||
         (near(g.y0, crop.y0) && !near(g.y0, 0)) ||
         (near(g.x1, crop.x1) && !near(g.x1, w)) ||
         (near(g.y1, crop.y1) && !near(g.y1, h));
}

// Content hash of an image (size and bytes): which image the model holds.
size_t ImageHash(const ColorImage& rgb) {
  const std::string_view bytes(
      reinterpret_cast<const char*>(rgb.data()),
      rgb.NumPixels() * static_cast<size_t>(rgb.channels()));
  return std::hash<std::string_view>{}(bytes) ^
         (static_cast<size_t>(rgb.width()) << 32 ^
          static_cast<size_t>(rgb.height()));
}

class AutomaticMaskGenerator : public MaskGenerator {
 public:
  AutomaticMaskGenerator(const infer::ModelRegistry& registry,
                         const MaskGeneratorOptions& options, bool reference)
      : options_(options), reference_(reference) {
    options_.Check();
    // The reference runs the decoder export as is (no image/prompt split).
    if (reference_) options_.model.split_decoder = false;
    model_ = PromptableSegmenter::Create(registry, options_.model);
  }

  std::vector<Mask> GenerateWhere(
      const ColorImage& rgb, const Image<uint8_t>& prompt_region) override {
    CheckArgument(
        prompt_region.SameSize(rgb) && prompt_region.channels() == 1,
        "mask generator: the prompt region must be a one-channel image of the "
        "frame's size");
    region_ = &prompt_region;
    try {
      std::vector<Mask> masks = Generate(rgb);
      region_ = nullptr;
      return masks;
    } catch (...) {
      region_ = nullptr;
      throw;
    }
  }

  std::vector<Mask> Generate(const ColorImage& rgb) override {
    stats_ = {};
    std::vector<int> layers;
    const std::vector<Box> crops =
        CropBoxes(rgb.width(), rgb.height(), options_.crop_layers,
                  options_.crop_overlap_ratio, &layers);
    std::vector<Mask> all;
    std::vector<float> scores;
    for (size_t k = 0; k < crops.size(); ++k) {
      const Box& crop = crops[k];
      int n = options_.points_per_side;
      for (int l = 0; l < layers[k]; ++l) {
        n = std::max(1, n / options_.crop_points_downscale);
      }
      std::vector<Mask> masks = GenerateInCrop(CropImage(rgb, crop), n, crop);
      for (Mask& m : masks) {
        if (layers[k] > 0 &&
            NearCropEdge(m.box, crop, rgb.width(), rgb.height())) {
          continue;  // cut by the crop: the full mask comes from another crop
        }
        m.box = Box{m.box.x0 + crop.x0, m.box.y0 + crop.y0, m.box.x1 + crop.x0,
                    m.box.y1 + crop.y0};
        m.point_x += static_cast<float>(crop.x0);
        m.point_y += static_cast<float>(crop.y0);
        m.image_width = rgb.width();
        m.image_height = rgb.height();
        // Across crops SAM prefers masks from smaller crops (more pixels per
        // object); within one crop the predicted IoU decides.
        scores.push_back(crops.size() > 1
                             ? 1.0f / static_cast<float>(crop.area())
                             : m.predicted_iou);
        all.push_back(std::move(m));
      }
    }
    const Stopwatch postprocess;
    std::vector<Mask> kept =
        crops.size() > 1
            ? NmsByScore(std::move(all), scores, options_.box_nms_threshold)
            : std::move(all);
    tbb::parallel_for(static_cast<size_t>(0), kept.size(), [&](size_t i) {
      RemoveSmallRegions(&kept[i], options_.min_region_area_px);
    });
    std::erase_if(kept, [](const Mask& m) { return m.area == 0; });
    std::stable_sort(
        kept.begin(), kept.end(),
        [](const Mask& a, const Mask& b) { return a.area > b.area; });
    stats_.kept = static_cast<int>(kept.size());
    stats_.postprocess_seconds = postprocess.Elapsed();
    return kept;
  }

  const MaskGeneratorStats& stats() const override { return stats_; }
  PromptableSegmenter& model() override { return *model_; }

  void EncodeUnlessCurrent(const ColorImage& rgb) override {
    const size_t hash = ImageHash(rgb);
    if (encoded_whole_ && encoded_hash_ == hash) return;
    const Stopwatch encode;
    model_->SetImage(rgb);
    ++stats_.encoder_calls;
    stats_.encode_seconds += encode.Elapsed();
    encoded_whole_ = true;
    encoded_hash_ = hash;
  }

 private:
  // Encode, decode the grid, filter and NMS within one image (or crop).
  std::vector<Mask> GenerateInCrop(const ColorImage& rgb, int points_per_side,
                                   const Box& crop) {
    auto points = GridPoints(points_per_side, rgb.width(), rgb.height(),
                             &levels_, &cells_);
    if (region_ != nullptr) {
      // Only the prompts the region allows (their order, levels and cells kept
      // aligned).
      size_t kept = 0;
      for (size_t p = 0; p < points.size(); ++p) {
        const int x = std::clamp(static_cast<int>(points[p][0]) + crop.x0, 0,
                                 region_->width() - 1);
        const int y = std::clamp(static_cast<int>(points[p][1]) + crop.y0, 0,
                                 region_->height() - 1);
        if ((*region_)(x, y) == 0) continue;
        points[kept] = points[p];
        levels_[kept] = levels_[p];
        cells_[kept] = cells_[p];
        ++kept;
      }
      points.resize(kept);
      levels_.resize(kept);
      cells_.resize(kept);
      if (points.empty()) {
        return {};  // nothing new here: no encoder, no decoder
      }
    }
    Stopwatch watch;
    model_->SetImage(rgb);
    ++stats_.encoder_calls;
    const double encode_seconds = watch.Lap();
    // `rgb` is a crop's copy when crops are on: only a whole image counts.
    encoded_whole_ = crop.x0 == 0 && crop.y0 == 0 && options_.crop_layers == 0;
    encoded_hash_ = ImageHash(rgb);
    grid_side_ = points_per_side;
    stats_.prompts_total += static_cast<int>(points.size());
    std::vector<Mask> candidates =
        reference_ ? DecodeAll(points)
                   : DecodeGridSkipping({points, levels_, cells_, grid_side_},
                                        options_, model_.get(), &stats_);
    stats_.candidates += static_cast<int>(candidates.size());
    stats_.encode_seconds += encode_seconds;
    stats_.decode_seconds += watch.Lap();
    return BoxNms(std::move(candidates), options_.box_nms_threshold);
  }

  bool Passes(const LowResMask& m, float stability) const {
    return PassesThresholds(options_, m, stability);
  }

  // The straightforward algorithm: every prompt, logits upsampled to full
  // resolution, stability on the full-resolution logits.
  std::vector<Mask> DecodeAll(const std::vector<std::array<float, 2>>& points) {
    std::vector<Mask> masks(points.size());
    std::vector<uint8_t> ok(points.size(), 0);
    tbb::parallel_for(static_cast<size_t>(0), points.size(), [&](size_t k) {
      const LowResMask m = model_->Decode(PointPrompt(points[k]));
      const Image<float> logits = model_->UpsampleLogits(m);
      const float stability =
          StabilityScore(logits.values(), 0.0f, options_.stability_offset);
      if (!Passes(m, stability)) return;
      Image<uint8_t> bin(logits.width(), logits.height());
      for (size_t i = 0; i < bin.NumPixels(); ++i) {
        bin.values()[i] = logits.values()[i] > 0.0f;
      }
      masks[k] = MaskFromImage(bin);
      masks[k].predicted_iou = m.predicted_iou;
      masks[k].stability = stability;
      masks[k].point_x = points[k][0];
      masks[k].point_y = points[k][1];
      if (!m.object_pointer.empty()) masks[k].embedding = m.object_pointer;
      ok[k] = masks[k].area > 0;
    });
    stats_.prompts_decoded = static_cast<int>(points.size());
    std::vector<Mask> out;
    for (size_t k = 0; k < points.size(); ++k) {
      if (ok[k]) out.push_back(std::move(masks[k]));
    }
    return out;
  }

  MaskGeneratorOptions options_;
  bool reference_;
  std::unique_ptr<PromptableSegmenter> model_;
  MaskGeneratorStats stats_;
  const Image<uint8_t>* region_ = nullptr;  // GenerateWhere's prompt region
  std::vector<int> levels_;  // grid level per point (see GridPoints)
  int grid_side_ = 0;        // points per side of the current grid
  std::vector<std::array<int, 2>> cells_;  // grid column and row per point
  // What model_ holds: a whole image (not a crop) with this content hash.
  bool encoded_whole_ = false;
  size_t encoded_hash_ = 0;
};

}  // namespace

std::unique_ptr<MaskGenerator> MaskGenerator::Create(
    const infer::ModelRegistry& registry, const MaskGeneratorOptions& options,
    bool reference) {
  return std::make_unique<AutomaticMaskGenerator>(registry, options, reference);
}

}  // namespace semrec::segment
