#include "semrec/infer/model_registry.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include "semrec/core/enum_names.h"
#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace semrec::infer {
namespace {

// Errors inside one entry; Load() adds the file and model name.
struct EntryError {
  std::string message;
};

template <typename T>
T Scalar(const YAML::Node& node, const std::string& key) {
  if (!node[key]) throw EntryError{"missing '" + key + "'"};
  try {
    return node[key].as<T>();
  } catch (const YAML::Exception&) {
    throw EntryError{"'" + key + "' has the wrong type"};
  }
}

template <typename T>
T ScalarOr(const YAML::Node& node, const std::string& key, T fallback) {
  return node[key] ? Scalar<T>(node, key) : fallback;
}

std::array<float, 3> Triple(const YAML::Node& node, const std::string& key,
                            float fallback) {
  if (!node[key]) return {fallback, fallback, fallback};
  const auto v = Scalar<std::vector<float>>(node, key);
  if (v.size() != 3) throw EntryError{"'" + key + "' needs 3 values"};
  return {v[0], v[1], v[2]};
}

TensorLayout Layout(const YAML::Node& node) {
  const auto s = ScalarOr<std::string>(node, "layout", "NCHW");
  if (s == "NCHW") return TensorLayout::kNCHW;
  if (s == "NHWC") return TensorLayout::kNHWC;
  throw EntryError{"layout must be NCHW or NHWC, not '" + s + "'"};
}

ImageInputSpec ParseInput(const YAML::Node& node) {
  ImageInputSpec in;
  in.name = Scalar<std::string>(node, "name");
  in.layout = Layout(node);
  in.width = Scalar<int>(node, "width");
  in.height = Scalar<int>(node, "height");
  if (in.width <= 0 || in.height <= 0) {
    throw EntryError{"input width and height must be > 0"};
  }
  const auto color = ScalarOr<std::string>(node, "color", "RGB");
  if (color != "RGB" && color != "BGR") {
    throw EntryError{"color must be RGB or BGR, not '" + color + "'"};
  }
  in.color = color == "RGB" ? ColorOrder::kRGB : ColorOrder::kBGR;
  const auto resize = ScalarOr<std::string>(node, "resize", "stretch");
  if (resize == "stretch") {
    in.resize = ResizePolicy::kStretch;
  } else if (resize == "letterbox") {
    in.resize = ResizePolicy::kLetterbox;
  } else {
    throw EntryError{"resize must be stretch or letterbox, not '" + resize +
                     "'"};
  }
  in.pad_value = ScalarOr<float>(node, "pad_value", 0.0f);
  const auto space = ScalarOr<std::string>(node, "pad_space", "raw");
  if (space != "raw" && space != "normalized") {
    throw EntryError{"pad_space must be raw or normalized"};
  }
  in.pad_normalized = space == "normalized";
  in.mean = Triple(node, "mean", 0.0f);
  in.std = Triple(node, "std", 1.0f);
  for (float s : in.std) {
    if (!(s > 0)) throw EntryError{"std values must be > 0"};
  }
  return in;
}

std::vector<TensorSignature> ParseSignature(const YAML::Node& node) {
  std::vector<TensorSignature> out;
  if (!node) return out;
  if (!node.IsMap()) throw EntryError{"signature lists must be maps"};
  for (const auto& kv : node) {
    TensorSignature t;
    t.name = kv.first.as<std::string>();
    try {
      t.shape = kv.second.as<std::vector<int64_t>>();
    } catch (const YAML::Exception&) {
      throw EntryError{"shape of '" + t.name + "' must be a list of integers"};
    }
    out.push_back(std::move(t));
  }
  return out;
}

ModelEntry ParseEntry(const std::string& name, const YAML::Node& node) {
  ModelEntry e;
  e.name = name;
  e.file = Scalar<std::string>(node, "file");
  e.sha256 = ScalarOr<std::string>(node, "sha256", "");
  if (!e.sha256.empty() &&
      (e.sha256.size() != 64 ||
       e.sha256.find_first_not_of("0123456789abcdef") != std::string::npos)) {
    throw EntryError{"sha256 must be 64 lower-case hex digits"};
  }
  try {
    e.role = ParseModelRole(Scalar<std::string>(node, "role"));
    e.backend = ParseMaskBackend(ScalarOr<std::string>(node, "backend", "sam"));
  } catch (const InvalidArgument& error) {
    throw EntryError{error.what()};
  }
  e.label_set = ScalarOr<std::string>(node, "label_set", "");
  e.label_offset = ScalarOr<int>(node, "label_offset", 0);
  if (const YAML::Node split = node["split"]) {
    e.split_image = Scalar<std::string>(split, "image");
    e.split_prompt = Scalar<std::string>(split, "prompt");
    e.split_masks = ScalarOr<std::string>(split, "masks", "");
    e.split_kernel = ScalarOr<std::string>(split, "kernel", "");
  }
  if (const YAML::Node off = node["disable_optimizers"]) {
    if (!off.IsSequence()) {
      throw EntryError{"disable_optimizers must be a list of names"};
    }
    for (const auto& name : off) {
      e.disabled_optimizers.push_back(name.as<std::string>());
    }
  }
  if (node["input"]) e.input = ParseInput(node["input"]);
  if (node["output"]) {
    const auto grid =
        ScalarOr<std::string>(node["output"], "grid", "half_pixel");
    if (grid != "half_pixel" && grid != "asymmetric") {
      throw EntryError{"output grid must be half_pixel or asymmetric, not '" +
                       grid + "'"};
    }
    e.output = OutputSpec{Scalar<std::string>(node["output"], "name"),
                          Layout(node["output"]),
                          grid == "asymmetric" ? GridAlignment::kAsymmetric
                                               : GridAlignment::kHalfPixel};
  }
  if (node["signature"]) {
    e.inputs = ParseSignature(node["signature"]["inputs"]);
    e.outputs = ParseSignature(node["signature"]["outputs"]);
  }
  if (e.role == ModelRole::kSemantic &&
      (!e.input || !e.output || e.label_set.empty())) {
    throw EntryError{"a semantic model needs input, output and label_set"};
  }
  if (e.role == ModelRole::kMaskEncoder && !e.input) {
    throw EntryError{"a mask encoder needs an input spec"};
  }
  return e;
}

}  // namespace

