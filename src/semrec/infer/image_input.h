// Turning an RGB image into a model's input tensor as the registry describes
// (resize policy, layout, colour order, normalisation), and mapping between
// image pixels and the model's input frame.
#pragma once

#include "semrec/core/image.h"
#include "semrec/infer/model_registry.h"
#include "semrec/infer/onnx_session.h"

namespace semrec::infer {

/// Where an image lies in the model's input frame. Continuous coordinates
/// (pixel centres at +0.5): input = image * scale. The image covers
/// [0, resized_width) x [0, resized_height) of the input frame (the rest is
/// letterbox padding).
struct InputTransform {
  int image_width = 0;
  int image_height = 0;
  int input_width = 0;
  int input_height = 0;
  int resized_width = 0;
  int resized_height = 0;
  double scale_x = 1.0;
  double scale_y = 1.0;
};

/// The transform `spec` applies to an image of this size. Letterbox keeps the
/// aspect ratio: scale = min(W_in / w, H_in / h), resized size rounded.
InputTransform ComputeInputTransform(int image_width, int image_height,
                                     const ImageInputSpec& spec);

/// The [1, 3, H, W] (NCHW) or [1, H, W, 3] (NHWC) input tensor for `rgb`
/// (8-bit, 3 channels; throws InvalidArgument otherwise), resized bilinearly.
Tensor ImageToTensor(const ColorImage& rgb, const ImageInputSpec& spec,
                     InputTransform* transform = nullptr);

}  // namespace semrec::infer
