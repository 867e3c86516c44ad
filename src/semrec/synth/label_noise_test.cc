#include "semrec/synth/label_noise.h"

#include <map>
#include <set>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/synth/generator.h"

namespace semrec::synth {
namespace {

struct View {
  Scene scene;
  Transform T_world_camera;
  CameraIntrinsics k;
  RenderedFrame frame;
};

// A view of the six-objects room from its orbit, at quarter resolution.
View SixObjectsView() {
  SynthOptions o = SynthOptions::Preset("six-objects");
  View view;
  view.scene = GenerateScene(o.scene);
  view.T_world_camera =
      MakeTrajectory(view.scene, o.trajectory, 1, o.fps, o.seed)[0];
  view.k = CameraIntrinsics{320, 240, 262.5, 262.5, 159.5, 119.5};
  view.frame = Render(view.scene, 0.0, view.T_world_camera, view.k);
  return view;
}

NoisyLabels Noisy(const View& v, const LabelNoiseOptions& o, uint64_t seed) {
  return ApplyLabelNoise(v.frame, v.scene, v.T_world_camera, v.k, o, seed, 7);
}

LabelNoiseOptions Clean() {
  LabelNoiseOptions o;
  o.split_probability = o.merge_probability = o.class_flip_probability = 0;
  o.jitter_px = 0;
  o.min_mask_pixels = 0;
  return o;
}

// GT object instance -> the noisy masks over its pixels (and the reverse).
std::map<uint16_t, std::set<uint16_t>> MasksPerObject(const View& v,
                                                      const NoisyLabels& n) {
  std::map<uint16_t, std::set<uint16_t>> out;
  for (size_t i = 0; i < v.frame.instance.NumPixels(); ++i) {
    const uint16_t gt = v.frame.instance.data()[i];
    if (v.scene.IsObject(gt)) out[gt].insert(n.instance.data()[i]);
  }
  return out;
}

TEST(LabelNoise, WithoutNoiseTheMasksAreTheGroundTruth) {
  const View v = SixObjectsView();
  const NoisyLabels n = Noisy(v, Clean(), 1);
  EXPECT_EQ(n.semantic, v.frame.semantic);
  // A bijection between ground-truth instances and masks.
  std::map<uint16_t, uint16_t> forward, backward;
  for (size_t i = 0; i < n.instance.NumPixels(); ++i) {
    const uint16_t gt = v.frame.instance.data()[i];
    const uint16_t mask = n.instance.data()[i];
    EXPECT_EQ(gt == 0, mask == 0);
    if (gt == 0) continue;
    EXPECT_EQ(forward.emplace(gt, mask).first->second, mask);
    EXPECT_EQ(backward.emplace(mask, gt).first->second, gt);
  }
  size_t objects = 0;
  for (const auto& [gt, mask] : forward) {
    objects += v.scene.IsObject(gt);
  }
  EXPECT_GE(objects, 4u) << "the view should show most of the six objects";
}

TEST(LabelNoise, SplitsCutObjectsIntoSeveralMasksOfTheirClass) {
  const View v = SixObjectsView();
  LabelNoiseOptions o = Clean();
  o.split_probability = 1.0;
  size_t split = 0, objects = 0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    const NoisyLabels n = Noisy(v, o, seed);
    EXPECT_EQ(n.semantic, v.frame.semantic);  // classes untouched
    for (const auto& [gt, masks] : MasksPerObject(v, n)) {
      ++objects;
      split += masks.size() >= 2;
    }
  }
  // Part splits may put every primitive into one piece; plane cuts through
  // the centre always cut what is in view.
  EXPECT_GE(split, objects * 2 / 3) << split << " of " << objects;
}

// A mask generator cuts some objects along the same parts in every view:
// with the share at 1 every object with parts is cut in most views, always
// into the same groups of parts; at 0 none is (random splits off here).
TEST(LabelNoise, ConsistentCutsSplitObjectsAlongTheSamePartsInEveryView) {
  const View v = SixObjectsView();
  for (const double share : {1.0, 0.0}) {
    LabelNoiseOptions o = Clean();
    o.consistent_cut_share = share;
    size_t cut = 0, seen = 0;
    // Per object: the part groupings (part -> piece, as sets of parts
    // sharing a mask) seen over the views that cut it.
    std::map<uint16_t, std::set<std::set<std::set<uint16_t>>>> groupings;
    for (uint64_t seed = 1; seed <= 10; ++seed) {
      const NoisyLabels n = Noisy(v, o, seed);
      EXPECT_EQ(n.semantic, v.frame.semantic);
      std::map<uint16_t, std::map<uint16_t, std::set<uint16_t>>> mask_parts;
      for (size_t i = 0; i < n.instance.NumPixels(); ++i) {
        const uint16_t gt = v.frame.instance.data()[i];
        const uint16_t part = v.frame.part.data()[i];
        if (!v.scene.IsObject(gt) || part == 0 ||
            v.scene.FindObject(gt)->parts.size() < 2) {
          continue;
        }
        mask_parts[gt][n.instance.data()[i]].insert(part);
      }
      for (const auto& [gt, masks] : mask_parts) {
        ++seen;
        if (masks.size() < 2) continue;
        ++cut;
        std::set<std::set<uint16_t>> grouping;
        for (const auto& [mask, parts] : masks) grouping.insert(parts);
        groupings[gt].insert(grouping);
      }
    }
    ASSERT_GE(seen, 10u) << "the view shows objects with parts";
    if (share > 0.0) {
      EXPECT_GE(cut, seen * 6 / 10) << cut << " of " << seen;
      for (const auto& [gt, distinct] : groupings) {
        EXPECT_EQ(distinct.size(), 1u) << "object " << gt << " cut differently";
      }
    } else {
      EXPECT_EQ(cut, 0u);
    }
  }
}

TEST(LabelNoise, MergesJoinTouchingNeighboursAndFlipsChangeClasses) {
  const View v = SixObjectsView();
  LabelNoiseOptions o = Clean();
  o.merge_probability = 1.0;
  const NoisyLabels merged = Noisy(v, o, 1);
  std::map<uint16_t, std::set<uint16_t>> objects_per_mask;
  for (size_t i = 0; i < merged.instance.NumPixels(); ++i) {
    const uint16_t gt = v.frame.instance.data()[i];
    if (v.scene.IsObject(gt)) {
      objects_per_mask[merged.instance.data()[i]].insert(gt);
    }
  }
  size_t joint = 0;
  for (const auto& [mask, objects] : objects_per_mask) {
    joint += objects.size() > 1;
  }
  EXPECT_GE(joint, 1u) << "objects touching in the view share a mask";

  o = Clean();
  o.class_flip_probability = 1.0;
  const NoisyLabels flipped = Noisy(v, o, 1);
  for (size_t i = 0; i < flipped.semantic.NumPixels(); ++i) {
    const uint16_t gt = v.frame.instance.data()[i];
    if (v.scene.IsObject(gt)) {
      ASSERT_NE(flipped.semantic.data()[i], v.frame.semantic.data()[i]);
    } else {
      ASSERT_EQ(flipped.semantic.data()[i], v.frame.semantic.data()[i]);
    }
  }
}

TEST(LabelNoise, JitterRaggesBoundariesAndSmallMasksAreDropped) {
  const View v = SixObjectsView();
  LabelNoiseOptions o = Clean();
  o.jitter_px = 2;
  const NoisyLabels jittered = Noisy(v, o, 1);
  const NoisyLabels clean = Noisy(v, Clean(), 1);
  size_t changed = 0;
  for (size_t i = 0; i < clean.instance.NumPixels(); ++i) {
    changed += jittered.instance.data()[i] != clean.instance.data()[i];
  }
  EXPECT_GT(changed, 0u);
  EXPECT_LT(changed, clean.instance.NumPixels() / 10) << "boundaries only";

  o = Clean();
  o.min_mask_pixels = 1 << 30;
  const NoisyLabels dropped = Noisy(v, o, 1);
  for (size_t i = 0; i < dropped.instance.NumPixels(); ++i) {
    const uint16_t gt = v.frame.instance.data()[i];
    if (v.scene.IsObject(gt)) {
      ASSERT_EQ(dropped.instance.data()[i], 0);
    } else {
      ASSERT_EQ(dropped.instance.data()[i] == 0, gt == 0);  // structure stays
    }
  }
}

TEST(LabelNoise, IsDeterministicInTheSeed) {
  const View v = SixObjectsView();
  const LabelNoiseOptions o;
  const NoisyLabels a = Noisy(v, o, 5), b = Noisy(v, o, 5), c = Noisy(v, o, 6);
  EXPECT_EQ(a.instance, b.instance);
  EXPECT_EQ(a.semantic, b.semantic);
  EXPECT_NE(a.instance, c.instance);
  LabelNoiseOptions bad;
  bad.split_probability = 2;
  EXPECT_THROW(bad.Check(), InvalidArgument);
}

}  // namespace
}  // namespace semrec::synth
