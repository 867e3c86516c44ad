// LabelNoiseOptions::bleed: object pixels at the floor or walls, or dark, take
// the structure's labels, the same parts in most views.
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/synth/generator.h"
#include "semrec/synth/label_noise.h"
#include "semrec/synth/scene.h"

namespace semrec::synth {
namespace {

struct Views {
  Scene scene;
  CameraIntrinsics k;
  std::vector<Transform> poses;
  std::vector<RenderedFrame> frames;
};

// `n` sparse views of a preset's scene (six-objects: robot height, floor
// contact in view; the small room makes them overlap), at quarter resolution.
Views SparseViews(int n, const std::string& preset = "six-objects") {
  SynthOptions o = SynthOptions::Preset(preset);
  o.trajectory.kind = TrajectoryOptions::Kind::kSparse;
  Views v;
  v.scene = GenerateScene(o.scene);
  v.k = CameraIntrinsics{160, 120, 131.25, 131.25, 79.5, 59.5};
  v.poses = MakeTrajectory(v.scene, o.trajectory, n, o.fps, o.seed);
  for (int i = 0; i < n; ++i) {
    v.frames.push_back(Render(v.scene, i / o.fps, v.poses[i], v.k));
  }
  return v;
}

LabelNoiseOptions BleedOnly(double share) {
  LabelNoiseOptions o;
  o.split_probability = o.merge_probability = o.class_flip_probability = 0;
  o.jitter_px = 0;
  o.min_mask_pixels = 0;
  o.bleed = true;
  o.bleed_share = share;
  return o;
}

// What the option promises, computed independently: an object pixel within
// bleed_contact_m of the floor or a wall, or dark.
bool IsCandidate(const Views& v, size_t view, int u, int w,
                 const LabelNoiseOptions& o) {
  const RenderedFrame& f = v.frames[view];
  if (!v.scene.IsObject(f.instance(u, w))) return false;
  const Eigen::Vector3d p =
      v.poses[view] * v.k.BackProject(u, w, f.depth(u, w));
  const Eigen::Vector3d& room = v.scene.room_size;
  const double to_structure =
      std::min({p.x(), p.y(), room.x() - p.x(), room.y() - p.y(), p.z()});
  if (to_structure <= o.bleed_contact_m + 1e-6) return true;
  const double luma = 0.299 * f.color(u, w, 0) + 0.587 * f.color(u, w, 1) +
                      0.114 * f.color(u, w, 2);
  return luma < o.bleed_dark_luma;
}

// Per view: object pixels labelled floor or wall.
std::vector<std::vector<bool>> Bled(const Views& v, const LabelNoiseOptions& o,
                                    uint64_t scene_seed) {
  std::vector<std::vector<bool>> out;
  for (size_t i = 0; i < v.frames.size(); ++i) {
    const NoisyLabels n = ApplyLabelNoise(v.frames[i], v.scene, v.poses[i], v.k,
                                          o, 100 + i, scene_seed);
    std::vector<bool> bled(n.semantic.NumPixels());
    for (size_t p = 0; p < bled.size(); ++p) {
      const uint16_t c = n.semantic.data()[p];
      bled[p] = v.scene.IsObject(v.frames[i].instance.data()[p]) &&
                (c == kClassFloor || c == kClassWall);
    }
    out.push_back(std::move(bled));
  }
  return out;
}

TEST(LabelBleed, OnlyCandidatesBleedAndJoinTheStructureMask) {
  const Views v = SparseViews(4);
  const LabelNoiseOptions all = BleedOnly(1.0);
  size_t candidates = 0, bled = 0;
  for (size_t i = 0; i < v.frames.size(); ++i) {
    const RenderedFrame& f = v.frames[i];
    const NoisyLabels n =
        ApplyLabelNoise(f, v.scene, v.poses[i], v.k, all, 1, 1);
    std::map<uint16_t, uint16_t> structure_mask_class;
    for (size_t p = 0; p < f.instance.NumPixels(); ++p) {
      if (!v.scene.IsObject(f.instance.data()[p])) {
        structure_mask_class[n.instance.data()[p]] = f.semantic.data()[p];
      }
    }
    for (int w = 0; w < v.k.height; ++w) {
      for (int u = 0; u < v.k.width; ++u) {
        const bool candidate = IsCandidate(v, i, u, w, all);
        const bool changed = n.semantic(u, w) != f.semantic(u, w);
        candidates += candidate;
        bled += changed;
        if (!changed) continue;
        ASSERT_TRUE(candidate) << "view " << i << " pixel " << u << "," << w;
        const auto it = structure_mask_class.find(n.instance(u, w));
        ASSERT_NE(it, structure_mask_class.end()) << "not a structure mask";
        EXPECT_EQ(it->second, n.semantic(u, w));
      }
    }
  }
  EXPECT_GT(candidates, 500u);
  // Share 1: every candidate next to a floor or wall in view bleeds.
  EXPECT_GE(bled, candidates * 9 / 10) << bled << " of " << candidates;

  // Off, or share 0: nothing bleeds; the bleed takes no draws from the other
  // noise, so with it on only candidates change.
  LabelNoiseOptions noisy;
  noisy.jitter_px = 0;
  noisy.min_mask_pixels = 0;
  LabelNoiseOptions noisy_bleed = noisy;
  noisy_bleed.bleed = true;
  noisy_bleed.bleed_share = 0.5;
  for (size_t i = 0; i < v.frames.size(); ++i) {
    const RenderedFrame& f = v.frames[i];
    const NoisyLabels a =
        ApplyLabelNoise(f, v.scene, v.poses[i], v.k, noisy, 5, 1);
    const NoisyLabels b =
        ApplyLabelNoise(f, v.scene, v.poses[i], v.k, noisy_bleed, 5, 1);
    for (int w = 0; w < v.k.height; ++w) {
      for (int u = 0; u < v.k.width; ++u) {
        if (a.semantic(u, w) != b.semantic(u, w)) {
          ASSERT_TRUE(IsCandidate(v, i, u, w, noisy_bleed));
        }
      }
    }
    const NoisyLabels none =
        ApplyLabelNoise(f, v.scene, v.poses[i], v.k, BleedOnly(0.0), 5, 1);
    EXPECT_EQ(none.semantic, f.semantic);
  }
}

// A wall lookalike (the kitchen's rows of base cabinets, "counter") is
// called wall whole, not only at contacts, in about 80 % of the views,
// whatever the share (0 here: nothing else bleeds); listed as none, it does
// not bleed.
TEST(LabelBleed, AWallLookalikeBleedsWholeIntoTheWall) {
  const Views v = SparseViews(16, "kitchen");
  const uint16_t counter = *SynthClasses().FindByName("counter");
  LabelNoiseOptions o = BleedOnly(0.0);
  size_t counter_px = 0, bled = 0;
  for (size_t i = 0; i < v.frames.size(); ++i) {
    const RenderedFrame& f = v.frames[i];
    const NoisyLabels n = ApplyLabelNoise(f, v.scene, v.poses[i], v.k, o, 7, 3);
    for (size_t p = 0; p < f.semantic.NumPixels(); ++p) {
      const bool is_counter = f.semantic.data()[p] == counter &&
                              v.scene.IsObject(f.instance.data()[p]);
      counter_px += is_counter;
      if (n.semantic.data()[p] == f.semantic.data()[p]) continue;
      ASSERT_TRUE(is_counter) << "view " << i << " pixel " << p;
      EXPECT_EQ(n.semantic.data()[p], kClassWall);
      ++bled;
    }
  }
  ASSERT_GT(counter_px, 2000u);
  const double share = static_cast<double>(bled) / counter_px;
  EXPECT_GT(share, 0.5) << bled << " of " << counter_px;
  EXPECT_LT(share, 0.97) << bled << " of " << counter_px;
  o.bleed_wall_lookalikes.clear();
  for (size_t i = 0; i < v.frames.size(); ++i) {
    const NoisyLabels n =
        ApplyLabelNoise(v.frames[i], v.scene, v.poses[i], v.k, o, 7, 3);
    EXPECT_EQ(n.semantic, v.frames[i].semantic);
  }
}

TEST(LabelBleed, ShareOfCandidatePixelsMatchesTheOption) {
  const Views v = SparseViews(8);
  for (double share : {0.3, 0.6}) {
    const LabelNoiseOptions o = BleedOnly(share);
    size_t candidates = 0, bled = 0;
    for (uint64_t scene_seed = 1; scene_seed <= 30; ++scene_seed) {
      const auto b = Bled(v, o, scene_seed);
      for (size_t i = 0; i < v.frames.size(); ++i) {
        for (int w = 0; w < v.k.height; ++w) {
          for (int u = 0; u < v.k.width; ++u) {
            candidates += IsCandidate(v, i, u, w, o);
            bled += b[i][static_cast<size_t>(w) * v.k.width + u];
          }
        }
      }
    }
    const double measured = static_cast<double>(bled) / candidates;
    EXPECT_NEAR(measured, share, 0.1) << bled << " of " << candidates;
  }
}

// The same parts bleed in most views: of the 5 cm cells that are candidates
// in two views, those bled in one are bled in the other far more often than
// the overall rate (independent per-view noise would give about that rate).
TEST(LabelBleed, IsCorrelatedAcrossViews) {
  const Views v = SparseViews(24);
  const LabelNoiseOptions o = BleedOnly(0.3);
  const auto bled = Bled(v, o, 3);
  // cell -> per view: -1 not a candidate there, 0 candidate, 1 bled.
  std::map<std::tuple<int, int, int>, std::vector<int>> cells;
  for (size_t i = 0; i < v.frames.size(); ++i) {
    for (int w = 0; w < v.k.height; ++w) {
      for (int u = 0; u < v.k.width; ++u) {
        if (!IsCandidate(v, i, u, w, o)) continue;
        const Eigen::Vector3d p =
            v.poses[i] * v.k.BackProject(u, w, v.frames[i].depth(u, w));
        const auto key = std::make_tuple(static_cast<int>(p.x() / 0.05),
                                         static_cast<int>(p.y() / 0.05),
                                         static_cast<int>(p.z() / 0.05));
        auto& views = cells.try_emplace(key, v.frames.size(), -1).first->second;
        views[i] = std::max(
            views[i],
            static_cast<int>(bled[i][static_cast<size_t>(w) * v.k.width + u]));
      }
    }
  }
  size_t seen = 0, bled_seen = 0, pairs_after_bleed = 0, bled_again = 0;
  for (const auto& [key, views] : cells) {
    for (size_t a = 0; a < views.size(); ++a) {
      if (views[a] < 0) continue;
      ++seen;
      bled_seen += views[a];
      for (size_t b = 0; b < views.size(); ++b) {
        if (b == a || views[b] < 0 || views[a] != 1) continue;
        ++pairs_after_bleed;
        bled_again += views[b];
      }
    }
  }
  ASSERT_GT(pairs_after_bleed, 100u);
  const double rate = static_cast<double>(bled_seen) / seen;
  const double again = static_cast<double>(bled_again) / pairs_after_bleed;
  EXPECT_GT(rate, 0.1);
  EXPECT_GT(again, 0.6) << "overall rate " << rate;
  EXPECT_GT(again, 2 * rate);
}

// In the flat, object pixels near an interior wall (and near no room face)
// take that wall's mask: the interior walls bleed like the room's.
TEST(LabelBleed, InteriorWallsBleedIntoTheirOwnMask) {
  const Views v = SparseViews(12, "flat");
  const LabelNoiseOptions o = BleedOnly(1.0);
  std::vector<const SceneObject*> interior;
  for (const SceneObject& s : v.scene.objects) {
    if (s.structure && !s.room_face) interior.push_back(&s);
  }
  ASSERT_EQ(interior.size(), 2u);
  size_t candidates = 0, bled = 0;
  for (size_t i = 0; i < v.frames.size(); ++i) {
    const RenderedFrame& f = v.frames[i];
    const NoisyLabels n =
        ApplyLabelNoise(f, v.scene, v.poses[i], v.k, o, 7 + i, 1);
    std::map<uint16_t, std::set<uint16_t>> masks;  // wall -> its masks
    for (size_t p = 0; p < f.instance.NumPixels(); ++p) {
      masks[f.instance.data()[p]].insert(n.instance.data()[p]);
    }
    for (int w = 0; w < v.k.height; ++w) {
      for (int u = 0; u < v.k.width; ++u) {
        if (!v.scene.IsObject(f.instance(u, w))) continue;
        const Eigen::Vector3d p =
            v.poses[i] * v.k.BackProject(u, w, f.depth(u, w));
        const Eigen::Vector3d& room = v.scene.room_size;
        const double to_room =
            std::min({p.x(), p.y(), room.x() - p.x(), room.y() - p.y(), p.z()});
        for (const SceneObject* wall : interior) {
          if (to_room <= o.bleed_contact_m + 0.02 ||
              wall->DistanceToSurface(p) > o.bleed_contact_m - 0.02 ||
              masks.count(wall->instance_id) == 0) {
            continue;
          }
          ++candidates;
          bled += n.semantic(u, w) == kClassWall &&
                  masks[wall->instance_id].count(n.instance(u, w)) != 0;
        }
      }
    }
  }
  ASSERT_GT(candidates, 50u);
  EXPECT_EQ(bled, candidates);
}

TEST(LabelBleed, IsDeterministicAndBadSharesAreRejected) {
  const Views v = SparseViews(2);
  const LabelNoiseOptions o = BleedOnly(0.5);
  EXPECT_EQ(Bled(v, o, 4), Bled(v, o, 4));
  EXPECT_NE(Bled(v, o, 4), Bled(v, o, 5)) << "other parts bleed";
  for (double share : {-0.1, 1.5}) {
    LabelNoiseOptions bad = o;
    bad.bleed_share = share;
    EXPECT_THROW(bad.Check(), InvalidArgument);
  }
}

}  // namespace
}  // namespace semrec::synth
