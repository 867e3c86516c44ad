// SceneFusion's evidence steps (FusionOptions::Merge::kEvidence): coverage of
// the scene's objects by a frame's masks, class votes, merges the views argue
// for, and the fragment clean-up at the end. See fuse/mask_coverage.h.
#include <algorithm>
#include <map>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "semrec/core/union_find.h"
#include "semrec/fuse/fusion.h"

namespace semrec::fuse {
namespace {

bool IsObject(const SceneSegment& s) { return s.kind != ClassKind::kStuff; }

double VoteShare(const SceneSegment& s, uint16_t class_id) {
  uint64_t total = 0;
  for (const auto& [cls, n] : s.class_votes) total += n;
  const auto it = s.class_votes.find(class_id);
  return total == 0 || it == s.class_votes.end()
             ? 0.0
             : static_cast<double>(it->second) / static_cast<double>(total);
}

// Points of `a` with a point of `b` within the correspondence distance.
uint32_t PointsOn(const Cloud& a, const SceneSegment& b, double max_dist_m) {
  const float max_d2 = static_cast<float>(max_dist_m * max_dist_m);
  uint64_t computations = 0;
  uint32_t count = 0;
  for (const auto& p : a) {
    if (b.corr_grid.Nearest(b.corr_points, p, max_d2, &computations).index >=
        0) {
      ++count;
    }
  }
  return count;
}

}  // namespace

const char* FusionEventKindName(FusionEvent::Kind kind) {
  switch (kind) {
    case FusionEvent::Kind::kEvidenceMerge:
      return "evidence_merge";
    case FusionEvent::Kind::kCrossClassMatch:
      return "cross_class_match";
    case FusionEvent::Kind::kFragmentMerge:
      return "fragment_merge";
    case FusionEvent::Kind::kDropped:
      return "dropped";
  }
  return "?";
}

bool SceneFusion::ConfusedWith(const SceneSegment& s, uint16_t class_id) const {
  return s.class_id == class_id ||
         (IsObject(s) &&
          VoteShare(s, class_id) >= options_.evidence.confusion_share);
}

SceneFusion::FrameCoverage SceneFusion::Coverage(
    const std::vector<FrameSegment>& frame_segments,
    const std::vector<Cloud>& frame_corr,
    const std::vector<Eigen::AlignedBox3f>& frame_bounds) const {
  FrameCoverage coverage;
  coverage.on.assign(frame_segments.size(),
                     std::vector<uint32_t>(segments_.size(), 0));
  coverage.nearest = coverage.on;
  const float margin = static_cast<float>(options_.max_corr_dist_m);
  const float max_d2 =
      static_cast<float>(options_.max_corr_dist_m * options_.max_corr_dist_m);
  tbb::parallel_for(size_t{0}, frame_segments.size(), [&](size_t f) {
    if (frame_segments[f].kind == ClassKind::kStuff) return;
    std::vector<size_t> reachable;
    for (size_t s = 0; s < segments_.size(); ++s) {
      if (IsObject(segments_[s]) &&
          BoxesWithin(frame_bounds[f], segments_[s].bounds, margin)) {
        reachable.push_back(s);
      }
    }
    uint64_t computations = 0;
    for (const auto& p : frame_corr[f]) {
      float best_d2 = max_d2;
      int64_t best = -1;
      for (size_t s : reachable) {
        const SceneSegment& scene = segments_[s];
        const Neighbor n = scene.corr_grid.Nearest(scene.corr_points, p, max_d2,
                                                   &computations);
        if (n.index < 0) continue;
        ++coverage.on[f][s];
        if (best < 0 || n.d2 < best_d2) {  // ties: the earlier object
          best_d2 = n.d2, best = static_cast<int64_t>(s);
        }
      }
      if (best >= 0) ++coverage.nearest[f][static_cast<size_t>(best)];
    }
  });
  return coverage;
}

void SceneFusion::RecordViewEvidence(
    const std::vector<FrameSegment>& frame_segments,
    const FrameCoverage& coverage, size_t frame_index) {
  for (size_t f = 0; f < frame_segments.size(); ++f) {
    for (size_t s = 0; s < segments_.size(); ++s) {
      if (coverage.nearest[f][s] > 0) {
        segments_[s].class_votes[frame_segments[f].class_id] +=
            coverage.nearest[f][s];
      }
    }
  }
  std::vector<size_t> sizes;
  for (const SceneSegment& s : segments_) sizes.push_back(s.corr_points.size());
  const float gap = static_cast<float>(options_.evidence.max_gap_m);
  const ViewEvidence view = EvaluateView(
      coverage.on, sizes, options_.evidence, [&](size_t s, size_t t) {
        return BoxesWithin(segments_[s].bounds, segments_[t].bounds, gap);
      });
  for (const auto& [s, t, one] : view.pairs) {
    evidence_.Record(segments_[s].id, segments_[t].id,
                     static_cast<uint32_t>(frame_index), one);
  }
}

void SceneFusion::Absorb(SceneSegment* into, SceneSegment* from) {
  into->points.insert(into->points.end(), from->points.begin(),
                      from->points.end());
  from->points.clear();
  for (const auto& [cls, n] : from->class_votes) into->class_votes[cls] += n;
  into->first_seen_frame =
      std::min(into->first_seen_frame, from->first_seen_frame);
  into->last_seen_frame =
      std::max(into->last_seen_frame, from->last_seen_frame);
  into->observations += from->observations;
  into->frames_seen = SortedUnion(into->frames_seen, from->frames_seen);
  merged_into_[from->id] = into->id;
  evidence_.Absorb(into->id, from->id);
}

void SceneFusion::Rebuild(SceneSegment* s) const {
  s->points = VoxelDownsample(s->points, options_.store_voxel_size_m);
  s->corr_points = VoxelDownsample(s->points, options_.corr_voxel_size_m);
  s->bounds = BoundsOf(s->corr_points);
  s->corr_grid = VoxelGrid(s->corr_points, options_.max_corr_dist_m);
}

void SceneFusion::UpdateClass(SceneSegment* s) const {
  if (!IsObject(*s) || s->class_votes.empty()) return;
  uint64_t best = 0;
  for (const auto& [cls, n] : s->class_votes) {
    if (n > best) best = n, s->class_id = cls;  // ties: the smaller id
  }
}

size_t SceneFusion::MergeGroups(
    const std::vector<std::vector<size_t>>& groups) {
  std::vector<bool> removed(segments_.size(), false);
  std::vector<size_t> changed;
  size_t absorbed = 0;
  for (const auto& group : groups) {
    SceneSegment* into = &segments_[group[0]];
    for (size_t k = 1; k < group.size(); ++k) {
      Absorb(into, &segments_[group[k]]);
      removed[group[k]] = true;
      ++absorbed;
    }
    UpdateClass(into);
    changed.push_back(group[0]);
  }
  tbb::parallel_for(size_t{0}, changed.size(),
                    [&](size_t c) { Rebuild(&segments_[changed[c]]); });
  std::vector<SceneSegment> kept;
  kept.reserve(segments_.size() - absorbed);
  for (size_t s = 0; s < segments_.size(); ++s) {
    if (!removed[s]) kept.push_back(std::move(segments_[s]));
  }
  segments_ = std::move(kept);
  return absorbed;
}

size_t SceneFusion::MergeByEvidence(size_t frame_index) {
  std::map<uint32_t, size_t> index;
  for (size_t s = 0; s < segments_.size(); ++s) index[segments_[s].id] = s;
  UnionFind groups(segments_.size());
  std::map<size_t, std::string> reasons;  // member index -> why
  for (const auto& [key, e] : evidence_.pairs()) {
    if (!EvidenceGraph::SaysOne(e, options_.evidence)) continue;
    const auto a = index.find(key.first), b = index.find(key.second);
    if (a == index.end() || b == index.end()) continue;
    const SceneSegment& x = segments_[a->second];
    const SceneSegment& y = segments_[b->second];
    if (!IsObject(x) || !IsObject(y) ||
        (!ConfusedWith(x, y.class_id) && !ConfusedWith(y, x.class_id))) {
      continue;
    }
    groups.Unite(a->second, b->second);
    reasons.emplace(b->second,
                    fmt::format("one mask held objects {} and {} in {} views, "
                                "separate masks in {}",
                                x.id, y.id, e.one(), e.two()));
  }
  const auto merged = groups.Groups();
  for (const auto& group : merged) {
    for (size_t k = 1; k < group.size(); ++k) {
      const auto it = reasons.find(group[k]);
      events_.push_back({FusionEvent::Kind::kEvidenceMerge, frame_index,
                         segments_[group[k]].id, segments_[group[0]].id,
                         it != reasons.end() ? it->second : "through the group",
                         segments_[group[k]].class_id,
                         segments_[group[0]].class_id});
    }
  }
  return merged.empty() ? 0 : MergeGroups(merged);
}

size_t SceneFusion::CleanFragments() {
  const EvidenceOptions& o = options_.evidence;
  auto is_fragment = [&](const SceneSegment& s) {
    return IsObject(s) && (s.frames_seen.size() < o.fragment_min_frames ||
                           s.points.size() < o.fragment_min_points);
  };
  std::vector<std::pair<size_t, uint32_t>> fragments;  // (points, id)
  for (const SceneSegment& s : segments_) {
    if (is_fragment(s)) fragments.emplace_back(s.points.size(), s.id);
  }
  std::sort(fragments.begin(), fragments.end());  // smallest first
  const float margin = static_cast<float>(options_.max_corr_dist_m);
  size_t done = 0;
  for (const auto& candidate : fragments) {
    const uint32_t id = candidate.second;
    const auto it =
        std::find_if(segments_.begin(), segments_.end(),
                     [&](const SceneSegment& s) { return s.id == id; });
    if (it == segments_.end() || !is_fragment(*it)) continue;
    const size_t f = static_cast<size_t>(it - segments_.begin());
    const SceneSegment& fragment = segments_[f];
    size_t best = 0, target = 0;
    for (size_t t = 0; t < segments_.size(); ++t) {
      const SceneSegment& other = segments_[t];
      if (t == f || other.class_id != fragment.class_id ||
          !BoxesWithin(fragment.bounds, other.bounds, margin)) {
        continue;
      }
      const size_t touching =
          PointsOn(fragment.corr_points, other, options_.max_corr_dist_m);
      if (touching > best) best = touching, target = t;
    }
    const std::string what = fmt::format(
        "a fragment: seen in {} frame(s), {} points (minimum {} frames, {} "
        "points)",
        fragment.frames_seen.size(), fragment.points.size(),
        o.fragment_min_frames, o.fragment_min_points);
    if (best > 0) {
      events_.push_back({FusionEvent::Kind::kFragmentMerge, last_frame_, id,
                         segments_[target].id,
                         fmt::format("{} touching object {} of its class", what,
                                     segments_[target].id),
                         fragment.class_id, segments_[target].class_id});
      MergeGroups({{target, f}});
    } else {
      events_.push_back({FusionEvent::Kind::kDropped, last_frame_, id, 0,
                         what + " touching no object of its class",
                         fragment.class_id, 0});
      merged_into_[id] = 0;
      evidence_.Erase(id);
      segments_.erase(segments_.begin() + static_cast<std::ptrdiff_t>(f));
    }
    ++done;
  }
  return done;
}

size_t SceneFusion::Finish() {
  if (!evidence_on()) return 0;
  const size_t merged = MergeByEvidence(last_frame_);
  // With voxel evidence, fragments are judged by visibility (ResolveMap).
  if (voxel_map_) return merged;
  return merged + CleanFragments();
}

const MapResolution& SceneFusion::ResolveMap(MapContext context) {
  MapPreview decided = DecideMap(std::move(context), &next_id_);
  resolution_ = std::move(decided.resolution);
  segments_ = std::move(decided.segments);
  return *resolution_;
}

SceneFusion::MapPreview SceneFusion::PreviewMap(MapContext context) const {
  uint32_t next_id = next_id_;  // ids a snapshot hands out are not kept
  return DecideMap(std::move(context), &next_id);
}

MapResolution SceneFusion::PreviewResolution(MapContext context) const {
  uint32_t next_id = next_id_;
  return DecideResolution(&context, &next_id);
}

MapResolution SceneFusion::DecideResolution(MapContext* context,
                                            uint32_t* next_id) const {
  CheckArgument(voxel_map_.has_value(),
                "SceneFusion::ResolveMap: only with merge 'voxel'");
  for (const SceneSegment& s : segments_) {
    context->objects[s.id] = {s.class_id, s.kind};
  }
  return ResolveMapObjects(
      *voxel_map_, *context, options_.map_objects,
      [this](uint32_t id) { return ResolveId(id); }, next_id);
}

SceneFusion::MapPreview SceneFusion::DecideMap(MapContext context,
                                               uint32_t* next_id) const {
  MapPreview decided;
  decided.resolution = DecideResolution(&context, next_id);
  std::map<uint32_t, const SceneSegment*> by_id;
  for (const SceneSegment& s : segments_) by_id[s.id] = &s;
  for (const MapObject& o : decided.resolution.objects) {
    SceneSegment s;
    s.id = o.id;
    s.class_id = o.class_id;
    s.kind = o.kind;
    s.class_votes = o.class_votes;
    s.first_seen_frame = last_frame_;
    for (uint32_t source : o.sources) {
      const auto it = by_id.find(source);
      if (it == by_id.end()) continue;
      const SceneSegment& from = *it->second;
      s.first_seen_frame = std::min(s.first_seen_frame, from.first_seen_frame);
      s.last_seen_frame = std::max(s.last_seen_frame, from.last_seen_frame);
      s.observations += from.observations;
      s.frames_seen = SortedUnion(s.frames_seen, from.frames_seen);
    }
    for (uint64_t key : o.voxels) {
      s.points.push_back(voxel_map_->voxels().at(key).Centroid());
    }
    Rebuild(&s);
    decided.segments.push_back(std::move(s));
  }
  return decided;
}

}  // namespace semrec::fuse
