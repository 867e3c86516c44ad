// Reading the kernel's weights (scripts/export_sam_kernel.py's file).
#include <fstream>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/sam/kernel.h"
#include "semrec/sam/kernel_ops.h"

namespace semrec::sam {

namespace ops = kernel_ops;

std::map<std::string, std::vector<float>> SamKernel::LoadTensors(
    const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "cannot open the SAM decoder kernel's weights");
  std::string line;
  std::getline(in, line);
  nlohmann::json header;
  try {
    header = nlohmann::json::parse(line);
  } catch (const nlohmann::json::exception&) {
    throw FormatError(path,
                      "not a SAM decoder kernel file (no JSON header); re-run "
                      "scripts/setup");
  }
  if (header.value("format", "") != "semrec-sam-kernel" ||
      header.value("version", 0) != 1) {
    throw FormatError(path,
                      "not a version 1 semrec-sam-kernel file; re-run "
                      "scripts/setup");
  }
  const std::streamoff start = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg() - start;
  std::map<std::string, std::vector<float>> tensors;
  try {
    for (const auto& [name, t] : header.at("tensors").items()) {
      size_t count = 1;
      for (const auto& d : t.at("shape")) count *= d.get<size_t>();
      const auto offset = t.at("offset").get<std::streamoff>();
      const auto bytes = static_cast<std::streamoff>(count * sizeof(float));
      if (offset < 0 || offset + bytes > size) {
        throw FormatError(path, fmt::format("tensor '{}' lies beyond the end "
                                            "of the file (truncated?)",
                                            name));
      }
      std::vector<float> values(count);
      in.seekg(start + offset);
      in.read(reinterpret_cast<char*>(values.data()), bytes);
      tensors[name] = std::move(values);
    }
    const auto& s = header.at("scalars");
    heads_ = s.at("heads").get<int>();
    norm_eps_ = s.at("norm_eps").get<float>();
    preview_eps_ = s.at("preview_eps").get<float>();
    points_offset_ = s.at("points_offset").get<float>();
    first_mask_reweight_ = s.at("first_mask_reweight").get<float>();
    input_size_ = s.at("input_size").get<float>();
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(path, std::string("malformed header: ") + e.what());
  }
  if (!in) throw IoError(path, "read failed");
  return tensors;
}

