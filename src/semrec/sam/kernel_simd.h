// The decoder kernel's vector code: templates over the vector width for
// kernel_ops.cc only (not part of the library's interface).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

// Each operation is one template over the vector width (GCC/Clang vector
// extensions), forced inline into a wrapper per instruction set that carries
// the target attribute: the wrapper's body is compiled for that set, and no
// out-of-line copy of shared code is (which the linker could pick for a CPU
// without it).
#define SEMREC_INLINE [[gnu::always_inline]] inline

namespace semrec::sam::kernel_ops::simd {

template <int W>
struct Lanes;
template <>
struct Lanes<16> {
  typedef float F __attribute__((vector_size(64)));
  typedef int32_t I __attribute__((vector_size(64)));
};
template <>
struct Lanes<8> {
  typedef float F __attribute__((vector_size(32)));
  typedef int32_t I __attribute__((vector_size(32)));
};
template <>
struct Lanes<4> {
  typedef float F __attribute__((vector_size(16)));
  typedef int32_t I __attribute__((vector_size(16)));
};

template <int W>
using F = typename Lanes<W>::F;
template <int W>
using I = typename Lanes<W>::I;

template <int W>
SEMREC_INLINE F<W> Load(const float* p) {
  F<W> v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <int W>
SEMREC_INLINE void Store(float* p, F<W> v) {
  // The analyzer follows the products from the dispatch table, whose callers
  // it cannot see, into a null output; none passes one.
  // NOLINTNEXTLINE(clang-analyzer-core.NonNullParamChecker)
  std::memcpy(p, &v, sizeof v);
}
template <int W>
SEMREC_INLINE F<W> Splat(float s) {
  return F<W>{} + s;
}
// Horizontal sum, halving the vector (not lane by lane).
template <int W>
SEMREC_INLINE float Sum(F<W> v) {
  if constexpr (W > 4) {
    F<W / 2> lo, hi;
    std::memcpy(&lo, &v, sizeof lo);
    std::memcpy(&hi, reinterpret_cast<const char*>(&v) + sizeof lo, sizeof hi);
    return Sum<W / 2>(lo + hi);
  } else {
    return (v[0] + v[2]) + (v[1] + v[3]);
  }
}
template <int W>
SEMREC_INLINE F<W> Max(F<W> a, F<W> b) {
  return a > b ? a : b;
}

// exp(x) as Cephes' expf: x = n ln 2 + r, |r| <= ln 2 / 2, a degree-6
// polynomial for exp(r), 2^n through the exponent bits.
template <int W>
SEMREC_INLINE F<W> ExpV(F<W> x) {
  x = Max<W>(x, Splat<W>(-87.3f));
  x = x < Splat<W>(88.3f) ? x : Splat<W>(88.3f);
  const F<W> t = x * 1.44269504088896341f + 0.5f;
  I<W> n = __builtin_convertvector(t, I<W>);
  n += (t < __builtin_convertvector(n, F<W>));  // floor: -1 where true
  const F<W> nf = __builtin_convertvector(n, F<W>);
  const F<W> r = x - nf * 0.693359375f + nf * 2.12194440e-4f;
  F<W> p = Splat<W>(1.9875691500e-4f);
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  const F<W> y = p * r * r + r + 1.0f;
  const I<W> bits = (n + 127) << 23;
  F<W> scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return y * scale;
}

// erf(x) after Abramowitz & Stegun 7.1.26 (absolute error <= 1.5e-7).
template <int W>
SEMREC_INLINE F<W> ErfV(F<W> x) {
  const F<W> a = x < 0.0f ? -x : x;
  const F<W> t = 1.0f / (1.0f + 0.3275911f * a);
  F<W> p = Splat<W>(1.061405429f);
  p = p * t - 1.453152027f;
  p = p * t + 1.421413741f;
  p = p * t - 0.284496736f;
  p = p * t + 0.254829592f;
  const F<W> y = 1.0f - p * t * ExpV<W>(-a * a);
  return x < 0.0f ? -y : y;
}
template <int W>
SEMREC_INLINE void AddT(float* out, const float* a, const float* b, size_t n) {
  size_t i = 0;
  for (; i + W <= n; i += W) Store<W>(out + i, Load<W>(a + i) + Load<W>(b + i));
  for (; i < n; ++i) out[i] = a[i] + b[i];
}

// out[i] = a's row i . x: a row's vectors into four partial sums, so the
// short rows (the mask features' 32) are not one chain of adds.
template <int W>
SEMREC_INLINE void RowDotsT(int m, int k, const float* a, int64_t lda,
                            const float* x, float* out) {
  for (int i = 0; i < m; ++i) {
    const float* row = a + i * lda;
    F<W> s0{}, s1{};
    int c = 0;
    for (; c + 2 * W <= k; c += 2 * W) {
      s0 += Load<W>(row + c) * Load<W>(x + c);
      s1 += Load<W>(row + c + W) * Load<W>(x + c + W);
    }
    for (; c + W <= k; c += W) s0 += Load<W>(row + c) * Load<W>(x + c);
    float tail = 0;
    for (; c < k; ++c) tail += row[c] * x[c];
    out[i] = Sum<W>(s0 + s1) + tail;
  }
}

// The products with a prompt's block-diagonal head matrices without their
// zeros (each head's dh channels only), each sum in the order a whole
// product takes it (the zero terms add nothing).
template <int W>
SEMREC_INLINE void HeadRowsProductT(int tokens, int heads, int dh,
                                    const float* x, int64_t ldx, const float* w,
                                    int64_t ldw, int n, float* out,
                                    int64_t ldo) {
  for (int64_t t = 0; t < tokens; ++t) {
    for (int64_t h = 0; h < heads; ++h) {
      const float* xr = x + t * ldx + h * dh;
      const float* wr = w + h * dh * ldw;
      float* o = out + (t * heads + h) * ldo;
      int j = 0;
      for (; j + W <= n; j += W) {
        F<W> acc{};
        for (int d = 0; d < dh; ++d) acc += xr[d] * Load<W>(wr + d * ldw + j);
        Store<W>(o + j, acc);
      }
      for (; j < n; ++j) {
        float acc = 0;
        for (int d = 0; d < dh; ++d) acc += xr[d] * wr[d * ldw + j];
        o[j] = acc;
      }
    }
  }
}

template <int W>
SEMREC_INLINE void HeadColumnsProductT(int tokens, int heads, int dh, int k,
                                       const float* a, int64_t lda,
                                       const float* w, int64_t ldw, float* out,
                                       int64_t ldo) {
  for (int64_t t = 0; t < tokens; ++t) {
    for (int64_t h = 0; h < heads; ++h) {
      const float* ar = a + (t * heads + h) * lda;
      float* o = out + t * ldo + h * dh;
      int d = 0;
      for (; d + W <= dh; d += W) {
        F<W> acc{};
        const float* wc = w + h * dh + d;
        for (int p = 0; p < k; ++p) acc += ar[p] * Load<W>(wc + p * ldw);
        Store<W>(o + d, acc);
      }
      for (; d < dh; ++d) {
        float acc = 0;
        for (int p = 0; p < k; ++p) acc += ar[p] * w[p * ldw + h * dh + d];
        o[d] = acc;
      }
    }
  }
}

template <int W>
SEMREC_INLINE void SubT(float* out, const float* a, const float* b, size_t n) {
  size_t i = 0;
  for (; i + W <= n; i += W) Store<W>(out + i, Load<W>(a + i) - Load<W>(b + i));
  for (; i < n; ++i) out[i] = a[i] - b[i];
}

template <int W>
SEMREC_INLINE void LayerNormRowsT(float* x, int rows, int cols, int64_t ld,
                                  const float* g, const float* beta, float eps,
                                  const float* add, float* out_add) {
  // Four partial sums per pass: one would chain every vector's add on the
  // last (the rows are short: latency, not throughput, bounds them).
  constexpr int64_t w = W;
  for (int r = 0; r < rows; ++r) {
    float* row = x + r * ld;
    F<W> a0{}, a1{}, a2{}, a3{};
    int c = 0;
    float tail = 0;
    for (; c + 4 * W <= cols; c += 4 * W) {
      a0 += Load<W>(row + c);
      a1 += Load<W>(row + c + W);
      a2 += Load<W>(row + c + 2 * w);
      a3 += Load<W>(row + c + 3 * w);
    }
    for (; c + W <= cols; c += W) a0 += Load<W>(row + c);
    for (; c < cols; ++c) tail += row[c];
    const float mean =
        (Sum<W>((a0 + a1) + (a2 + a3)) + tail) / static_cast<float>(cols);
    const F<W> mv = Splat<W>(mean);
    a0 = a1 = a2 = a3 = F<W>{};
    tail = 0;
    for (c = 0; c + 4 * W <= cols; c += 4 * W) {
      const F<W> d0 = Load<W>(row + c) - mv, d1 = Load<W>(row + c + W) - mv;
      const F<W> d2 = Load<W>(row + c + 2 * w) - mv;
      const F<W> d3 = Load<W>(row + c + 3 * w) - mv;
      a0 += d0 * d0;
      a1 += d1 * d1;
      a2 += d2 * d2;
      a3 += d3 * d3;
    }
    for (; c + W <= cols; c += W) {
      const F<W> d = Load<W>(row + c) - mv;
      a0 += d * d;
    }
    for (; c < cols; ++c) tail += (row[c] - mean) * (row[c] - mean);
    const float inv = 1.0f / std::sqrt((Sum<W>((a0 + a1) + (a2 + a3)) + tail) /
                                           static_cast<float>(cols) +
                                       eps);
    const F<W> iv = Splat<W>(inv);
    if (add != nullptr) {
      const float* in = add + r * ld;
      float* out = out_add + r * ld;
      for (c = 0; c + W <= cols; c += W) {
        const F<W> y =
            (Load<W>(row + c) - mv) * iv * Load<W>(g + c) + Load<W>(beta + c);
        Store<W>(row + c, y);
        Store<W>(out + c, y + Load<W>(in + c));
      }
    } else {
      for (c = 0; c + W <= cols; c += W) {
        Store<W>(row + c, (Load<W>(row + c) - mv) * iv * Load<W>(g + c) +
                              Load<W>(beta + c));
      }
    }
    for (; c < cols; ++c) {
      row[c] = (row[c] - mean) * inv * g[c] + beta[c];
      if (add != nullptr) out_add[r * ld + c] = row[c] + add[r * ld + c];
    }
  }
}

// x = op(x), whole vectors and the tail through a padded one. (The op is a
// template argument, not a lambda: a lambda would be compiled without the
// target attribute.)
template <int W, F<W> (*Op)(F<W>)>
SEMREC_INLINE void MapT(float* x, size_t n) {
  size_t i = 0;
  for (; i + W <= n; i += W) Store<W>(x + i, Op(Load<W>(x + i)));
  if (i < n) {
    float buf[W] = {};
    std::copy(x + i, x + n, buf);
    Store<W>(buf, Op(Load<W>(buf)));
    std::copy(buf, buf + (n - i), x + i);
  }
}

template <int W>
SEMREC_INLINE void ExpT(float* x, size_t n) {
  MapT<W, ExpV<W>>(x, n);
}

template <int W>
SEMREC_INLINE F<W> GeluV(F<W> v) {
  return v * 0.5f * (1.0f + ErfV<W>(v * 0.70710678118654752f));
}

template <int W>
SEMREC_INLINE void GeluT(float* x, size_t n) {
  MapT<W, GeluV<W>>(x, n);
}

template <int W>
SEMREC_INLINE void SoftmaxRowsT(float* s, int rows, int cols, int64_t ld) {
  for (int r = 0; r < rows; ++r) {
    float* row = s + r * ld;
    F<W> mv = Splat<W>(-1e30f);
    int c = 0;
    for (; c + W <= cols; c += W) mv = Max<W>(mv, Load<W>(row + c));
    float m = -1e30f;
    for (int i = 0; i < W; ++i) m = std::max(m, mv[i]);
    for (; c < cols; ++c) m = std::max(m, row[c]);
    const F<W> msplat = Splat<W>(m);
    for (c = 0; c + W <= cols; c += W) {
      Store<W>(row + c, Load<W>(row + c) - msplat);
    }
    for (; c < cols; ++c) row[c] -= m;
    ExpT<W>(row, static_cast<size_t>(cols));
    F<W> sv{};
    float tail = 0;
    for (c = 0; c + W <= cols; c += W) sv += Load<W>(row + c);
    for (; c < cols; ++c) tail += row[c];
    const float inv = 1.0f / (Sum<W>(sv) + tail);
    for (c = 0; c + W <= cols; c += W) {
      Store<W>(row + c, Load<W>(row + c) * inv);
    }
    for (; c < cols; ++c) row[c] *= inv;
  }
}

template <int W>
SEMREC_INLINE void SoftmaxHeadsT(float* s, int rows, int64_t ld, int tokens,
                                 const float* bias) {
  const size_t cols = static_cast<size_t>(tokens) * 8;
  // exp over whole vectors where the row stride leaves room (the padding's
  // values are overwritten): no tail.
  const size_t whole = (cols + W - 1) / W * W;
  const size_t exp_cols = whole <= static_cast<size_t>(ld) ? whole : cols;
  for (int r = 0; r < rows; ++r) {
    float* row = s + r * ld;
    if (bias != nullptr) AddT<W>(row, row, bias, cols);
    F<8> m = Load<8>(row);
    for (int64_t t = 1; t < tokens; ++t) m = Max<8>(m, Load<8>(row + t * 8));
    for (int64_t t = 0; t < tokens; ++t) {
      Store<8>(row + t * 8, Load<8>(row + t * 8) - m);
    }
    ExpT<W>(row, exp_cols);
    F<8> sum = Load<8>(row);
    for (int64_t t = 1; t < tokens; ++t) sum += Load<8>(row + t * 8);
    const F<8> inv = 1.0f / sum;
    for (int64_t t = 0; t < tokens; ++t) {
      Store<8>(row + t * 8, Load<8>(row + t * 8) * inv);
    }
  }
}

// The first n (< W) lanes through a zeroed buffer: a row's last vector where
// the row stride leaves no room for a whole one.
template <int W>
SEMREC_INLINE F<W> LoadPart(const float* p, int n) {
  float buf[W] = {};
  std::copy(p, p + n, buf);
  return Load<W>(buf);
}
template <int W>
SEMREC_INLINE void StorePart(float* p, F<W> v, int n) {
  float buf[W];
  Store<W>(buf, v);
  std::copy(buf, buf + n, p);
}

// OnlineSoftmaxColumns on up to 256 columns (`room` of them writable in each
// row): the columns' state in registers; the last vector whole when the row
// leaves room for it (the kernel's 56 head columns in rows of 64), else
// through a buffer. rescale is written for every column (1 where the
// maximum stayed).
template <int W>
SEMREC_INLINE bool OnlineSoftmaxChunk(float* s, int rows, int cols,
                                      int64_t room, int64_t ld, float* max,
                                      float* sum, float* rescale) {
  constexpr float kSlack = 16.0f;
  constexpr int kMaxVectors = 256 / W;
  const int64_t nv = (cols + W - 1) / W;
  // Lanes of the last vector read and written (all W where there is room).
  const int last = static_cast<int>(nv * W <= room ? W : cols - (nv - 1) * W);
  float m_pad[256], s_pad[256], r_pad[256];
  std::copy(max, max + cols, m_pad);
  std::copy(sum, sum + cols, s_pad);
  std::fill(m_pad + cols, m_pad + nv * W, 0.0f);
  std::fill(s_pad + cols, s_pad + nv * W, 0.0f);
  F<W> block[kMaxVectors];
  for (int64_t v = 0; v < nv; ++v) block[v] = Splat<W>(-1e30f);
  for (int r = 0; r < rows; ++r) {
    const float* row = s + r * ld;
    for (int64_t v = 0; v < nv; ++v) {
      const F<W> x = v + 1 < nv || last == W ? Load<W>(row + v * W)
                                             : LoadPart<W>(row + v * W, last);
      block[v] = Max<W>(block[v], x);
    }
  }
  // Padding lanes never move (their block maximum is below any slack).
  for (int64_t c = cols; c < nv * W; ++c) block[c / W][c % W] = -1e30f;
  bool moved = false;
  F<W> m[kMaxVectors];
  for (int64_t v = 0; v < nv; ++v) {
    const F<W> old = Load<W>(m_pad + v * W);
    const I<W> move = (block[v] > old + kSlack) | (old <= -1e29f);
    for (int i = 0; i < W; ++i) moved = moved || move[i] != 0;
    m[v] = move ? block[v] : old;
    Store<W>(r_pad + v * W, move ? old - block[v] : Splat<W>(0.0f));
  }
  F<W> acc[kMaxVectors];
  for (int64_t v = 0; v < nv; ++v) acc[v] = F<W>{};
  for (int r = 0; r < rows; ++r) {
    float* row = s + r * ld;
    for (int64_t v = 0; v < nv; ++v) {
      const bool whole = v + 1 < nv || last == W;
      const F<W> x =
          whole ? Load<W>(row + v * W) : LoadPart<W>(row + v * W, last);
      // (Padding lanes sum into lanes past `cols`, which are not kept.)
      const F<W> e = ExpV<W>(x - m[v]);
      if (whole) {
        Store<W>(row + v * W, e);
      } else {
        StorePart<W>(row + v * W, e, last);
      }
      acc[v] += e;
    }
  }
  // exp(0) = 1 exactly: where the maximum stayed the sum is unchanged.
  for (int64_t v = 0; v < nv; ++v) {
    const F<W> resc = ExpV<W>(Load<W>(r_pad + v * W));
    Store<W>(s_pad + v * W, Load<W>(s_pad + v * W) * resc + acc[v]);
    Store<W>(r_pad + v * W, resc);
    Store<W>(m_pad + v * W, m[v]);
  }
  std::copy(m_pad, m_pad + cols, max);
  std::copy(s_pad, s_pad + cols, sum);
  std::copy(r_pad, r_pad + cols, rescale);
  return moved;
}

template <int W>
SEMREC_INLINE bool OnlineSoftmaxColumnsT(float* s, int rows, int cols,
                                         int64_t ld, float* max, float* sum,
                                         float* rescale) {
  bool moved = false;
  for (int c0 = 0; c0 < cols; c0 += 256) {
    moved |=
        OnlineSoftmaxChunk<W>(s + c0, rows, std::min(256, cols - c0), ld - c0,
                              ld, max + c0, sum + c0, rescale + c0);
  }
  return moved;
}

// The operations of one instruction set.
}  // namespace semrec::sam::kernel_ops::simd
