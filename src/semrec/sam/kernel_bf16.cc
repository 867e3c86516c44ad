// The decoder kernel's products with bf16 inputs (AVX512_BF16: VDPBF16PS
// multiplies pairs of bf16 values and adds them to fp32 sums, twice the
// multiply-adds per instruction of fp32 FMA). Compiled for that instruction
// set only and reachable only where the CPU has it: a PackedB comes only
// from PackBf16, which checks HasBf16(), and the products of an empty one
// return at once.
#include <immintrin.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "semrec/core/error.h"
#include "semrec/sam/kernel_ops.h"

#define SEMREC_BF16 \
  __attribute__((target("avx512f,avx512bw,avx512vl,avx512dq,avx512bf16")))

namespace semrec::sam::kernel_ops {
namespace {

// fp32 -> bf16, round to nearest even (as VCVTNEPS2BF16, except that it
// keeps denormals; no NaNs here).
uint16_t ToBf16(float x) {
  uint32_t u;
  std::memcpy(&u, &x, sizeof u);
  return static_cast<uint16_t>((u + 0x7fffu + ((u >> 16) & 1u)) >> 16);
}

// The interleaving of two rows' 16 bf16 values each ([row 0 | row 1], as
// VCVTNE2PS2BF16 leaves them) into 16 pairs.
SEMREC_BF16 __m512i Interleave(__m512bh both) {
  const __m512i order = _mm512_set_epi16(31, 15, 30, 14, 29, 13, 28, 12, 27, 11,
                                         26, 10, 25, 9, 24, 8, 23, 7, 22, 6, 21,
                                         5, 20, 4, 19, 3, 18, 2, 17, 1, 16, 0);
  return _mm512_permutexvar_epi16(order,
                                  reinterpret_cast<const __m512i&>(both));
}

// A [m x k] in bf16, each row's pair (p, p + 1) one 32-bit word, at
// data + i * row + (p / 2) * pair (in bf16 values). Row-major A: rows of kp
// = k rounded up to even (a zero pads an odd k); a transposed A (a_row = 1:
// the attention weights' columns) pair-major, [kp / 2 x mp x 2] with m
// rounded up to mp, a multiple of 16, packed a vector at a time from two of
// its rows.
struct PackedA {
  std::vector<uint16_t> data;
  int64_t row = 0, pair = 0;
};

SEMREC_BF16 void PackA(int m, int k, const float* a, int64_t a_row,
                       int64_t a_col, PackedA* out) {
  const int kp = (k + 1) & ~1;
  if (a_row == 1 && a_col != 1) {
    const int mp = (m + 15) & ~15;
    out->data.resize(static_cast<size_t>(mp) * kp);
    out->row = 2;
    out->pair = 2L * mp;
    for (int q = 0; q < kp / 2; ++q) {
      const float* r0 = a + (2 * static_cast<int64_t>(q)) * a_col;
      const bool odd_tail = 2 * q + 1 >= k;
      for (int i = 0; i < m; i += 16) {
        const auto mask =
            static_cast<__mmask16>(m - i >= 16 ? 0xffff : (1u << (m - i)) - 1);
        const __m512 lo = _mm512_maskz_loadu_ps(mask, r0 + i);
        const __m512 hi = odd_tail
                              ? _mm512_setzero_ps()
                              : _mm512_maskz_loadu_ps(mask, r0 + a_col + i);
        _mm512_storeu_si512(
            out->data.data() + (static_cast<size_t>(q) * mp + i) * 2,
            Interleave(_mm512_cvtne2ps_pbh(hi, lo)));
      }
    }
    return;
  }
  out->data.resize(static_cast<size_t>(m) * kp);
  out->row = kp;
  out->pair = 2;
  uint16_t* o = out->data.data();
  for (int i = 0; i < m; ++i) {
    const float* row = a + i * a_row;
    uint16_t* orow = o + static_cast<size_t>(i) * kp;
    if (a_col == 1) {
      // 32 at a time, the tail through masks (a prompt's 56 head columns).
      for (int p = 0; p < k; p += 32) {
        const int left = k - p;
        const auto lo_mask =
            static_cast<__mmask16>(left >= 16 ? 0xffff : (1u << left) - 1);
        const auto hi_mask =
            static_cast<__mmask16>(left >= 32   ? 0xffff
                                   : left <= 16 ? 0
                                                : (1u << (left - 16)) - 1);
        const __m512bh v =
            _mm512_cvtne2ps_pbh(_mm512_maskz_loadu_ps(hi_mask, row + p + 16),
                                _mm512_maskz_loadu_ps(lo_mask, row + p));
        const auto store_mask =
            static_cast<__mmask32>(left >= 32 ? 0xffffffffu : (1u << left) - 1);
        _mm512_mask_storeu_epi16(orow + p, store_mask,
                                 reinterpret_cast<const __m512i&>(v));
      }
    } else {
      for (int p = 0; p < k; ++p) orow[p] = ToBf16(row[p * a_col]);
    }
    if (kp != k) orow[k] = 0;
  }
}

template <int MR, int NV>
SEMREC_BF16 [[gnu::always_inline]] inline void TileBf16(
    int kp, const uint16_t* a, int64_t a_rs, int64_t a_ps, const uint16_t* b,
    int n, float* c, int64_t ldc, const float* init, int64_t ld_init,
    const float* bias, bool accumulate) {
  __m512 s[MR][NV];
  const float* from = init != nullptr ? init : accumulate ? c : nullptr;
  const int64_t ld_from = init != nullptr ? ld_init : ldc;
  for (int i = 0; i < MR; ++i) {
    for (int64_t j = 0; j < NV; ++j) {
      s[i][j] = from != nullptr ? _mm512_loadu_ps(from + i * ld_from + j * 16)
                                : _mm512_setzero_ps();
      if (bias != nullptr) {
        s[i][j] = _mm512_add_ps(s[i][j], _mm512_loadu_ps(bias + j * 16));
      }
    }
  }
  for (int q = 0; q < kp / 2; ++q) {
    __m512bh bv[NV];
#pragma GCC unroll 4
    for (int64_t j = 0; j < NV; ++j) {
      const __m512i v =
          _mm512_loadu_si512(b + (static_cast<int64_t>(q) * n + j * 16) * 2);
      bv[j] = reinterpret_cast<const __m512bh&>(v);
    }
    const uint16_t* aq = a + q * a_ps;
#pragma GCC unroll 8
    for (int i = 0; i < MR; ++i) {
      uint32_t pair;
      std::memcpy(&pair, aq + i * a_rs, 4);
      const __m512i av = _mm512_set1_epi32(static_cast<int>(pair));
#pragma GCC unroll 4
      for (int64_t j = 0; j < NV; ++j) {
        s[i][j] = _mm512_dpbf16_ps(
            s[i][j], reinterpret_cast<const __m512bh&>(av), bv[j]);
      }
    }
  }
  for (int i = 0; i < MR; ++i) {
    for (int64_t j = 0; j < NV; ++j) {
      _mm512_storeu_ps(c + i * ldc + j * 16, s[i][j]);
    }
  }
}

template <int NV>
SEMREC_BF16 [[gnu::always_inline]] inline void ColumnsBf16(
    int m, int kp, const PackedA& a, const uint16_t* b, int n, float* c,
    int64_t ldc, const float* init, int64_t ld_init, const float* bias,
    bool accumulate) {
  int i = 0;
  for (; i + 8 <= m; i += 8) {
    TileBf16<8, NV>(kp, a.data.data() + i * a.row, a.row, a.pair, b, n,
                    c + i * ldc, ldc, init ? init + i * ld_init : nullptr,
                    ld_init, bias, accumulate);
  }
  const uint16_t* ar = a.data.data() + i * a.row;
  float* cr = c + i * ldc;
  const float* ir = init ? init + i * ld_init : nullptr;
  switch (m - i) {
#define SEMREC_ROWS(R)                                                         \
  case R:                                                                      \
    TileBf16<(R), NV>(kp, ar, a.row, a.pair, b, n, cr, ldc, ir, ld_init, bias, \
                      accumulate);                                             \
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

SEMREC_BF16 void GemmBf16Impl(int m, int n, int k, const float* a,
                              int64_t a_row, int64_t a_col, const PackedB& b,
                              float* c, int64_t ldc, const float* init,
                              int64_t ld_init, const float* bias,
                              bool accumulate) {
  thread_local PackedA packed_a;
  PackA(m, k, a, a_row, a_col, &packed_a);
  const int kp = (k + 1) & ~1;
  int j = 0;
  for (; j + 32 <= n; j += 32) {
    ColumnsBf16<2>(m, kp, packed_a, b.data.data() + static_cast<int64_t>(j) * 2,
                   n, c + j, ldc, init ? init + j : nullptr, ld_init,
                   bias ? bias + j : nullptr, accumulate);
  }
  for (; j < n; j += 16) {
    ColumnsBf16<1>(m, kp, packed_a, b.data.data() + static_cast<int64_t>(j) * 2,
                   n, c + j, ldc, init ? init + j : nullptr, ld_init,
                   bias ? bias + j : nullptr, accumulate);
  }
}

SEMREC_BF16 void PackBImpl(int k, int n, const float* b, int64_t ldb,
                           PackedB* out) {
  const int kp = (k + 1) & ~1;
  out->k = k;
  out->n = n;
  out->data.resize(static_cast<size_t>(kp) * n);
  uint16_t* o = out->data.data();
  // Pair (2q, 2q + 1) of rows, interleaved: o[(q n + j) 2 + r] = B(2q + r, j).
  for (int q = 0; q < kp / 2; ++q) {
    const float* r0 = b + (2 * static_cast<int64_t>(q)) * ldb;
    const bool odd_tail = 2 * q + 1 >= k;
    for (int j = 0; j < n; j += 16) {
      const __m512 lo = _mm512_loadu_ps(r0 + j);
      const __m512 hi =
          odd_tail ? _mm512_setzero_ps() : _mm512_loadu_ps(r0 + ldb + j);
      _mm512_storeu_si512(o + (static_cast<size_t>(q) * n + j) * 2,
                          Interleave(_mm512_cvtne2ps_pbh(hi, lo)));
    }
  }
}

}  // namespace

bool HasBf16() {
#if defined(__x86_64__)
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") &&
           __builtin_cpu_supports("avx512bw") &&
           __builtin_cpu_supports("avx512vl") &&
           __builtin_cpu_supports("avx512dq") &&
           __builtin_cpu_supports("avx512bf16");
  }();
  return has;
#else
  return false;
#endif
}

void PackBf16(int k, int n, const float* b, int64_t ldb, PackedB* out) {
  if (!HasBf16()) throw InvalidArgument("bf16 products need AVX512_BF16");
  if (n % 16 != 0) {
    throw InvalidArgument("bf16 products: columns must be a multiple of 16");
  }
  PackBImpl(k, n, b, ldb, out);
}

void GemmBf16(int m, const float* a, int64_t a_row, int64_t a_col,
              const PackedB& b, float* c, int64_t ldc, bool accumulate) {
  if (m <= 0 || b.n <= 0) return;
  GemmBf16Impl(m, b.n, b.k, a, a_row, a_col, b, c, ldc, nullptr, 0, nullptr,
               accumulate);
}

void GemmOntoBf16(int m, const float* a, int64_t a_row, int64_t a_col,
                  const PackedB& b, float* c, int64_t ldc, const float* init,
                  int64_t ld_init, const float* bias) {
  if (m <= 0 || b.n <= 0) return;
  GemmBf16Impl(m, b.n, b.k, a, a_row, a_col, b, c, ldc, init, ld_init, bias,
               false);
}

}  // namespace semrec::sam::kernel_ops