const char* ModelRoleName(ModelRole role) {
  switch (role) {
    case ModelRole::kSemantic:
      return "semantic";
    case ModelRole::kMaskEncoder:
      return "mask_encoder";
    case ModelRole::kMaskDecoder:
      return "mask_decoder";
    case ModelRole::kMaskDecoderPart:
      return "mask_decoder_part";
    case ModelRole::kDetector:
      return "detector";
  }
  return "?";
}

ModelRole ParseModelRole(const std::string& name) {
  return ParseEnumName(
      name,
      {ModelRole::kSemantic, ModelRole::kMaskEncoder, ModelRole::kMaskDecoder,
       ModelRole::kMaskDecoderPart, ModelRole::kDetector},
      ModelRoleName, "role");
}

const char* MaskBackendName(MaskBackend backend) {
  switch (backend) {
    case MaskBackend::kSam:
      return "sam";
    case MaskBackend::kSam2:
      return "sam2";
  }
  return "?";
}

MaskBackend ParseMaskBackend(const std::string& name) {
  return ParseEnumName(name, {MaskBackend::kSam, MaskBackend::kSam2},
                       MaskBackendName, "backend");
}

ModelRegistry ModelRegistry::Load(const std::filesystem::path& path) {
  const std::string text = ReadTextFile(path);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw FormatError(path, std::string("invalid YAML: ") + e.what());
  }
  if (!root.IsMap() || !root["models"] || !root["models"].IsMap()) {
    throw FormatError(path, "expected a 'models:' map of model entries");
  }
  ModelRegistry registry;
  registry.path_ = path;
  for (const auto& kv : root["models"]) {
    if (!kv.first.IsScalar()) {
      throw FormatError(path, "model names must be plain strings");
    }
    const std::string name = kv.first.Scalar();
    try {
      registry.Add(ParseEntry(name, kv.second));
    } catch (const EntryError& e) {
      throw FormatError(path, "model '" + name + "': " + e.message);
    } catch (const YAML::Exception& e) {
      throw FormatError(path, "model '" + name + "': " + e.what());
    }
  }
  // A split names parts of the same file's registry.
  for (const std::string& name : registry.Names()) {
    const ModelEntry& e = registry.Get(name);
    for (const std::string* part :
         {&e.split_image, &e.split_prompt, &e.split_masks, &e.split_kernel}) {
      if (part->empty()) continue;
      if (!registry.Contains(*part) ||
          registry.Get(*part).role != ModelRole::kMaskDecoderPart) {
        throw FormatError(
            path, fmt::format("model '{}': split part '{}' must be an entry "
                              "of this file with role mask_decoder_part",
                              name, *part));
      }
    }
  }
  return registry;
}

std::filesystem::path ModelRegistry::DefaultPath() {
  return ProjectDataDir() / "models.yaml";
}

ModelRegistry ModelRegistry::LoadDefault() { return Load(DefaultPath()); }

ModelRegistry ModelRegistry::LoadDefaultWith(
    const std::filesystem::path& extra) {
  ModelRegistry registry = LoadDefault();
  if (!extra.empty()) registry.Merge(Load(extra));
  return registry;
}

const ModelEntry& ModelRegistry::Get(const std::string& name) const {
  auto it = entries_.find(name);
  if (it == entries_.end()) {
    throw InvalidArgument(
        fmt::format("unknown model '{}' (registry {}; known: {})", name,
                    path_.string(), fmt::join(Names(), ", ")));
  }
  return it->second;
}

std::vector<std::string> ModelRegistry::Names() const {
  std::vector<std::string> names;
  for (const auto& [name, entry] : entries_) names.push_back(name);
  return names;
}

void ModelRegistry::Add(const ModelEntry& entry) {
  CheckArgument(!entry.name.empty(), "model registry: empty model name");
  entries_[entry.name] = entry;
}

void ModelRegistry::Merge(const ModelRegistry& other) {
  for (const auto& [name, entry] : other.entries_) Add(entry);
}

}  // namespace semrec::infer
