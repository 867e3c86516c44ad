#include "semrec/infer/onnx_model.h"

#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/sha256.h"

namespace semrec::infer {

void OnnxModelOptions::Check() const {
  CheckArgument(intra_op_threads >= 0, "model: intra_op_threads must be >= 0");
}

namespace {

std::string Describe(const std::vector<TensorInfo>& infos) {
  std::vector<std::string> parts;
  parts.reserve(infos.size());
  for (const auto& i : infos) {
    parts.push_back(fmt::format("{} [{}]", i.name, fmt::join(i.shape, ",")));
  }
  return fmt::format("{}", fmt::join(parts, ", "));
}

void CheckList(const std::filesystem::path& file, const char* kind,
               const std::vector<TensorInfo>& actual,
               const std::vector<TensorSignature>& expected) {
  for (const TensorSignature& want : expected) {
    auto it =
        std::find_if(actual.begin(), actual.end(),
                     [&](const TensorInfo& i) { return i.name == want.name; });
    if (it == actual.end()) {
      throw FormatError(
          file, fmt::format("the model has no {} named '{}' (its {}s: {}); "
                            "is this the model the registry describes? (A "
                            "model scripts/setup derives, such as the split "
                            "SAM decoder, is remade by running it again.)",
                            kind, want.name, kind, Describe(actual)));
    }
    bool ok = it->shape.size() == want.shape.size();
    for (size_t d = 0; ok && d < want.shape.size(); ++d) {
      ok = want.shape[d] < 0 || it->shape[d] < 0 ||
           want.shape[d] == it->shape[d];
    }
    if (!ok) {
      throw FormatError(
          file, fmt::format("{} '{}' has shape [{}], the registry expects [{}]",
                            kind, want.name, fmt::join(it->shape, ","),
                            fmt::join(want.shape, ",")));
    }
    if (!it->is_float) {
      throw FormatError(file,
                        fmt::format("{} '{}' is not float32", kind, want.name));
    }
  }
}

}  // namespace

void CheckSignature(const std::filesystem::path& file,
                    const OnnxSession& session,
                    const std::vector<TensorSignature>& inputs,
                    const std::vector<TensorSignature>& outputs) {
  CheckList(file, "input", session.inputs(), inputs);
  CheckList(file, "output", session.outputs(), outputs);
  if (!inputs.empty()) {
    for (const TensorInfo& info : session.inputs()) {
      const bool declared = std::any_of(
          inputs.begin(), inputs.end(),
          [&](const TensorSignature& s) { return s.name == info.name; });
      if (!declared) {
        throw FormatError(file,
                          fmt::format("the model has an extra input '{}' "
                                      "[{}] the registry does not declare",
                                      info.name, fmt::join(info.shape, ",")));
      }
    }
  }
}

std::filesystem::path ModelFile(const ModelEntry& entry,
                                const OnnxModelOptions& options) {
  const auto dir =
      options.model_dir.empty() ? DefaultModelDir() : options.model_dir;
  return dir / entry.file;
}

OnnxModel::OnnxModel(const ModelEntry& entry, const OnnxModelOptions& options)
    : entry_(entry) {
  options.Check();
  file_ = ModelFile(entry, options);
  Load(options);
}

OnnxModel::OnnxModel(const ModelEntry& entry, const std::filesystem::path& file,
                     const OnnxModelOptions& options)
    : entry_(entry), file_(file) {
  options.Check();
  Load(options);
}

void OnnxModel::Load(const OnnxModelOptions& options) {
  if (!std::filesystem::is_regular_file(file_)) {
    throw IoError(file_,
                  fmt::format("model '{}' is not installed: run scripts/setup "
                              "(or set SEMREC_MODELS to the folder that holds "
                              "{})",
                              entry_.name, entry_.file));
  }
  if (options.verify_checksum && !entry_.sha256.empty()) {
    const std::string actual = Sha256File(file_);
    if (actual != entry_.sha256) {
      throw FormatError(
          file_,
          fmt::format("model '{}' has sha256 {}, the registry expects {}: "
                      "the file is corrupt or a different model; delete "
                      "it and re-run scripts/setup",
                      entry_.name, actual, entry_.sha256));
    }
  }
  OnnxSessionOptions session_options;
  session_options.intra_op_threads = options.intra_op_threads;
  session_options.provider = options.provider;
  session_options.disabled_optimizers = entry_.disabled_optimizers;
  session_options.spin_between_ops = options.spin_between_ops;
  session_ = std::make_unique<OnnxSession>(file_, session_options);
  CheckSignature(file_, *session_, entry_.inputs, entry_.outputs);
}

}  // namespace semrec::infer
