#include "semrec/track/box.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace semrec::track {

namespace {

Eigen::Vector4d Measure(const Box& b) {
  return {b.left + b.width / 2, b.top + b.height / 2, b.width * b.height,
          b.height > 0 ? b.width / b.height : 1.0};
}

Box FromState(double cx, double cy, double area, double aspect) {
  // Both positive by construction (area clamped in Predict, aspect measured).
  const double w = std::sqrt(std::max(area, 0.0) * std::max(aspect, 1e-6));
  const double h = w > 0 ? std::max(area, 0.0) / w : 0.0;
  return {cx - w / 2, cy - h / 2, w, h};
}

// Transition (x += v per frame) and measurement (first four states).
Eigen::Matrix<double, 7, 7> Transition() {
  Eigen::Matrix<double, 7, 7> F = Eigen::Matrix<double, 7, 7>::Identity();
  F(0, 4) = F(1, 5) = F(2, 6) = 1.0;
  return F;
}

Eigen::Matrix<double, 4, 7> Observation() {
  Eigen::Matrix<double, 4, 7> H = Eigen::Matrix<double, 4, 7>::Zero();
  for (int i = 0; i < 4; ++i) H(i, i) = 1.0;
  return H;
}

}  // namespace

BoxFilter::BoxFilter(const Box& box) {
  x_.head<4>() = Measure(box);
  // Position known to the detector's noise; velocities unknown.
  Vector7 p;
  p << 10, 10, 10, 10, 1e4, 1e4, 1e4;
  P_ = p.asDiagonal();
}

Box BoxFilter::Predict() {
  // An area about to turn negative stops shrinking.
  if (x_(2) + x_(6) <= 0) x_(6) = 0;
  const Matrix7 F = Transition();
  Vector7 q;
  q << 1, 1, 1, 1, 0.01, 0.01, 1e-4;
  x_ = F * x_;
  P_ = F * P_ * F.transpose() + Matrix7(q.asDiagonal());
  return Estimate();
}

void BoxFilter::Update(const Box& box) {
  const Eigen::Matrix<double, 4, 7> H = Observation();
  Eigen::Vector4d r(1, 1, 10, 10);
  const Eigen::Matrix4d S =
      H * P_ * H.transpose() + Eigen::Matrix4d(r.asDiagonal());
  const Eigen::Matrix<double, 7, 4> K = P_ * H.transpose() * S.inverse();
  x_ += K * (Measure(box) - H * x_);
  P_ = (Matrix7::Identity() - K * H) * P_;
}

Box BoxFilter::Estimate() const {
  return FromState(x_(0), x_(1), x_(2), x_(3));
}

}  // namespace semrec::track
