#include "semrec/sam/kernel_ops.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "semrec/core/error.h"
#include "semrec/sam/kernel_simd.h"

namespace semrec::sam::kernel_ops {
namespace simd {
namespace {

// One MR x (NV * W) tile of C over the whole k.
// Where C starts: zero, C itself (accumulate) or init + bias (a residual
// and a bias folded into the product).
struct Start {
  bool accumulate = false;
  const float* init = nullptr;  // rows of ld_init, or null
  int64_t ld_init = 0;
  const float* bias = nullptr;  // per column, or null
};

template <int W, int MR, int NV>
SEMREC_INLINE void Tile(int k, const float* a, int64_t a_row, int64_t a_col,
                        const float* b, int64_t ldb, float* c, int64_t ldc,
                        const Start& start, int col) {
  F<W> s[MR][NV];
  // The start's kind once per tile, each a loop of its own (a branch per
  // element would stay in the unrolled loop).
  const float* init = start.init;
  const float* bias = start.bias != nullptr ? start.bias + col : nullptr;
  const float* from = init != nullptr    ? init + col
                      : start.accumulate ? c
                                         : nullptr;
  const int64_t ld_from = init != nullptr ? start.ld_init : ldc;
  if (from != nullptr) {
#pragma GCC unroll 8
    for (int i = 0; i < MR; ++i) {
#pragma GCC unroll 4
      for (int64_t j = 0; j < NV; ++j) {
        s[i][j] = Load<W>(from + i * ld_from + j * W);
      }
    }
  } else {
#pragma GCC unroll 8
    for (int i = 0; i < MR; ++i) {
#pragma GCC unroll 4
      for (int64_t j = 0; j < NV; ++j) s[i][j] = F<W>{};
    }
  }
  if (bias != nullptr) {
#pragma GCC unroll 8
    for (int i = 0; i < MR; ++i) {
#pragma GCC unroll 4
      for (int64_t j = 0; j < NV; ++j) s[i][j] += Load<W>(bias + j * W);
    }
  }
  for (int p = 0; p < k; ++p) {
    F<W> bv[NV];
#pragma GCC unroll 4
    for (int64_t j = 0; j < NV; ++j) bv[j] = Load<W>(b + p * ldb + j * W);
#pragma GCC unroll 8
    for (int i = 0; i < MR; ++i) {
      // A scalar times a vector broadcasts it (Splat's 0 + s would add).
      const float av = a[i * a_row + p * a_col];
#pragma GCC unroll 4
      for (int64_t j = 0; j < NV; ++j) s[i][j] += av * bv[j];
    }
  }
#pragma GCC unroll 8
  for (int i = 0; i < MR; ++i) {
#pragma GCC unroll 4
    for (int64_t j = 0; j < NV; ++j) Store<W>(c + i * ldc + j * W, s[i][j]);
  }
}

template <int W, int MR, int NV>
SEMREC_INLINE void Columns(int m, int k, const float* a, int64_t a_row,
                           int64_t a_col, const float* b, int64_t ldb, float* c,
                           int64_t ldc, const Start& start, int col) {
  static_assert(MR <= 8, "the remainder switch covers up to 7 rows");
  int i = 0;
  Start rows = start;
  for (; i + MR <= m; i += MR) {
    rows.init = start.init ? start.init + i * start.ld_init : nullptr;
    Tile<W, MR, NV>(k, a + i * a_row, a_row, a_col, b, ldb, c + i * ldc, ldc,
                    rows, col);
  }
  // The rows left, as one shorter tile (a prompt's 7 tokens read each
  // weight once, not 7 times).
  const float* ar = a + i * a_row;
  float* cr = c + i * ldc;
  rows.init = start.init ? start.init + i * start.ld_init : nullptr;
  switch (m - i) {
    case 0:
      break;
#define SEMREC_ROWS(R)                                                   \
  case R:                                                                \
    if constexpr ((R) < MR) {                                            \
      Tile<W, (R), NV>(k, ar, a_row, a_col, b, ldb, cr, ldc, rows, col); \
    }                                                                    \
    break;
      SEMREC_ROWS(1)
      SEMREC_ROWS(2)
      SEMREC_ROWS(3)
      SEMREC_ROWS(4)
      SEMREC_ROWS(5)
      SEMREC_ROWS(6)
      SEMREC_ROWS(7)
#undef SEMREC_ROWS
    default:
      break;
  }
}

template <int W, int MR, int NV>
SEMREC_INLINE void GemmT(int m, int n, int k, const float* a, int64_t a_row,
                         int64_t a_col, const float* b, int64_t ldb, float* c,
                         int64_t ldc, const Start& start) {
  int j = 0;
  for (; j + NV * W <= n; j += NV * W) {
    Columns<W, MR, NV>(m, k, a, a_row, a_col, b + j, ldb, c + j, ldc, start, j);
  }
  for (; j + W <= n; j += W) {
    Columns<W, MR, 1>(m, k, a, a_row, a_col, b + j, ldb, c + j, ldc, start, j);
  }
  // Half a vector (8 of AVX-512's 16: a prompt's 7 tokens x 8 heads = 56).
  if constexpr (W >= 8) {
    if (j + W / 2 <= n) {
      Columns<W / 2, MR, 1>(m, k, a, a_row, a_col, b + j, ldb, c + j, ldc,
                            start, j);
      j += W / 2;
    }
  }
  for (; j < n; ++j) {
    for (int i = 0; i < m; ++i) {
      float s = start.init != nullptr
                    ? start.init[i * start.ld_init + j] + start.bias[j]
                : start.bias != nullptr ? start.bias[j]
                : start.accumulate      ? c[i * ldc + j]
                                        : 0.0f;
      for (int p = 0; p < k; ++p) {
        s += a[i * a_row + p * a_col] * b[p * ldb + j];
      }
      c[i * ldc + j] = s;
    }
  }
}

struct Ops {
  const char* name;
  void (*gemm)(int, int, int, const float*, int64_t, int64_t, const float*,
               int64_t, float*, int64_t, const Start&);
  void (*add)(float*, const float*, const float*, size_t);
  void (*layer_norm)(float*, int, int, int64_t, const float*, const float*,
                     float, const float*, float*);
  void (*softmax_rows)(float*, int, int, int64_t);
  void (*softmax_heads)(float*, int, int64_t, int, const float*);
  bool (*online_softmax)(float*, int, int, int64_t, float*, float*, float*);
  void (*gelu)(float*, size_t);
  void (*exp)(float*, size_t);
  void (*row_dots)(int, int, const float*, int64_t, const float*, float*);
  void (*head_rows)(int, int, int, const float*, int64_t, const float*, int64_t,
                    int, float*, int64_t);
  void (*head_columns)(int, int, int, int, const float*, int64_t, const float*,
                       int64_t, float*, int64_t);
};

// TARGET is an attribute: it cannot be parenthesised.
// NOLINTBEGIN(bugprone-macro-parentheses)
#define SEMREC_OPS(SUFFIX, TARGET, W, MR, NV)                                  \
  TARGET void Gemm##SUFFIX(int m, int n, int k, const float* a, int64_t a_row, \
                           int64_t a_col, const float* b, int64_t ldb,         \
                           float* c, int64_t ldc, const Start& start) {        \
    GemmT<(W), (MR), (NV)>(m, n, k, a, a_row, a_col, b, ldb, c, ldc, start);   \
  }                                                                            \
  TARGET void Add##SUFFIX(float* out, const float* a, const float* b,          \
                          size_t n) {                                          \
    AddT<(W)>(out, a, b, n);                                                   \
  }                                                                            \
  TARGET void LayerNorm##SUFFIX(float* x, int rows, int cols, int64_t ld,      \
                                const float* g, const float* beta, float eps,  \
                                const float* add, float* out_add) {            \
    LayerNormRowsT<(W)>(x, rows, cols, ld, g, beta, eps, add, out_add);        \
  }                                                                            \
  TARGET void SoftmaxRows##SUFFIX(float* s, int rows, int cols, int64_t ld) {  \
    SoftmaxRowsT<(W)>(s, rows, cols, ld);                                      \
  }                                                                            \
  TARGET void SoftmaxHeads##SUFFIX(float* s, int rows, int64_t ld, int tokens, \
                                   const float* bias) {                        \
    SoftmaxHeadsT<(W)>(s, rows, ld, tokens, bias);                             \
  }                                                                            \
  TARGET bool OnlineSoftmax##SUFFIX(float* s, int rows, int cols, int64_t ld,  \
                                    float* max, float* sum, float* rescale) {  \
    return OnlineSoftmaxColumnsT<(W)>(s, rows, cols, ld, max, sum, rescale);   \
  }                                                                            \
  TARGET void Gelu##SUFFIX(float* x, size_t n) { GeluT<(W)>(x, n); }           \
  TARGET void HeadRows##SUFFIX(int tokens, int heads, int dh, const float* x,  \
                               int64_t ldx, const float* w, int64_t ldw,       \
                               int n, float* out, int64_t ldo) {               \
    HeadRowsProductT<(W)>(tokens, heads, dh, x, ldx, w, ldw, n, out, ldo);     \
  }                                                                            \
  TARGET void HeadColumns##SUFFIX(int tokens, int heads, int dh, int k,        \
                                  const float* a, int64_t lda, const float* w, \
                                  int64_t ldw, float* out, int64_t ldo) {      \
    HeadColumnsProductT<(W)>(tokens, heads, dh, k, a, lda, w, ldw, out, ldo);  \
  }                                                                            \
  TARGET void RowDots##SUFFIX(int m, int k, const float* a, int64_t lda,       \
                              const float* x, float* out) {                    \
    RowDotsT<(W)>(m, k, a, lda, x, out);                                       \
  }                                                                            \
  TARGET void Exp##SUFFIX(float* x, size_t n) { ExpT<(W)>(x, n); }             \
  constexpr Ops kOps##SUFFIX = {#SUFFIX,                                       \
                                Gemm##SUFFIX,                                  \
                                Add##SUFFIX,                                   \
                                LayerNorm##SUFFIX,                             \
                                SoftmaxRows##SUFFIX,                           \
                                SoftmaxHeads##SUFFIX,                          \
                                OnlineSoftmax##SUFFIX,                         \
                                Gelu##SUFFIX,                                  \
                                Exp##SUFFIX,                                   \
                                RowDots##SUFFIX,                               \
                                HeadRows##SUFFIX,                              \
                                HeadColumns##SUFFIX};
