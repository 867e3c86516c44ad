#include "semrec/sam/kernel.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>

#include "semrec/core/error.h"
#include "semrec/sam/kernel_internal.h"
#include "semrec/sam/kernel_ops.h"

namespace semrec::sam {

namespace ops = kernel_ops;
using kernel_detail::Padded;
using kernel_detail::Sum;

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

void SamKernel::Product(int m, const float* a, int64_t a_row, int64_t a_col,
                        const Rhs& b, float* c, int64_t ldc,
                        bool accumulate) const {
  if (precision_ == Precision::kBf16) {
    ops::GemmBf16(m, a, a_row, a_col, b.packed, c, ldc, accumulate);
  } else {
    ops::Gemm(m, b.n, b.k, a, a_row, a_col, b.w, b.n, c, ldc, accumulate);
  }
}

void SamKernel::ProductOnto(int m, const float* a, int64_t a_row, int64_t a_col,
                            const Rhs& b, float* c, int64_t ldc,
                            const float* init, int64_t ld_init,
                            const float* bias) const {
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
    ops::Add(e, e,
             point_embeddings_.data() + static_cast<int64_t>(label) * kDim,
             kDim);
  }
}

void SamKernel::FirstLayerTokens(const Image& im,
                                 std::vector<State>* states) const {
  const size_t n = states->size();
  const int dh = kCrossDim / heads_;
  const float scale = CrossScale();
  const Layer& l0 = layers_[0];
  // Its first self-attention has no positional encoding and no residual.
  std::vector<int> first_row(n + 1, 0);
  for (size_t p = 0; p < n; ++p) {
    State& s = (*states)[p];
    s.queries = TokenAttention(l0.self_attn, s.query_pe, s.query_pe, s.query_pe,
                               s.tokens);
    ops::LayerNormRows(s.queries.data(), s.tokens, kDim, kDim,
                       l0.norm1.g.data(), l0.norm1.b.data(), norm_eps_);
    first_row[p + 1] = first_row[p] + s.tokens;
  }
  // The token-to-image attention of all the batch's tokens in one pass over
  // the image's keys and values (each row as alone).
  const int rows = first_row[n];
  std::vector<float> q(static_cast<size_t>(rows) * kCrossDim);
  for (size_t p = 0; p < n; ++p) {
    const State& s = (*states)[p];
    const std::vector<float> qp =
        ApplyTokens(l0.t2i.q, Sum(s.queries, s.query_pe), s.tokens);
    std::copy(qp.begin(), qp.end(),
              q.begin() + static_cast<size_t>(first_row[p]) * kCrossDim);
  }
  for (float& x : q) x *= scale;
  std::vector<float> probs(static_cast<size_t>(rows) * im.tokens);
  std::vector<float> o(static_cast<size_t>(rows) * kCrossDim);
  for (int h = 0; h < heads_; ++h) {
    ops::Gemm(rows, im.tokens, dh, q.data() + static_cast<int64_t>(h) * dh,
              kCrossDim, 1,
              im.t2i_keys_t.data() + static_cast<size_t>(h * dh) * im.tokens,
              im.tokens, probs.data(), im.tokens, false);
    ops::SoftmaxRows(probs.data(), rows, im.tokens, im.tokens);
    ops::Gemm(rows, dh, im.tokens, probs.data(), im.tokens, 1,
              im.t2i_values.data() + static_cast<size_t>(h) * im.tokens * dh,
              dh, o.data() + static_cast<int64_t>(h) * dh, kCrossDim, false);
  }
  for (size_t p = 0; p < n; ++p) {
    State& s = (*states)[p];
    const auto from =
        o.begin() + static_cast<ptrdiff_t>(first_row[p]) * kCrossDim;
    const std::vector<float> op(
        from, from + static_cast<ptrdiff_t>(s.tokens) * kCrossDim);
    const std::vector<float> out = ApplyTokens(l0.t2i.o, op, s.tokens);
    ops::Add(s.queries.data(), s.queries.data(), out.data(), out.size());
    ops::LayerNormRows(s.queries.data(), s.tokens, kDim, kDim,
                       l0.norm2.g.data(), l0.norm2.b.data(), norm_eps_);
  }
}

void SamKernel::ImageSides(const Image& im,
                           const std::vector<Request>& requests,
                           const std::vector<std::vector<float>>& layer0_tokens,
                           std::vector<State>* states, Scratch* scratch) const {
  const size_t n = requests.size();
  {
    std::vector<FirstLayerWork> work;
    work.reserve(n);  // no moves: the right-hand sides point into them
    for (size_t p = 0; p < n; ++p) {
      work.emplace_back(*this, layer0_tokens[p], &(*states)[p],
                        requests[p].out->second_layer.image_tokens.data());
    }
    for (int b0 = 0; b0 < im.tokens; b0 += kBlock) {
      for (FirstLayerWork& w : work) FirstLayerBlock(im, b0, &w);
    }
    for (FirstLayerWork& w : work) FirstLayerFinish(&w);
  }
  std::vector<SecondLayerWork> work;
  work.reserve(n);
  for (size_t p = 0; p < n; ++p) {
    work.emplace_back(*this, &(*states)[p], &requests[p].out->second_layer,
                      scratch->features[p].data());
  }
  for (int b0 = 0; b0 < im.tokens; b0 += kBlock) {
    for (SecondLayerWork& w : work) SecondLayerBlock(im, b0, &w);
  }
  for (SecondLayerWork& w : work) SecondLayerFinish(&w);
}

void SamKernel::Heads(const Image& im, const std::vector<Request>& requests,
                      const std::vector<State>& states,
                      const Scratch& scratch) const {
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
  for (size_t p = 0; p < requests.size(); ++p) {
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
  // Layer 0, token side.
  FirstLayerTokens(im, &states);
  // Layer 1's self-attention needs only the tokens: before the image side,
  // which takes layer 0's tokens and layer 1's.
  const Layer& l0 = layers_[0];
  const Layer& l1 = layers_[1];
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
  ImageSides(im, requests, layer0_tokens, &states, &scratch);
  // The heads: IoU prediction and the mask tokens' hypernetworks.
  Heads(im, requests, states, scratch);
}

}  // namespace semrec::sam
