// Multi-object tracking metrics with MOTChallenge conventions: CLEAR MOT
// (Bernardin & Stiefelhagen 2008, as py-motmetrics computes it), identity
// metrics (Ristani et al. 2016) and HOTA (Luiten et al. 2021, as TrackEval
// computes it). Boxes match when IoU >= 0.5.
#pragma once

#include <cstddef>
#include <vector>

#include "semrec/io/mot_io.h"

namespace semrec::eval {

struct MotMetrics {
  size_t frames = 0;
  size_t gt_boxes = 0;
  size_t predicted_boxes = 0;
  size_t gt_ids = 0;
  size_t predicted_ids = 0;
  // CLEAR MOT.
  size_t true_positives = 0;
  size_t false_positives = 0;
  size_t false_negatives = 0;
  size_t id_switches = 0;
  size_t fragmentations = 0;
  double mota = 0.0;
  /// Mean 1 - IoU of the matches (py-motmetrics' distance form).
  double motp = 0.0;
  double precision = 0.0;
  double recall = 0.0;
  size_t mostly_tracked = 0;
  size_t partially_tracked = 0;
  size_t mostly_lost = 0;
  // Identity metrics.
  size_t idtp = 0;
  double idf1 = 0.0;
  double idp = 0.0;
  double idr = 0.0;
  // HOTA, averaged over the localisation thresholds 0.05, 0.10, ..., 0.95.
  double hota = 0.0;
  double deta = 0.0;
  double assa = 0.0;
};

/// Intersection over union of two (left, top, width, height) boxes.
double BoxIou(const io::MotBox& a, const io::MotBox& b);

MotMetrics EvaluateMot(const std::vector<io::MotBox>& gt,
                       const std::vector<io::MotBox>& predicted,
                       double iou_threshold = 0.5);

}  // namespace semrec::eval
