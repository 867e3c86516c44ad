// The segmentation pipeline on tiny generated models that "segment by
// colour" (tests/models/make_tiny_models.py), where every answer is known.
#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/random.h"
#include "semrec/segment/hybrid_segmenter.h"
#include "semrec/segment/mask_generator.h"
#include "semrec/segment/semantic_segmenter.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::segment {
namespace {

std::vector<std::array<uint8_t, 3>> Palette() {
  const auto j = nlohmann::json::parse(
      ReadTextFile(semrec::testing::TinyModelDir() / "tiny_palette150.json"));
  return j.get<std::vector<std::array<uint8_t, 3>>>();
}

infer::ModelRegistry TinyRegistry() {
  // Written by make_tiny_models.py beside the models.
  return infer::ModelRegistry::Load(semrec::testing::TinyModelDir() /
                                    "registry.yaml");
}

infer::OnnxModelOptions Runtime() {
  infer::OnnxModelOptions o;
  o.model_dir = semrec::testing::TinyModelDir();
  o.intra_op_threads = 1;
  return o;
}

// A 320 x 240 scene: background colour 0, four rectangles of colours 20, 45,
// 80, 130 (palette indices). Returns the image and the ground-truth regions.
struct Scene {
  ColorImage rgb;
  std::vector<Box> boxes;
  std::vector<int> colours;
};

Scene MakeScene() {
  const auto palette = Palette();
  Scene s;
  s.rgb = ColorImage(320, 240, 3);
  s.boxes = {{20, 20, 120, 100},
             {160, 30, 300, 110},
             {40, 140, 110, 220},
             {180, 150, 260, 200}};
  s.colours = {20, 45, 80, 130};
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) {
      int colour = 0;
      for (size_t b = 0; b < s.boxes.size(); ++b) {
        const Box& r = s.boxes[b];
        if (x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1) {
          colour = s.colours[b];
        }
      }
      for (int c = 0; c < 3; ++c) s.rgb(x, y, c) = palette[colour][c];
    }
  }
  return s;
}

Mask BoxMask(int w, int h, const Box& b) {
  Image<uint8_t> img(w, h);
  for (int y = b.y0; y < b.y1; ++y) {
    for (int x = b.x0; x < b.x1; ++x) img(x, y) = 1;
  }
  return MaskFromImage(img);
}

double BestIou(const Mask& gt, const std::vector<Mask>& masks) {
  double best = 0;
  for (const Mask& m : masks) best = std::max(best, MaskIoU(gt, m));
  return best;
}

TEST(TinyModels, SegformerStyleSemanticBranchLabelsEveryRegion) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  SemanticSegmenterOptions options;
  options.model = "tiny_segformer";
  options.runtime = Runtime();
  const SemanticSegmenter segmenter(TinyRegistry(), options);
  EXPECT_EQ(segmenter.label_set().size(), 150u);
  const Scene s = MakeScene();
  const SemanticResult r = segmenter.Segment(s.rgb);
  ASSERT_TRUE(r.labels.SameSize(320, 240));
  // Class = palette index + 1 (label_offset); logits at 1/4 of a stretched
  // 512 x 512 frame blur borders by ~1 logit cell = 2.5 image pixels.
  int64_t wrong = 0, interior_wrong = 0;
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) {
      int colour = 0;
      bool near_border = false;
      for (size_t b = 0; b < s.boxes.size(); ++b) {
        const Box& box = s.boxes[b];
        if (x >= box.x0 && x < box.x1 && y >= box.y0 && y < box.y1) {
          colour = s.colours[b];
        }
        const Box grown{box.x0 - 3, box.y0 - 3, box.x1 + 3, box.y1 + 3};
        const Box shrunk{box.x0 + 3, box.y0 + 3, box.x1 - 3, box.y1 - 3};
        const bool in_grown =
            x >= grown.x0 && x < grown.x1 && y >= grown.y0 && y < grown.y1;
        const bool in_shrunk =
            x >= shrunk.x0 && x < shrunk.x1 && y >= shrunk.y0 && y < shrunk.y1;
        near_border |= in_grown && !in_shrunk;
      }
      const bool ok = r.labels(x, y) == colour + 1;
      wrong += !ok;
      interior_wrong += !ok && !near_border;
    }
  }
  EXPECT_EQ(interior_wrong, 0);
  EXPECT_LT(wrong, 320 * 240 / 25);
}

