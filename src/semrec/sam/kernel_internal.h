// The decoder kernel's internals shared by its source files (not part of
// the library's interface).
#pragma once

#include <vector>

#include "semrec/sam/kernel.h"
#include "semrec/sam/kernel_ops.h"

namespace semrec::sam {

namespace kernel_detail {

// Columns of the per-prompt attention matrices: heads x prompt tokens,
// padded to whole vectors.
inline int Padded(int columns) { return (columns + 15) / 16 * 16; }

inline std::vector<float> Sum(const std::vector<float>& a,
                              const std::vector<float>& b) {
  std::vector<float> out(a.size());
  kernel_ops::Add(out.data(), a.data(), b.data(), a.size());
  return out;
}

}  // namespace kernel_detail

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

struct SamKernel::FirstLayerWork {
  FirstLayerWork(const SamKernel& k, const std::vector<float>& layer0_tokens,
                 State* state, float* tokens_out);
  State* s;
  float* image_tokens;
  std::vector<float> kbd, u0, qk1;
  Rhs kbd_rhs, u0_rhs, qk1_rhs;
  OnlineAttention online;
};

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

}  // namespace semrec::sam
