#include "semrec/segment/sam_kernel.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>

#include "semrec/core/error.h"
#include "semrec/segment/sam_kernel_ops.h"

namespace semrec::segment {

namespace ops = kernel_ops;

namespace {

// Columns of the per-prompt attention matrices: heads x prompt tokens,
// padded to whole vectors.
int Padded(int columns) { return (columns + 15) / 16 * 16; }

std::vector<float> Sum(const std::vector<float>& a,
                       const std::vector<float>& b) {
  std::vector<float> out(a.size());
  ops::Add(out.data(), a.data(), b.data(), a.size());
  return out;
}

}  // namespace

// Per-thread buffers, kept between prompts (fresh 4 MB buffers per prompt
// cost page faults).
struct SamKernel::Scratch {
  std::vector<float> up;                     // [block x 256]: layer 1's norm4
  std::vector<std::vector<float>> features;  // per prompt [tokens x 32]
  std::vector<float> scores;                 // [block x padded]
  std::vector<float> keys_pe;                // [block x 256]
  std::vector<float> hidden;                 // [block x 64]
};

// One token-to-image attention computed block by block: per column (head x
// prompt token) the running maximum and sum of its softmax, and the weighted
// sum of image tokens [cols x 256].
struct SamKernel::OnlineAttention {
  explicit OnlineAttention(int cols)
      : max(static_cast<size_t>(cols), -1e30f),
        sum(max.size(), 0.0f),
        rescale(max.size()),
        acc(max.size() * kDim, 0.0f) {}
  std::vector<float> max, sum, rescale, acc;
};

struct SamKernel::State {
  int tokens = 0;  // the prompt's tokens (output tokens + points)
  int cols = 0;    // heads x tokens, column t * heads + h
  int padded = 0;  // cols rounded up to 16
  std::vector<float> queries, query_pe;  // [tokens x 256]
  Scratch* scratch = nullptr;
};

std::vector<float> SamKernel::ApplyTokens(const Linear& l,
                                          const std::vector<float>& x,
                                          int rows) const {
  if (l.rhs.w == nullptr) return Apply(l, x, rows);
  std::vector<float> out(static_cast<size_t>(rows) * l.out);
  ProductOnto(rows, x.data(), l.in, 1, l.rhs, out.data(), l.out, nullptr, 0,
              l.b.data());
  return out;
}

SamKernel::Rhs SamKernel::MakeRhs(const float* w, int k, int n) const {
  Rhs r;
  r.w = w;
  r.k = k;
  r.n = n;
  if (precision_ == Precision::kBf16) ops::PackBf16(k, n, w, n, &r.packed);
  return r;
}

void SamKernel::Product(int m, const float* a, long a_row, long a_col,
                        const Rhs& b, float* c, long ldc,
                        bool accumulate) const {
  if (precision_ == Precision::kBf16) {
    ops::GemmBf16(m, a, a_row, a_col, b.packed, c, ldc, accumulate);
  } else {
    ops::Gemm(m, b.n, b.k, a, a_row, a_col, b.w, b.n, c, ldc, accumulate);
  }
}

void SamKernel::ProductOnto(int m, const float* a, long a_row, long a_col,
                            const Rhs& b, float* c, long ldc, const float* init,
                            long ld_init, const float* bias) const {
  if (precision_ == Precision::kBf16) {
    ops::GemmOntoBf16(m, a, a_row, a_col, b.packed, c, ldc, init, ld_init,
                      bias);
  } else {
    ops::GemmOnto(m, b.n, b.k, a, a_row, a_col, b.w, b.n, c, ldc, init, ld_init,
                  bias);
  }
}

std::vector<float> SamKernel::Apply(const Linear& l,
                                    const std::vector<float>& x,
                                    int rows) const {
  std::vector<float> out(static_cast<size_t>(rows) * l.out);
  ops::GemmOnto(rows, l.out, l.in, x.data(), l.in, 1, l.w.data(), l.out,
                out.data(), l.out, nullptr, 0, l.b.data());
  return out;
}

std::vector<float> SamKernel::TokenAttention(const Attention& a,
                                             const std::vector<float>& q_in,
                                             const std::vector<float>& k_in,
                                             const std::vector<float>& v_in,
                                             int rows) const {
  const std::vector<float> q = ApplyTokens(a.q, q_in, rows);
  const std::vector<float> k = ApplyTokens(a.k, k_in, rows);
  const std::vector<float> v = ApplyTokens(a.v, v_in, rows);
  const int inner = a.q.out, dh = inner / heads_;
  const float scale = 1.0f / std::sqrt(static_cast<float>(dh));
  std::vector<float> out(static_cast<size_t>(rows) * inner, 0.0f);
  std::vector<float> p(static_cast<size_t>(rows));
  for (int h = 0; h < heads_; ++h) {
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < rows; ++j) {
        float s = 0;
        for (int d = 0; d < dh; ++d) {
          s += q[i * inner + h * dh + d] * k[j * inner + h * dh + d];
        }
        p[j] = s * scale;
      }
      const float m = *std::max_element(p.begin(), p.end());
      float sum = 0;
      for (float& x : p) sum += (x = std::exp(x - m));
      for (int j = 0; j < rows; ++j) {
        for (int d = 0; d < dh; ++d) {
          out[i * inner + h * dh + d] += p[j] / sum * v[j * inner + h * dh + d];
        }
      }
    }
  }
  return ApplyTokens(a.o, out, rows);
}

