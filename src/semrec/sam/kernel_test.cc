// The decoder kernel's operations against straightforward loops, on the
// CPU's best instruction set and on the baseline one; the weights file's
// errors. (The kernel against ONNX Runtime on the real decoder:
// real_models_test.cc.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>
#include <utility>
#include <vector>

#include "semrec/core/error.h"
#include "semrec/sam/kernel.h"
#include "semrec/sam/kernel_ops.h"
#include "semrec/testing/test_util.h"

namespace semrec::sam {
namespace {

namespace ops = kernel_ops;

std::vector<float> Random(size_t n, unsigned seed, float scale = 1.0f) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> d(0.0f, scale);
  std::vector<float> v(n);
  for (float& x : v) x = d(rng);
  return v;
}

// Runs `test` on each instruction set this CPU has (the baseline on every
// CPU), then goes back to the best.
template <typename Test>
void OnEachLevel(const Test& test) {
  for (const std::string& level : ops::SupportedLevels()) {
    SCOPED_TRACE("instruction set " + level);
    ops::UseLevel(level);
    test();
  }
  ops::UseLevel("");
}

TEST(KernelOps, GemmMatchesTheDefinition) {
  OnEachLevel([] {
    // Shapes as the kernel uses them (a prompt's 7 tokens, 56 head columns,
    // blocks of 64 image tokens) and awkward ones (tails of every width).
    const int shapes[][3] = {{64, 256, 56}, {7, 2048, 256}, {56, 256, 64},
                             {64, 64, 128}, {5, 37, 19},    {1, 16, 4096},
                             {9, 1, 32},    {13, 56, 7}};
    for (const auto& [m, n, k] : shapes) {
      for (const bool transposed : {false, true}) {
        for (const bool accumulate : {false, true}) {
          const std::vector<float> a = Random(static_cast<size_t>(m) * k, 1);
          const std::vector<float> b = Random(static_cast<size_t>(k) * n, 2);
          std::vector<float> c = Random(static_cast<size_t>(m) * n, 3);
          std::vector<float> expected = c;
          const int64_t a_row = transposed ? 1 : k, a_col = transposed ? m : 1;
          for (int i = 0; i < m; ++i) {
            for (int j = 0; j < n; ++j) {
              double s = accumulate ? expected[i * n + j] : 0.0;
              for (int p = 0; p < k; ++p) {
                s += static_cast<double>(a[i * a_row + p * a_col]) *
                     b[p * n + j];
              }
              expected[i * n + j] = static_cast<float>(s);
            }
          }
          ops::Gemm(m, n, k, a.data(), a_row, a_col, b.data(), n, c.data(), n,
                    accumulate);
          for (size_t i = 0; i < c.size(); ++i) {
            ASSERT_NEAR(c[i], expected[i], 1e-4 * std::sqrt(k) + 1e-5)
                << m << "x" << n << "x" << k << " transposed " << transposed
                << " accumulate " << accumulate << " at " << i;
          }
          // Onto a residual and a bias per column, or onto the bias alone.
          const std::vector<float> residual = Random(c.size(), 13);
          const std::vector<float> bias = Random(static_cast<size_t>(n), 14);
          std::vector<float> onto(c.size());
          ops::GemmOnto(m, n, k, a.data(), a_row, a_col, b.data(), n,
                        onto.data(), n, accumulate ? residual.data() : nullptr,
                        n, bias.data());
          for (int i = 0; i < m; ++i) {
            for (int j = 0; j < n; ++j) {
              double s = (accumulate ? residual[i * n + j] : 0.0) + bias[j];
              for (int p = 0; p < k; ++p) {
                s += static_cast<double>(a[i * a_row + p * a_col]) *
                     b[p * n + j];
              }
              ASSERT_NEAR(onto[i * n + j], s, 1e-4 * std::sqrt(k) + 1e-5)
                  << "onto " << m << "x" << n << "x" << k;
            }
          }
        }
      }
    }
  });
}

// x rounded to bf16 (nearest, ties to even), as a float.
float RoundToBf16(float x) {
  uint32_t u;
  std::memcpy(&u, &x, sizeof u);
  u = (u + 0x7fffu + ((u >> 16) & 1u)) & 0xffff0000u;
  float r;
  std::memcpy(&r, &u, sizeof r);
  return r;
}

TEST(KernelOps, Bf16ProductsAreTheProductsOfTheRoundedInputs) {
  std::vector<float> b16 = Random(size_t{16} * 16, 2);
  ops::PackedB packed;
  if (!ops::HasBf16()) {  // this CPU cannot: an error, not garbage
    EXPECT_THROW(ops::PackBf16(16, 16, b16.data(), 16, &packed),
                 InvalidArgument);
    return;
  }
  EXPECT_THROW(ops::PackBf16(16, 8, b16.data(), 16, &packed), InvalidArgument);
  // The kernel's shapes (k = 56 head columns, 64 block tokens, 128, 256),
  // an odd k and row tails; A plain, transposed and with a stride.
  const int shapes[][3] = {{64, 256, 56}, {56, 256, 64}, {64, 64, 128},
                           {64, 64, 256}, {13, 48, 7},   {3, 16, 1}};
  for (const auto& [m, n, k] : shapes) {
    for (const bool transposed : {false, true}) {
      for (const int kind : {0, 1, 2}) {  // zero, accumulate, onto + bias
        const int64_t lda = std::max(m, k) + 3;
        const std::vector<float> a =
            Random(static_cast<size_t>(transposed ? k : m) * lda, 1);
        const std::vector<float> b = Random(static_cast<size_t>(k) * n, 2);
        const std::vector<float> start = Random(static_cast<size_t>(m) * n, 3);
        const std::vector<float> bias = Random(static_cast<size_t>(n), 4);
        const int64_t a_row = transposed ? 1 : lda,
                      a_col = transposed ? lda : 1;
        ops::PackBf16(k, n, b.data(), n, &packed);
        std::vector<float> c = start;
        if (kind == 2) {
          ops::GemmOntoBf16(m, a.data(), a_row, a_col, packed, c.data(), n,
                            start.data(), n, bias.data());
        } else {
          ops::GemmBf16(m, a.data(), a_row, a_col, packed, c.data(), n,
                        kind == 1);
        }
        for (int i = 0; i < m; ++i) {
          for (int j = 0; j < n; ++j) {
            double s = kind == 0   ? 0.0
                       : kind == 1 ? start[i * n + j]
                                   : start[i * n + j] + bias[j];
            for (int p = 0; p < k; ++p) {
              s += static_cast<double>(RoundToBf16(a[i * a_row + p * a_col])) *
                   RoundToBf16(b[p * n + j]);
            }
            // The products of bf16 values are exact in fp32: only the sums
            // round (plain fp32 inputs would be off by ~1e-2 here).
            ASSERT_NEAR(c[i * n + j], s, 1e-5 * std::sqrt(k) + 1e-5)
                << m << "x" << n << "x" << k << " transposed " << transposed
                << " kind " << kind << " at " << i << "," << j;
          }
        }
      }
    }
  }
}

TEST(KernelOps, ElementWiseOperationsMatchTheDefinitions) {
  OnEachLevel([] {
    // exp over the range softmax sees, GELU with std::erf.
    std::vector<float> x = Random(1003, 4, 6.0f);
    std::vector<float> e = x;
    ops::Exp(e.data(), e.size());
    std::vector<float> g = x;
    ops::Gelu(g.data(), g.size());
    for (size_t i = 0; i < x.size(); ++i) {
      const float v = std::min(x[i], 0.0f) - 20.0f * (i % 2);
      float one = v;
      ops::Exp(&one, 1);
      ASSERT_NEAR(one, std::exp(v), 3e-7f * std::exp(v)) << v;
      ASSERT_NEAR(e[i], std::exp(x[i]), 3e-7f * std::exp(x[i])) << x[i];
      const double gelu = 0.5 * x[i] * (1.0 + std::erf(x[i] / std::sqrt(2.0)));
      ASSERT_NEAR(g[i], gelu, 1e-6 * (1.0 + std::abs(x[i]))) << x[i];
    }
    // LayerNorm rows (a stride wider than the row; four vectors at a time,
    // then single vectors, then a tail).
    for (const int cols : {70, 90}) {
      const int rows = 5, ld = 100;
      std::vector<float> ln = Random(static_cast<size_t>(rows) * ld, 5, 3.0f);
      const std::vector<float> before = ln;
      const std::vector<float> gamma = Random(cols, 6), beta = Random(cols, 7);
      ops::LayerNormRows(ln.data(), rows, cols, ld, gamma.data(), beta.data(),
                         1e-5f);
      for (int r = 0; r < rows; ++r) {
        double mean = 0, var = 0;
        for (int c = 0; c < cols; ++c) mean += before[r * ld + c];
        mean /= cols;
        for (int c = 0; c < cols; ++c) {
          var += (before[r * ld + c] - mean) * (before[r * ld + c] - mean);
        }
        var /= cols;
        for (int c = 0; c < cols; ++c) {
          const double y =
              (before[r * ld + c] - mean) / std::sqrt(var + 1e-5) * gamma[c] +
              beta[c];
          ASSERT_NEAR(ln[r * ld + c], y, 1e-5 * (1 + std::abs(y)));
        }
        for (int c = cols; c < ld; ++c) {
          ASSERT_EQ(ln[r * ld + c], before[r * ld + c]);  // beyond the row
        }
      }
    }
    // Row dot products (the mask features' 32, and a k with a tail).
    for (const int k : {32, 45}) {
      const int m = 9, lda = 48;
      const std::vector<float> a = Random(static_cast<size_t>(m) * lda, 8);
      const std::vector<float> v = Random(static_cast<size_t>(k), 9);
      std::vector<float> dots(m);
      ops::RowDots(m, k, a.data(), lda, v.data(), dots.data());
      for (int i = 0; i < m; ++i) {
        double d = 0;
        for (int c = 0; c < k; ++c) d += a[i * lda + c] * v[c];
        ASSERT_NEAR(dots[i], d, 1e-5 * (1 + std::abs(d))) << "k " << k;
      }
    }
  });
}

TEST(KernelOps, HeadProductsAreTheProductsWithTheBlockDiagonalMatrices) {
  // A prompt's 7 tokens x 8 heads of 16 channels: the products skip the
  // block-diagonal matrices' zeros and keep the whole products' sums.
  OnEachLevel([] {
    const int tokens = 7, heads = 8, dh = 16, inner = heads * dh, n = 256;
    const int rows = tokens * heads, padded = 64;
    const std::vector<float> x =
        Random(static_cast<size_t>(tokens) * inner, 11);
    const std::vector<float> w = Random(static_cast<size_t>(inner) * n, 12);
    std::vector<float> block(static_cast<size_t>(padded) * inner, 0.0f);
    for (int t = 0; t < tokens; ++t) {
      for (int h = 0; h < heads; ++h) {
        for (int d = 0; d < dh; ++d) {
          block[static_cast<size_t>(t * heads + h) * inner +
                static_cast<size_t>(h * dh + d)] = x[t * inner + h * dh + d];
        }
      }
    }
    std::vector<float> whole(static_cast<size_t>(padded) * n), rows_out(whole);
    ops::Gemm(padded, n, inner, block.data(), inner, 1, w.data(), n,
              whole.data(), n, false);
    std::fill(rows_out.begin(), rows_out.end(), 0.0f);
    ops::HeadRowsProduct(tokens, heads, dh, x.data(), inner, w.data(), n, n,
                         rows_out.data(), n);
    for (size_t i = 0; i < whole.size(); ++i) {
      ASSERT_NEAR(rows_out[i], whole[i], 1e-5f * (1 + std::abs(whole[i]))) << i;
    }
    // Each row's own head of a [rows x n] times [n x inner] product.
    const std::vector<float> a = Random(static_cast<size_t>(rows) * n, 13);
    const std::vector<float> v = Random(static_cast<size_t>(n) * inner, 14);
    std::vector<float> full(static_cast<size_t>(rows) * inner);
    ops::Gemm(rows, inner, n, a.data(), n, 1, v.data(), inner, full.data(),
              inner, false);
    std::vector<float> own(static_cast<size_t>(tokens) * inner);
    ops::HeadColumnsProduct(tokens, heads, dh, n, a.data(), n, v.data(), inner,
                            own.data(), inner);
    for (int t = 0; t < tokens; ++t) {
      for (int c = 0; c < inner; ++c) {
        const float want =
            full[static_cast<size_t>(t * heads + c / dh) * inner + c];
        ASSERT_NEAR(own[t * inner + c], want, 1e-5f * (1 + std::abs(want)))
            << t << " " << c;
      }
    }
  });
}

TEST(KernelOps, SoftmaxesMatchTheDefinition) {
  OnEachLevel([] {
    // Rows.
    const int rows = 3, cols = 4100;
    std::vector<float> s = Random(static_cast<size_t>(rows) * cols, 8, 4.0f);
    const std::vector<float> raw = s;
    ops::SoftmaxRows(s.data(), rows, cols, cols);
    for (int r = 0; r < rows; ++r) {
      double z = 0;
      for (int c = 0; c < cols; ++c) z += std::exp(raw[r * cols + c]);
      for (int c = 0; c < cols; c += 97) {
        ASSERT_NEAR(s[r * cols + c], std::exp(raw[r * cols + c]) / z, 1e-6);
      }
    }
    // 8 heads over 7 tokens, column t * 8 + h, with a bias.
    const int tokens = 7, ld = 64;
    std::vector<float> h = Random(static_cast<size_t>(rows) * ld, 9, 3.0f);
    const std::vector<float> bias = Random(static_cast<size_t>(tokens) * 8, 10);
    const std::vector<float> h_raw = h;
    ops::SoftmaxHeads(h.data(), rows, ld, tokens, bias.data());
    for (int r = 0; r < rows; ++r) {
      for (int head = 0; head < 8; ++head) {
        double z = 0;
        for (int t = 0; t < tokens; ++t) {
          z += std::exp(h_raw[r * ld + t * 8 + head] + bias[t * 8 + head]);
        }
        for (int t = 0; t < tokens; ++t) {
          const double p =
              std::exp(h_raw[r * ld + t * 8 + head] + bias[t * 8 + head]) / z;
          ASSERT_NEAR(h[r * ld + t * 8 + head], p, 1e-6);
        }
      }
    }
  });
}

TEST(KernelOps, OnlineSoftmaxOverBlocksEqualsTheWholeSoftmax) {
  OnEachLevel([] {
    // A weighted sum over 300 rows in blocks of 64, with the running maximum,
    // sum and rescaling, against the softmax over all rows at once. The scores
    // grow along the rows so the maximum moves past its slack. Rows of 5
    // columns (no room to round up: tails), the kernel's 56 columns in rows
    // of 64 (whole vectors), and 300 (a chunk of 256 and one with a tail).
    for (const auto& [cols, ld] :
         {std::pair{5, 5}, std::pair{56, 64}, std::pair{300, 300}}) {
      SCOPED_TRACE(cols);
      const int n = 300, channels = 3, block = 64;
      std::vector<float> scores = Random(static_cast<size_t>(n) * ld, 11, 2.0f);
      for (size_t i = 0; i < static_cast<size_t>(n); ++i) {
        scores[i * ld] += 0.2f * static_cast<float>(i);
        scores[i * ld + cols - 1] -= 0.3f * static_cast<float>(i);
      }
      const std::vector<float> values =
          Random(static_cast<size_t>(n) * channels, 12);
      std::vector<float> max(cols, -1e30f), sum(cols, 0.0f), rescale(cols);
      std::vector<float> acc(static_cast<size_t>(cols) * channels, 0.0f);
      int rescaled = 0;
      for (int b0 = 0; b0 < n; b0 += block) {
        const int nb = std::min(block, n - b0);
        std::vector<float> s(
            scores.begin() + static_cast<ptrdiff_t>(b0) * ld,
            scores.begin() + static_cast<ptrdiff_t>(b0 + nb) * ld);
        if (ops::OnlineSoftmaxColumns(s.data(), nb, cols, ld, max.data(),
                                      sum.data(), rescale.data())) {
          ++rescaled;
          for (int c = 0; c < cols; ++c) {
            for (int k = 0; k < channels; ++k) {
              acc[c * channels + k] *= rescale[c];
            }
          }
        }
        ops::Gemm(cols, channels, nb, s.data(), 1, ld,
                  values.data() + static_cast<ptrdiff_t>(b0) * channels,
                  channels, acc.data(), channels, true);
      }
      EXPECT_GE(rescaled, 2);  // the first block and the growing column
      for (int c = 0; c < cols; ++c) {
        double m = -1e30;
        for (int i = 0; i < n; ++i) {
          m = std::max<double>(m, scores[i * ld + c]);
        }
        double z = 0;
        std::vector<double> w(channels, 0.0);
        for (int i = 0; i < n; ++i) {
          const double p = std::exp(scores[i * ld + c] - m);
          z += p;
          for (int k = 0; k < channels; ++k) {
            w[k] += p * values[i * channels + k];
          }
        }
        for (int k = 0; k < channels; ++k) {
          ASSERT_NEAR(acc[c * channels + k] / sum[c], w[k] / z, 1e-5)
              << "column " << c;
        }
      }
    }
  });
}

TEST(SamKernel, WeightFilesThatAreNotTheKernelsAreRefusedByName) {
  semrec::testing::TempDir dir;
  EXPECT_THROW(SamKernel(dir.path() / "missing.bin"), IoError);
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir.path() / name, std::ios::binary) << text;
    return dir.path() / name;
  };
  const auto expect_format_error = [](const std::filesystem::path& path,
                                      const std::string& part) {
    try {
      SamKernel kernel(path);
      ADD_FAILURE() << "accepted " << path;
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos);
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
          << e.what();
    }
  };
  expect_format_error(write("onnx.bin", "\x08\x07garbage"), "JSON header");
  expect_format_error(
      write("other.bin", "{\"format\":\"other\",\"version\":1}\n"),
      "semrec-sam-kernel");
  const std::string scalars =
      "\"scalars\":{\"heads\":8,\"norm_eps\":1e-5,\"preview_eps\":1e-6,"
      "\"points_offset\":2.5,\"first_mask_reweight\":1000,"
      "\"input_size\":1024}";
  expect_format_error(write("empty.bin",
                            "{\"format\":\"semrec-sam-kernel\",\"version\":1,"
                            "\"tensors\":{}," +
                                scalars + "}\n"),
                      "layers.0.self_attn.q.w");
  expect_format_error(
      write("short.bin",
            "{\"format\":\"semrec-sam-kernel\",\"version\":1,\"tensors\":{"
            "\"no_mask\":{\"shape\":[256],\"offset\":0}}," +
                scalars + "}\n" + std::string(100, '\0')),
      "truncated");
}

}  // namespace
}  // namespace semrec::sam