// NOLINTEND(bugprone-macro-parentheses)

#if defined(__x86_64__)
// AVX-512: 8 x 32 tiles (16 accumulators of 32 registers).
SEMREC_OPS(avx512, __attribute__((target("avx512f,avx512vl,avx512dq,fma"))), 16,
           8, 2)
// AVX2: 4 x 16 tiles (8 accumulators of 16 registers).
SEMREC_OPS(avx2, __attribute__((target("avx2,fma"))), 8, 6, 2)
#endif
SEMREC_OPS(baseline, , 4, 4, 2)

std::vector<const Ops*> Supported() {
  std::vector<const Ops*> levels;
#if defined(__x86_64__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("fma")) {
    levels.push_back(&kOpsavx512);
  }
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    levels.push_back(&kOpsavx2);
  }
#endif
  levels.push_back(&kOpsbaseline);
  return levels;
}

std::atomic<const Ops*> g_ops{nullptr};

// The best set, or the one SEMREC_KERNEL_ISA names (for measuring one
// against another; an unsupported name is ignored).
const Ops* Initial() {
  const std::vector<const Ops*> levels = Supported();
  if (const char* wanted = std::getenv("SEMREC_KERNEL_ISA")) {
    for (const Ops* ops : levels) {
      if (std::strcmp(ops->name, wanted) == 0) return ops;
    }
  }
  return levels.front();
}

