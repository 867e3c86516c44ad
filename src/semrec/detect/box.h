// Boxes in image pixels and the two measures the detector's NMS and the
// tracker's association use.
#pragma once

namespace semrec::detect {

/// An axis-aligned box in pixels: left, top, width, height.
struct Box {
  double left = 0.0;
  double top = 0.0;
  double width = 0.0;
  double height = 0.0;
};

/// Sum of the distances between corresponding corners (the paper's c_ij).
double CornerDistance(const Box& a, const Box& b);
double Iou(const Box& a, const Box& b);

}  // namespace semrec::detect
