// The kernel's mask part: the upscaling tokens of the image tokens a mask
// needs (UpscalingTokens) and their low-res logits (UpscaleBlocks).
#include <algorithm>

#include <fmt/format.h>

#include "semrec/core/error.h"
#include "semrec/sam/kernel.h"
#include "semrec/sam/kernel_ops.h"

namespace semrec::sam {

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

// Per block of tokens: the upscaling's features at all 16 cells
// (UpscalingFeatures, in the order of the mask part's block_logits) and the
// mask's hypernetwork row.
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
  thread_local std::vector<float> up, hidden, features;
  up.resize(static_cast<size_t>(kBlock) * kDim);
  hidden.resize(static_cast<size_t>(kBlock) * upscale1_.out);
  features.resize(static_cast<size_t>(kBlock) * kCellsPerToken * kPreviewDim);
  for (size_t b0 = 0; b0 < tokens.size(); b0 += kBlock) {
    const int nb =
        static_cast<int>(std::min<size_t>(kBlock, tokens.size() - b0));
    UpscalingTokenBlock(im, decoded, tokens.data() + b0, nb, up.data());
    UpscalingFeatures(up.data(), nb, upscale1_, upscale2_, hidden.data(),
                      features.data());
    const size_t cells = static_cast<size_t>(nb) * kCellsPerToken;
    ops::RowDots(static_cast<int>(cells), kPreviewDim, features.data(),
                 kPreviewDim, decoded.mask_hyper.data(),
                 out + b0 * kCellsPerToken);
  }
}

}  // namespace semrec::sam
