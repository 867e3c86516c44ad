// SAM's mask decoder, per prompt, as semrec's own CPU kernel. ONNX Runtime
// runs the prompt part op by op, each op one pass over the 4096 x 256 image
// tokens (adds, layer norms, softmaxes: about a third of a prompt's time);
// here each pass works on a block of 64 image tokens while it is in the
// cache, the softmaxes over all tokens run online (a running maximum and
// sum), and the products use the CPU's widest vectors (sam/kernel_ops.h).
// Same arithmetic as the export up to float rounding: the outputs are the
// split prompt part's (docs/models.md), for the mask part to upscale.
// Weights: scripts/export_sam_kernel.py (run by scripts/setup).
#pragma once

#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "semrec/sam/kernel_ops.h"

namespace semrec::sam {

class SamKernel {
 public:
  static constexpr int kDim = 256;        // SAM's token width
  static constexpr int kCrossDim = 128;   // cross attention's inner width
  static constexpr int kBlock = 64;       // image tokens per block
  static constexpr int kPreviewDim = 32;  // the mask features per token
  /// The upscaling's low-res cells per image token (two 2x2 steps).
  static constexpr int kCellsPerToken = 16;

  /// The large products' inputs: fp32, or rounded to bf16 (fp32 sums) where
  /// the CPU multiplies bf16 pairs (AVX512_BF16: twice the multiply-adds per
  /// instruction; kernel_ops::HasBf16()).
  enum class Precision { kFp32, kBf16 };

  /// Loads the weights `path` (written by scripts/export_sam_kernel.py).
  /// Throws IoError when it cannot be read, FormatError (naming the file and
  /// the tensor) when it is not such a file or a tensor has the wrong shape,
  /// InvalidArgument for kBf16 on a CPU without bf16 products.
  explicit SamKernel(const std::filesystem::path& path,
                     Precision precision = Precision::kFp32);
  SamKernel(const SamKernel&) = delete;  // holds pointers into itself
  SamKernel& operator=(const SamKernel&) = delete;
  Precision precision() const { return precision_; }

  /// What the decoder needs of one image, computed once per image.
  struct Image {
    int tokens = 0;           // h x w of the embedding grid (SAM: 64 x 64)
    std::vector<float> keys;  // [tokens x 256]: embedding + no-mask
    std::vector<float> pe;    // [tokens x 256]: positional encoding
    std::vector<float> t2i_keys_t;   // [128 x tokens]: layer 0's keys
    std::vector<float> t2i_values;   // [8 heads x tokens x 16]
    std::vector<float> i2t_queries;  // [tokens x 128]
  };
  /// From the image encoder's output [1, 256, h, w] (values, shape).
  Image Prepare(const std::vector<float>& embedding,
                const std::vector<int64_t>& shape) const;

  /// A product's right-hand side [k x n] (w, not owned), packed for bf16
  /// products when the kernel uses them.
  struct Rhs {
    const float* w = nullptr;
    int k = 0, n = 0;
    kernel_ops::PackedB packed;
  };

  struct Output {
    float predicted_iou = 0;        // of the chosen mask
    std::vector<float> mask_hyper;  // [32]
    std::vector<float> preview;     // [tokens]: the chosen mask's
    /// What UpscalingTokens() needs of the prompt: layer 1's image tokens
    /// before its image-to-token attention [tokens x 256], and that
    /// attention's score matrix [256 x heads * prompt tokens], score bias and
    /// per-head values through the output projection.
    struct SecondLayer {
      SecondLayer() = default;
      // scores and values point into scores_w and values_w: a copy's would
      // point into the original's (a move keeps the buffers).
      SecondLayer(const SecondLayer&) = delete;
      SecondLayer& operator=(const SecondLayer&) = delete;
      SecondLayer(SecondLayer&&) = default;
      SecondLayer& operator=(SecondLayer&&) = default;
      int prompt_tokens = 0;
      std::vector<float> image_tokens, bias, scores_w, values_w;
      Rhs scores, values;
    } second_layer;
  };
  /// Decodes one prompt: points in the model frame (the encoder's input,
  /// SAM: 1024 px) with SAM's labels (1 foreground, 0 background, 2 / 3 box
  /// corners, -1 padding). The mask is chosen as SAM's export does.
  /// `out`'s buffers are reused (a caller keeping one per thread saves the
  /// allocations). Thread-safe.
  void Decode(const Image& image,
              const std::vector<std::array<float, 2>>& points,
              const std::vector<float>& labels, Output* out) const;

