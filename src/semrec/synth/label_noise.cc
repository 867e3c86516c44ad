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
      if (!scene.IsObject(instance)) continue;
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

namespace {

// Visible objects, their sizes and which touch which in the image.
struct VisibleObjects {
  std::map<uint16_t, size_t> pixels;
  std::set<std::pair<uint16_t, uint16_t>> touching;
  std::vector<uint16_t> ids;         // ascending
  std::map<uint16_t, size_t> index;  // id -> position in ids
};

VisibleObjects FindVisibleObjects(const RenderedFrame& frame,
                                  const Scene& scene) {
  const int w = frame.instance.width(), h = frame.instance.height();
  VisibleObjects out;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const uint16_t a = frame.instance(u, v);
      if (!scene.IsObject(a)) continue;
      ++out.pixels[a];
      for (const auto& [du, dv] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (u + du >= w || v + dv >= h) continue;
        const uint16_t b = frame.instance(u + du, v + dv);
        if (b != a && scene.IsObject(b)) {
          out.touching.emplace(std::min(a, b), std::max(a, b));
        }
      }
    }
  }
  for (const auto& [id, n] : out.pixels) {
    out.index[id] = out.ids.size();
    out.ids.push_back(id);
  }
  return out;
}

// Under-segmentation: some objects join a touching neighbour's mask; a joined
// mask takes its largest member's class.
struct Joins {
  UnionFind joined;
  std::vector<bool> was_joined;
  std::map<size_t, uint16_t> group_class;  // root -> class
};

Joins JoinNeighbours(const VisibleObjects& visible, const Scene& scene,
                     const LabelNoiseOptions& options, Rng* rng) {
  const size_t n = visible.ids.size();
  Joins out{UnionFind(n), std::vector<bool>(n, false), {}};
  for (size_t i = 0; i < n; ++i) {
    if (rng->Uniform() >= options.merge_probability) continue;
    std::vector<uint16_t> neighbours;
    for (const auto& [a, b] : visible.touching) {
      if (a == visible.ids[i]) neighbours.push_back(b);
      if (b == visible.ids[i]) neighbours.push_back(a);
    }
    if (neighbours.empty()) continue;
    const uint16_t other = neighbours[static_cast<size_t>(
        rng->UniformInt(0, static_cast<int64_t>(neighbours.size()) - 1))];
    const size_t j = visible.index.at(other);
    out.joined.Unite(i, j);
    out.was_joined[i] = out.was_joined[j] = true;
  }
  std::map<size_t, size_t> group_best;
  for (size_t i = 0; i < n; ++i) {
    const size_t root = out.joined.Find(i);
    const size_t pixels = visible.pixels.at(visible.ids[i]);
    if (pixels > group_best[root]) {
      group_best[root] = pixels;
      out.group_class[root] = scene.FindObject(visible.ids[i])->class_id;
    }
  }
  return out;
}

// Over-segmentation of one object: pieces by primitive or by planes.
struct Cut {
  bool by_parts = false;
  std::vector<int> part_piece;  // piece of each primitive
  std::vector<Eigen::Vector3d> normals;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
};

std::map<uint16_t, Cut> ChooseCuts(const VisibleObjects& visible,
                                   const Joins& joins, const Scene& scene,
                                   const LabelNoiseOptions& options,
                                   uint64_t seed, uint64_t scene_seed,
                                   Rng* rng) {
  std::map<uint16_t, Cut> cuts;
  for (size_t i = 0; i < visible.ids.size(); ++i) {
    if (joins.was_joined[i]) continue;
    const uint16_t id = visible.ids[i];
    const SceneObject& o = *scene.FindObject(id);
    if (options.consistent_cut_share > 0.0 && o.parts.size() >= 2) {
      const uint64_t object = MixSeed(scene_seed, 0xc07c07ULL + id);
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
        cuts[id] = std::move(cut);
        continue;
      }
    }
    if (rng->Uniform() >= options.split_probability) continue;
    Cut cut;
    const int pieces = static_cast<int>(rng->UniformInt(2, 3));
    if (o.parts.size() >= 2 && rng->Uniform() < 0.5) {
      cut.by_parts = true;
      for (size_t p = 0; p < o.parts.size(); ++p) {
        cut.part_piece.push_back(
            static_cast<int>(rng->UniformInt(0, pieces - 1)));
      }
    } else {
      cut.center = o.Bounds().center();
      for (int c = 0; c + 1 < pieces; ++c) {
        cut.normals.push_back(
            Eigen::Vector3d(rng->Normal(), rng->Normal(), rng->Normal())
                .normalized());
      }
    }
    cuts[id] = std::move(cut);
  }
  return cuts;
}