class TinyAmg : public ::testing::TestWithParam<std::string> {};

TEST_P(TinyAmg, FindsEveryColourRegionLikeTheReference) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  const std::string backend = GetParam();
  MaskGeneratorOptions options;
  options.model.backend = infer::ParseMaskBackend(backend);
  options.model.encoder = "tiny_" + backend + "_encoder";
  options.model.decoder = "tiny_" + backend + "_decoder";
  options.model.runtime = Runtime();
  options.points_per_side = 16;
  const auto registry = TinyRegistry();
  auto fast = MaskGenerator::Create(registry, options);
  auto reference = MaskGenerator::Create(registry, options, /*reference=*/true);
  const Scene s = MakeScene();
  const std::vector<Mask> masks = fast->Generate(s.rgb);
  const std::vector<Mask> ref = reference->Generate(s.rgb);
  EXPECT_LT(fast->stats().prompts_decoded, reference->stats().prompts_decoded);
  EXPECT_EQ(reference->stats().prompts_decoded, 256);
  // Each rectangle is found by both, and the background too (IoU > 0.9:
  // the encoder's pooling blurs edges by about a pixel).
  Image<uint8_t> background(320, 240, 1, 1);
  for (const Box& b : s.boxes) {
    const Mask gt = BoxMask(320, 240, b);
    EXPECT_GT(BestIou(gt, masks), 0.9) << backend;
    EXPECT_GT(BestIou(gt, ref), 0.9) << backend;
    for (int y = b.y0; y < b.y1; ++y) {
      for (int x = b.x0; x < b.x1; ++x) background(x, y) = 0;
    }
  }
  EXPECT_GT(BestIou(MaskFromImage(background), masks), 0.9);
  // Five regions, five masks: duplicates are removed by NMS.
  EXPECT_EQ(masks.size(), 5u);
  EXPECT_EQ(ref.size(), 5u);
  // Largest first.
  for (size_t i = 1; i < masks.size(); ++i) {
    EXPECT_GE(masks[i - 1].area, masks[i].area);
  }
  if (backend == "sam2") {
    // The object pointer is the mean colour / 255 of the mask.
    const auto palette = Palette();
    for (const Mask& m : masks) {
      ASSERT_EQ(m.embedding.size(), 256u);
      const int x = static_cast<int>(m.point_x),
                y = static_cast<int>(m.point_y);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(m.embedding[c], s.rgb(x, y, c) / 255.0, 0.02);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, TinyAmg, ::testing::Values("sam", "sam2"));

// The tiny SAM on a 16 x 16 prompt grid.
MaskGeneratorOptions TinySamOptions() {
  MaskGeneratorOptions options;
  options.model.encoder = "tiny_sam_encoder";
  options.model.decoder = "tiny_sam_decoder";
  options.model.runtime = Runtime();
  options.points_per_side = 16;
  return options;
}

TEST(TinyModels, PromptsOnlyWhereTheRegionAllows) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  auto generator = MaskGenerator::Create(TinyRegistry(), TinySamOptions());
  const Scene s = MakeScene();
  // What the map cannot explain: the second rectangle only (say, an object that
  // just entered).
  const Box& fresh = s.boxes[1];
  Image<uint8_t> region(320, 240);
  for (int y = fresh.y0; y < fresh.y1; ++y) {
    for (int x = fresh.x0; x < fresh.x1; ++x) region(x, y) = 1;
  }
  const std::vector<Mask> masks = generator->GenerateWhere(s.rgb, region);
  // The grid points inside the rectangle: columns 8..14 (x = 20 * i + 10 in
  // [160, 300)), rows 2..6 (y = 15 * j + 7.5 in [30, 110)).
  EXPECT_EQ(generator->stats().prompts_total, 7 * 5);
  ASSERT_FALSE(masks.empty());
  for (const Mask& m : masks) {
    EXPECT_NE(region(static_cast<int>(m.point_x), static_cast<int>(m.point_y)),
              0);
  }
  EXPECT_GT(BestIou(BoxMask(320, 240, fresh), masks), 0.9);
  EXPECT_LT(BestIou(BoxMask(320, 240, s.boxes[0]), masks),
            0.1);  // not prompted: not found

  // Nothing unexplained: no masks and no encoder run.
  const std::vector<Mask> none =
      generator->GenerateWhere(s.rgb, Image<uint8_t>(320, 240));
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(generator->stats().prompts_total, 0);
  EXPECT_EQ(generator->stats().encode_seconds, 0.0);
  EXPECT_EQ(generator->stats().encoder_calls, 0);
  // The whole frame: as Generate.
  const std::vector<Mask> all =
      generator->GenerateWhere(s.rgb, Image<uint8_t>(320, 240, 1, 1));
  EXPECT_EQ(all.size(), generator->Generate(s.rgb).size());
  EXPECT_THROW(generator->GenerateWhere(s.rgb, Image<uint8_t>(32, 24)),
               InvalidArgument);
}

