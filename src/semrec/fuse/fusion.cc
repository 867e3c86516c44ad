#define SPDLOG_ACTIVE_LEVEL SPDLOG_LEVEL_TRACE
#include "semrec/fuse/fusion.h"

#include <algorithm>
#include <map>
#include <numeric>
#include <optional>
#include <set>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include "semrec/core/enum_names.h"
#include "semrec/core/error.h"
#include "semrec/core/stopwatch.h"
#include "semrec/core/union_find.h"
#include "semrec/fuse/overlap.h"

namespace semrec::fuse {

void FusionOptions::Check() const {
  CheckArgument(corr_voxel_size_m > 0.0,
                "fusion: corr_voxel_size_m must be > 0");
  CheckArgument(store_voxel_size_m > 0.0,
                "fusion: store_voxel_size_m must be > 0");
  CheckArgument(max_corr_dist_m > 0.0, "fusion: max_corr_dist_m must be > 0");
  CheckArgument(alpha >= 0.0 && alpha < 1.0, "fusion: alpha must be in [0, 1)");
  evidence.Check();
  voxel_evidence.Check();
  map_objects.Check();
}

const char* MergeName(FusionOptions::Merge merge) {
  switch (merge) {
    case FusionOptions::Merge::kPaper:
      return "paper";
    case FusionOptions::Merge::kEvidence:
      return "evidence";
    case FusionOptions::Merge::kVoxel:
      return "voxel";
  }
  return "?";
}

FusionOptions::Merge ParseMerge(const std::string& name) {
  using Merge = FusionOptions::Merge;
  return ParseEnumName(name, {Merge::kPaper, Merge::kEvidence, Merge::kVoxel},
                       MergeName, "merge rule");
}

SceneFusion::SceneFusion(const FusionOptions& options) : options_(options) {
  options_.Check();
  if (options_.merge == FusionOptions::Merge::kVoxel) {
    voxel_map_.emplace(options_.store_voxel_size_m, options_.voxel_evidence);
  }
}

namespace {

// True when some stuff class has more than one segment in the frame: only
// then does JoinStuffPerClass change anything.
bool HasRepeatedStuffClass(const std::vector<FrameSegment>& segments) {
  std::set<uint16_t> seen;
  for (const FrameSegment& s : segments) {
    if (s.kind == ClassKind::kStuff && !seen.insert(s.class_id).second) {
      return true;
    }
  }
  return false;
}

// The frame's segments of one stuff class joined into one (at its first
// position), things unchanged; `origin[i]` is the joined index of input
// segment i.
std::vector<FrameSegment> JoinStuffPerClass(
    const std::vector<FrameSegment>& input, std::vector<size_t>* origin) {
  std::vector<FrameSegment> joined;
  std::map<uint16_t, size_t> stuff_index;
  origin->resize(input.size());
  for (size_t i = 0; i < input.size(); ++i) {
    const FrameSegment& s = input[i];
    if (s.kind == ClassKind::kStuff) {
      const auto [it, added] = stuff_index.emplace(s.class_id, joined.size());
      if (!added) {
        FrameSegment& joint = joined[it->second];
        Cloud& into = joint.points_world;
        into.insert(into.end(), s.points_world.begin(), s.points_world.end());
        // Projected and found pixels together: a segment found in the frame.
        if (joint.map_object != s.map_object) joint.map_object = 0;
        (*origin)[i] = it->second;
        continue;
      }
    }
    (*origin)[i] = joined.size();
    joined.push_back(s);
  }
  return joined;
}

}  // namespace

FrameFusionStats SceneFusion::Integrate(
    const std::vector<FrameSegment>& input_segments, size_t frame_index,
    const FrameObservation* observation) {
  const Stopwatch start;
  last_frame_ = frame_index;
  // Joined stuff segments only when there is something to join: a copy of
  // every frame segment's points per frame is not free.
  const bool join =
      options_.stuff_per_class && HasRepeatedStuffClass(input_segments);
  std::vector<size_t> origin;
  std::vector<FrameSegment> joined;
  if (join) joined = JoinStuffPerClass(input_segments, &origin);
  const std::vector<FrameSegment>& frame_segments =
      join ? joined : input_segments;
  FrameFusionStats stats;
  stats.frame_index = frame_index;
  stats.frame_segments = input_segments.size();
  stats.scene_segments_before = segments_.size();

  FrameClouds clouds = PrepareClouds(frame_segments, &stats);
  const std::vector<std::optional<size_t>> map_object =
      MapObjectsOf(frame_segments);
  // Evidence: where the frame's object masks fall on the scene's objects.
  double evidence_seconds = 0.0;
  FrameCoverage coverage;
  if (evidence_on()) {
    const Stopwatch t0;
    coverage = Coverage(frame_segments, clouds.corr, clouds.bounds);
    // The map seeing itself is neither a class vote nor a view.
    for (size_t f = 0; f < frame_segments.size(); ++f) {
      if (!map_object[f]) continue;
      std::fill(coverage.on[f].begin(), coverage.on[f].end(), 0u);
      std::fill(coverage.nearest[f].begin(), coverage.nearest[f].end(), 0u);
    }
    evidence_seconds += t0.Elapsed();
  }
  const auto matches = MatchSegments(frame_segments, clouds, map_object,
                                     coverage, frame_index, &stats);
  if (evidence_on()) {
    const Stopwatch t0;
    RecordViewEvidence(frame_segments, coverage, frame_index);
    evidence_seconds += t0.Elapsed();
  }
  ApplyMatches(frame_segments, matches, map_object, frame_index, &clouds,
               &stats);
  if (join) {  // report per input segment
    std::vector<uint32_t> ids(input_segments.size());
    for (size_t i = 0; i < ids.size(); ++i) {
      ids[i] = stats.assigned_ids[origin[i]];
    }
    stats.assigned_ids = std::move(ids);
  }
  if (evidence_on()) {
    const Stopwatch t0;
    for (SceneSegment& s : segments_) UpdateClass(&s);
    stats.evidence_merges = MergeByEvidence(frame_index);
    evidence_seconds += t0.Elapsed();
  }
  if (voxel_map_) {
    const Stopwatch t0;
    voxel_map_->AddFrame(input_segments, stats.assigned_ids, observation,
                         frame_index);
    evidence_seconds += t0.Elapsed();
  }
  stats.evidence_seconds = evidence_seconds;
  stats.seconds = start.Elapsed();
  return stats;
}

SceneFusion::FrameClouds SceneFusion::PrepareClouds(
    const std::vector<FrameSegment>& frame_segments,
    FrameFusionStats* stats) const {
  // Frame segments at the stored resolution (what a merge adds) and at the
  // comparison resolution (from the stored one: a few thousand points instead
  // of the raw pixels).
  const bool fast = options_.method == FusionOptions::Method::kFast;
  const size_t n = frame_segments.size();
  FrameClouds c;
  c.store.resize(n);
  c.corr.resize(n);
  c.bounds.resize(n);
  c.grids.resize(fast ? n : 0);
  tbb::parallel_for(size_t{0}, n, [&](size_t f) {
    c.store[f] = VoxelDownsample(frame_segments[f].points_world,
                                 options_.store_voxel_size_m);
    c.corr[f] = VoxelDownsample(c.store[f], options_.corr_voxel_size_m);
    c.bounds[f] = BoundsOf(c.corr[f]);
    if (fast) c.grids[f] = VoxelGrid(c.corr[f], options_.max_corr_dist_m);
  });
  for (const Cloud& corr : c.corr) stats->frame_points += corr.size();
  for (const SceneSegment& s : segments_) {
    stats->scene_points += s.corr_points.size();
  }
  for (size_t f = 0; f < n; ++f) {
    for (const SceneSegment& s : segments_) {
      const uint64_t pairs =
          static_cast<uint64_t>(c.corr[f].size()) * s.corr_points.size();
      stats->distance_computations_ungated += pairs;
      if (s.class_id == frame_segments[f].class_id) {
        stats->distance_computations_gated += pairs;
      }
    }
  }
  return c;
}

std::vector<std::optional<size_t>> SceneFusion::MapObjectsOf(
    const std::vector<FrameSegment>& frame_segments) const {
  // Map-guided segments belong to the object the map says they are (while it
  // exists; merged: the object it went into).
  std::vector<std::optional<size_t>> map_object(frame_segments.size());
  for (size_t f = 0; f < frame_segments.size(); ++f) {
    if (frame_segments[f].map_object == 0) continue;
    const uint32_t id = ResolveId(frame_segments[f].map_object);
    const auto it =
        std::find_if(segments_.begin(), segments_.end(),
                     [id](const SceneSegment& s) { return s.id == id; });
    if (it != segments_.end()) {
      map_object[f] = static_cast<size_t>(it - segments_.begin());
    }
  }
  return map_object;
}

std::vector<SceneFusion::Candidate> SceneFusion::ListCandidates(
    const std::vector<FrameSegment>& frame_segments, const FrameClouds& clouds,
    const std::vector<std::optional<size_t>>& map_object,
    const FrameCoverage& coverage, std::vector<std::vector<size_t>>* matches,
    FrameFusionStats* stats) const {
  // Same class, or with evidence an object of another class the segment lies
  // on; for `fast`, bounding boxes within reach.
  const bool fast = options_.method == FusionOptions::Method::kFast;
  const auto margin = static_cast<float>(options_.max_corr_dist_m);
  std::vector<Candidate> candidates;
  for (size_t f = 0; f < frame_segments.size(); ++f) {
    if (map_object[f]) {
      (*matches)[f].push_back(*map_object[f]);
      continue;
    }
    const bool stuff = frame_segments[f].kind == ClassKind::kStuff;
    for (size_t s = 0; s < segments_.size(); ++s) {
      const bool same_class =
          segments_[s].class_id == frame_segments[f].class_id;
      if (stuff && options_.stuff_per_class) {
        // Structure joins its class's segment, whatever the overlap.
        if (same_class) (*matches)[f].push_back(s);
        continue;
      }
      if (options_.label_gating && !same_class) {
        // Across classes only with evidence, for objects, when most of the
        // frame segment lies on this object.
        const double alpha = options_.evidence.cross_class_alpha;
        if (evidence_on() && !stuff && alpha < 1.0 &&
            segments_[s].kind != ClassKind::kStuff &&
            coverage.nearest[f][s] >
                alpha * static_cast<double>(clouds.corr[f].size())) {
          candidates.push_back({f, s, alpha, {}, false});
        }
        continue;
      }
      ++stats->compared_pairs;
      // No pair can be close.
      if (fast && !BoxesWithin(clouds.bounds[f], segments_[s].bounds, margin)) {
        continue;
      }
      candidates.push_back({f, s, options_.alpha, {}, false});
    }
  }
  return candidates;
}

std::vector<std::vector<size_t>> SceneFusion::MatchSegments(
    const std::vector<FrameSegment>& frame_segments, const FrameClouds& clouds,
    const std::vector<std::optional<size_t>>& map_object,
    const FrameCoverage& coverage, size_t frame_index,
    FrameFusionStats* stats) {
  // Every frame segment against the scene before this frame: the candidate
  // pairs are compared in parallel pair by pair (one large segment, floor or
  // wall, would otherwise keep a core busy alone).
  std::vector<std::vector<size_t>> matches(frame_segments.size());
  const Stopwatch compare_start;
  std::vector<Candidate> candidates = ListCandidates(
      frame_segments, clouds, map_object, coverage, &matches, stats);
  const bool fast = options_.method == FusionOptions::Method::kFast;
  auto compare = [&](size_t k) {
    Candidate& c = candidates[k];
    const SceneSegment& scene = segments_[c.scene_segment];
    if (fast) {
      // Stops as soon as the decision is settled (same decision as the full
      // sigma).
      const OverlapDecision d = MutualOverlapExceeds(
          clouds.corr[c.frame_segment], clouds.grids[c.frame_segment],
          scene.corr_points, scene.corr_grid, options_.max_corr_dist_m,
          c.alpha);
      c.overlap = d.partial;
      c.exceeds = d.exceeds;
    } else {
      c.overlap =
          MutualOverlapBruteForce(clouds.corr[c.frame_segment],
                                  scene.corr_points, options_.max_corr_dist_m);
      c.exceeds = c.overlap.sigma > c.alpha;
    }
  };
  if (fast) {
    tbb::parallel_for(size_t{0}, candidates.size(), compare);
  } else {
    for (size_t k = 0; k < candidates.size(); ++k) compare(k);
  }
  stats->compare_seconds = compare_start.Elapsed();
  for (const Candidate& c : candidates) {
    stats->distance_computations_done += c.overlap.distance_computations;
    SPDLOG_TRACE(
        "frame {} segment {} (class {}, {} pts) vs scene {} ({} pts): "
        "|M|{}{} sigma{}{:.3f} -> {}",
        frame_index, c.frame_segment, frame_segments[c.frame_segment].class_id,
        clouds.corr[c.frame_segment].size(), segments_[c.scene_segment].id,
        segments_[c.scene_segment].corr_points.size(), fast ? ">=" : "=",
        c.overlap.mutual_pairs, fast ? ">=" : "=", c.overlap.sigma,
        c.exceeds ? "merge" : "no");
    if (!c.exceeds) continue;
    // In increasing scene order per frame segment (the list's order).
    matches[c.frame_segment].push_back(c.scene_segment);
    const SceneSegment& scene = segments_[c.scene_segment];
    const uint16_t segment_class = frame_segments[c.frame_segment].class_id;
    if (scene.class_id != segment_class) {
      ++stats->cross_class_matches;
      events_.push_back(
          {FusionEvent::Kind::kCrossClassMatch, frame_index, 0, scene.id,
           fmt::format("a segment of another class lies on object {} (overlap "
                       "sigma >= {:.2f} > {})",
                       scene.id, c.overlap.sigma, c.alpha),
           segment_class, scene.class_id});
    }
  }
  return matches;
}

void SceneFusion::ApplyMatches(
    const std::vector<FrameSegment>& frame_segments,
    const std::vector<std::vector<size_t>>& matches,
    const std::vector<std::optional<size_t>>& map_object, size_t frame_index,
    FrameClouds* clouds, FrameFusionStats* stats) {
  // Scene segments linked through a frame segment become one; the frame
  // segments attach to it, or become new segments.
  UnionFind groups(segments_.size());
  for (const auto& m : matches) {
    for (size_t k = 1; k < m.size(); ++k) groups.Unite(m[0], m[k]);
  }
  std::map<size_t, std::vector<size_t>> attached;  // root -> frame segments
  std::vector<SceneSegment> created;
  stats->assigned_ids.resize(frame_segments.size());
  for (size_t f = 0; f < frame_segments.size(); ++f) {
    if (matches[f].empty()) {
      SceneSegment s;
      s.id = next_id_++;
      stats->assigned_ids[f] = s.id;
      s.class_id = frame_segments[f].class_id;
      s.kind = frame_segments[f].kind;
      s.class_votes[s.class_id] = clouds->corr[f].size();
      s.points = std::move(clouds->store[f]);
      s.first_seen_frame = s.last_seen_frame = frame_index;
      s.observations = 1;
      s.frames_seen = {static_cast<uint32_t>(frame_index)};
      created.push_back(std::move(s));
    } else {
      const size_t root = groups.Find(matches[f][0]);
      attached[root].push_back(f);
      stats->assigned_ids[f] = segments_[root].id;
      ++stats->merged_frame_segments;
    }
  }
  std::map<size_t, std::vector<size_t>> members;  // root -> scene segments
  for (size_t s = 0; s < segments_.size(); ++s) {
    members[groups.Find(s)].push_back(s);
  }
  std::vector<SceneSegment> next;
  std::vector<size_t> changed;  // indices into `next` to rebuild
  for (auto& [root, group] : members) {
    const auto it = attached.find(root);
    if (it == attached.end()) {  // untouched this frame
      for (size_t s : group) next.push_back(std::move(segments_[s]));
      continue;
    }
    next.push_back(MergeGroup(root, group, it->second, frame_segments,
                              map_object, *clouds, frame_index, stats));
    changed.push_back(next.size() - 1);
  }
  for (SceneSegment& s : created) {
    changed.push_back(next.size());
    next.push_back(std::move(s));
  }
  stats->new_segments = created.size();
  tbb::parallel_for(size_t{0}, changed.size(),
                    [&](size_t c) { Rebuild(&next[changed[c]]); });
  std::sort(
      next.begin(), next.end(),
      [](const SceneSegment& a, const SceneSegment& b) { return a.id < b.id; });
  segments_ = std::move(next);
}

SceneSegment SceneFusion::MergeGroup(
    size_t root, const std::vector<size_t>& group,
    const std::vector<size_t>& attached,
    const std::vector<FrameSegment>& frame_segments,
    const std::vector<std::optional<size_t>>& map_object,
    const FrameClouds& clouds, size_t frame_index, FrameFusionStats* stats) {
  SceneSegment merged = std::move(segments_[root]);
  std::map<uint16_t, size_t> class_points;
  class_points[merged.class_id] += merged.points.size();
  for (size_t s : group) {
    if (s == root) continue;
    SceneSegment& other = segments_[s];
    class_points[other.class_id] += other.points.size();
    Absorb(&merged, &other);
    ++stats->removed_by_merge;
  }
  for (size_t f : attached) {
    const Cloud& p = clouds.store[f];
    class_points[frame_segments[f].class_id] += p.size();
    merged.points.insert(merged.points.end(), p.begin(), p.end());
    ++merged.observations;
    // The map's own projection is no new sighting (fragments seen once stay
    // fragments) and no class vote.
    if (map_object[f]) continue;
    SortedInsert(&merged.frames_seen, static_cast<uint32_t>(frame_index));
    // With evidence the coverage counted this segment's vote already.
    if (!evidence_on()) {
      merged.class_votes[frame_segments[f].class_id] += clouds.corr[f].size();
    }
  }
  // With evidence every class is updated from the votes.
  if (!evidence_on() && !options_.label_gating) {
    size_t best = 0;
    for (const auto& [cls, count] : class_points) {
      if (count > best) best = count, merged.class_id = cls;
    }
  }
  merged.last_seen_frame = frame_index;
  return merged;
}

uint32_t SceneFusion::ResolveId(uint32_t id) const {
  for (auto it = merged_into_.find(id); it != merged_into_.end();
       it = merged_into_.find(id)) {
    id = it->second;
  }
  return id;
}

}  // namespace semrec::fuse
