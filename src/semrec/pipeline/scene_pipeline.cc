#include "semrec/pipeline/scene_pipeline.h"

#include <algorithm>
#include <map>
#include <set>

#include <tbb/task_group.h>

#include "semrec/core/error.h"
#include "semrec/core/stopwatch.h"
#include "semrec/segment/mask.h"
#include "semrec/segment/segment_io.h"

namespace semrec::pipeline {
void ScenePipelineOptions::Check() const {
  CheckArgument(segment_every >= 1, "pipeline: segment_every must be >= 1");
  if (labels == Labels::kModels) {
    segmenter.Check();
    if (map_guidance) {
      guidance.Check();
      projection.Check();
    }
    if (track_people) people.Check();
  }
  offline.Check();
  scene.Check();
}

namespace {

// The people tracker's share of a detector pass over every class.
std::vector<track::Detection> PersonDetections(
    const std::vector<detect::LabeledDetection>& all,
    const detect::YoloxOptions& people) {
  std::vector<track::Detection> out;
  for (const detect::LabeledDetection& d : all) {
    const bool wanted = people.classes.empty() ||
                        std::find(people.classes.begin(), people.classes.end(),
                                  d.class_id) != people.classes.end();
    if (wanted && d.score >= people.score_threshold) {
      out.push_back({.box = d.box, .score = d.score, .embedding = {}});
    }
  }
  return out;
}

}  // namespace

std::vector<PersonObservation> PeopleFromIdMap(const LabelMap& person_ids) {
  std::set<uint16_t> ids(person_ids.values().begin(),
                         person_ids.values().end());
  ids.erase(0);
  std::vector<PersonObservation> people;
  for (const uint16_t id : ids) {
    Image<uint8_t> pixels(person_ids.width(), person_ids.height(), 1);
    for (size_t p = 0; p < person_ids.NumPixels(); ++p) {
      pixels.data()[p] = person_ids.data()[p] == id ? 1 : 0;
    }
    PersonObservation person;
    person.mask = segment::MaskFromImage(pixels);
    const segment::Box& b = person.mask.box;
    person.box.track_id = id;
    person.box.box = {static_cast<double>(b.x0), static_cast<double>(b.y0),
                      static_cast<double>(b.width()),
                      static_cast<double>(b.height())};
    people.push_back(std::move(person));
  }
  return people;
}

ScenePipeline::ScenePipeline(const infer::ModelRegistry* registry,
                             const LabelSet* given_classes,
                             const ScenePipelineOptions& options)
    : options_(options) {
  options_.Check();
  if (options_.labels == ScenePipelineOptions::Labels::kModels) {
    CheckArgument(registry != nullptr,
                  "pipeline: running the models needs a model registry");
    segmenter_ = std::make_unique<segment::HybridSegmenter>(*registry,
                                                            options_.segmenter);
    if (options_.track_people) {
      tracker_ = std::make_unique<PeopleTracker>(*registry, options_.people);
      const detect::YoloxOptions& people = options_.people.detector;
      const segment::ObjectDetectorOptions& objects =
          options_.segmenter.objects;
      if (objects.enabled() && objects.model == people.model) {
        // Per-class NMS and a class filter after it: the people's boxes are
        // exactly those of a people-only pass.
        detect::YoloxOptions shared = people;
        shared.classes.clear();
        shared.score_threshold =
            std::min(people.score_threshold, objects.score_threshold);
        shared_detector_ =
            std::make_unique<detect::YoloxDetector>(*registry, shared);
      }
    }
    builder_ =
        std::make_unique<SceneBuilder>(segmenter_->label_set(), options_.scene);
  } else {
    CheckArgument(given_classes != nullptr,
                  "pipeline: given labels need their class table");
    builder_ = std::make_unique<SceneBuilder>(*given_classes, options_.scene);
  }
}

ScenePipeline::~ScenePipeline() = default;

PipelineFrameResult ScenePipeline::Process(const PipelineInput& input) {
  return Integrate(Prepare(PipelineInput(input)));
}

PreparedFrame ScenePipeline::Prepare(PipelineInput input) {
  CheckArgument(!finished_, "pipeline: Process() after Finish()");
  const bool models = options_.labels == ScenePipelineOptions::Labels::kModels;
  PreparedFrame prepared;
  prepared.frame = std::move(input.frame);
  prepared.position = frames_;
  prepared.replay = input.replay.has_value();
  const Frame& frame = prepared.frame;
  StageWatch watch;

  // One detector pass for people and objects (when they share a detector).
  std::optional<std::vector<detect::LabeledDetection>> detections;
  if (shared_detector_ && !input.replay) {
    try {
      detections = shared_detector_->Detect(frame.color);
    } catch (const InvalidArgument& e) {
      throw FormatError(frame.color_path, e.what());
    }
  }

  // People first (every frame): map guidance leaves their pixels to them.
  std::vector<PersonObservation>& people = prepared.people;
  std::optional<LabelMap>& person_ids = prepared.person_ids;
  const int w = frame.color.width(), h = frame.color.height();
  if (options_.track_people) {
    if (input.replay) {
      const auto boxes = tracker_->Replay(input.replay->tracker_input);
      person_ids = std::move(input.replay->person_ids);
      for (const track::TrackedBox& box : boxes) {
        PersonObservation p;
        p.box = box;
        people.push_back(std::move(p));
      }
      prepared.tracker_input = std::move(input.replay->tracker_input);
    } else if (models) {
      PeopleFrame tracked;
      try {
        tracked = tracker_->Process(
            frame.color, detections
                             ? std::make_optional(PersonDetections(
                                   *detections, options_.people.detector))
                             : std::nullopt);
      } catch (const InvalidArgument& e) {
        throw FormatError(frame.color_path, e.what());
      }
      people = std::move(tracked.people);
      person_ids = PersonInstanceMap(people, w, h);
      prepared.tracker_input = std::move(tracked.tracker_input);
    } else if (input.person_ids) {
      person_ids = std::move(input.person_ids);
      people = PeopleFromIdMap(*person_ids);
    }
    for (const PersonObservation& p : people) {
      track_points_.push_back(
          {static_cast<int>(frame.index) + 1, p.box, false});
    }
  }
  AddLap(watch.Next(), &StageSeconds::track);

  // Segmentation: every segment_every-th frame (the first one always).
  std::optional<fuse::FrameLabels>& labels = prepared.labels;
  if (input.replay) {
    CheckArgument(models, "pipeline: replay is for model outputs");
    labels = std::move(input.replay->labels);
    prepared.guidance = input.replay->guidance;
    if (labels) CountGuidance(prepared.guidance, frame.T_world_camera);
  } else if (frames_ % options_.segment_every == 0) {
    if (models) {
      labels =
          SegmentFrame(frame, prepared.position, person_ids, &prepared.guidance,
                       options_.overlays ? &prepared.decision : nullptr,
                       detections ? &*detections : nullptr);
      if (detections) ++object_counts_.shared_passes;
    } else {
      CheckArgument(input.labels.has_value(),
                    "pipeline: frame " + input.name + " came without labels");
      labels = std::move(input.labels);
    }
  }
  AddLap(watch.Next(), &StageSeconds::segment);
  ++frames_;
  return prepared;
}

fuse::FrameLabels ScenePipeline::SegmentFrame(
    const Frame& frame, size_t position,
    const std::optional<LabelMap>& person_ids, std::string* mode,
    std::optional<GuidanceDecision>* decision_out,
    const std::vector<detect::LabeledDetection>* detections) {
  const std::string source = frame.color_path.string();
  // Without guidance, or before there is a map: a full frame.
  GuidanceDecision decision;
  fuse::ProjectedMap projected;
  std::optional<segment::SemanticResult> semantic;
  if (options_.map_guidance) {
    const std::shared_ptr<const std::vector<fuse::SceneSegment>> map =
        MapFor(position);
    if (map->empty()) {
      decision.reason = GuidanceReason::kNoMapYet;
    } else {
      try {
        projected =
            fuse::ProjectMap(*map, frame.intrinsics, frame.T_world_camera,
                             frame.depth, options_.projection);
        const bool people = person_ids && person_ids->NumPixels() > 0;
        decision =
            DecideFrame(projected, frame.T_world_camera, T_world_last_full_,
                        frames_since_full_ + 1, options_.guidance,
                        people ? &*person_ids : nullptr);
      } catch (const InvalidArgument& e) {
        throw FormatError(frame.depth_path, e.what());
      }
    }
    if (options_.guidance.prompt_on_disagreement &&
        decision.mode != FrameMode::kFull) {
      try {
        semantic = segmenter_->SegmentSemantic(frame.color);
      } catch (const InvalidArgument& e) {
        throw FormatError(frame.color_path, e.what());
      }
      AddDisagreement(projected, semantic->labels, options_.guidance,
                      &decision);
      if (decision.reason == GuidanceReason::kDisagreement) {
        ++guidance_counts_.disagreement;
      }
    }
    *mode = FrameModeName(decision.mode);
    CountGuidance(*mode, frame.T_world_camera);
    if (decision.mode != FrameMode::kFull) {
      guidance_counts_.unexplained_share_sum += decision.unexplained_share;
    }
    if (decision_out != nullptr) *decision_out = decision;
  }
  if (decision.mode == FrameMode::kProjectionOnly) {
    return ComposeFrameLabels(projected, decision, nullptr,
                              source + " (map projection)");
  }
  segment::HybridResult hybrid;
  try {
    hybrid = decision.mode == FrameMode::kFull
                 ? segmenter_->Segment(frame.color, detections)
                 : segmenter_->SegmentWhere(frame.color, decision.prompt_region,
                                            std::move(semantic), detections);
  } catch (const InvalidArgument& e) {
    throw FormatError(frame.color_path, e.what());
  }
  guidance_counts_.encoder_calls +=
      static_cast<size_t>(hybrid.mask_stats.encoder_calls);
  guidance_counts_.prompts_decoded +=
      static_cast<size_t>(hybrid.mask_stats.prompts_decoded);
  object_counts_.detections += hybrid.detections.size();
  object_counts_.matched += static_cast<size_t>(hybrid.detections_matched);
  object_counts_.added += static_cast<size_t>(hybrid.detections_added);
  object_counts_.parts += static_cast<size_t>(hybrid.detection_parts);
  object_counts_.parts_joined += static_cast<size_t>(hybrid.parts_joined);
  std::map<uint16_t, float> confidence = segment::InstanceConfidence(
      hybrid.vote, hybrid.semantic_branch.confidence);
  if (decision.mode == FrameMode::kFull) {
    fuse::FrameLabels labels{std::move(hybrid.vote.instance),
                             std::move(hybrid.vote.semantic), source};
    labels.confidence = std::move(confidence);
    return labels;
  }
  fuse::FrameLabels labels = ComposeFrameLabels(
      projected, decision, &hybrid.vote, source + " (map-guided)");
  // Fresh instances keep their ids; the map's own cast no vote.
  for (const auto& [instance, c] : confidence) {
    if (labels.map_objects.count(instance) == 0) {
      labels.confidence[instance] = c;
    }
  }
  return labels;
}

void ScenePipeline::CountGuidance(const std::string& mode,
                                  const Transform& T_world_camera) {
  if (mode.empty()) return;
  if (mode == FrameModeName(FrameMode::kFull)) {
    ++guidance_counts_.full;
    T_world_last_full_ = T_world_camera;
    frames_since_full_ = 0;
    return;
  }
  ++frames_since_full_;
  if (mode == FrameModeName(FrameMode::kPartial)) {
    ++guidance_counts_.partial;
  } else {
    ++guidance_counts_.projection;
  }
}

std::shared_ptr<const std::vector<fuse::SceneSegment>> ScenePipeline::MapFor(
    size_t position) {
  std::lock_guard<std::mutex> lock(maps_mutex_);
  // The newest map published after a frame at least two places back.
  std::shared_ptr<const std::vector<fuse::SceneSegment>> map;
  while (!maps_.empty() && maps_.front().first + 2 <= position) {
    map = maps_.front().second;
    if (maps_.size() > 1 && maps_[1].first + 2 <= position) {
      maps_.pop_front();
    } else {
      break;
    }
  }
  if (!map) map = std::make_shared<const std::vector<fuse::SceneSegment>>();
  return map;
}

void ScenePipeline::PublishMap(size_t position,
                               const fuse::FrameLabels& labels) {
  // A frame voted when it holds instances of its own (not the map's): only
  // then can the decision change (projection casts no vote).
  bool voted = false;
  for (const uint16_t instance : labels.instance.values()) {
    if (instance != 0 && labels.map_objects.count(instance) == 0) {
      voted = true;
      break;
    }
  }
  auto map = std::make_shared<std::vector<fuse::SceneSegment>>(
      builder_->MapForGuidance(options_.guidance.project_decided_map, voted));
  std::lock_guard<std::mutex> lock(maps_mutex_);
  maps_.emplace_back(position, std::move(map));
}

PipelineFrameResult ScenePipeline::Integrate(PreparedFrame prepared) {
  const bool models = options_.labels == ScenePipelineOptions::Labels::kModels;
  const std::optional<fuse::FrameLabels>& labels = prepared.labels;
  const std::optional<LabelMap>& person_ids = prepared.person_ids;
  PipelineFrameResult result;
  // The overlay needs only the frame's labels: drawn on another core while
  // the frame is fused (its time overlaps fuse's and volumes').
  tbb::task_group overlay_task;
  StageWatch::Lap overlay_lap;
  if (options_.overlays && !prepared.replay) {
    overlay_task.run([&] {
      StageWatch overlay_watch;
      const ColorImage base =
          labels ? segment::RenderLabelOverlay(prepared.frame.color,
                                               labels->semantic,
                                               labels->instance, classes())
                 : prepared.frame.color;
      result.overlay = RenderPeopleOverlay(base, prepared.people);
      if (prepared.decision) {
        result.overlay =
            RenderGuidanceOverlay(result.overlay, *prepared.decision);
      }
      overlay_lap = overlay_watch.Next();
    });
  }
  StageWatch watch;
  const SceneFrameStats stats =
      builder_->Add(prepared.frame, labels ? &*labels : nullptr,
                    person_ids ? &*person_ids : nullptr);
  AddLap({stats.fusion_seconds, stats.fusion_cpu_seconds}, &StageSeconds::fuse);
  AddLap({stats.volume_seconds, stats.volume_cpu_seconds},
         &StageSeconds::volumes);
  watch.Next();  // Add()'s own laps are above
  if (options_.map_guidance && labels) {
    // Deciding the map for guidance is fusion's work.
    PublishMap(prepared.position, *labels);
    AddLap(watch.Next(), &StageSeconds::fuse);
  }

  overlay_task.wait();
  AddLap(overlay_lap, &StageSeconds::overlay);

  if (models) {
    result.outputs.tracker_input = std::move(prepared.tracker_input);
    result.outputs.labels = labels;
    result.outputs.guidance = prepared.guidance;
    if (person_ids) result.outputs.person_ids = *person_ids;
  }
  result.segmented = labels.has_value();
  result.segments = stats.segments;
  result.people = prepared.people.size();
  segmented_frames_ += result.segmented ? 1 : 0;
  return result;
}

void ScenePipeline::Finish() {
  if (finished_) return;
  finished_ = true;
  builder_->Finish();
  finished_tracks_ = track::FinishTracks(track_points_, options_.offline);
  // People prims show the tracks the result file keeps, in its frames.
  std::map<uint32_t, std::set<size_t>> frames;
  for (const track::TrackPoint& p : finished_tracks_) {
    frames[static_cast<uint32_t>(p.box.track_id)].insert(
        static_cast<size_t>(p.frame - 1));
  }
  builder_->set_person_frames(std::move(frames));
}

SceneWriteResult ScenePipeline::Write(const std::filesystem::path& out_dir,
                                      const SceneWriteOptions& write_options) {
  StageWatch watch;
  SceneWriteResult result = builder_->Write(out_dir, write_options);
  AddLap(watch.Next(), &StageSeconds::write);
  return result;
}

std::vector<usd::MeshPrim> ScenePipeline::Meshes(SceneWriteResult* result) {
  return builder_->Meshes(result);
}

std::vector<io::MotBox> ScenePipeline::Tracks() const {
  return track::ToMotBoxes(finished_ ? finished_tracks_ : track_points_);
}

}  // namespace semrec::pipeline
