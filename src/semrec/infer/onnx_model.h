// A registry model loaded from the model cache: file present, checksum right,
// inputs/outputs as the registry declares, execution provider chosen.
#pragma once

#include <filesystem>
#include <map>
#include <string>

#include "semrec/infer/model_registry.h"
#include "semrec/infer/onnx_session.h"

namespace semrec::infer {

struct OnnxModelOptions {
  /// Threads for one operator; 0 = all cores.
  int intra_op_threads = 0;
  /// Where the model runs (onnx_session.h: auto, cpu, cuda).
  Provider provider = Provider::kAuto;
  /// Verify the file's sha256 against the registry before loading (~0.1 s
  /// per 30 MB); catches truncated downloads and swapped files.
  bool verify_checksum = true;
  /// The model cache; empty = DefaultModelDir() ($SEMREC_MODELS or
  /// .deps/models).
  std::filesystem::path model_dir;
  /// ONNX Runtime's worker threads spin between operators (the former
  /// default; OnnxSessionOptions::spin_between_ops).
  bool spin_between_ops = false;
  void Check() const;
};

class OnnxModel {
 public:
  /// Loads `entry` from the model cache. Throws IoError when the file is
  /// missing, FormatError for a checksum mismatch or a signature that differs
  /// from the registry's, each naming the model, the file and how to fix it.
  explicit OnnxModel(const ModelEntry& entry,
                     const OnnxModelOptions& options = {});
  /// Same, for an explicit file (checksum and signature still checked).
  OnnxModel(const ModelEntry& entry, const std::filesystem::path& file,
            const OnnxModelOptions& options);

  const ModelEntry& entry() const { return entry_; }
  const OnnxSession& session() const { return *session_; }
  const std::filesystem::path& file() const { return file_; }
  /// The execution provider in use: kCpu or kCuda.
  Provider provider() const { return session_->provider(); }

  std::map<std::string, Tensor> Run(
      const std::map<std::string, Tensor>& inputs) const {
    return session_->Run(inputs);
  }
  std::map<std::string, Tensor> RunRefs(const TensorRefs& inputs) const {
    return session_->RunRefs(inputs);
  }

 private:
  void Load(const OnnxModelOptions& options);
  ModelEntry entry_;
  std::filesystem::path file_;
  std::unique_ptr<OnnxSession> session_;
};

/// Where `entry`'s file lies: options.model_dir (or the default cache) /
/// entry.file.
std::filesystem::path ModelFile(const ModelEntry& entry,
                                const OnnxModelOptions& options);

/// Checks a session's inputs/outputs against signatures (-1 = any; a dynamic
/// model dimension matches anything). Throws FormatError naming `file`, the
/// tensor and both shapes. Extra model inputs are an error (nobody would feed
/// them); extra outputs are fine.
void CheckSignature(const std::filesystem::path& file,
                    const OnnxSession& session,
                    const std::vector<TensorSignature>& inputs,
                    const std::vector<TensorSignature>& outputs);

}  // namespace semrec::infer