// dense_stride sets how many grid points are always decoded (every
// dense_stride-th row and column); each finer level is skipped where an
// accepted mask covers it, or between rejected points of the level above
// (points skipped so count as rejected for the next level).
TEST(TinyModels, CoarserDenseGridsDecodeFewerPromptsAndFindTheSameRegions) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  const Scene s = MakeScene();
  int previous = 16 * 16 + 1;
  for (int stride : {2, 4, 8}) {
    MaskGeneratorOptions options = TinySamOptions();
    options.dense_stride = stride;
    auto generator = MaskGenerator::Create(TinyRegistry(), options);
    const std::vector<Mask> masks = generator->Generate(s.rgb);
    EXPECT_EQ(masks.size(), 5u) << stride;
    for (const Box& b : s.boxes) {
      EXPECT_GT(BestIou(BoxMask(320, 240, b), masks), 0.9) << stride;
    }
    const int decoded = generator->stats().prompts_decoded;
    EXPECT_LE(decoded, previous) << stride;
    EXPECT_GE(decoded, (16 / stride) * (16 / stride)) << stride;
    previous = decoded;

    // Every mask rejected: only the dense points are decoded when points
    // between rejected ones are skipped whatever the embedding says; each
    // level's skipped points stand for rejected ones for the next level.
    options.pred_iou_threshold = 1.0f;  // above the tiny model's IoUs
    options.rejected_similarity = 0.0f;
    auto rejecting = MaskGenerator::Create(TinyRegistry(), options);
    EXPECT_TRUE(rejecting->Generate(s.rgb).empty());
    EXPECT_EQ(rejecting->stats().prompts_decoded, (16 / stride) * (16 / stride))
        << stride;
    options.skip_between_rejected = false;
    auto every = MaskGenerator::Create(TinyRegistry(), options);
    every->Generate(s.rgb);
    EXPECT_EQ(every->stats().prompts_decoded, 256) << stride;
  }
}

// A point between rejected ones is skipped where it lies inside each of
// their rejected masks; a small object there lies outside them and is still
// prompted, where skipping between rejected points blindly loses it. Scene:
// a colour ramp (every mask a band, unstable: rejected) and a small square
// around one finest-level grid point only.
TEST(TinyModels, PointsInsideRejectedMasksAreSkippedOthersNot) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  ColorImage rgb(320, 240, 3);
  // Around grid point (30, 22.5) (column 1, row 1) and no other.
  const Box square{14, 10, 46, 35};
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) {
      const bool in =
          x >= square.x0 && x < square.x1 && y >= square.y0 && y < square.y1;
      const auto ramp = static_cast<uint8_t>(60 + 2 * x / 5);
      rgb(x, y, 0) = in ? 230 : ramp;
      rgb(x, y, 1) = in ? 30 : 100;
      rgb(x, y, 2) = in ? 30 : static_cast<uint8_t>(300 - ramp);
    }
  }
  const auto run = [&](float rejected_similarity, float inside_similarity,
                       float inside_logit, bool skip = true) {
    MaskGeneratorOptions options = TinySamOptions();
    options.rejected_similarity = rejected_similarity;
    options.rejected_inside_similarity = inside_similarity;
    options.rejected_inside_logit = inside_logit;
    options.skip_between_rejected = skip;
    auto generator = MaskGenerator::Create(TinyRegistry(), options);
    const std::vector<Mask> masks = generator->Generate(rgb);
    return std::make_pair(BestIou(BoxMask(320, 240, square), masks),
                          generator->stats().prompts_decoded);
  };
  // Nothing skipped between rejected points: every prompt, the square found,
  // the ramp's bands all rejected.
  const auto [every_iou, every] = run(0.0f, 1.0f, 0.0f, false);
  EXPECT_EQ(every, 256);
  EXPECT_GT(every_iou, 0.7);  // 1-pixel edges of the low-res mask
  // Inside the rejected masks only (the embedding test all but off: no two
  // points of the ramp look exactly alike): half the ramp's prompts skipped,
  // the square (outside every band) still prompted.
  const auto [inside_iou, inside] = run(0.9999f, 0.0f, 0.0f);
  EXPECT_GT(inside_iou, 0.7);
  EXPECT_LT(inside, every * 2 / 3);
  // Inside only where the mask is surer than any logit here: as without it.
  const auto [none_iou, none] = run(0.9999f, 0.0f, 100.0f);
  EXPECT_GT(none_iou, 0.7);
  EXPECT_GT(none, inside);
  // The embedding's test alone, blind: the square's point is skipped too.
  const auto [blind_iou, blind] = run(0.0f, 1.0f, 0.0f);
  EXPECT_LT(blind_iou, 0.1);
  EXPECT_LE(blind, inside);
}

