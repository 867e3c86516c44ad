#include "semrec/fuse/mask_coverage.h"

#include <algorithm>
#include <iterator>

#include "semrec/core/error.h"

namespace semrec::fuse {
namespace {

std::vector<uint32_t> Difference(const std::vector<uint32_t>& a,
                                 const std::vector<uint32_t>& b) {
  std::vector<uint32_t> out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(),
                      std::back_inserter(out));
  return out;
}

}  // namespace

std::vector<uint32_t> SortedUnion(const std::vector<uint32_t>& a,
                                  const std::vector<uint32_t>& b) {
  std::vector<uint32_t> out;
  std::set_union(a.begin(), a.end(), b.begin(), b.end(),
                 std::back_inserter(out));
  return out;
}

void SortedInsert(std::vector<uint32_t>* v, uint32_t x) {
  const auto it = std::lower_bound(v->begin(), v->end(), x);
  if (it == v->end() || *it != x) v->insert(it, x);
}

void EvidenceOptions::Check() const {
  CheckArgument(min_seen_points >= 1,
                "fusion evidence: min_seen_points must be >= 1");
  CheckArgument(min_seen_share >= 0.0 && min_seen_share <= 1.0,
                "fusion evidence: min_seen_share must be in [0, 1]");
  CheckArgument(min_hold_share > 0.0 && min_hold_share <= 1.0,
                "fusion evidence: min_hold_share must be in (0, 1]");
  CheckArgument(min_one_views >= 1,
                "fusion evidence: min_one_views must be >= 1");
  CheckArgument(min_views >= 1, "fusion evidence: min_views must be >= 1");
  CheckArgument(two_weight >= 0.0, "fusion evidence: two_weight must be >= 0");
  CheckArgument(max_gap_m >= 0.0, "fusion evidence: max_gap_m must be >= 0");
  CheckArgument(cross_class_alpha > 0.0 && cross_class_alpha <= 1.0,
                "fusion evidence: cross_class_alpha must be in (0, 1] (1 "
                "turns cross-class merges off)");
  CheckArgument(confusion_share > 0.0 && confusion_share <= 1.0,
                "fusion evidence: confusion_share must be in (0, 1]");
}

void EvidenceGraph::Record(uint32_t a, uint32_t b, uint32_t frame, bool one) {
  if (a == b) return;
  PairEvidence& e = pairs_[Key(a, b)];
  if (one) {
    SortedInsert(&e.one_frames, frame);
    e.two_frames = Difference(e.two_frames, {frame});
  } else if (!std::binary_search(e.one_frames.begin(), e.one_frames.end(),
                                 frame)) {
    SortedInsert(&e.two_frames, frame);
  }
}

void EvidenceGraph::Absorb(uint32_t into, uint32_t from) {
  if (into == from) return;
  std::vector<std::pair<uint32_t, PairEvidence>> moved;
  for (auto it = pairs_.begin(); it != pairs_.end();) {
    const auto [a, b] = it->first;
    if (a == from || b == from) {
      const uint32_t other = a == from ? b : a;
      if (other != into) moved.emplace_back(other, std::move(it->second));
      it = pairs_.erase(it);
    } else {
      ++it;
    }
  }
  for (auto& [other, e] : moved) {
    PairEvidence& target = pairs_[Key(into, other)];
    target.one_frames = SortedUnion(target.one_frames, e.one_frames);
    target.two_frames = Difference(SortedUnion(target.two_frames, e.two_frames),
                                   target.one_frames);
  }
}

void EvidenceGraph::Erase(uint32_t id) {
  for (auto it = pairs_.begin(); it != pairs_.end();) {
    if (it->first.first == id || it->first.second == id) {
      it = pairs_.erase(it);
    } else {
      ++it;
    }
  }
}

const PairEvidence* EvidenceGraph::Find(uint32_t a, uint32_t b) const {
  const auto it = pairs_.find(Key(a, b));
  return it == pairs_.end() ? nullptr : &it->second;
}

bool EvidenceGraph::SaysOne(const PairEvidence& e,
                            const EvidenceOptions& options) {
  return e.one() >= options.min_one_views &&
         e.one() + e.two() >= options.min_views &&
         static_cast<double>(e.one()) >
             options.two_weight * static_cast<double>(e.two());
}

}  // namespace semrec::fuse
