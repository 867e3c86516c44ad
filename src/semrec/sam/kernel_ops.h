// The few dense float operations SAM's decoder kernel (sam/kernel.h) is made
// of, each compiled for AVX-512, AVX2 + FMA and baseline x86-64 and chosen
// once at run time for the CPU (the build targets baseline x86-64, where
// they run several times slower). Row-major matrices with explicit strides.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace semrec::sam::kernel_ops {

/// The instruction set in use: "avx512", "avx2" or "baseline".
const char* SimdLevel();
/// The instruction sets this CPU runs, best first (of "avx512", "avx2",
/// "baseline").
std::vector<std::string> SupportedLevels();
/// Uses `level` (one of SupportedLevels(): tests compare them), "" the best.
/// Throws InvalidArgument for another.
void UseLevel(const std::string& level);

/// C[m x n] (row stride ldc) = (accumulate ? C : 0) + A B, where A(i, p) is
/// a[i * a_row + p * a_col] (a transposed A: a_row = 1) and B is row-major
/// [k x n] with row stride ldb.
void Gemm(int m, int n, int k, const float* a, int64_t a_row, int64_t a_col,
          const float* b, int64_t ldb, float* c, int64_t ldc, bool accumulate);

/// Gemm onto a residual and a bias: C = init (rows of stride ld_init; null:
/// none) + bias (per column) + A B, in one pass.
void GemmOnto(int m, int n, int k, const float* a, int64_t a_row, int64_t a_col,
              const float* b, int64_t ldb, float* c, int64_t ldc,
              const float* init, int64_t ld_init, const float* bias);

/// out[i] = a[i] + b[i].
void Add(float* out, const float* a, const float* b, size_t n);

/// Each of `rows` rows of x (stride ld, `cols` values) becomes
/// LayerNorm(x) * g + beta (biased variance, as PyTorch / ONNX); with `add`,
/// out_add (same layout) = that + add, in the same pass.
void LayerNormRows(float* x, int rows, int cols, int64_t ld, const float* g,
                   const float* beta, float eps, const float* add = nullptr,
                   float* out_add = nullptr);

/// Each row of s (`cols` values, stride ld) becomes its softmax.
void SoftmaxRows(float* s, int rows, int cols, int64_t ld);

/// Attention weights of 8 heads over a prompt's tokens: each row of s
/// (stride ld) holds tokens x 8 scores, column t * 8 + h; with the bias
/// (tokens x 8 values, or null) added, each head's scores become a softmax
/// over the tokens. Columns past tokens x 8, up to a whole vector, may be
/// overwritten where ld leaves room.
void SoftmaxHeads(float* s, int rows, int64_t ld, int tokens,
                  const float* bias);

/// One block of a softmax over many rows, column by column (a column per
/// attention query): `max` and `sum` hold the running maximum and sum of
/// exp(s - max) of each of the `cols` columns over the blocks so far (start
/// with max -1e30, sum 0). s (rows x cols, stride ld) becomes exp(s - max).
/// The maximum moves only when a score exceeds it by more than 16 (exp of
/// up to e^16 stays far from float's range), so the caller seldom rescales:
/// returns whether it must, by `rescale[c]` = exp(old max - new max), what it
/// accumulated for column c. Columns past `cols`, up to a whole vector, may
/// be overwritten where ld leaves room.
bool OnlineSoftmaxColumns(float* s, int rows, int cols, int64_t ld, float* max,
                          float* sum, float* rescale);

/// x = GELU(x) = x / 2 (1 + erf(x / sqrt 2)) (erf to ~2e-7).
void Gelu(float* x, size_t n);

/// x = exp(x) (to ~2 ulp for the values softmax sees).
void Exp(float* x, size_t n);

/// out[i] = sum_c a[i * lda + c] x[c], i < m, c < k.
void RowDots(int m, int k, const float* a, int64_t lda, const float* x,
             float* out);

/// The product of a prompt's per-head rows with w: row t * heads + h of out
/// (j < n) = sum_{d < dh} x[t * ldx + h * dh + d] w[(h * dh + d) * ldw + j]
/// (Gemm of the block-diagonal matrix whose row t * heads + h holds token
/// t's head-h channels, without its zeros; the same sums).
void HeadRowsProduct(int tokens, int heads, int dh, const float* x, int64_t ldx,
                     const float* w, int64_t ldw, int n, float* out,
                     int64_t ldo);

/// Each row's own head of a product: out[t * ldo + h * dh + d] = sum_{p <
/// k} a[(t * heads + h) * lda + p] w[p * ldw + h * dh + d] (the columns of
/// Gemm(a, w) that an attention's per-head values keep).
void HeadColumnsProduct(int tokens, int heads, int dh, int k, const float* a,
                        int64_t lda, const float* w, int64_t ldw, float* out,
                        int64_t ldo);

/// Whether this CPU has bf16 dot products (AVX512_BF16), which the *Bf16
/// products below need.
bool HasBf16();

/// B [k x n] rounded to bf16 (to nearest even) and packed for GemmBf16:
/// rows in pairs, interleaved, so that one instruction multiplies two of A's
/// values by two of B's rows.
struct PackedB {
  std::vector<uint16_t> data;
  int k = 0, n = 0;
};
/// Packs b (row stride ldb). n must be a multiple of 16; throws
/// InvalidArgument otherwise or without HasBf16().
void PackBf16(int k, int n, const float* b, int64_t ldb, PackedB* out);

/// Gemm and GemmOnto with A and B rounded to bf16 (fp32 sums): twice the
/// multiply-adds per instruction, at bf16's 8-bit mantissa in the inputs.
/// b's k and n are the product's.
void GemmBf16(int m, const float* a, int64_t a_row, int64_t a_col,
              const PackedB& b, float* c, int64_t ldc, bool accumulate);
void GemmOntoBf16(int m, const float* a, int64_t a_row, int64_t a_col,
                  const PackedB& b, float* c, int64_t ldc, const float* init,
                  int64_t ld_init, const float* bias);

}  // namespace semrec::sam::kernel_ops