TEST(TinyModels, CropLayersStillFindEveryRegionOnce) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  MaskGeneratorOptions options = TinySamOptions();
  options.crop_layers = 1;  // the image + 2 x 2 overlapping crops
  options.crop_points_downscale = 2;
  auto generator = MaskGenerator::Create(TinyRegistry(), options);
  const Scene s = MakeScene();
  const std::vector<Mask> masks = generator->Generate(s.rgb);
  // 16^2 prompts on the image, 8^2 on each of the 4 crops.
  EXPECT_EQ(generator->stats().prompts_total, 256 + 4 * 64);
  for (const Box& b : s.boxes) {
    EXPECT_GT(BestIou(BoxMask(320, 240, b), masks), 0.9);
  }
  // No rectangle twice: crop duplicates are removed by the cross-crop NMS.
  for (const Box& b : s.boxes) {
    int copies = 0;
    for (const Mask& m : masks) {
      copies += MaskIoU(BoxMask(320, 240, b), m) > 0.5;
    }
    EXPECT_EQ(copies, 1);
  }
  for (const Mask& m : masks) {
    EXPECT_EQ(m.image_width, 320);
    EXPECT_LE(m.box.x1, 320);
  }
}

TEST(TinyModels, BoxPromptsAndPooledEmbeddings) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  PromptableOptions options;
  options.encoder = "tiny_sam_encoder";
  options.decoder = "tiny_sam_decoder";
  options.runtime = Runtime();
  auto model = PromptableSegmenter::Create(TinyRegistry(), options);
  const Scene s = MakeScene();
  model->SetImage(s.rgb);
  Prompt prompt;
  prompt.box = Box{150, 20, 310, 120};  // around rectangle 1, with margin
  const Mask mask = model->Upsample(model->Decode(prompt));
  EXPECT_GT(MaskIoU(mask, BoxMask(320, 240, s.boxes[1])), 0.9);
  // The pooled encoder feature (mean embedding under the mask) differs
  // between regions of different colour and matches for equal ones.
  const auto a = model->PooledEmbedding(BoxMask(320, 240, s.boxes[0]));
  const auto a2 = model->PooledEmbedding(BoxMask(320, 240, {30, 30, 60, 60}));
  const auto b = model->PooledEmbedding(BoxMask(320, 240, s.boxes[1]));
  double same = 0, differ = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    same += std::abs(a[i] - a2[i]);
    differ += std::abs(a[i] - b[i]);
  }
  EXPECT_LT(same, 0.2 * differ);
  // The low-res forms used to decide which prompts to skip: the embedding at
  // a point of a region and the mean under that region's decoded mask agree
  // (one colour); another region's point does not.
  Prompt inside;
  inside.points = {{70, 60}};
  inside.labels = {1};
  const auto pooled = model->PooledEmbedding(model->Decode(inside));
  const auto here = model->EmbeddingAt(50, 40);
  const auto there = model->EmbeddingAt(200, 60);
  ASSERT_EQ(pooled.size(), here.size());
  double near = 0, far = 0;
  for (size_t i = 0; i < pooled.size(); ++i) {
    near += std::abs(pooled[i] - here[i]);
    far += std::abs(pooled[i] - there[i]);
  }
  EXPECT_LT(near, 0.1 * far);
  EXPECT_TRUE(model->PooledEmbedding(LowResMask{2, 2, {-1, -1, -1, -1}, 0, {}})
                  .empty());
}

