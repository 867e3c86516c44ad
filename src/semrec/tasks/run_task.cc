#include "semrec/tasks/run_task.h"

#include "semrec/core/error.h"
#include "semrec/track/tracker.h"

namespace semrec::tasks {

void ModelChoice::Check() const {
  CheckArgument(!semantic.empty(), "models: no semantic model named");
  CheckArgument(!masks.empty(),
                "models: masks must name a mask model or be 'none'");
  CheckArgument(masks != "none" || object_detector.empty(),
                "models: the object detector needs the mask model (its boxes "
                "are mask prompts): name a mask model, or no object detector");
  CheckArgument(!people_detector.empty(), "models: no people detector named");
  CheckArgument(people_score >= 0.0f && people_score <= 1.0f,
                "models: people_score must be in [0, 1]");
  CheckArgument(mask_margin_logits >= 0.0f,
                "models: mask_margin_logits must be >= 0");
  runtime.Check();
}

void ApplyModelChoice(const infer::ModelRegistry& registry,
                      const ModelChoice& choice,
                      pipeline::ScenePipelineOptions* pipeline) {
  choice.Check();
  pipeline->labels = pipeline::ScenePipelineOptions::Labels::kModels;
  segment::HybridSegmenterOptions& segmenter = pipeline->segmenter;
  segmenter.semantic.model = choice.semantic;
  segmenter.semantic.runtime = choice.runtime;
  segmenter.use_masks = choice.masks != "none";
  if (segmenter.use_masks) {
    segmenter.masks.model = segment::PromptableOptions::FromRegistry(
        registry, choice.masks, choice.runtime);
    segmenter.masks.model.mask_margin_logits = choice.mask_margin_logits;
    segmenter.masks.model.decoder_kernel = choice.decoder_kernel;
  }
  segmenter.objects.model = choice.object_detector;
  segmenter.objects.runtime = choice.runtime;
  pipeline::PeopleTrackerOptions& people = pipeline->people;
  people.detector.model = choice.people_detector;
  people.detector.score_threshold = choice.people_score;
  people.detector.runtime = choice.runtime;
  people.masks = segmenter.use_masks;
  if (people.masks) people.mask_model = segmenter.masks.model;
  people.tracker = track::TrackerOptions::Improved();
}

void RunTaskOptions::Check() const {
  CheckArgument(!sequence.empty(), "run: no recording given");
  CheckArgument(!out.empty(), "run: no output folder given");
  CheckArgument(!labels.given() || !run.pipeline.map_guidance,
                "run: map guidance guides the segmentation models: it needs "
                "labels 'models'");
  if (!labels.given()) models.Check();
  reader.Check();
  run.Check();
}

RunTaskResult RunTask(const RunTaskOptions& options,
                      const ProgressOptions& progress) {
  options.Check();
  pipeline::RunOptions run = options.run;
  std::optional<infer::ModelRegistry> registry;
  if (!options.labels.given()) {
    registry = infer::ModelRegistry::LoadDefaultWith(options.models.registry);
    ApplyModelChoice(*registry, options.models, &run.pipeline);
  } else {
    run.pipeline.labels = pipeline::ScenePipelineOptions::Labels::kGiven;
    run.given_labels = options.labels;
  }
  run.Check();
  io::SequenceReaderOptions reader_options = options.reader;
  reader_options.max_depth_m = run.pipeline.scene.meshing.tsdf.max_depth_m;
  // A recording without poses opens when they may be estimated.
  reader_options.require_poses =
      run.poses == pipeline::RunOptions::Poses::kFile;
  const io::SequenceReader reader =
      io::SequenceReader::Open(options.sequence, reader_options);
  RunTaskResult result;
  result.run = pipeline::RunSequence(reader, registry ? &*registry : nullptr,
                                     run, options.out, progress);
  if (options.report_html) {
    result.report =
        viewer::WriteHtmlReport(options.out, options.report_pictures);
  }
  return result;
}

}  // namespace semrec::tasks