// The piece of cut `cut` pixel (u, v) falls in.
int PieceOf(const Cut& cut, const RenderedFrame& frame, int u, int v,
            const Transform& T_world_camera, const CameraIntrinsics& k) {
  if (cut.by_parts) {
    const uint16_t part = frame.part(u, v);
    return part >= 1 ? cut.part_piece[part - 1] : 0;
  }
  const Eigen::Vector3d p =
      T_world_camera *
      k.BackProject(u, v, static_cast<double>(frame.depth(u, v)));
  int piece = 0;
  for (size_t n = 0; n < cut.normals.size(); ++n) {
    if (cut.normals[n].dot(p - cut.center) > 0) piece |= 1 << n;
  }
  return piece;
}

// The new masks: (key, piece) -> instance id, in order of first appearance,
// and each mask's class (index = id).
struct Masks {
  std::map<std::pair<uint32_t, int>, uint16_t> id;
  std::vector<uint16_t> class_of = {0};
};

Masks PaintMasks(const RenderedFrame& frame, const VisibleObjects& visible,
                 Joins* joins, const std::map<uint16_t, Cut>& cuts,
                 const Transform& T_world_camera, const CameraIntrinsics& k,
                 NoisyLabels* out) {
  const int w = frame.instance.width(), h = frame.instance.height();
  Masks masks;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const uint16_t inst = frame.instance(u, v);
      if (inst == 0) continue;
      uint16_t cls = frame.semantic(u, v);
      if (inst >= kPersonInstanceBase) {  // people stay as they are
        out->instance(u, v) = inst;
        out->semantic(u, v) = cls;
        continue;
      }
      uint32_t key = inst;
      int piece = 0;
      if (const auto it = visible.index.find(inst); it != visible.index.end()) {
        const size_t root = joins->joined.Find(it->second);
        key = visible.ids[root];
        cls = joins->group_class[root];
        if (const auto c = cuts.find(inst); c != cuts.end()) {
          piece = PieceOf(c->second, frame, u, v, T_world_camera, k);
        }
      }
      auto [it, added] = masks.id.try_emplace(
          {key, piece}, static_cast<uint16_t>(masks.class_of.size()));
      if (added) masks.class_of.push_back(cls);
      out->instance(u, v) = it->second;
    }
  }
  CheckArgument(masks.class_of.size() < kPersonInstanceBase,
                "label noise: too many masks in one view");
  return masks;
}

// Class flips among the scene's object classes; then every mask's pixels
// take its class.
void FlipClasses(const Scene& scene, const LabelNoiseOptions& options,
                 Masks* masks, Rng* rng, NoisyLabels* out) {
  std::vector<uint16_t> object_classes;
  for (const SceneObject& o : scene.objects) {
    if (!o.structure) object_classes.push_back(o.class_id);
  }
  std::sort(object_classes.begin(), object_classes.end());
  object_classes.erase(
      std::unique(object_classes.begin(), object_classes.end()),
      object_classes.end());
  std::vector<uint16_t>& mask_class = masks->class_of;
  for (const auto& [key, id] : masks->id) {
    const bool object = scene.IsObject(static_cast<uint16_t>(key.first));
    if (!object || object_classes.size() < 2 ||
        rng->Uniform() >= options.class_flip_probability) {
      continue;
    }
    uint16_t flipped = mask_class[id];
    while (flipped == mask_class[id]) {
      flipped = object_classes[static_cast<size_t>(
          rng->UniformInt(0, static_cast<int64_t>(object_classes.size()) - 1))];
    }
    mask_class[id] = flipped;
  }
  for (int v = 0; v < out->instance.height(); ++v) {
    for (int u = 0; u < out->instance.width(); ++u) {
      const uint16_t id = out->instance(u, v);
      if (id != 0 && id < kPersonInstanceBase) {
        out->semantic(u, v) = mask_class[id];
      }
    }
  }
}

