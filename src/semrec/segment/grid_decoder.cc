#include "semrec/segment/grid_decoder.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

namespace semrec::segment {
namespace {

// Cosine similarity of two embedding vectors (1 when either is zero).
double Cosine(const std::vector<float>& a, const std::vector<float>& b) {
  double dot = 0, aa = 0, bb = 0;
  for (size_t k = 0; k < a.size() && k < b.size(); ++k) {
    dot += double{a[k]} * b[k];
    aa += double{a[k]} * a[k];
    bb += double{b[k]} * b[k];
  }
  return aa > 0 && bb > 0 ? dot / std::sqrt(aa * bb) : 1.0;
}

// The low-res cell (row-major in a width x height grid over the model frame)
// nearest the image point p (continuous: pixel x spans [x, x + 1)).
size_t NearestLowResCell(const infer::InputTransform& transform, int width,
                         int height, const std::array<float, 2>& p) {
  LowResMask dims;
  dims.width = width;
  dims.height = height;
  const auto [u, v] = ImageToLowRes(transform, dims, p[0] - 0.5, p[1] - 0.5);
  const int iu = std::clamp(static_cast<int>(std::lround(u)), 0, width - 1);
  const int iv = std::clamp(static_cast<int>(std::lround(v)), 0, height - 1);
  return static_cast<size_t>(iv) * width + iu;
}

// Outcome per grid cell.
enum Outcome : uint8_t { kNotDecoded = 0, kRejected = 1, kAccepted = 2 };

class SkippingDecoder {
 public:
  SkippingDecoder(const PromptGrid& grid, const MaskGeneratorOptions& options,
                  PromptableSegmenter* model)
      : grid_(grid),
        options_(options),
        model_(model),
        n_(grid.side),
        inside_test_(options.rejected_inside_similarity < 1.0f),
        outcome_(static_cast<size_t>(n_) * n_, kNotDecoded),
        point_of_cell_(outcome_.size(), 0),
        rejected_logits_(outcome_.size()) {
    while ((1 << dense_level_) < options_.dense_stride) ++dense_level_;
    for (size_t p = 0; p < grid_.cells.size(); ++p) {
      point_of_cell_[CellOf(p)] = p;
    }
  }

  std::vector<Mask> Run(MaskGeneratorStats* stats) {
    size_t next = 0;
    while (next < grid_.points.size()) {
      const std::vector<size_t> wave = NextWave(&next);
      Wave decoded = Decode(wave);
      stats->prompts_decoded += static_cast<int>(wave.size());
      Record(wave, &decoded, stats);
    }
    return std::move(candidates_);
  }

 private:
  // A wave's results, per prompt.
  struct Wave {
    std::vector<LowResMask> decoded;
    std::vector<float> stability;
    std::vector<Mask> upsampled;
    std::vector<int> low_res_area;
    std::vector<std::vector<float>> pooled;
    std::vector<std::vector<float>> logits_at;
    explicit Wave(size_t n)
        : decoded(n),
          stability(n),
          upsampled(n),
          low_res_area(n, 0),
          pooled(n),
          logits_at(n) {}
  };

  size_t CellOf(size_t p) const {
    return static_cast<size_t>(grid_.cells[p][1]) * n_ + grid_.cells[p][0];
  }

  // Inside an accepted mask whose embedding the image here resembles.
  bool IsCovered(const std::array<float, 2>& p) const {
    if (covered_.empty()) return false;
    const int owner =
        covered_[NearestLowResCell(model_->transform(), cw_, ch_, p)];
    if (owner < 0) return false;
    if (options_.covered_similarity <= 0) return true;
    return Cosine(model_->EmbeddingAt(p[0], p[1]), mask_embedding_[owner]) >=
           options_.covered_similarity;
  }

  // A rejected mask's logit (or its preview's) at every grid point.
  std::vector<float> LogitsAtPoints(const LowResMask& m) const {
    std::vector<float> at(outcome_.size(), 0.0f);
    for (size_t q = 0; q < grid_.points.size(); ++q) {
      at[CellOf(q)] = m.logits[NearestLowResCell(model_->transform(), m.width,
                                                 m.height, grid_.points[q])];
    }
    return at;
  }