TEST(TinyModels, SplitDecoderGivesTheExportsMasks) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  PromptableOptions options;
  options.encoder = "tiny_sam_encoder";
  options.decoder = "tiny_sam_decoder";
  options.runtime = Runtime();
  auto split = PromptableSegmenter::Create(TinyRegistry(), options);
  options.split_decoder = false;
  auto whole = PromptableSegmenter::Create(TinyRegistry(), options);
  const Scene s = MakeScene();
  split->SetImage(s.rgb);
  whole->SetImage(s.rgb);
  std::vector<Prompt> prompts(4);
  prompts[0].points = {{70, 60}};
  prompts[0].labels = {1};
  prompts[1].points = {{5, 5}};  // background
  prompts[1].labels = {1};
  prompts[2].box = Box{150, 20, 310, 120};
  prompts[3].points = {{200, 170}, {10, 230}, {300, 10}};  // 4 points: N varies
  prompts[3].labels = {1, 0, 0};
  for (size_t i = 0; i < prompts.size(); ++i) {
    const LowResMask a = split->Decode(prompts[i]),
                     b = whole->Decode(prompts[i]);
    ASSERT_EQ(a.logits.size(), b.logits.size());
    int inside = 0;
    for (size_t k = 0; k < a.logits.size(); ++k) {
      ASSERT_NEAR(a.logits[k], b.logits[k], 1e-5) << "prompt " << i;
      inside += a.logits[k] > 0;
    }
    EXPECT_GT(inside, 100) << "prompt " << i;  // a real mask, not all empty
    EXPECT_FLOAT_EQ(a.predicted_iou, b.predicted_iou);
  }
}

TEST(TinyModels, SplitDecoderPartsAreUsedAndChecked) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  // A registry whose prompt part is the image part: the split path must be the
  // one that runs (the export would decode fine) and say what is wrong.
  infer::ModelRegistry registry = TinyRegistry();
  infer::ModelEntry decoder = registry.Get("tiny_sam_decoder");
  decoder.split_prompt = decoder.split_image;
  registry.Add(decoder);
  PromptableOptions options;
  options.encoder = "tiny_sam_encoder";
  options.decoder = "tiny_sam_decoder";
  options.runtime = Runtime();
  auto model = PromptableSegmenter::Create(registry, options);
  model->SetImage(MakeScene().rgb);
  Prompt prompt;
  prompt.points = {{70, 60}};
  prompt.labels = {1};
  try {
    model->Decode(prompt);
    FAIL() << "decoding with a wrong prompt part succeeded";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("no input named 'point_coords'"),
              std::string::npos)
        << e.what();
  }
  options.split_decoder = false;
  EXPECT_NO_THROW(PromptableSegmenter::Create(registry, options)
                      ->SetImage(MakeScene().rgb));
}

infer::Tensor RandomTensor(const std::vector<int64_t>& shape,
                           semrec::Rng* rng) {
  infer::Tensor t = infer::Tensor::Zeros(shape);
  for (float& v : t.data) v = static_cast<float>(rng->Normal());
  return t;
}

// Same shape and values within float rounding (relative to the largest).
void ExpectSameValues(const infer::Tensor& expected, const infer::Tensor& got,
                      const std::string& name) {
  ASSERT_EQ(expected.shape, got.shape) << name;
  double scale = 0;
  for (float v : expected.data) scale = std::max(scale, std::abs(double{v}));
  ASSERT_GT(scale, 0.1) << name;
  for (size_t i = 0; i < expected.data.size(); ++i) {
    ASSERT_NEAR(expected.data[i], got.data[i], 1e-4 * scale)
        << name << " value " << i;
  }
}

