// Helpers the end-to-end benchmarks share.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <utility>

#include "semrec/core/file_util.h"
#include "semrec/core/label_map.h"
#include "semrec/core/progress.h"
#include "semrec/core/sample_data.h"
#include "semrec/core/stopwatch.h"

namespace semrec::bench {

/// No progress output (the benchmarks print their own tables).
inline ProgressOptions Quiet() {
  ProgressOptions p;
  p.mode = ProgressOptions::Mode::kOff;
  return p;
}

/// The real sample data (semrec::SampleDataDir; a path that does not exist
/// when there is none, so that each benchmark says what it skips).
inline std::filesystem::path SampleDataDir() {
  return semrec::SampleDataDir().value_or("../shared/data");
}

/// An instance of a reference label map and how well another map recovers it.
struct InstanceMatch {
  size_t area = 0;
  /// Best IoU with one instance of the other map.
  double best_iou = 0.0;
};

/// Per instance of `reference` (id != 0), over the pixels `use(i)` accepts:
/// its area and its best IoU with an instance of `other` (id != 0).
template <typename Use>
std::map<uint16_t, InstanceMatch> MatchInstances(const LabelMap& reference,
                                                 const LabelMap& other,
                                                 const Use& use) {
  std::map<uint16_t, size_t> area_other;
  std::map<uint16_t, InstanceMatch> out;
  std::map<std::pair<uint16_t, uint16_t>, size_t> both;
  for (size_t i = 0; i < reference.NumPixels(); ++i) {
    if (!use(i)) continue;
    const uint16_t a = reference.data()[i], b = other.data()[i];
    if (a != 0) ++out[a].area;
    if (b != 0) ++area_other[b];
    if (a != 0 && b != 0) ++both[{a, b}];
  }
  for (const auto& [pair, n] : both) {
    InstanceMatch& m = out[pair.first];
    const double iou =
        static_cast<double>(n) /
        static_cast<double>(m.area + area_other[pair.second] - n);
    m.best_iou = std::max(m.best_iou, iou);
  }
  return out;
}

}  // namespace semrec::bench