  // A fine point whose surrounding coarser points were all rejected lies in
  // a region where SAM finds no good mask; decoding it again rarely helps.
  // (A point skipped between rejected ones counts as rejected: with several
  // skippable levels its finer neighbours are judged by it.)
  bool BetweenRejected(size_t p) const {
    if (!options_.skip_between_rejected) return false;
    const auto [i, j] = grid_.cells[p];
    // The surrounding points of the next coarser level.
    const int stride = 2 << grid_.levels[p];
    const auto neighbours = [&](int v) {
      const int lo = v / stride * stride;
      return v % stride == 0 || lo + stride >= n_
                 ? std::vector<int>{lo}
                 : std::vector<int>{lo, lo + stride};
    };
    std::vector<float> here;
    for (int u : neighbours(i)) {
      for (int v : neighbours(j)) {
        const size_t cell = static_cast<size_t>(v) * n_ + u;
        if (outcome_[cell] != kRejected) return false;
        // Only where the image looks the same as at the rejected points, or
        // a little less alike inside their masks.
        if (options_.rejected_similarity <= 0) continue;
        if (here.empty()) {
          here = model_->EmbeddingAt(grid_.points[p][0], grid_.points[p][1]);
        }
        const auto& q = grid_.points[point_of_cell_[cell]];
        const double similarity = Cosine(here, model_->EmbeddingAt(q[0], q[1]));
        const std::vector<float>& logits = rejected_logits_[cell];
        const bool inside =
            inside_test_ && !logits.empty() &&
            logits[CellOf(p)] > options_.rejected_inside_logit &&
            similarity >= options_.rejected_inside_similarity;
        if (similarity < options_.rejected_similarity && !inside) {
          return false;
        }
      }
    }
    return true;
  }

  // The next wave's prompts from *next on; skipped points are marked.
  std::vector<size_t> NextWave(size_t* next) {
    std::vector<size_t> wave;
    const std::vector<int>& levels = grid_.levels;
    while (*next < grid_.points.size() &&
           static_cast<int>(wave.size()) < options_.prompts_per_wave) {
      const size_t p = *next;
      // A skippable level starts a wave of its own: its points are judged by
      // the results of the level above.
      if (!wave.empty() && levels[p] < dense_level_ &&
          levels[p] != levels[wave.front()]) {
        break;
      }
      if (!options_.skip_covered_points || levels[p] >= dense_level_) {
        wave.push_back(p);
      } else if (!IsCovered(grid_.points[p])) {
        if (BetweenRejected(p)) {
          outcome_[CellOf(p)] = kRejected;
        } else {
          wave.push_back(p);
        }
      }
      ++*next;
    }
    return wave;
  }

  // Decode, score, upsample and describe in parallel (the wave was chosen
  // before any of its results).
  Wave Decode(const std::vector<size_t>& wave) const {
    Wave w(wave.size());
    const MaskFilter filter = options_.Filter();
    // In pairs: the decoder kernel decodes two prompts in one pass over the
    // image's arrays (bench_prompts).
    constexpr size_t kBatch = 2;
    const size_t batches = (wave.size() + kBatch - 1) / kBatch;
    tbb::parallel_for(static_cast<size_t>(0), batches, [&](size_t b) {
      const size_t first = b * kBatch;
      const size_t end = std::min(wave.size(), first + kBatch);
      std::vector<Prompt> prompts;
      for (size_t k = first; k < end; ++k) {
        prompts.push_back(PointPrompt(grid_.points[wave[k]]));
      }
      std::vector<LowResMask> batch =
          model_->DecodeBatchUnlessRejected(prompts, filter);
      for (size_t k = first; k < end; ++k) {
        const LowResMask& m = w.decoded[k] = std::move(batch[k - first]);
        const bool finer = grid_.levels[wave[k]] > 0;
        if (m.rejected_early) {
          if (inside_test_ && finer && !m.logits.empty()) {
            w.logits_at[k] = LogitsAtPoints(m);
          }
          continue;
        }
        w.stability[k] =
            model_->StabilityScore(m, 0.0f, options_.stability_offset);
        if (!PassesThresholds(options_, m, w.stability[k])) {
          if (inside_test_ && finer) w.logits_at[k] = LogitsAtPoints(m);
          continue;
        }
        w.upsampled[k] = model_->Upsample(m);
        for (float logit : m.logits) w.low_res_area[k] += logit > 0.0f;
        if (options_.covered_similarity > 0) {
          w.pooled[k] = model_->PooledEmbedding(m);
        }
      }
    });
    return w;
  }