SamKernel::SamKernel(const std::filesystem::path& path, Precision precision)
    : precision_(precision), path_(path) {
  if (precision == Precision::kBf16 && !ops::HasBf16()) {
    throw InvalidArgument(
        "SAM decoder kernel: bf16 products need a CPU with AVX512_BF16");
  }
  std::map<std::string, std::vector<float>> t = LoadTensors(path);
  const auto take = [&](const std::string& name, size_t size) {
    auto it = t.find(name);
    if (it == t.end() || it->second.size() != size) {
      throw FormatError(
          path_, fmt::format("tensor '{}' is {} (expected {} values); re-run "
                             "scripts/setup",
                             name,
                             it == t.end() ? std::string("missing")
                                           : std::to_string(it->second.size()),
                             size));
    }
    return std::move(it->second);
  };
  const auto linear = [&](const std::string& name, int in, int out) {
    Linear l;
    l.w = take(name + ".w", static_cast<size_t>(in) * out);
    l.b = take(name + ".b", static_cast<size_t>(out));
    l.in = in;
    l.out = out;
    return l;
  };
  const auto norm = [&](const std::string& name, int n) {
    return Norm{take(name + ".g", static_cast<size_t>(n)),
                take(name + ".b", static_cast<size_t>(n))};
  };
  const auto attention = [&](const std::string& name, int inner) {
    return Attention{
        linear(name + ".q", kDim, inner), linear(name + ".k", kDim, inner),
        linear(name + ".v", kDim, inner), linear(name + ".o", inner, kDim)};
  };
  if (heads_ != 8) {
    throw FormatError(path_,
                      fmt::format("{} attention heads (SAM has 8)", heads_));
  }
  for (int i = 0; i < 2; ++i) {
    const std::string p = fmt::format("layers.{}", i);
    Layer& l = layers_[i];
    l.self_attn = attention(p + ".self_attn", kDim);
    l.t2i = attention(p + ".t2i", kCrossDim);
    l.i2t = attention(p + ".i2t", kCrossDim);
    const auto hidden = static_cast<int>(t[p + ".mlp1.b"].size());
    l.mlp1 = linear(p + ".mlp1", kDim, hidden);
    l.mlp2 = linear(p + ".mlp2", hidden, kDim);
    l.norm1 = norm(p + ".norm1", kDim);
    l.norm2 = norm(p + ".norm2", kDim);
    l.norm3 = norm(p + ".norm3", kDim);
    l.norm4 = norm(p + ".norm4", kDim);
  }
  final_ = attention("final", kCrossDim);
  final_norm_ = norm("final_norm", kDim);
  for (int i = 0; i < 4; ++i) {
    hyper_[i][0] = linear(fmt::format("hyper{}.0", i), kDim, kDim);
    hyper_[i][1] = linear(fmt::format("hyper{}.1", i), kDim, kDim);
    hyper_[i][2] = linear(fmt::format("hyper{}.2", i), kDim, kPreviewDim);
  }
  iou_[0] = linear("iou.0", kDim, kDim);
  iou_[1] = linear("iou.1", kDim, kDim);
  iou_[2] = linear("iou.2", kDim, 4);
  pe_gaussian_ = take("pe_gaussian", 2 * kDim / 2);
  not_a_point_ = take("not_a_point", kDim);
  point_embeddings_ = take("point_embeddings", size_t{4} * kDim);
  output_tokens_ = take("output_tokens", size_t{5} * kDim);
  no_mask_ = take("no_mask", kDim);
  preview1_.in = kDim;
  preview1_.out = 64;
  preview1_.w = take("preview.w1", size_t{kDim} * 64);
  preview1_.b = take("preview.b1", 64);
  preview2_.w = take("preview.w2", size_t{64} * kPreviewDim);
  preview2_.b = take("preview.b2", kPreviewDim);
  preview2_.in = 64;
  preview2_.out = kPreviewDim;
  preview_norm_ = Norm{take("preview.g", 64), take("preview.beta", 64)};
  // The mask part's weights (optional: files written before the kernel
  // upscaled lack them, and the mask part runs in ONNX Runtime).
  if (t.count("upscaling.1.w") != 0) {
    upscale1_ = linear("upscaling.1", kDim, 4 * 64);
    upscale2_ = linear("upscaling.2", 64, 4 * kPreviewDim);
  }
  // (bf16 products take whole vectors of columns: the IoU head's 4 stay
  // fp32.)
  const auto pack = [&](Linear& l) {
    if (l.out % 16 == 0) l.rhs = MakeRhs(l.w.data(), l.in, l.out);
  };
  const auto pack_attention = [&](Attention& a) {
    for (Linear* l : {&a.q, &a.k, &a.v, &a.o}) pack(*l);
  };
  for (Layer& l : layers_) {
    for (Attention* a : {&l.self_attn, &l.t2i, &l.i2t}) pack_attention(*a);
    pack(l.mlp1);
    pack(l.mlp2);
  }
  pack_attention(final_);
  for (auto& h : hyper_) {
    for (Linear& l : h) pack(l);
  }
  for (Linear& l : iou_) pack(l);
  pack(preview1_);
  pack(preview2_);
  // Fold()'s layers transposed.
  for (Linear* l : {&layers_[1].t2i.k, &layers_[1].i2t.q, &final_.k}) {
    l->wt.resize(l->w.size());
    for (int r = 0; r < l->in; ++r) {
      for (int c = 0; c < l->out; ++c) {
        l->wt[static_cast<size_t>(c) * l->in + r] =
            l->w[static_cast<size_t>(r) * l->out + c];
      }
    }
  }
  if (CanUpscale()) {
    pack(upscale1_);
    pack(upscale2_);
  }
}

}  // namespace semrec::sam
