#include "semrec/infer/onnx_session.h"

#include <dlfcn.h>
#include <onnxruntime_cxx_api.h>
#include <onnxruntime_session_options_config_keys.h>

#include <algorithm>
#include <string>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <spdlog/spdlog.h>
#include "semrec/core/enum_names.h"
#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace semrec::infer {

const char* ProviderName(Provider provider) {
  switch (provider) {
    case Provider::kAuto:
      return "auto";
    case Provider::kCpu:
      return "cpu";
    case Provider::kCuda:
      return "cuda";
  }
  return "?";
}

Provider ParseProvider(const std::string& name) {
  return ParseEnumName(name, {Provider::kAuto, Provider::kCpu, Provider::kCuda},
                       ProviderName, "provider");
}

void OnnxSessionOptions::Check() const {
  CheckArgument(intra_op_threads >= 0,
                "onnx session: intra_op_threads must be >= 0");
}

size_t Tensor::NumElements(const std::vector<int64_t>& shape) {
  size_t n = 1;
  for (int64_t d : shape) n *= static_cast<size_t>(std::max<int64_t>(d, 0));
  return n;
}

Tensor Tensor::Zeros(const std::vector<int64_t>& shape) {
  for (int64_t d : shape) {
    CheckArgument(d >= 0, "Tensor::Zeros: negative dimension");
  }
  return {shape, std::vector<float>(NumElements(shape), 0.0f)};
}

struct OnnxSession::Impl {
  Ort::Env env{ORT_LOGGING_LEVEL_WARNING, "semrec"};
  Ort::Session session{nullptr};
  Ort::MemoryInfo memory =
      Ort::MemoryInfo::CreateCpu(OrtArenaAllocator, OrtMemTypeDefault);
};

namespace {

TensorInfo Describe(const std::string& name, const Ort::TypeInfo& type) {
  TensorInfo info;
  info.name = name;
  if (type.GetONNXType() != ONNX_TYPE_TENSOR) {
    info.is_float = false;
    return info;
  }
  const auto tensor = type.GetTensorTypeAndShapeInfo();
  info.shape = tensor.GetShape();
  info.is_float =
      tensor.GetElementType() == ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT;
  return info;
}

}  // namespace

// ONNX Runtime loads its CUDA provider from a library beside its own; looking
// first avoids an error log on every CPU-only machine.
bool CudaProviderInstalled() {
  static const bool installed = [] {
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&OrtGetApiBase), &info) == 0 ||
        info.dli_fname == nullptr) {
      return false;
    }
    const auto dir = std::filesystem::path(info.dli_fname).parent_path();
    return std::filesystem::exists(dir / "libonnxruntime_providers_cuda.so");
  }();
  return installed;
}

OnnxSession::OnnxSession(const std::filesystem::path& model_path,
                         const OnnxSessionOptions& options)
    : model_path_(model_path), impl_(std::make_unique<Impl>()) {
  options.Check();
  RequireFile(model_path, "ONNX model");
  Ort::SessionOptions session_options;
  session_options.SetIntraOpNumThreads(options.intra_op_threads);
  session_options.SetGraphOptimizationLevel(
      options.optimize ? GraphOptimizationLevel::ORT_ENABLE_ALL
                       : GraphOptimizationLevel::ORT_DISABLE_ALL);
  // SEMREC_ORT_SPIN=1: spinning everywhere (to measure against the former
  // default).
  const char* spin_env = std::getenv("SEMREC_ORT_SPIN");
  const bool spin = options.spin_between_ops ||
                    (spin_env != nullptr && std::string(spin_env) == "1");
  session_options.AddConfigEntry(kOrtSessionOptionsConfigAllowIntraOpSpinning,
                                 spin ? "1" : "0");
  if (const char* prefix = std::getenv("SEMREC_ORT_PROFILE")) {
    const std::string p = std::string(prefix) + model_path.stem().string();
    session_options.EnableProfiling(p.c_str());
  }
  if (!options.disabled_optimizers.empty()) {
    session_options.AddConfigEntry(
        kOrtSessionOptionsDisableSpecifiedOptimizers,
        fmt::format("{}", fmt::join(options.disabled_optimizers, ",")).c_str());
  }
  if (options.provider == Provider::kCuda ||
      (options.provider == Provider::kAuto && CudaProviderInstalled())) {
    // The CUDA provider is a separate shared library that needs a GPU and the
    // CUDA runtime; appending it fails cleanly when either is missing.
    try {
      OrtCUDAProviderOptions cuda;
      session_options.AppendExecutionProvider_CUDA(cuda);
      provider_ = Provider::kCuda;
    } catch (const Ort::Exception& e) {
      if (options.provider == Provider::kCuda) {
        throw Error(
            model_path.string() +
            ": the CUDA execution provider is unavailable: " + e.what());
      }
      spdlog::debug("{}: CUDA unavailable ({}), running on the CPU",
                    model_path.filename().string(), e.what());
    }
  }
  try {
    impl_->session =
        Ort::Session(impl_->env, model_path.c_str(), session_options);
  } catch (const Ort::Exception& e) {
    throw FormatError(
        model_path,
        std::string("ONNX Runtime cannot load the model (a damaged file? "
                    "re-run scripts/setup for the installed models): ") +
            e.what());
  }
  Ort::AllocatorWithDefaultOptions allocator;
  for (size_t i = 0; i < impl_->session.GetInputCount(); ++i) {
    inputs_.push_back(
        Describe(impl_->session.GetInputNameAllocated(i, allocator).get(),
                 impl_->session.GetInputTypeInfo(i)));
  }
  for (size_t i = 0; i < impl_->session.GetOutputCount(); ++i) {
    outputs_.push_back(
        Describe(impl_->session.GetOutputNameAllocated(i, allocator).get(),
                 impl_->session.GetOutputTypeInfo(i)));
  }
}