void SamKernel::TokenMlpAndNorm(const Layer& l, std::vector<float>* queries,
                                int rows) const {
  std::vector<float> hidden = ApplyTokens(l.mlp1, *queries, rows);
  for (float& x : hidden) x = std::max(x, 0.0f);
  const std::vector<float> mlp = ApplyTokens(l.mlp2, hidden, rows);
  ops::Add(queries->data(), queries->data(), mlp.data(), queries->size());
  ops::LayerNormRows(queries->data(), rows, kDim, kDim, l.norm3.g.data(),
                     l.norm3.b.data(), norm_eps_);
}

// SAM's random Fourier positional encoding of (cx, cy) in [-1, 1]: 128
// sines then 128 cosines (the image's tokens and the prompt's points alike).
void SamKernel::EncodePosition(float cx, float cy, float* out) const {
  for (int j = 0; j < kDim / 2; ++j) {
    const float a = (cx * pe_gaussian_[j] + cy * pe_gaussian_[kDim / 2 + j]) *
                    2.0f * std::numbers::pi_v<float>;
    out[j] = std::sin(a);
    out[kDim / 2 + j] = std::cos(a);
  }
}

SamKernel::Image SamKernel::Prepare(const std::vector<float>& embedding,
                                    const std::vector<int64_t>& shape) const {
  if (shape.size() != 4 || shape[0] != 1 || shape[1] != kDim ||
      embedding.size() != static_cast<size_t>(kDim * shape[2] * shape[3])) {
    throw InvalidArgument(
        "SAM decoder kernel: the image embedding must be [1, 256, h, w]");
  }
  const int h = static_cast<int>(shape[2]), w = static_cast<int>(shape[3]);
  const int n = h * w;
  Image im;
  im.tokens = n;
  im.keys.resize(static_cast<size_t>(n) * kDim);
  im.pe.resize(static_cast<size_t>(n) * kDim);
  for (int c = 0; c < kDim; ++c) {
    for (int i = 0; i < n; ++i) {
      im.keys[static_cast<size_t>(i) * kDim + c] =
          embedding[static_cast<size_t>(c) * n + i] + no_mask_[c];
    }
  }
  {
    // The grid's encoding is the same for every image of its size: once.
    std::lock_guard<std::mutex> lock(pe_mutex_);
    auto& [grid, pe] = pe_cache_;
    if (grid != std::make_pair(h, w)) {
      pe.resize(im.pe.size());
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          const float cx =
              (static_cast<float>(x) + 0.5f) / static_cast<float>(w) * 2.0f -
              1.0f;
          const float cy =
              (static_cast<float>(y) + 0.5f) / static_cast<float>(h) * 2.0f -
              1.0f;
          EncodePosition(cx, cy,
                         pe.data() + static_cast<size_t>(y * w + x) * kDim);
        }
      }
      grid = {h, w};
    }
    im.pe = pe;
  }
  const std::vector<float> keys_pe = Sum(im.keys, im.pe);
  const Layer& l0 = layers_[0];
  const int dh = kCrossDim / heads_;
  // The three projections side by side (the cores are free between the
  // encoder and the prompts).
  tbb::parallel_invoke(
      [&] {
        const std::vector<float> k = Apply(l0.t2i.k, keys_pe, n);
        im.t2i_keys_t.resize(k.size());
        for (int i = 0; i < n; ++i) {
          for (int c = 0; c < kCrossDim; ++c) {
            im.t2i_keys_t[static_cast<size_t>(c) * n + i] =
                k[i * kCrossDim + c];
          }
        }
      },
      [&] {
        // Per head, [heads x tokens x 16]: each head's values are read in
        // one stream.
        const std::vector<float> v = Apply(l0.t2i.v, im.keys, n);
        im.t2i_values.resize(v.size());
        for (int i = 0; i < n; ++i) {
          for (int c = 0; c < kCrossDim; ++c) {
            im.t2i_values[(static_cast<size_t>(c / dh) * n + i) * dh + c % dh] =
                v[static_cast<size_t>(i) * kCrossDim + c];
          }
        }
      },
      [&] { im.i2t_queries = Apply(l0.i2t.q, keys_pe, n); });
  return im;
}

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
        m[static_cast<size_t>(h * dh + d) * s.padded + t * heads_ + h] =
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
struct SamKernel::FirstLayerWork {
  FirstLayerWork(const SamKernel& k, const std::vector<float>& layer0_tokens,
                 State* state, float* tokens_out);
  State* s;
  float* image_tokens;
  std::vector<float> kbd, u0, qk1;
  Rhs kbd_rhs, u0_rhs, qk1_rhs;
  OnlineAttention online;
};

