// A constant-velocity Kalman filter over a box in pixels (the state SORT
// uses: centre, area, aspect ratio).
#pragma once

#include <Eigen/Core>

#include "semrec/detect/box.h"

namespace semrec::track {

// The tracker works on the detector's boxes.
using detect::Box;
using detect::CornerDistance;
using detect::Iou;

/// Kalman filter with state (cx, cy, area, aspect, d cx, d cy, d area): the
/// aspect ratio is taken as constant, the centre and the area move linearly.
/// Noise levels are in pixels (centre) and pixels^2 (area), tuned for
/// pedestrians at 10-30 fps; they matter less than the gating they feed.
class BoxFilter {
 public:
  BoxFilter() = default;
  /// Starts at `box` with zero velocity and a wide velocity prior.
  explicit BoxFilter(const Box& box);

  /// Advances one frame and returns the predicted box.
  Box Predict();
  /// Corrects the state with an observed box.
  void Update(const Box& box);
  /// The current estimate.
  Box Estimate() const;

 private:
  using Vector7 = Eigen::Matrix<double, 7, 1>;
  using Matrix7 = Eigen::Matrix<double, 7, 7>;
  Vector7 x_ = Vector7::Zero();
  Matrix7 P_ = Matrix7::Identity();
};

}  // namespace semrec::track