TEST(TinyModels, UpscalingRewriteGivesTheExportsLogits) {
  // scripts/split_sam_decoder.py replaces SAM's NCHW upscaling (ConvTranspose,
  // LayerNorm2d, GELU, ConvTranspose, GELU, hypernetwork product) by
  // channel-last GEMMs and one final permutation; ONNX Runtime running the
  // exported form is the reference.
  const fs::path dir = semrec::testing::TinyModelDir();
  ASSERT_FALSE(dir.empty());
  const infer::OnnxSession exported(dir / "tiny_sam_upscaling.onnx");
  const infer::OnnxSession rewritten(dir / "tiny_sam_upscaling_rewritten.onnx");
  semrec::Rng rng(3);
  const infer::Tensor tokens = RandomTensor({1, 16, 8}, &rng);
  const infer::Tensor hyper = RandomTensor({1, 2, 4}, &rng);
  const auto a = exported.Run({{"tokens", tokens}, {"hyper", hyper}});
  const auto b = rewritten.Run({{"tokens", tokens}, {"hyper", hyper}});
  ASSERT_EQ(a.at("logits").shape, (std::vector<int64_t>{1, 2, 256}));
  // Exact up to float rounding, at every output pixel (a wrong raster
  // permutation or weight layout moves or mixes values).
  ExpectSameValues(a.at("logits"), b.at("logits"), "logits");
}

TEST(TinyModels, MaskPartAndPreviewGiveTheExportsChosenMask) {
  // split_mask_part: the prompt side keeps the export's choice (ArgMax of the
  // predicted IoUs) and a preview, the mask part upscales the chosen mask.
  const fs::path dir = semrec::testing::TinyModelDir();
  ASSERT_FALSE(dir.empty());
  const infer::OnnxSession exported(dir / "tiny_sam_mask_choice.onnx");
  const infer::OnnxSession prompt(dir / "tiny_sam_mask_choice_prompt.onnx");
  const infer::OnnxSession masks(dir / "tiny_sam_mask_choice_masks.onnx");
  semrec::Rng rng(9);
  const infer::Tensor tokens = RandomTensor({1, 16, 8}, &rng);
  const infer::Tensor hyper = RandomTensor({1, 2, 4}, &rng);
  for (const auto& iou : {infer::Tensor{{1, 2}, {0.9f, 0.2f}},
                          infer::Tensor{{1, 2}, {0.1f, 0.8f}}}) {
    SCOPED_TRACE(iou.data[0] > iou.data[1] ? "mask 0 chosen" : "mask 1 chosen");
    const auto a =
        exported.Run({{"tokens", tokens}, {"hyper", hyper}, {"iou", iou}});
    const auto p =
        prompt.Run({{"tokens", tokens}, {"hyper", hyper}, {"iou", iou}});
    const auto m = masks.Run({{"upscaling_tokens", p.at("upscaling_tokens")},
                              {"mask_hyper", p.at("mask_hyper")}});
    const infer::Tensor& low_res = a.at("low_res_masks");
    // The mask part gives each token's 4 x 4 cells in the order (ky1, kx1,
    // ky2, kx2): cell (4y + 2 ky1 + ky2, 4x + 2 kx1 + kx2) of the 16 x 16 mask.
    const infer::Tensor& blocks = m.at("block_logits");
    ASSERT_EQ(blocks.shape, (std::vector<int64_t>{1, 16, 16}));
    infer::Tensor composed = infer::Tensor::Zeros({1, 1, 16, 16});
    for (size_t t = 0; t < 16; ++t) {
      for (size_t c = 0; c < 16; ++c) {
        const size_t row = 4 * (t / 4) + 2 * ((c >> 3) & 1) + ((c >> 1) & 1);
        const size_t col = 4 * (t % 4) + 2 * ((c >> 2) & 1) + (c & 1);
        composed.data[row * 16 + col] = blocks.data[t * 16 + c];
      }
    }
    ExpectSameValues(low_res, composed, "low_res_masks");
    // Any tokens (those near a mask's edge): the same cells for those.
    const infer::Tensor& all = p.at("upscaling_tokens");
    infer::Tensor some = infer::Tensor::Zeros({1, 2, 8});
    std::copy_n(all.data.begin() + 5 * 8, 8, some.data.begin());
    std::copy_n(all.data.begin() + 10 * 8, 8, some.data.begin() + 8);
    const auto m2 = masks.Run(
        {{"upscaling_tokens", some}, {"mask_hyper", p.at("mask_hyper")}});
    const infer::Tensor& two = m2.at("block_logits");
    ASSERT_EQ(two.shape, (std::vector<int64_t>{1, 2, 16}));
    for (size_t c = 0; c < 16; ++c) {
      EXPECT_NEAR(two.data[c], blocks.data[5 * 16 + c], 1e-5);
      EXPECT_NEAR(two.data[16 + c], blocks.data[10 * 16 + c], 1e-5);
    }
    // preview(x, y) = low_res(4x + 2, 4y + 2): the 4 x 4 token grid.
    const infer::Tensor& preview = p.at("mask_preview");
    ASSERT_EQ(preview.shape, (std::vector<int64_t>{1, 1, 4, 4}));
    infer::Tensor expected = infer::Tensor::Zeros({1, 1, 4, 4});
    for (int y = 0; y < 4; ++y) {
      for (int x = 0; x < 4; ++x) {
        expected.data[static_cast<size_t>(y) * 4 + x] =
            low_res.data[static_cast<size_t>(4 * y + 2) * 16 +
                         static_cast<size_t>(4 * x + 2)];
      }
    }
    ExpectSameValues(expected, preview, "mask_preview");
  }
}