  /// Several prompts at once: each Output as Decode() writes it (the same
  /// values), the image's arrays read once per block for all of them.
  struct Request {
    const std::vector<std::array<float, 2>>* points = nullptr;
    const std::vector<float>* labels = nullptr;
    Output* out = nullptr;
  };
  void DecodeBatch(const Image& image,
                   const std::vector<Request>& requests) const;

  /// The mask part's input (the upscaling tokens) for the image tokens
  /// `tokens` (indices into the grid) of the prompt `decoded` came from:
  /// [tokens.size() x 256], each token's values the same whichever others
  /// are asked with it. Only what the mask part will upscale is computed:
  /// most prompts stop on their preview, the others upscale near the mask's
  /// edge (writing all 4 MB per prompt cost ~7% of a prompt).
  void UpscalingTokens(const Image& image, const Output& decoded,
                       const std::vector<int64_t>& tokens, float* out) const;

  /// Whether the weights include the mask part's upscaling (files written
  /// before it lack them: scripts/setup remakes the file).
  bool CanUpscale() const { return upscale1_.out != 0; }
  /// The mask part, in the kernel: the chosen mask's low-res logits at the
  /// image tokens `tokens` of the prompt `decoded` came from,
  /// [tokens.size() x 16], each token's 4 x 4 cells in the order (ky1, kx1,
  /// ky2, kx2): cell (4y + 2 ky1 + ky2, 4x + 2 kx1 + kx2), as the split's
  /// mask part's block_logits (docs/models.md). Throws InvalidArgument
  /// without CanUpscale() or for a token or prompt UpscalingTokens refuses.
  void UpscaleBlocks(const Image& image, const Output& decoded,
                     const std::vector<int64_t>& tokens, float* out) const;

 private:
  struct Linear {
    std::vector<float> w;   // [in x out]
    std::vector<float> b;   // [out]
    std::vector<float> wt;  // [out x in], for Fold's layers
    int in = 0, out = 0;
    Rhs rhs;  // w for Product()
  };
  struct Norm {
    std::vector<float> g, b;
  };
  struct Attention {
    Linear q, k, v, o;
  };
  struct Layer {
    Attention self_attn, t2i, i2t;
    Linear mlp1, mlp2;
    Norm norm1, norm2, norm3, norm4;
  };
  struct Scratch;
  struct OnlineAttention;
  struct State;  // one prompt's tokens
  Rhs MakeRhs(const float* w, int k, int n) const;
  // C[m x n] = (accumulate ? C : 0) + A B, or init + bias + A B (Onto), at
  // the kernel's precision.
  void Product(int m, const float* a, int64_t a_row, int64_t a_col,
               const Rhs& b, float* c, int64_t ldc, bool accumulate) const;
  void ProductOnto(int m, const float* a, int64_t a_row, int64_t a_col,
                   const Rhs& b, float* c, int64_t ldc, const float* init,
                   int64_t ld_init, const float* bias) const;

