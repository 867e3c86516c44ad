// The decoder kernel's image side: per prompt and block of image tokens,
// the two layers' attentions between the prompt's tokens and the image's.
#include <algorithm>
#include <cmath>

#include "semrec/sam/kernel.h"
#include "semrec/sam/kernel_internal.h"
#include "semrec/sam/kernel_ops.h"

namespace semrec::sam {

namespace ops = kernel_ops;
using kernel_detail::Sum;

// The prompt's per-head rows or columns as a block-diagonal matrix: column
// (or row) t * heads + h holds token t's head-h channels of x [tokens x 128]
// at their own rows (columns), zeros elsewhere; scaled. Products with it
// compute all heads' attention terms at once.
std::vector<float> SamKernel::HeadColumns(const std::vector<float>& x,
                                          const State& s, float scale) const {
  const int dh = kCrossDim / heads_;
  std::vector<float> m(static_cast<size_t>(kCrossDim) * s.padded, 0.0f);
  for (int t = 0; t < s.tokens; ++t) {
    for (int h = 0; h < heads_; ++h) {
      for (int d = 0; d < dh; ++d) {
        m[static_cast<size_t>(h * dh + d) * s.padded +
          static_cast<size_t>(t * heads_ + h)] =
            x[t * kCrossDim + h * dh + d] * scale;
      }
    }
  }
  return m;
}

// w [256 x 128] times the HeadColumns matrix of x (scaled): [256 x
// padded], from each head's channels only (w transposed: each column a
// HeadRowsProduct row).
std::vector<float> SamKernel::Fold(const Linear& l, const std::vector<float>& x,
                                   const State& s, float scale) const {
  const int dh = kCrossDim / heads_;
  std::vector<float> scaled(x.size());
  for (size_t i = 0; i < x.size(); ++i) scaled[i] = x[i] * scale;
  std::vector<float> rows(static_cast<size_t>(s.padded) * kDim, 0.0f);
  ops::HeadRowsProduct(s.tokens, heads_, dh, scaled.data(), kCrossDim,
                       l.wt.data(), kDim, kDim, rows.data(), kDim);
  std::vector<float> out(static_cast<size_t>(kDim) * s.padded);
  for (int c = 0; c < s.padded; ++c) {
    for (int r = 0; r < kDim; ++r) {
      out[static_cast<size_t>(r) * s.padded + c] =
          rows[static_cast<size_t>(c) * kDim + r];
    }
  }
  return out;
}

// Each token's value through its head's share of the output projection o
// [128 x 256]: HeadRows(v) o, [padded x 256] (padding rows zero).
void SamKernel::HeadValues(const Linear& o, const std::vector<float>& v,
                           const State& s, std::vector<float>* out) const {
  out->assign(static_cast<size_t>(s.padded) * kDim, 0.0f);
  ops::HeadRowsProduct(s.tokens, heads_, kCrossDim / heads_, v.data(),
                       kCrossDim, o.w.data(), kDim, kDim, out->data(), kDim);
}

// The token-to-image attention's output from its accumulated weighted sums
// of image tokens `acc` [cols x 256] and their weights' sums: the value
// projection after the sum (the weights sum to 1, so the value bias passes
// as it is), then the output projection.
std::vector<float> SamKernel::AttentionOutput(const Attention& a,
                                              OnlineAttention* online,
                                              const State& s) const {
  const int dh = kCrossDim / heads_;
  std::vector<float>* acc = &online->acc;
  for (int c = 0; c < s.cols; ++c) {
    float* row = acc->data() + static_cast<size_t>(c) * kDim;
    const float inv = 1.0f / online->sum[c];
    for (int i = 0; i < kDim; ++i) row[i] *= inv;
  }
  // Each column (token, head) keeps its own head's values only.
  std::vector<float> o(static_cast<size_t>(s.tokens) * kCrossDim);
  ops::HeadColumnsProduct(s.tokens, heads_, dh, kDim, acc->data(), kDim,
                          a.v.w.data(), kCrossDim, o.data(), kCrossDim);
  for (int t = 0; t < s.tokens; ++t) {
    for (int c = 0; c < kCrossDim; ++c) o[t * kCrossDim + c] += a.v.b[c];
  }
  return ApplyTokens(a.o, o, s.tokens);
}

// One block's share of a token-to-image attention, online: the scores of
// the block's image tokens `keys_pe` against the folded queries, their
// running softmax, and the weighted sum of the block's `values` into acc.
void SamKernel::AttendBlock(const float* keys_pe, const float* values, int nb,
                            const Rhs& folded, float* scores,
                            OnlineAttention* online, const State& s) const {
  float* acc = online->acc.data();
  Product(nb, keys_pe, kDim, 1, folded, scores, s.padded, false);
  if (ops::OnlineSoftmaxColumns(scores, nb, s.cols, s.padded,
                                online->max.data(), online->sum.data(),
                                online->rescale.data())) {
    for (int c = 0; c < s.cols; ++c) {
      float* row = acc + static_cast<size_t>(c) * kDim;
      for (int i = 0; i < kDim; ++i) row[i] *= online->rescale[c];
    }
  }
  // The values are this block's image tokens: packed here when bf16.
  thread_local Rhs block;
  block.w = values;
  block.k = nb;
  block.n = kDim;
  if (precision_ == Precision::kBf16) {
    ops::PackBf16(nb, kDim, values, kDim, &block.packed);
  }
  Product(s.cols, scores, 1, s.padded, block, acc, kDim, true);
}

// Layer 0's image side after its token side: the prompt's tokens update the
// image tokens (image-to-token attention, norm4), and layer 1's
// token-to-image attention, whose queries are known by then, runs over the
// same blocks with an online softmax. One prompt's share: set up, then per
// block (the prompts of a batch take each block in turn while it is in the
// cache), then finished.

SamKernel::FirstLayerWork::FirstLayerWork(
    const SamKernel& k, const std::vector<float>& layer0_tokens, State* state,
    float* tokens_out)
    : s(state), image_tokens(tokens_out), online(state->cols) {
  const Layer& l0 = k.layers_[0];
  const Layer& l1 = k.layers_[1];
  const int T = s->tokens;
  const float scale = k.CrossScale();
  const std::vector<float> k0 =
      k.ApplyTokens(l0.i2t.k, Sum(layer0_tokens, s->query_pe), T);
  kbd = k.HeadColumns(k0, *s, scale);
  k.HeadValues(l0.i2t.o, k.ApplyTokens(l0.i2t.v, layer0_tokens, T), *s, &u0);
  qk1 =
      k.Fold(l1.t2i.k, k.ApplyTokens(l1.t2i.q, Sum(s->queries, s->query_pe), T),
             *s, scale);
  kbd_rhs = k.MakeRhs(kbd.data(), kCrossDim, s->padded);
  u0_rhs = k.MakeRhs(u0.data(), s->cols, kDim);
  qk1_rhs = k.MakeRhs(qk1.data(), kDim, s->padded);
}

void SamKernel::FirstLayerBlock(const Image& im, int b0,
                                FirstLayerWork* w) const {
  const Layer& l0 = layers_[0];
  State* s = w->s;
  Scratch& x = *s->scratch;
  const int nb = std::min(kBlock, im.tokens - b0);
  const size_t at = static_cast<size_t>(b0) * kDim;
  float* keys = w->image_tokens + at;
  Product(nb, im.i2t_queries.data() + static_cast<int64_t>(b0) * kCrossDim,
          kCrossDim, 1, w->kbd_rhs, x.scores.data(), s->padded, false);
  ops::SoftmaxHeads(x.scores.data(), nb, s->padded, s->tokens, nullptr);
  // keys + output bias + attention output, normalised; and + PE for the
  // next attention's keys.
  ProductOnto(nb, x.scores.data(), s->padded, 1, w->u0_rhs, keys, kDim,
              im.keys.data() + at, kDim, l0.i2t.o.b.data());
  ops::LayerNormRows(keys, nb, kDim, kDim, l0.norm4.g.data(), l0.norm4.b.data(),
                     norm_eps_, im.pe.data() + at, x.keys_pe.data());
  AttendBlock(x.keys_pe.data(), keys, nb, w->qk1_rhs, x.scores.data(),
              &w->online, *s);
}

void SamKernel::FirstLayerFinish(FirstLayerWork* w) const {
  const Layer& l1 = layers_[1];
  State* s = w->s;
  const int T = s->tokens;
  const std::vector<float> out = AttentionOutput(l1.t2i, &w->online, *s);
  ops::Add(s->queries.data(), s->queries.data(), out.data(), out.size());
  ops::LayerNormRows(s->queries.data(), T, kDim, kDim, l1.norm2.g.data(),
                     l1.norm2.b.data(), norm_eps_);
  TokenMlpAndNorm(l1, &s->queries, T);
}

// Layer 1's image side: image-to-token attention and norm4 (the mask
// part's upscaling tokens, kept only per block), the final token-to-image
// attention online, and each token's mask features (the preview before the
// mask is chosen); by blocks as the first layer's.

SamKernel::SecondLayerWork::SecondLayerWork(const SamKernel& k, State* state,
                                            Output::SecondLayer* second_layer,
                                            float* features_out)
    : s(state),
      second(second_layer),
      features(features_out),
      online(state->cols) {
  const Layer& l1 = k.layers_[1];
  const int T = s->tokens;
  const float scale = k.CrossScale();
  const std::vector<float> qpe = Sum(s->queries, s->query_pe);
  const std::vector<float> k1 = k.ApplyTokens(l1.i2t.k, qpe, T);
  second->prompt_tokens = T;
  second->scores_w = k.Fold(l1.i2t.q, k1, *s, scale);
  second->bias.resize(static_cast<size_t>(s->padded));
  ops::Gemm(1, s->padded, kCrossDim, l1.i2t.q.b.data(), 0, 1,
            k.HeadColumns(k1, *s, scale).data(), s->padded, second->bias.data(),
            s->padded, false);
  k.HeadValues(l1.i2t.o, k.ApplyTokens(l1.i2t.v, s->queries, T), *s,
               &second->values_w);
  second->scores = k.MakeRhs(second->scores_w.data(), kDim, s->padded);
  second->values = k.MakeRhs(second->values_w.data(), s->cols, kDim);
  qkf = k.Fold(k.final_.k, k.ApplyTokens(k.final_.q, qpe, T), *s, scale);
  qkf_rhs = k.MakeRhs(qkf.data(), kDim, s->padded);
}

void SamKernel::SecondLayerBlock(const Image& im, int b0,
                                 SecondLayerWork* w) const {
  State* s = w->s;
  Scratch& x = *s->scratch;
  const int nb = std::min(kBlock, im.tokens - b0);
  const size_t at = static_cast<size_t>(b0) * kDim;
  float* up = x.up.data();
  SecondLayerTokens(*w->second, w->second->image_tokens.data() + at,
                    im.pe.data() + at, nb, x.keys_pe.data(), x.scores.data(),
                    up);
  // The final token-to-image attention.
  AttendBlock(x.keys_pe.data(), up, nb, w->qkf_rhs, x.scores.data(), &w->online,
              *s);
  // The mask features: the upscaling's two steps at the preview's cell.
  UpscalingFeatures(up, nb, preview1_, preview2_, x.hidden.data(),
                    w->features + static_cast<size_t>(b0) * kPreviewDim);
}

void SamKernel::SecondLayerFinish(SecondLayerWork* w) const {
  State* s = w->s;
  const std::vector<float> out = AttentionOutput(final_, &w->online, *s);
  ops::Add(s->queries.data(), s->queries.data(), out.data(), out.size());
  ops::LayerNormRows(s->queries.data(), s->tokens, kDim, kDim,
                     final_norm_.g.data(), final_norm_.b.data(), norm_eps_);
}

// The upscaling's two transposed convolutions on nb upscaling tokens `up`
// (all four sub-pixels, or the preview's one): `first`'s columns are
// sub-pixels of 64 channels, each layer-normed and through GELU, then
// `second` on each sub-pixel and GELU: [nb * sub-pixels x second.out] into
// features (hidden: [nb x first.out] scratch).
void SamKernel::UpscalingFeatures(const float* up, int nb, const Linear& first,
                                  const Linear& second, float* hidden,
                                  float* features) const {
  const int mid = second.in, sub = first.out / mid;
  ProductOnto(nb, up, kDim, 1, first.rhs, hidden, first.out, nullptr, 0,
              first.b.data());
  ops::LayerNormRows(hidden, nb * sub, mid, mid, preview_norm_.g.data(),
                     preview_norm_.b.data(), preview_eps_);
  ops::Gelu(hidden, static_cast<size_t>(nb) * first.out);
  ProductOnto(nb * sub, hidden, mid, 1, second.rhs, features, second.out,
              nullptr, 0, second.b.data());
  ops::Gelu(features, static_cast<size_t>(nb) * sub * second.out);
}

void SamKernel::SecondLayerTokens(const Output::SecondLayer& second,
                                  const float* keys, const float* pe, int nb,
                                  float* keys_pe, float* scores,
                                  float* up) const {
  const Layer& l1 = layers_[1];
  const int padded = second.scores.n;
  ops::Add(keys_pe, keys, pe, static_cast<size_t>(nb) * kDim);
  Product(nb, keys_pe, kDim, 1, second.scores, scores, padded, false);
  ops::SoftmaxHeads(scores, nb, padded, second.prompt_tokens,
                    second.bias.data());
  ProductOnto(nb, scores, padded, 1, second.values, up, kDim, keys, kDim,
              l1.i2t.o.b.data());
  ops::LayerNormRows(up, nb, kDim, kDim, l1.norm4.g.data(), l1.norm4.b.data(),
                     norm_eps_, pe, keys_pe);
}

}  // namespace semrec::sam