TEST(TinyModels, AttentionRewriteGivesTheExportsOutputs) {
  // The reordered cross-attention (projections folded into the few tokens'
  // side) against the exported blocks, for two token counts.
  const fs::path dir = semrec::testing::TinyModelDir();
  ASSERT_FALSE(dir.empty());
  const infer::OnnxSession exported(dir / "tiny_sam_attention.onnx");
  const infer::OnnxSession rewritten(dir / "tiny_sam_attention_rewritten.onnx");
  semrec::Rng rng(5);
  for (int64_t tokens : {3, 6}) {
    const infer::Tensor t = RandomTensor({1, tokens, 8}, &rng);
    const infer::Tensor image = RandomTensor({1, 16, 8}, &rng);
    const auto a = exported.Run({{"tokens", t}, {"image", image}});
    const auto b = rewritten.Run({{"tokens", t}, {"image", image}});
    for (const char* name : {"tokens_out", "image_out"}) {
      SCOPED_TRACE(std::to_string(tokens) + " tokens");
      ExpectSameValues(a.at(name), b.at(name), name);
    }
  }
}

TEST(TinyModels, HybridVoteGivesEachMaskItsMajorityClass) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  HybridSegmenterOptions options;
  options.semantic.model = "tiny_segformer";
  options.semantic.runtime = Runtime();
  options.masks.model.encoder = "tiny_sam_encoder";
  options.masks.model.decoder = "tiny_sam_decoder";
  options.masks.model.runtime = Runtime();
  options.masks.points_per_side = 16;
  HybridSegmenter segmenter(TinyRegistry(), options);
  const Scene s = MakeScene();
  const HybridResult r = segmenter.Segment(s.rgb);
  ASSERT_EQ(r.masks.size(), 5u);
  // The vote fixes the semantic branch's blurred borders: every pixel of a
  // rectangle now has its class exactly where the mask is sharp.
  for (size_t b = 0; b < s.boxes.size(); ++b) {
    const Box& box = s.boxes[b];
    for (int y = box.y0 + 1; y < box.y1 - 1; ++y) {
      for (int x = box.x0 + 1; x < box.x1 - 1; ++x) {
        ASSERT_EQ(r.vote.semantic(x, y), s.colours[b] + 1) << x << "," << y;
      }
    }
  }
  EXPECT_THROW(segmenter.Segment(ColorImage(8, 8, 3)), InvalidArgument);
}

TEST(TinyModels, WrongSignaturesAreCaughtAtLoad) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  infer::ModelRegistry registry = TinyRegistry();
  infer::ModelEntry entry = registry.Get("tiny_segformer");
  entry.inputs = {{"pixel_values", {1, 3, 640, 640}}};
  registry.Add(entry);
  SemanticSegmenterOptions options;
  options.model = "tiny_segformer";
  options.runtime = Runtime();
  EXPECT_THROW(SemanticSegmenter(registry, options), FormatError);
  // A decoder used as the semantic model.
  options.model = "tiny_sam_decoder";
  EXPECT_THROW(SemanticSegmenter(registry, options), InvalidArgument);
}

}  // namespace
}  // namespace semrec::segment