  void EncodePosition(float cx, float cy, float* out) const;
  // Rows x in -> rows x out (fp32: the image's projections in Prepare()).
  std::vector<float> Apply(const Linear& l, const std::vector<float>& x,
                           int rows) const;
  // The same at the kernel's precision (the prompt's tokens).
  std::vector<float> ApplyTokens(const Linear& l, const std::vector<float>& x,
                                 int rows) const;
  // SAM's attention among the prompt's tokens (q, k, v: rows x 256).
  std::vector<float> TokenAttention(const Attention& a,
                                    const std::vector<float>& q,
                                    const std::vector<float>& k,
                                    const std::vector<float>& v,
                                    int rows) const;
  void TokenMlpAndNorm(const Layer& l, std::vector<float>* queries,
                       int rows) const;
  std::vector<float> HeadColumns(const std::vector<float>& x, const State& s,
                                 float scale) const;
  std::vector<float> Fold(const Linear& l, const std::vector<float>& x,
                          const State& s, float scale) const;
  void HeadValues(const Linear& o, const std::vector<float>& v, const State& s,
                  std::vector<float>* out) const;
  std::vector<float> AttentionOutput(const Attention& a,
                                     OnlineAttention* online,
                                     const State& s) const;
  void AttendBlock(const float* keys_pe, const float* values, int nb,
                   const Rhs& folded, float* scores, OnlineAttention* online,
                   const State& s) const;
  void PromptTokens(const Request& r, State* s) const;
  // DecodeBatch's steps: layer 0's token side (self-attention, then the
  // batch's token-to-image attention in one pass), both layers' image sides
  // block by block, and the IoU and hypernetwork heads.
  void FirstLayerTokens(const Image& im, std::vector<State>* states) const;
  void ImageSides(const Image& im, const std::vector<Request>& requests,
                  const std::vector<std::vector<float>>& layer0_tokens,
                  std::vector<State>* states, Scratch* scratch) const;
  void Heads(const Image& im, const std::vector<Request>& requests,
             const std::vector<State>& states, const Scratch& scratch) const;
  // A prompt's share of each layer's image side: set up, then per block of
  // image tokens, then finished (the first writes layer 1's image tokens).
  struct FirstLayerWork;
  struct SecondLayerWork;
  void FirstLayerBlock(const Image& image, int b0, FirstLayerWork* w) const;
  void FirstLayerFinish(FirstLayerWork* w) const;
  void SecondLayerBlock(const Image& image, int b0, SecondLayerWork* w) const;
  void SecondLayerFinish(SecondLayerWork* w) const;
  // Layer 1's image-to-token attention and norm4 for nb image tokens (keys:
  // their layer-1 tokens [nb x 256], pe: their positional encoding): the
  // upscaling tokens into up, up + pe into keys_pe; scores is scratch.
  void SecondLayerTokens(const Output::SecondLayer& second, const float* keys,
                         const float* pe, int nb, float* keys_pe, float* scores,
                         float* up) const;
  void UpscalingFeatures(const float* up, int nb, const Linear& first,
                         const Linear& second, float* hidden,
                         float* features) const;
  // The cross attentions' score scale, 1 / sqrt(channels per head).
  float CrossScale() const {
    return 1.0f / std::sqrt(static_cast<float>(kCrossDim) /
                            static_cast<float>(heads_));
  }
  // Throws unless `decoded` is a prompt this kernel decoded on `image`.
  void CheckDecoded(const Image& image, const Output& decoded) const;
  // UpscalingTokens for up to kBlock tokens.
  void UpscalingTokenBlock(const Image& image, const Output& decoded,
                           const int64_t* tokens, int nb, float* out) const;

  std::map<std::string, std::vector<float>> LoadTensors(
      const std::filesystem::path& path);

  Layer layers_[2];
  Attention final_;
  Norm final_norm_;
  Linear hyper_[4][3];
  Linear iou_[3];
  std::vector<float> pe_gaussian_;       // [2 x 128]
  std::vector<float> not_a_point_;       // [256]
  std::vector<float> point_embeddings_;  // [4 x 256]
  std::vector<float> output_tokens_;     // [5 x 256]
  std::vector<float> no_mask_;           // [256]
  Linear preview1_, preview2_;           // [256 x 64], [64 x 32]
  Norm preview_norm_;
  // The mask part's two transposed convolutions as products: [256 x 4 * 64]
  // (columns: sub-pixel, channel) and [64 x 4 * 32]; out = 0 when absent.
  Linear upscale1_, upscale2_;
  float norm_eps_ = 1e-5f, preview_eps_ = 1e-6f;
  float points_offset_ = 2.5f, first_mask_reweight_ = 1000.0f;
  float input_size_ = 1024.0f;
  int heads_ = 8;
  Precision precision_ = Precision::kFp32;
  std::filesystem::path path_;
  // The positional encoding of the last grid size Prepare() saw.
  mutable std::mutex pe_mutex_;
  mutable std::pair<std::pair<int, int>, std::vector<float>> pe_cache_;
};

}  // namespace semrec::sam