// Ragged boundaries: a pixel near another mask may take that mask's labels.
void JitterBoundaries(const RenderedFrame& frame, int jitter_px, Rng* rng,
                      NoisyLabels* out) {
  const int w = frame.instance.width(), h = frame.instance.height();
  const NoisyLabels clean = *out;
  const int j = jitter_px;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const int du = static_cast<int>(rng->UniformInt(-j, j));
      const int dv = static_cast<int>(rng->UniformInt(-j, j));
      const bool coin = rng->Uniform() < 0.5;
      const int x = u + du, y = v + dv;
      if (!coin || x < 0 || y < 0 || x >= w || y >= h) continue;
      if (frame.depth(u, v) <= 0.0f || frame.depth(x, y) <= 0.0f) continue;
      out->instance(u, v) = clean.instance(x, y);
      out->semantic(u, v) = clean.semantic(x, y);
    }
  }
}

// Object masks smaller than min_mask_pixels are dropped.
void DropSmallMasks(const Scene& scene, const Masks& masks, int min_mask_pixels,
                    NoisyLabels* out) {
  std::map<uint16_t, size_t> sizes;
  for (size_t i = 0; i < out->instance.NumPixels(); ++i) {
    ++sizes[out->instance.data()[i]];
  }
  std::set<uint16_t> objects_masks;
  for (const auto& [key, id] : masks.id) {
    if (scene.IsObject(static_cast<uint16_t>(key.first))) {
      objects_masks.insert(id);
    }
  }
  for (size_t i = 0; i < out->instance.NumPixels(); ++i) {
    const uint16_t id = out->instance.data()[i];
    if (objects_masks.count(id) != 0 &&
        sizes[id] < static_cast<size_t>(min_mask_pixels)) {
      out->instance.data()[i] = 0;
    }
  }
}

}  // namespace

NoisyLabels ApplyLabelNoise(const RenderedFrame& frame, const Scene& scene,
                            const Transform& T_world_camera,
                            const CameraIntrinsics& k,
                            const LabelNoiseOptions& options, uint64_t seed,
                            uint64_t scene_seed) {
  options.Check();
  const int w = frame.instance.width(), h = frame.instance.height();
  Rng rng(seed);
  const VisibleObjects visible = FindVisibleObjects(frame, scene);
  Joins joins = JoinNeighbours(visible, scene, options, &rng);
  const std::map<uint16_t, Cut> cuts =
      ChooseCuts(visible, joins, scene, options, seed, scene_seed, &rng);
  NoisyLabels out{LabelMap(w, h), LabelMap(w, h)};
  Masks masks =
      PaintMasks(frame, visible, &joins, cuts, T_world_camera, k, &out);
  FlipClasses(scene, options, &masks, &rng, &out);
  if (options.bleed) {
    ApplyStructureBleed(frame, scene, T_world_camera, k, options, masks.id,
                        MixSeed(seed, 0xb1eed), scene_seed, &out);
  }
  if (options.jitter_px > 0)
    JitterBoundaries(frame, options.jitter_px, &rng, &out);
  DropSmallMasks(scene, masks, options.min_mask_pixels, &out);
  return out;
}

}  // namespace semrec::synth
