// The automatic mask generator's fast path over its grid of point prompts:
// masks filtered at low resolution (full resolution only for survivors), and
// finer points skipped inside accepted masks or between rejected ones where
// the image embedding says the image looks alike. Internal to the mask
// generator (mask_generator.cc); its tests go through MaskGenerator.
#pragma once

#include <array>
#include <vector>

#include "semrec/segment/mask_generator.h"
#include "semrec/segment/promptable.h"

namespace semrec::segment {

/// The point prompts, coarse to fine, with each point's grid level (0 =
/// finest) and grid column and row.
struct PromptGrid {
  const std::vector<std::array<float, 2>>& points;
  const std::vector<int>& levels;
  const std::vector<std::array<int, 2>>& cells;
  int side = 0;  // points per side
};

/// Decodes the grid in waves of options.prompts_per_wave (a skippable level
/// starts a wave of its own: its points are judged by the level above);
/// returns the masks that pass the IoU and stability thresholds, in prompt
/// order. Counts decoded and early-rejected prompts into *stats.
std::vector<Mask> DecodeGridSkipping(const PromptGrid& grid,
                                     const MaskGeneratorOptions& options,
                                     PromptableSegmenter* model,
                                     MaskGeneratorStats* stats);

/// A decoded prompt's mask is kept: not rejected on its preview, predicted
/// IoU and stability at least the options' thresholds.
bool PassesThresholds(const MaskGeneratorOptions& options, const LowResMask& m,
                      float stability);

/// One foreground point.
Prompt PointPrompt(const std::array<float, 2>& p);

}  // namespace semrec::segment
