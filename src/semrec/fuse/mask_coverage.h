// Multi-view evidence for fusion: which scene objects a frame's masks fall on.
//
// The paper's rule merges a frame segment into scene segments it overlaps in
// space, so the parts of one object that sit side by side (a chair's seat and
// back, the two halves of a sofa that SAM cut apart in the first views) stay
// separate objects forever. Every later view says more: a mask that covers two
// scene objects is evidence they are one; two separate masks over them are
// evidence they are two. Mask generators over-segment far more often than they
// join two real objects into one mask, so a view showing one mask weighs more
// than a view showing two (`two_weight`).
//
// Coverage is measured in 3D against the scene as it was before the frame: a
// frame point "lies on" an object when one of the object's comparison points is
// within the correspondence distance. The frame's points are what the camera
// sees, so occluded parts of an object give no evidence either way.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <tuple>
#include <utility>
#include <vector>

namespace semrec::fuse {

struct EvidenceOptions {
  /// An object is seen in a frame when at least this many of the frame's
  /// comparison points (corr_voxel_size_m voxels) lie on it.
  size_t min_seen_points = 4;
  /// ... and at least this share of the object's own comparison points: a
  /// neighbour's mask grazing an object that is out of view says nothing
  /// about it.
  double min_seen_share = 0.2;
  /// A frame segment holds an object in that view when it has at least this
  /// share of the object's seen points.
  double min_hold_share = 0.5;
  /// Merge two objects when at least `min_one_views` views held both in one
  /// segment and one > two_weight x two (views holding them in different
  /// segments): with 0.5, one view in three showing a single mask suffices.
  size_t min_one_views = 2;
  double two_weight = 0.5;
  /// ... and the pair was seen together (held by one or by two segments) in at
  /// least this many views: early views alone do not decide.
  size_t min_views = 3;
  /// Views count only for objects whose bounding boxes are within this gap:
  /// parts of one object touch, and a mask that spans two objects far apart
  /// joined them through a third (a chair, the table, another chair).
  double max_gap_m = 0.3;
  /// Objects of different classes merge only when the class votes show the
  /// two classes confused (one object's votes give the other's class at least
  /// `confusion_share`), by view evidence or when they cover the same surface
  /// (overlap sigma > cross_class_alpha: one surface, labelled differently in
  /// different views).
  double confusion_share = 0.35;
  double cross_class_alpha = 0.8;
  /// At the end, an object seen in fewer frames or with fewer stored points is
  /// a fragment: merged into the object of its class it touches most, or
  /// dropped.
  size_t fragment_min_frames = 2;
  size_t fragment_min_points = 20;

  void Check() const;
};

/// Sets of frame indices kept as sorted vectors without duplicates.
std::vector<uint32_t> SortedUnion(const std::vector<uint32_t>& a,
                                  const std::vector<uint32_t>& b);
void SortedInsert(std::vector<uint32_t>* v, uint32_t x);

/// Views in which a pair of objects was held by one segment, and views in
/// which both were held by different segments.
struct PairEvidence {
  std::vector<uint32_t> one_frames;  // sorted, unique
  std::vector<uint32_t> two_frames;  // sorted, unique, none in one_frames
  size_t one() const { return one_frames.size(); }
  size_t two() const { return two_frames.size(); }
};

/// The evidence graph over scene object ids.
class EvidenceGraph {
 public:
  /// A view of `frame` held objects a and b in one segment (`one`) or in two.
  void Record(uint32_t a, uint32_t b, uint32_t frame, bool one);
  /// Object `from` was merged into `into`: its pairs become `into`'s (views
  /// joined; a view that showed both one and two counts as one).
  void Absorb(uint32_t into, uint32_t from);
  /// Object `id` is gone: its pairs are forgotten.
  void Erase(uint32_t id);
  /// Evidence for the pair, or nullptr.
  const PairEvidence* Find(uint32_t a, uint32_t b) const;
  const std::map<std::pair<uint32_t, uint32_t>, PairEvidence>& pairs() const {
    return pairs_;
  }
  /// True when the views say "one": one >= min_one_views and one >
  /// two_weight * two.
  static bool SaysOne(const PairEvidence& e, const EvidenceOptions& options);

 private:
  static std::pair<uint32_t, uint32_t> Key(uint32_t a, uint32_t b) {
    return a < b ? std::make_pair(a, b) : std::make_pair(b, a);
  }
  std::map<std::pair<uint32_t, uint32_t>, PairEvidence> pairs_;
};

/// What one view says, from the coverage counts near[f][s] (points of frame
/// segment f lying on object s). Objects seen (>= min_seen_points) and held by
/// a segment (>= min_hold_share of their seen points) form pairs when
/// `adjacent(s, t)`: same holder -> one, different holders -> two.
struct ViewEvidence {
  /// (s, t, one) over object indices, s < t.
  std::vector<std::tuple<size_t, size_t, bool>> pairs;
  /// Holder segment per object, -1 when not seen or not held.
  std::vector<int64_t> holder;
};
/// `object_points[s]`: object s's comparison points.
template <typename Adjacent>
ViewEvidence EvaluateView(const std::vector<std::vector<uint32_t>>& near,
                          const std::vector<size_t>& object_points,
                          const EvidenceOptions& options,
                          const Adjacent& adjacent) {
  const size_t objects = object_points.size();
  ViewEvidence view;
  view.holder.assign(objects, -1);
  for (size_t s = 0; s < objects; ++s) {
    uint64_t seen = 0, best = 0;
    int64_t holder = -1;
    for (size_t f = 0; f < near.size(); ++f) {
      seen += near[f][s];
      if (near[f][s] > best) {
        best = near[f][s], holder = static_cast<int64_t>(f);
      }
    }
    if (seen >= options.min_seen_points &&
        static_cast<double>(seen) >=
            options.min_seen_share * static_cast<double>(object_points[s]) &&
        static_cast<double>(best) >=
            options.min_hold_share * static_cast<double>(seen)) {
      view.holder[s] = holder;
    }
  }
  for (size_t s = 0; s < objects; ++s) {
    if (view.holder[s] < 0) continue;
    for (size_t t = s + 1; t < objects; ++t) {
      if (view.holder[t] < 0) continue;
      if (adjacent(s, t)) {
        view.pairs.emplace_back(s, t, view.holder[s] == view.holder[t]);
      }
    }
  }
  return view;
}

}  // namespace semrec::fuse