  // Book-keeping in prompt order: outcomes, the covered map (per low-res
  // cell the smallest accepted mask covering it), the candidates.
  void Record(const std::vector<size_t>& wave, Wave* w,
              MaskGeneratorStats* stats) {
    for (size_t k = 0; k < wave.size(); ++k) {
      const LowResMask& m = w->decoded[k];
      stats->prompts_rejected_early += m.rejected_early;
      const bool passes = PassesThresholds(options_, m, w->stability[k]);
      outcome_[CellOf(wave[k])] = passes ? kAccepted : kRejected;
      if (!passes) {
        rejected_logits_[CellOf(wave[k])] = std::move(w->logits_at[k]);
        continue;
      }
      if (covered_.empty()) {
        cw_ = m.width;
        ch_ = m.height;
        covered_.assign(static_cast<size_t>(cw_) * ch_, -1);
        covered_area_.assign(covered_.size(), 0);
      }
      const int area = w->low_res_area[k];
      const int id = static_cast<int>(mask_embedding_.size());
      mask_embedding_.push_back(std::move(w->pooled[k]));
      for (size_t i = 0; i < covered_.size(); ++i) {
        if (m.logits[i] > 0.0f &&
            (covered_[i] < 0 || area < covered_area_[i])) {
          covered_[i] = id;
          covered_area_[i] = area;
        }
      }
      Mask& mask = w->upsampled[k];
      if (mask.area == 0) continue;
      mask.stability = w->stability[k];
      mask.point_x = grid_.points[wave[k]][0];
      mask.point_y = grid_.points[wave[k]][1];
      if (!m.object_pointer.empty()) mask.embedding = m.object_pointer;
      candidates_.push_back(std::move(mask));
    }
  }

  const PromptGrid& grid_;
  const MaskGeneratorOptions& options_;
  PromptableSegmenter* model_;
  const int n_;
  const bool inside_test_;
  int dense_level_ = 0;
  std::vector<uint8_t> outcome_;
  std::vector<size_t> point_of_cell_;
  // Per rejected cell whose points have finer neighbours: its mask's logit
  // (or preview's) at every grid point.
  std::vector<std::vector<float>> rejected_logits_;
  // Per low-res cell: the smallest accepted mask covering it (-1: none).
  std::vector<int> covered_;
  std::vector<int> covered_area_;
  std::vector<std::vector<float>> mask_embedding_;
  int cw_ = 0, ch_ = 0;
  std::vector<Mask> candidates_;
};

}  // namespace

bool PassesThresholds(const MaskGeneratorOptions& options, const LowResMask& m,
                      float stability) {
  return !m.rejected_early && m.predicted_iou >= options.pred_iou_threshold &&
         stability >= options.stability_threshold;
}

Prompt PointPrompt(const std::array<float, 2>& p) {
  Prompt prompt;
  prompt.points = {p};
  prompt.labels = {1};
  return prompt;
}

std::vector<Mask> DecodeGridSkipping(const PromptGrid& grid,
                                     const MaskGeneratorOptions& options,
                                     PromptableSegmenter* model,
                                     MaskGeneratorStats* stats) {
  return SkippingDecoder(grid, options, model).Run(stats);
}

}  // namespace semrec::segment
