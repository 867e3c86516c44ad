// The kernel's mask part: the upscaling tokens of the image tokens a mask
// needs (UpscalingTokens) and their low-res logits (UpscaleBlocks).
#include <algorithm>

#include <fmt/format.h>

#include "semrec/core/error.h"
#include "semrec/segment/sam_kernel.h"
#include "semrec/segment/sam_kernel_ops.h"

namespace semrec::segment {

namespace ops = kernel_ops;

void SamKernel::CheckDecoded(const Image& im, const Output& decoded) const {
  const Output::SecondLayer& second = decoded.second_layer;
  if (second.image_tokens.size() != static_cast<size_t>(im.tokens) * kDim ||
      second.scores.n == 0 ||
      (precision_ == Precision::kBf16) != (second.scores.packed.n != 0)) {
    throw InvalidArgument(
        "SAM decoder kernel: upscaling needs a prompt this kernel decoded on "
        "this image");
  }
}

void SamKernel::UpscalingTokenBlock(const Image& im, const Output& decoded,
                                    const int64_t* tokens, int nb,
                                    float* out) const {
  const Output::SecondLayer& second = decoded.second_layer;
  thread_local std::vector<float> keys, pe, keys_pe, scores;
  keys.resize(static_cast<size_t>(kBlock) * kDim);
  pe.resize(keys.size());
  keys_pe.resize(keys.size());
  scores.resize(static_cast<size_t>(kBlock) * second.scores.n);
  for (int i = 0; i < nb; ++i) {
    const int64_t t = tokens[i];
    if (t < 0 || t >= im.tokens) {
      throw InvalidArgument(fmt::format(
          "SAM decoder kernel: token {} outside the image's {}", t, im.tokens));
    }
    const size_t from = static_cast<size_t>(t) * kDim;
    std::copy_n(second.image_tokens.data() + from, kDim,
                keys.data() + static_cast<size_t>(i) * kDim);
    std::copy_n(im.pe.data() + from, kDim,
                pe.data() + static_cast<size_t>(i) * kDim);
  }
  SecondLayerTokens(second, keys.data(), pe.data(), nb, keys_pe.data(),
                    scores.data(), out);
}

void SamKernel::UpscalingTokens(const Image& im, const Output& decoded,
                                const std::vector<int64_t>& tokens,
                                float* out) const {
  CheckDecoded(im, decoded);
  for (size_t b0 = 0; b0 < tokens.size(); b0 += kBlock) {
    const int nb =
        static_cast<int>(std::min<size_t>(kBlock, tokens.size() - b0));
    UpscalingTokenBlock(im, decoded, tokens.data() + b0, nb, out + b0 * kDim);
  }
}

// Per block of tokens: the first transposed convolution (each token's four
// sub-pixels' 64 channels), a layer norm and GELU per sub-pixel, the second
// (each sub-pixel's four), GELU, and the mask's hypernetwork row: the same
// operations as the mask part, in the order of its block_logits.
void SamKernel::UpscaleBlocks(const Image& im, const Output& decoded,
                              const std::vector<int64_t>& tokens,
                              float* out) const {
  if (!CanUpscale()) {
    throw InvalidArgument(fmt::format(
        "SAM decoder kernel: {} has no upscaling weights (written before "
        "the kernel upscaled); re-run scripts/setup",
        path_.string()));
  }
  CheckDecoded(im, decoded);
  if (decoded.mask_hyper.size() != static_cast<size_t>(kPreviewDim)) {
    throw InvalidArgument("SAM decoder kernel: the prompt has no mask chosen");
  }
  const int mid = upscale2_.in, sub = upscale1_.out / mid;
  thread_local std::vector<float> up, hidden, features;
  up.resize(static_cast<size_t>(kBlock) * kDim);
  hidden.resize(static_cast<size_t>(kBlock) * upscale1_.out);
  features.resize(static_cast<size_t>(kBlock) * sub * upscale2_.out);
  for (size_t b0 = 0; b0 < tokens.size(); b0 += kBlock) {
    const int nb =
        static_cast<int>(std::min<size_t>(kBlock, tokens.size() - b0));
    UpscalingTokenBlock(im, decoded, tokens.data() + b0, nb, up.data());
    ProductOnto(nb, up.data(), kDim, 1, upscale1_.rhs, hidden.data(),
                upscale1_.out, nullptr, 0, upscale1_.b.data());
    // [nb x sub x mid] as nb * sub rows of mid channels.
    ops::LayerNormRows(hidden.data(), nb * sub, mid, mid,
                       preview_norm_.g.data(), preview_norm_.b.data(),
                       preview_eps_);
    ops::Gelu(hidden.data(), static_cast<size_t>(nb) * upscale1_.out);
    ProductOnto(nb * sub, hidden.data(), mid, 1, upscale2_.rhs, features.data(),
                upscale2_.out, nullptr, 0, upscale2_.b.data());
    const size_t cells = static_cast<size_t>(nb) * kCellsPerToken;
    ops::Gelu(features.data(), cells * kPreviewDim);
    ops::RowDots(static_cast<int>(cells), kPreviewDim, features.data(),
                 kPreviewDim, decoded.mask_hyper.data(),
                 out + b0 * kCellsPerToken);
  }
}

}  // namespace semrec::segment
