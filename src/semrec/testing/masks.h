// Rectangular masks for the segmentation tests (header only: the test
// executables that include it link semrec_segment).
#pragma once

#include "semrec/core/image.h"
#include "semrec/segment/mask.h"

namespace semrec::testing {

/// A w x h mask covering `box` (x0 <= x < x1, y0 <= y < y1).
inline segment::Mask RectMask(int w, int h, const segment::Box& box,
                              float predicted_iou = 0.95f) {
  Image<uint8_t> img(w, h);
  for (int y = box.y0; y < box.y1; ++y) {
    for (int x = box.x0; x < box.x1; ++x) img(x, y) = 1;
  }
  segment::Mask m = segment::MaskFromImage(img);
  m.predicted_iou = predicted_iou;
  return m;
}

}  // namespace semrec::testing