const Ops& Current() {
  const Ops* ops = g_ops.load(std::memory_order_acquire);
  if (ops == nullptr) {
    ops = Initial();
    g_ops.store(ops, std::memory_order_release);
  }
  return *ops;
}

}  // namespace
}  // namespace simd

using simd::Current;
using simd::g_ops;
using simd::Ops;
using simd::Start;
using simd::Supported;

const char* SimdLevel() { return Current().name; }

std::vector<std::string> SupportedLevels() {
  std::vector<std::string> names;
  for (const Ops* ops : Supported()) names.emplace_back(ops->name);
  return names;
}

void UseLevel(const std::string& level) {
  for (const Ops* ops : Supported()) {
    if (level.empty() || level == ops->name) {
      g_ops.store(ops, std::memory_order_release);
      return;
    }
  }
  throw InvalidArgument("decoder kernel: instruction set '" + level +
                        "' is not supported by this CPU");
}

void Gemm(int m, int n, int k, const float* a, int64_t a_row, int64_t a_col,
          const float* b, int64_t ldb, float* c, int64_t ldc, bool accumulate) {
  if (m <= 0 || n <= 0) return;
  Start start;
  start.accumulate = accumulate;
  Current().gemm(m, n, k, a, a_row, a_col, b, ldb, c, ldc, start);
}