SamKernel::FirstLayerWork::FirstLayerWork(
    const SamKernel& k, const std::vector<float>& layer0_tokens, State* state,
    float* tokens_out)
    : s(state), image_tokens(tokens_out), online(state->cols) {
  const Layer& l0 = k.layers_[0];
  const Layer& l1 = k.layers_[1];
  const int T = s->tokens;
  const float scale =
      1.0f / std::sqrt(static_cast<float>(kCrossDim / k.heads_));
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
  Product(nb, im.i2t_queries.data() + b0 * kCrossDim, kCrossDim, 1, w->kbd_rhs,
          x.scores.data(), s->padded, false);
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
struct SamKernel::SecondLayerWork {
  SecondLayerWork(const SamKernel& k, State* state,
                  Output::SecondLayer* second_layer, float* features_out);
  State* s;
  Output::SecondLayer* second;
  float* features;  // [image tokens x 32]
  std::vector<float> qkf;
  Rhs qkf_rhs;
  OnlineAttention online;
};

SamKernel::SecondLayerWork::SecondLayerWork(const SamKernel& k, State* state,
                                            Output::SecondLayer* second_layer,
                                            float* features_out)
    : s(state),
      second(second_layer),
      features(features_out),
      online(state->cols) {
  const Layer& l1 = k.layers_[1];
  const int T = s->tokens;
  const float scale =
      1.0f / std::sqrt(static_cast<float>(kCrossDim / k.heads_));
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
  ProductOnto(nb, up, kDim, 1, preview1_.rhs, x.hidden.data(), 64, nullptr, 0,
              preview1_.b.data());
  ops::LayerNormRows(x.hidden.data(), nb, 64, 64, preview_norm_.g.data(),
                     preview_norm_.b.data(), preview_eps_);
  ops::Gelu(x.hidden.data(), static_cast<size_t>(nb) * 64);
  float* f = w->features + static_cast<size_t>(b0) * kPreviewDim;
  ProductOnto(nb, x.hidden.data(), 64, 1, preview2_.rhs, f, kPreviewDim,
              nullptr, 0, preview2_.b.data());
  ops::Gelu(f, static_cast<size_t>(nb) * kPreviewDim);
}

void SamKernel::SecondLayerFinish(SecondLayerWork* w) const {
  State* s = w->s;
  const std::vector<float> out = AttentionOutput(final_, &w->online, *s);
  ops::Add(s->queries.data(), s->queries.data(), out.data(), out.size());
  ops::LayerNormRows(s->queries.data(), s->tokens, kDim, kDim,
                     final_norm_.g.data(), final_norm_.b.data(), norm_eps_);
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

void SamKernel::Decode(const Image& im,
                       const std::vector<std::array<float, 2>>& points,
                       const std::vector<float>& labels, Output* out) const {
  DecodeBatch(im, {Request{&points, &labels, out}});
}

// The prompt's tokens: the output tokens, then each point's positional
// encoding plus its label's embedding (padding: not-a-point alone).
void SamKernel::PromptTokens(const Request& r, State* s) const {
  const std::vector<std::array<float, 2>>& points = *r.points;
  const std::vector<float>& labels = *r.labels;
  const int count = static_cast<int>(points.size());
  s->tokens = 5 + count;
  s->cols = heads_ * s->tokens;
  s->padded = Padded(s->cols);
  s->query_pe = output_tokens_;
  s->query_pe.resize(static_cast<size_t>(s->tokens) * kDim);
  for (int i = 0; i < count; ++i) {
    float* e = s->query_pe.data() + static_cast<size_t>(5 + i) * kDim;
    const int label = static_cast<int>(labels[i]);
    if (label == -1) {
      std::copy(not_a_point_.begin(), not_a_point_.end(), e);
      continue;
    }
    if (label < 0 || label > 3) {
      throw InvalidArgument(fmt::format(
          "SAM decoder kernel: point label {} (expected -1..3)", label));
    }
    EncodePosition((points[i][0] + 0.5f) / input_size_ * 2.0f - 1.0f,
                   (points[i][1] + 0.5f) / input_size_ * 2.0f - 1.0f, e);
    ops::Add(e, e, point_embeddings_.data() + label * kDim, kDim);
  }
}

void SamKernel::DecodeBatch(const Image& im,
                            const std::vector<Request>& requests) const {
  if (im.tokens == 0) {
    throw InvalidArgument("SAM decoder kernel: the image is not prepared");
  }
  for (const Request& r : requests) {
    if (r.points == nullptr || r.labels == nullptr || r.out == nullptr ||
        r.points->empty() || r.points->size() != r.labels->size()) {
      throw InvalidArgument(
          "SAM decoder kernel: one label per point and at least one point "
          "are required");
    }
  }
  const size_t n = requests.size();
  thread_local Scratch scratch;
  scratch.up.resize(static_cast<size_t>(kBlock) * kDim);
  scratch.keys_pe.resize(static_cast<size_t>(kBlock) * kDim);
  scratch.hidden.resize(static_cast<size_t>(kBlock) * 64);
  if (scratch.features.size() < n) scratch.features.resize(n);
  std::vector<State> states(n);
  for (size_t p = 0; p < n; ++p) {
    states[p].scratch = &scratch;
    PromptTokens(requests[p], &states[p]);
    scratch.features[p].resize(static_cast<size_t>(im.tokens) * kPreviewDim);
    requests[p].out->second_layer.image_tokens.resize(
        static_cast<size_t>(im.tokens) * kDim);
  }
  size_t scores = 0;
  for (const State& s : states) {
    scores = std::max(scores, static_cast<size_t>(kBlock) * s.padded);
  }
  scratch.scores.resize(scores);
  const int dh = kCrossDim / heads_;
  const float scale = 1.0f / std::sqrt(static_cast<float>(dh));
  const Layer& l0 = layers_[0];
  const Layer& l1 = layers_[1];
  // Layer 0, token side (its first self-attention has no positional
  // encoding and no residual).
  std::vector<int> first_row(n + 1, 0);
  for (size_t p = 0; p < n; ++p) {
    State& s = states[p];
    s.queries = TokenAttention(l0.self_attn, s.query_pe, s.query_pe, s.query_pe,
                               s.tokens);
    ops::LayerNormRows(s.queries.data(), s.tokens, kDim, kDim,
                       l0.norm1.g.data(), l0.norm1.b.data(), norm_eps_);
    first_row[p + 1] = first_row[p] + s.tokens;
  }
  {
    // The token-to-image attention of all the batch's tokens in one pass
    // over the image's keys and values (each row as alone).
    const int rows = first_row[n];
    std::vector<float> q(static_cast<size_t>(rows) * kCrossDim);
    for (size_t p = 0; p < n; ++p) {
      const State& s = states[p];
      const std::vector<float> qp =
          ApplyTokens(l0.t2i.q, Sum(s.queries, s.query_pe), s.tokens);
      std::copy(qp.begin(), qp.end(),
                q.begin() + static_cast<size_t>(first_row[p]) * kCrossDim);
    }
    for (float& x : q) x *= scale;
    std::vector<float> probs(static_cast<size_t>(rows) * im.tokens);
    std::vector<float> o(static_cast<size_t>(rows) * kCrossDim);
    for (int h = 0; h < heads_; ++h) {
      ops::Gemm(rows, im.tokens, dh, q.data() + h * dh, kCrossDim, 1,
                im.t2i_keys_t.data() + static_cast<size_t>(h * dh) * im.tokens,
                im.tokens, probs.data(), im.tokens, false);
      ops::SoftmaxRows(probs.data(), rows, im.tokens, im.tokens);
      ops::Gemm(rows, dh, im.tokens, probs.data(), im.tokens, 1,
                im.t2i_values.data() + static_cast<size_t>(h) * im.tokens * dh,
                dh, o.data() + h * dh, kCrossDim, false);
    }
    for (size_t p = 0; p < n; ++p) {
      State& s = states[p];
      const auto from =
          o.begin() + static_cast<ptrdiff_t>(first_row[p]) * kCrossDim;
      const std::vector<float> op(
          from, from + static_cast<ptrdiff_t>(s.tokens * kCrossDim));
      const std::vector<float> out = ApplyTokens(l0.t2i.o, op, s.tokens);
      ops::Add(s.queries.data(), s.queries.data(), out.data(), out.size());
      ops::LayerNormRows(s.queries.data(), s.tokens, kDim, kDim,
                         l0.norm2.g.data(), l0.norm2.b.data(), norm_eps_);
    }
  }
  // Layer 1's self-attention needs only the tokens: before the image side,
  // which takes layer 0's tokens and layer 1's.
  std::vector<std::vector<float>> layer0_tokens(n);
  for (size_t p = 0; p < n; ++p) {
    State& s = states[p];
    TokenMlpAndNorm(l0, &s.queries, s.tokens);
    layer0_tokens[p] = s.queries;
    const std::vector<float> q = Sum(s.queries, s.query_pe);
    const std::vector<float> out =
        TokenAttention(l1.self_attn, q, q, s.queries, s.tokens);
    ops::Add(s.queries.data(), s.queries.data(), out.data(), out.size());
    ops::LayerNormRows(s.queries.data(), s.tokens, kDim, kDim,
                       l1.norm1.g.data(), l1.norm1.b.data(), norm_eps_);
  }
  // The image sides: block by block, each block for every prompt in turn
  // (the image's arrays read once per block for the batch).
  {
    std::vector<FirstLayerWork> work;
    work.reserve(n);  // no moves: the right-hand sides point into them
    for (size_t p = 0; p < n; ++p) {
      work.emplace_back(*this, layer0_tokens[p], &states[p],
                        requests[p].out->second_layer.image_tokens.data());
    }
    for (int b0 = 0; b0 < im.tokens; b0 += kBlock) {
      for (FirstLayerWork& w : work) FirstLayerBlock(im, b0, &w);
    }
    for (FirstLayerWork& w : work) FirstLayerFinish(&w);
  }
  {
    std::vector<SecondLayerWork> work;
    work.reserve(n);
    for (size_t p = 0; p < n; ++p) {
      work.emplace_back(*this, &states[p], &requests[p].out->second_layer,
                        scratch.features[p].data());
    }
    for (int b0 = 0; b0 < im.tokens; b0 += kBlock) {
      for (SecondLayerWork& w : work) SecondLayerBlock(im, b0, &w);
    }
    for (SecondLayerWork& w : work) SecondLayerFinish(&w);
  }
  // The heads: IoU prediction and the mask tokens' hypernetworks.
  const auto mlp3 = [&](const Linear(&l)[3], const float* x) {
    std::vector<float> h(x, x + kDim);
    for (int i = 0; i < 3; ++i) {
      h = ApplyTokens(l[i], h, 1);
      if (i < 2) {
        for (float& v : h) v = std::max(v, 0.0f);
      }
    }
    return h;
  };
  for (size_t p = 0; p < n; ++p) {
    const State& s = states[p];
    Output* out = requests[p].out;
    const auto count = static_cast<float>(requests[p].points->size());
    const std::vector<float> iou = mlp3(iou_, s.queries.data());
    int best = 0;
    float best_score = -1e30f;
    for (int j = 0; j < 4; ++j) {
      const float score =
          iou[j] +
          (j == 0 ? (count - points_offset_) * first_mask_reweight_ : 0.0f);
      if (score > best_score) {
        best_score = score;
        best = j;
      }
    }
    out->predicted_iou = iou[best];
    out->mask_hyper = mlp3(
        hyper_[best], s.queries.data() + static_cast<size_t>(1 + best) * kDim);
    out->preview.resize(static_cast<size_t>(im.tokens));
    ops::RowDots(im.tokens, kPreviewDim, scratch.features[p].data(),
                 kPreviewDim, out->mask_hyper.data(), out->preview.data());
  }
}

}  // namespace semrec::segment
