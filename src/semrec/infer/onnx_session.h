// A thin, checked wrapper over an ONNX Runtime session (CPU). Inputs and
// outputs are named float tensors; shapes are checked against the model before
// running, so a wrong input gives a message naming the model, the input and
// both shapes instead of an ONNX Runtime stack trace.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace semrec::infer {

/// Where ONNX Runtime runs a model. kAuto: CUDA when ONNX Runtime can use it
/// at run time, else the CPU; kCuda: fail when CUDA is unavailable.
enum class Provider { kAuto, kCpu, kCuda };
/// "auto", "cpu", "cuda"; ParseProvider throws InvalidArgument for anything
/// else, naming the choices.
const char* ProviderName(Provider provider);
Provider ParseProvider(const std::string& name);

struct OnnxSessionOptions {
  /// Threads for one operator; 0 lets ONNX Runtime choose (all cores).
  int intra_op_threads = 0;
  /// Enable all graph optimisations (slower load, faster runs).
  bool optimize = true;
  Provider provider = Provider::kAuto;
  /// ONNX Runtime graph optimisers to switch off (by name).
  std::vector<std::string> disabled_optimizers;
  /// Let the worker threads spin between operators instead of sleeping. Off:
  /// spinning makes a small model alone faster (YOLOX-Nano 4.5 vs 6.3 ms on 2
  /// cores) but takes the cores the rest of a run needs (`semrec run
  /// --map-guidance` on chess: 8% less process CPU, 3% less wall without).
  bool spin_between_ops = false;
  void Check() const;
};

/// Whether ONNX Runtime's CUDA provider library is installed beside
/// libonnxruntime (it still needs a GPU and the CUDA runtime to work). The
/// official CPU build that scripts/setup assembles has none.
bool CudaProviderInstalled();

/// A dense float32 tensor, row-major.
struct Tensor {
  std::vector<int64_t> shape;
  std::vector<float> data;

  static size_t NumElements(const std::vector<int64_t>& shape);
  /// A zero tensor of `shape` (all dims >= 0).
  static Tensor Zeros(const std::vector<int64_t>& shape);
};

/// Named input tensors by pointer (not owned).
using TensorRefs = std::map<std::string, const Tensor*>;

/// Shape of a model input/output; -1 marks a dynamic dimension.
struct TensorInfo {
  std::string name;
  std::vector<int64_t> shape;
  bool is_float = true;
};

class OnnxSession {
 public:
  /// Loads `model_path`. Throws IoError when missing, FormatError when ONNX
  /// Runtime rejects it.
  explicit OnnxSession(const std::filesystem::path& model_path,
                       const OnnxSessionOptions& options = {});
  ~OnnxSession();
  OnnxSession(const OnnxSession&) = delete;
  OnnxSession& operator=(const OnnxSession&) = delete;

  const std::vector<TensorInfo>& inputs() const { return inputs_; }
  const std::vector<TensorInfo>& outputs() const { return outputs_; }
  const std::filesystem::path& model_path() const { return model_path_; }
  /// The execution provider in use: kCpu or kCuda.
  Provider provider() const { return provider_; }

  /// Runs the model. Every model input must be given, with a matching rank and
  /// fixed dims. Returns all outputs by name. Throws InvalidArgument for
  /// missing/extra/misshapen inputs.
  std::map<std::string, Tensor> Run(
      const std::map<std::string, Tensor>& inputs) const;
  /// Same with the inputs by pointer: large tensors shared by many calls
  /// (an image embedding) are not copied per call.
  std::map<std::string, Tensor> RunRefs(const TensorRefs& inputs) const;

  /// Version string of the loaded ONNX Runtime library (e.g. "1.30.0").
  static std::string RuntimeVersion();

 private:
  struct Impl;
  std::filesystem::path model_path_;
  Provider provider_ = Provider::kCpu;
  std::unique_ptr<Impl> impl_;
  std::vector<TensorInfo> inputs_;
  std::vector<TensorInfo> outputs_;
};

}  // namespace semrec::infer
