// The model registry: a data file (data/models.yaml, or a user's own) saying
// what each model file is and how to feed it, so a new export needs a registry
// entry, not code.
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace semrec::infer {

enum class TensorLayout { kNCHW, kNHWC };
enum class ColorOrder { kRGB, kBGR };
enum class ResizePolicy {
  /// Resize to the input size, ignoring the aspect ratio.
  kStretch,
  /// Scale to fit keeping the aspect ratio, image at the top-left, the rest
  /// padded.
  kLetterbox,
};

/// How an image becomes the model's input tensor.
struct ImageInputSpec {
  std::string name;
  TensorLayout layout = TensorLayout::kNCHW;
  int width = 0;
  int height = 0;
  ColorOrder color = ColorOrder::kRGB;
  ResizePolicy resize = ResizePolicy::kStretch;
  /// Letterbox padding: `pad_value` in 0..255 before normalising
  /// (pad_normalized = false), or 0 after normalising (pad_normalized = true,
  /// as SAM does).
  float pad_value = 0.0f;
  bool pad_normalized = false;
  /// Per channel in the model's colour order: (x - mean) / std, x in 0..255.
  std::array<float, 3> mean = {0, 0, 0};
  std::array<float, 3> std = {1, 1, 1};
};

/// Where the cells of a coarse output grid sit in the input frame:
/// half-pixel centres (cell i covers [i, i + 1) * stride, centre at
/// (i + 0.5) * stride; most exports) or asymmetric (cell i at i * stride: a
/// TFLite RESIZE_BILINEAR without align_corners / half_pixel_centers).
enum class GridAlignment { kHalfPixel, kAsymmetric };

struct OutputSpec {
  std::string name;
  TensorLayout layout = TensorLayout::kNCHW;
  GridAlignment grid = GridAlignment::kHalfPixel;
};

/// A tensor name and shape; -1 = any size.
struct TensorSignature {
  std::string name;
  std::vector<int64_t> shape;
};

/// What a model is for (the registry's `role`).
enum class ModelRole {
  kSemantic,
  kMaskEncoder,
  kMaskDecoder,
  /// A part of a split mask decoder (scripts/split_sam_decoder.py).
  kMaskDecoderPart,
  kDetector,
};
/// "semantic", "mask_encoder", "mask_decoder", "mask_decoder_part",
/// "detector"; ParseModelRole throws InvalidArgument for anything else, naming
/// the choices.
const char* ModelRoleName(ModelRole role);
ModelRole ParseModelRole(const std::string& name);

/// Which export a mask model is: SAM's (encoder `output`, decoder with
/// orig_im_size and low_res_masks) or SAM2's (high-resolution features, a
/// decoder returning low-res masks, IoUs and an object pointer).
enum class MaskBackend { kSam, kSam2 };
/// "sam", "sam2"; ParseMaskBackend throws InvalidArgument for anything else.
const char* MaskBackendName(MaskBackend backend);
MaskBackend ParseMaskBackend(const std::string& name);

struct ModelEntry {
  std::string name;
  std::string file;
  /// Lower-case hex; empty = not checked.
  std::string sha256;
  ModelRole role = ModelRole::kSemantic;
  std::string label_set;
  int label_offset = 0;
  /// Mask decoders: which export.
  MaskBackend backend = MaskBackend::kSam;
  /// Mask decoders: registry names of the parts made from this decoder by
  /// scripts/split_sam_decoder.py (role mask_decoder_part): `split_image`
  /// runs once per image, `split_prompt` per prompt, `split_masks` (optional)
  /// the mask upscaling per prompt whose mask is worth it; `split_kernel`
  /// (optional) the weights of semrec's own decoder kernel
  /// (scripts/export_sam_kernel.py), which replaces the image and prompt
  /// parts. Empty = not split.
  std::string split_image;
  std::string split_prompt;
  std::string split_masks;
  std::string split_kernel;
  /// ONNX Runtime graph optimisers to switch off for this model (names as in
  /// ONNX Runtime's graph_transformer_utils.cc), where one makes it slower.
  std::vector<std::string> disabled_optimizers;
  std::optional<ImageInputSpec> input;
  std::optional<OutputSpec> output;
  std::vector<TensorSignature> inputs;
  std::vector<TensorSignature> outputs;
};

class ModelRegistry {
 public:
  /// Parses a registry file. Throws IoError / FormatError naming the file and
  /// the model whose entry is wrong.
  static ModelRegistry Load(const std::filesystem::path& path);
  /// data/models.yaml of the project (see ProjectDataDir()).
  static ModelRegistry LoadDefault();
  /// The default registry with the entries of `extra` merged over it (a
  /// user's own exports); `extra` empty: the default alone.
  static ModelRegistry LoadDefaultWith(const std::filesystem::path& extra);
  /// The default registry's path.
  static std::filesystem::path DefaultPath();

  const std::filesystem::path& path() const { return path_; }
  bool Contains(const std::string& name) const {
    return entries_.count(name) != 0;
  }
  /// Throws InvalidArgument listing the known names.
  const ModelEntry& Get(const std::string& name) const;
  std::vector<std::string> Names() const;
  /// Adds or replaces an entry (e.g. from a user's registry).
  void Add(const ModelEntry& entry);
  /// Adds all entries of `other`, replacing same-named ones.
  void Merge(const ModelRegistry& other);

 private:
  std::filesystem::path path_;
  std::map<std::string, ModelEntry> entries_;
};

}  // namespace semrec::infer