void GemmOnto(int m, int n, int k, const float* a, int64_t a_row, int64_t a_col,
              const float* b, int64_t ldb, float* c, int64_t ldc,
              const float* init, int64_t ld_init, const float* bias) {
  if (m <= 0 || n <= 0) return;
  Start start;
  start.init = init;
  start.ld_init = ld_init;
  start.bias = bias;
  Current().gemm(m, n, k, a, a_row, a_col, b, ldb, c, ldc, start);
}

void Add(float* out, const float* a, const float* b, size_t n) {
  Current().add(out, a, b, n);
}

void LayerNormRows(float* x, int rows, int cols, int64_t ld, const float* g,
                   const float* beta, float eps, const float* add,
                   float* out_add) {
  Current().layer_norm(x, rows, cols, ld, g, beta, eps, add, out_add);
}

void SoftmaxRows(float* s, int rows, int cols, int64_t ld) {
  Current().softmax_rows(s, rows, cols, ld);
}

void SoftmaxHeads(float* s, int rows, int64_t ld, int tokens,
                  const float* bias) {
  Current().softmax_heads(s, rows, ld, tokens, bias);
}

bool OnlineSoftmaxColumns(float* s, int rows, int cols, int64_t ld, float* max,
                          float* sum, float* rescale) {
  return Current().online_softmax(s, rows, cols, ld, max, sum, rescale);
}

void Gelu(float* x, size_t n) { Current().gelu(x, n); }

void Exp(float* x, size_t n) { Current().exp(x, n); }

void RowDots(int m, int k, const float* a, int64_t lda, const float* x,
             float* out) {
  Current().row_dots(m, k, a, lda, x, out);
}

void HeadRowsProduct(int tokens, int heads, int dh, const float* x, int64_t ldx,
                     const float* w, int64_t ldw, int n, float* out,
                     int64_t ldo) {
  Current().head_rows(tokens, heads, dh, x, ldx, w, ldw, n, out, ldo);
}

void HeadColumnsProduct(int tokens, int heads, int dh, int k, const float* a,
                        int64_t lda, const float* w, int64_t ldw, float* out,
                        int64_t ldo) {
  Current().head_columns(tokens, heads, dh, k, a, lda, w, ldw, out, ldo);
}

}  // namespace semrec::sam::kernel_ops