OnnxSession::~OnnxSession() = default;

std::map<std::string, Tensor> OnnxSession::Run(
    const std::map<std::string, Tensor>& inputs) const {
  TensorRefs refs;
  for (const auto& [name, tensor] : inputs) refs.emplace(name, &tensor);
  return RunRefs(refs);
}

std::map<std::string, Tensor> OnnxSession::RunRefs(
    const TensorRefs& inputs) const {
  const std::string model = model_path_.filename().string();
  for (const auto& input : inputs) {
    const std::string& name = input.first;
    const bool known =
        std::any_of(inputs_.begin(), inputs_.end(),
                    [&](const TensorInfo& i) { return i.name == name; });
    CheckArgument(known, fmt::format("{}: the model has no input named '{}'",
                                     model, name));
  }
  std::vector<const char*> input_names;
  std::vector<Ort::Value> input_values;
  for (const TensorInfo& info : inputs_) {
    auto it = inputs.find(info.name);
    CheckArgument(it != inputs.end(),
                  fmt::format("{}: input '{}' is missing", model, info.name));
    CheckArgument(info.is_float,
                  fmt::format("{}: input '{}' is not float32 (unsupported)",
                              model, info.name));
    CheckArgument(it->second != nullptr,
                  fmt::format("{}: input '{}' is null", model, info.name));
    const Tensor& t = *it->second;
    bool shape_ok = t.shape.size() == info.shape.size();
    for (size_t d = 0; shape_ok && d < t.shape.size(); ++d) {
      shape_ok =
          t.shape[d] >= 0 && (info.shape[d] < 0 || info.shape[d] == t.shape[d]);
    }
    CheckArgument(
        shape_ok,
        fmt::format("{}: input '{}' has shape [{}], the model expects [{}]",
                    model, info.name, fmt::join(t.shape, ","),
                    fmt::join(info.shape, ",")));
    CheckArgument(
        t.data.size() == Tensor::NumElements(t.shape),
        fmt::format("{}: input '{}' has {} values for shape [{}]", model,
                    info.name, t.data.size(), fmt::join(t.shape, ",")));
    input_names.push_back(info.name.c_str());
    input_values.push_back(Ort::Value::CreateTensor<float>(
        impl_->memory, const_cast<float*>(t.data.data()), t.data.size(),
        t.shape.data(), t.shape.size()));
  }
  std::vector<const char*> output_names;
  for (const TensorInfo& info : outputs_) {
    output_names.push_back(info.name.c_str());
  }
  std::vector<Ort::Value> results;
  try {
    results = impl_->session.Run(Ort::RunOptions{nullptr}, input_names.data(),
                                 input_values.data(), input_values.size(),
                                 output_names.data(), output_names.size());
  } catch (const Ort::Exception& e) {
    throw Error(fmt::format("{}: inference failed: {}", model, e.what()));
  }
  std::map<std::string, Tensor> out;
  for (size_t i = 0; i < results.size(); ++i) {
    const auto info = results[i].GetTensorTypeAndShapeInfo();
    if (info.GetElementType() != ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT) {
      throw Error(fmt::format("{}: output '{}' is not float32 (unsupported)",
                              model, outputs_[i].name));
    }
    Tensor t;
    t.shape = info.GetShape();
    const float* p = results[i].GetTensorData<float>();
    t.data.assign(p, p + info.GetElementCount());
    out.emplace(outputs_[i].name, std::move(t));
  }
  return out;
}

std::string OnnxSession::RuntimeVersion() { return Ort::GetVersionString(); }

}  // namespace semrec::infer
