#include "semrec/synth/label_noise.h"

#include <algorithm>
#include <array>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "semrec/core/error.h"
#include "semrec/core/random.h"
#include "semrec/core/union_find.h"
#include "semrec/synth/seed.h"

namespace semrec::synth {
namespace {

bool IsObject(uint16_t instance, const Scene& scene) {
  if (instance == 0 || instance >= kPersonInstanceBase) return false;
  const SceneObject* o = scene.FindObject(instance);
  return o != nullptr && !o->structure;
}

// Share of the views in which a bleeding part bleeds (LabelNoiseOptions).
constexpr double kBleedViewRate = 0.8;
// Views in which an object cut the same way in every view is cut so.
constexpr double kConsistentCutViewRate = 0.8;

// Distance from p to room face `face` (Scene::room_faces order).
double FaceDistance(const Eigen::Vector3d& room, int face,
                    const Eigen::Vector3d& p) {
  const int axis = face / 2;
  return face % 2 == 1 ? room[axis] - p[axis] : p[axis];
}

double Luma(const ColorImage& color, int u, int v) {
  return 0.299 * color(u, v, 0) + 0.587 * color(u, v, 1) +
         0.114 * color(u, v, 2);
}

// LabelNoiseOptions::bleed. Decisions read the ground truth only, so the order
// of pixels does not matter; draws are hashes, not the noise stream.
void ApplyStructureBleed(
    const RenderedFrame& frame, const Scene& scene,
    const Transform& T_world_camera, const CameraIntrinsics& k,
    const LabelNoiseOptions& options,
    const std::map<std::pair<uint32_t, int>, uint16_t>& mask_id,
    uint64_t view_seed, uint64_t scene_seed, NoisyLabels* out) {
  // Floor and walls in view (the ceiling touches nothing) and their masks:
  // the room's faces keep their index (it seeds the draws), interior walls
  // follow from 6 on.
  struct Side {
    int face;                 // room face, or 6 + index of an interior wall
    const SceneObject* wall;  // interior walls only
    uint16_t mask, class_id;
  };
  std::map<uint16_t, int> face_of;  // in instance order: ties go the same way
  for (int f = 0; f < 5; ++f) {
    const uint16_t instance = scene.room_faces[f];
    if (instance != 0 && mask_id.count({instance, 0}) != 0) {
      face_of[instance] = f;
    }
  }
  std::vector<Side> sides;
  sides.reserve(face_of.size() + scene.objects.size());
  for (const auto& [instance, f] : face_of) {
    sides.push_back({f, nullptr, mask_id.at({instance, 0}),
                     scene.FindObject(instance)->class_id});
  }
  int interior = 0;
  for (const SceneObject& o : scene.objects) {
    if (!o.structure || o.room_face) continue;
    const int face = 6 + interior++;
    const auto it = mask_id.find({o.instance_id, 0});
    if (it == mask_id.end()) continue;
    sides.push_back({face, &o, it->second, o.class_id});
  }
  if (sides.empty()) return;
  std::set<uint16_t> lookalike;  // instances
  for (const SceneObject& o : scene.objects) {
    const std::string& name = SynthClasses().Get(o.class_id).name;
    if (!o.structure && std::find(options.bleed_wall_lookalikes.begin(),
                                  options.bleed_wall_lookalikes.end(), name) !=
                            options.bleed_wall_lookalikes.end()) {
      lookalike.insert(o.instance_id);
    }
  }
  const double view_rate = std::max(options.bleed_share, kBleedViewRate);
  // (object, face) -> whether that side of the object bleeds in this view.
  std::map<std::pair<uint16_t, int>, bool> side_bleeds;
  for (int v = 0; v < frame.instance.height(); ++v) {
    for (int u = 0; u < frame.instance.width(); ++u) {
      const uint16_t instance = frame.instance(u, v);
      if (!IsObject(instance, scene)) continue;
      const Eigen::Vector3d p =
          T_world_camera *
          k.BackProject(u, v, static_cast<double>(frame.depth(u, v)));
      // A wall lookalike bleeds whole, into the nearest wall.
      const bool whole = lookalike.count(instance) != 0;
      const Side* nearest = nullptr;
      double nearest_m = std::numeric_limits<double>::infinity();
      for (const Side& side : sides) {
        if (whole && side.class_id != kClassWall) continue;
        const double d = side.wall != nullptr
                             ? side.wall->DistanceToSurface(p)
                             : FaceDistance(scene.room_size, side.face, p);
        if (d < nearest_m) nearest = &side, nearest_m = d;
      }
      if (nearest == nullptr ||
          (!whole && nearest_m > options.bleed_contact_m &&
           Luma(frame.color, u, v) >= options.bleed_dark_luma)) {
        continue;
      }
      const int face = nearest->face;
      const auto [it, added] = side_bleeds.try_emplace({instance, face}, false);
      if (added) {
        const uint64_t side = MixSeed(MixSeed(scene_seed, instance), face);
        it->second =
            (whole || UnitFromHash(side) < options.bleed_share / view_rate) &&
            UnitFromHash(MixSeed(view_seed, side)) <
                (whole ? kBleedViewRate : view_rate);
      }
      if (!it->second) continue;
      out->instance(u, v) = nearest->mask;
      out->semantic(u, v) = nearest->class_id;
    }
  }
}

}  // namespace

void LabelNoiseOptions::Check() const {
  for (double p : {split_probability, merge_probability, class_flip_probability,
                   consistent_cut_share}) {
    CheckArgument(p >= 0.0 && p <= 1.0,
                  "label noise: probabilities must be in [0, 1]");
  }
  CheckArgument(jitter_px >= 0, "label noise: jitter_px must be >= 0");
  CheckArgument(min_mask_pixels >= 0,
                "label noise: min_mask_pixels must be >= 0");
  CheckArgument(bleed_share >= 0.0 && bleed_share <= 1.0,
                "label noise: the bleed share must be in [0, 1]");
  CheckArgument(bleed_contact_m >= 0.0,
                "label noise: bleed_contact_m must be >= 0");
  CheckArgument(bleed_dark_luma >= 0.0,
                "label noise: bleed_dark_luma must be >= 0");
}

NoisyLabels ApplyLabelNoise(const RenderedFrame& frame, const Scene& scene,
                            const Transform& T_world_camera,
                            const CameraIntrinsics& k,
                            const LabelNoiseOptions& options, uint64_t seed,
                            uint64_t scene_seed) {
  options.Check();
  const int w = frame.instance.width(), h = frame.instance.height();
  Rng rng(seed);

  // Visible objects, their sizes and which touch which in the image.
  std::map<uint16_t, size_t> pixels;
  std::set<std::pair<uint16_t, uint16_t>> touching;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const uint16_t a = frame.instance(u, v);
      if (!IsObject(a, scene)) continue;
      ++pixels[a];
      for (const auto& [du, dv] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (u + du >= w || v + dv >= h) continue;
        const uint16_t b = frame.instance(u + du, v + dv);
        if (b != a && IsObject(b, scene)) {
          touching.emplace(std::min(a, b), std::max(a, b));
        }
      }
    }
  }
  std::vector<uint16_t> visible;
  std::map<uint16_t, size_t> index;
  for (const auto& [id, n] : pixels) {
    index[id] = visible.size();
    visible.push_back(id);
  }

  // Under-segmentation: some objects join a touching neighbour's mask.
  UnionFind joined(visible.size());
  std::vector<bool> was_joined(visible.size(), false);
  for (size_t i = 0; i < visible.size(); ++i) {
    if (rng.Uniform() >= options.merge_probability) continue;
    std::vector<uint16_t> neighbours;
    for (const auto& [a, b] : touching) {
      if (a == visible[i]) neighbours.push_back(b);
      if (b == visible[i]) neighbours.push_back(a);
    }
    if (neighbours.empty()) continue;
    const uint16_t other = neighbours[static_cast<size_t>(
        rng.UniformInt(0, static_cast<int64_t>(neighbours.size()) - 1))];
    joined.Unite(i, index[other]);
    was_joined[i] = was_joined[index[other]] = true;
  }
  // A joined mask takes its largest member's class.
  std::map<size_t, uint16_t> group_class;
  std::map<size_t, size_t> group_best;
  for (size_t i = 0; i < visible.size(); ++i) {
    const size_t root = joined.Find(i);
    if (pixels[visible[i]] > group_best[root]) {
      group_best[root] = pixels[visible[i]];
      group_class[root] = scene.FindObject(visible[i])->class_id;
    }
  }

  // Over-segmentation: per object, pieces by primitive or by planes.
  struct Cut {
    bool by_parts = false;
    std::vector<int> part_piece;  // piece of each primitive
    std::vector<Eigen::Vector3d> normals;
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
  };
  std::map<uint16_t, Cut> cuts;
  for (size_t i = 0; i < visible.size(); ++i) {
    if (was_joined[i]) continue;
    const SceneObject& o = *scene.FindObject(visible[i]);
    if (options.consistent_cut_share > 0.0 && o.parts.size() >= 2) {
      const uint64_t object = MixSeed(scene_seed, 0xc07c07ULL + visible[i]);
      if (UnitFromHash(object) < options.consistent_cut_share &&
          UnitFromHash(MixSeed(seed, object)) < kConsistentCutViewRate) {
        // The first two primitives apart, the others with one of them: the
        // same pieces in every view.
        Cut cut;
        cut.by_parts = true;
        for (size_t p = 0; p < o.parts.size(); ++p) {
          cut.part_piece.push_back(
              p < 2 ? static_cast<int>(p)
                    : static_cast<int>(MixSeed(object, p) % 2));
        }
        cuts[visible[i]] = std::move(cut);
        continue;
      }
    }
    if (rng.Uniform() >= options.split_probability) continue;
    Cut cut;
    const int pieces = static_cast<int>(rng.UniformInt(2, 3));
    if (o.parts.size() >= 2 && rng.Uniform() < 0.5) {
      cut.by_parts = true;
      for (size_t p = 0; p < o.parts.size(); ++p) {
        cut.part_piece.push_back(
            static_cast<int>(rng.UniformInt(0, pieces - 1)));
      }
    } else {
      cut.center = o.Bounds().center();
      for (int c = 0; c + 1 < pieces; ++c) {
        cut.normals.push_back(
            Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal())
                .normalized());
      }
    }
    cuts[visible[i]] = std::move(cut);
  }

  // New masks: (key, piece) -> instance id, in order of first appearance.
  NoisyLabels out{LabelMap(w, h), LabelMap(w, h)};
  std::map<std::pair<uint32_t, int>, uint16_t> mask_id;
  std::vector<uint16_t> mask_class(1, 0);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const uint16_t inst = frame.instance(u, v);
      if (inst == 0) continue;
      uint16_t cls = frame.semantic(u, v);
      if (inst >= kPersonInstanceBase) {  // people stay as they are
        out.instance(u, v) = inst;
        out.semantic(u, v) = cls;
        continue;
      }
      uint32_t key = inst;
      int piece = 0;
      if (const auto it = index.find(inst); it != index.end()) {
        const size_t root = joined.Find(it->second);
        key = visible[root];
        cls = group_class[root];
        if (const auto c = cuts.find(inst); c != cuts.end()) {
          const Cut& cut = c->second;
          const uint16_t part = frame.part(u, v);
          if (cut.by_parts && part >= 1) {
            piece = cut.part_piece[part - 1];
          } else if (!cut.by_parts) {
            const Eigen::Vector3d p =
                T_world_camera *
                k.BackProject(u, v, static_cast<double>(frame.depth(u, v)));
            for (size_t n = 0; n < cut.normals.size(); ++n) {
              if (cut.normals[n].dot(p - cut.center) > 0) piece |= 1 << n;
            }
          }
        }
      }
      auto [it, added] = mask_id.try_emplace(
          {key, piece}, static_cast<uint16_t>(mask_class.size()));
      if (added) mask_class.push_back(cls);
      out.instance(u, v) = it->second;
    }
  }
  CheckArgument(mask_class.size() < kPersonInstanceBase,
                "label noise: too many masks in one view");

  // Class flips among the scene's object classes.
  std::vector<uint16_t> object_classes;
  for (const SceneObject& o : scene.objects) {
    if (!o.structure) object_classes.push_back(o.class_id);
  }
  std::sort(object_classes.begin(), object_classes.end());
  object_classes.erase(
      std::unique(object_classes.begin(), object_classes.end()),
      object_classes.end());
  for (const auto& [key, id] : mask_id) {
    const bool object = IsObject(static_cast<uint16_t>(key.first), scene);
    if (!object || object_classes.size() < 2 ||
        rng.Uniform() >= options.class_flip_probability) {
      continue;
    }
    uint16_t flipped = mask_class[id];
    while (flipped == mask_class[id]) {
      flipped = object_classes[static_cast<size_t>(
          rng.UniformInt(0, static_cast<int64_t>(object_classes.size()) - 1))];
    }
    mask_class[id] = flipped;
  }
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const uint16_t id = out.instance(u, v);
      if (id != 0 && id < kPersonInstanceBase) {
        out.semantic(u, v) = mask_class[id];
      }
    }
  }

  if (options.bleed) {
    ApplyStructureBleed(frame, scene, T_world_camera, k, options, mask_id,
                        MixSeed(seed, 0xb1eed), scene_seed, &out);
  }

  // Ragged boundaries: a pixel near another mask may take that mask's labels.
  if (options.jitter_px > 0) {
    const NoisyLabels clean = out;
    const int j = options.jitter_px;
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const int du = static_cast<int>(rng.UniformInt(-j, j));
        const int dv = static_cast<int>(rng.UniformInt(-j, j));
        const bool coin = rng.Uniform() < 0.5;
        const int x = u + du, y = v + dv;
        if (!coin || x < 0 || y < 0 || x >= w || y >= h) continue;
        if (frame.depth(u, v) <= 0.0f || frame.depth(x, y) <= 0.0f) continue;
        out.instance(u, v) = clean.instance(x, y);
        out.semantic(u, v) = clean.semantic(x, y);
      }
    }
  }

  // Small object masks are dropped.
  std::map<uint16_t, size_t> sizes;
  for (size_t i = 0; i < out.instance.NumPixels(); ++i) {
    ++sizes[out.instance.data()[i]];
  }
  std::set<uint16_t> objects_masks;
  for (const auto& [key, id] : mask_id) {
    if (IsObject(static_cast<uint16_t>(key.first), scene)) {
      objects_masks.insert(id);
    }
  }
  for (size_t i = 0; i < out.instance.NumPixels(); ++i) {
    const uint16_t id = out.instance.data()[i];
    if (objects_masks.count(id) != 0 &&
        sizes[id] < static_cast<size_t>(options.min_mask_pixels)) {
      out.instance.data()[i] = 0;
    }
  }
  return out;
}

}  // namespace semrec::synth
