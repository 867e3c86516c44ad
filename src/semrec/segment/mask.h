// A binary image mask stored inside its bounding box, so painting, voting and
// IoU cost O(mask area) instead of O(image) per mask.
#pragma once

#include <cstdint>
#include <vector>

#include "semrec/core/image.h"

namespace semrec::segment {

/// Pixel box [x0, x1) x [y0, y1).
struct Box {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  int64_t area() const {
    return x1 > x0 && y1 > y0 ? static_cast<int64_t>(x1 - x0) * (y1 - y0) : 0;
  }
};

double BoxIoU(const Box& a, const Box& b);

struct Mask {
  /// Size of the image the mask belongs to.
  int image_width = 0;
  int image_height = 0;
  /// Tight bounding box of the set pixels; `bits` is box.width() x
  /// box.height(), row-major, 1 = inside.
  Box box;
  std::vector<uint8_t> bits;
  int64_t area = 0;
  /// The mask decoder's predicted IoU and the stability score (SAM).
  float predicted_iou = 0.0f;
  float stability = 0.0f;
  /// The point prompt that produced the mask (image pixels).
  float point_x = 0.0f, point_y = 0.0f;
  /// An appearance embedding (SAM2 object pointer or a mask-pooled encoder
  /// feature); empty when not computed.
  std::vector<float> embedding;

  bool Contains(int x, int y) const {
    return x >= box.x0 && x < box.x1 && y >= box.y0 && y < box.y1 &&
           bits[static_cast<size_t>(y - box.y0) * box.width() + (x - box.x0)] !=
               0;
  }
  /// The mask as a full-size 0/1 image.
  Image<uint8_t> ToImage() const;
  /// Centroid of the set pixels (image pixels, centres at +0.5).
  void Centroid(double* x, double* y) const;
};

/// Builds a mask from a full-size image (non-zero = inside); tight box, area.
Mask MaskFromImage(const Image<uint8_t>& image);

/// Crops `mask.bits` to the tight box of its set pixels and recounts the area
/// (after editing bits). An empty mask gets an empty box.
void Tighten(Mask* mask);

/// |a ∩ b| (pixels; one pass over the boxes' overlap).
int64_t MaskIntersection(const Mask& a, const Mask& b);

/// |a ∩ b| / |a ∪ b| (0 when both are empty).
double MaskIoU(const Mask& a, const Mask& b);

/// SAM's stability score of logits: |logits > t + offset| / |logits > t -
/// offset| (1 when both are empty).
float StabilityScore(const std::vector<float>& logits, float threshold,
                     float offset);

/// Removes connected regions (8-connected) and fills holes (4-connected
/// background not touching the box border... see .cc) smaller than
/// `min_area_px`; re-tightens the mask.
void RemoveSmallRegions(Mask* mask, int min_area_px);

/// Greedy NMS on boxes: masks sorted by `predicted_iou` (then prompt order);
/// a mask is dropped when its box IoU with a kept one exceeds `threshold`.
std::vector<Mask> BoxNms(std::vector<Mask> masks, float threshold);

/// Greedy NMS on boxes by `scores` (one per mask, highest first; ties: input
/// order).
std::vector<Mask> NmsByScore(std::vector<Mask> masks,
                             const std::vector<float>& scores, float threshold);

}  // namespace semrec::segment
