// The map's final objects, decided per place from the voxel evidence
// (fuse/voxel_votes.h) at the end of a sequence.
//
// MapResolver::Passes() runs these in order; each can be left out alone
// (MapObjectOptions::skip_passes, `--resolver-skip`), and docs/fusion.md
// describes each with its parameters and its measured effect.
//  - (cells) Each voxel's class is its histogram's winner (distance-weighted
//    view shares; ties: the smaller class id).
//  - gate-structure: structure only where the geometry says so. A wall vote
//    counts only on a large vertical plane that is no furniture front (no
//    surface behind its top edge, not a hand's width in front of a larger
//    wall), a floor vote only on the lowest large horizontal plane, a ceiling
//    vote only on the highest; elsewhere the next class with real evidence
//    wins (a chair some views call wall stays a chair). A class with no plane
//    large enough is not gated.
//  - release-flush-parts: structure voxels on their plane that many views
//    gave a touching thing's class join the thing (a headboard).
//  - assign-owners: each thing voxel belongs to the fusion object of its
//    class most views put it in; structure voxels to their class's object.
//  - split-by-masks, split-disconnected: an object whose parts the views held
//    in different masks is cut into them; pieces that do not touch are split
//    unless the views that saw both put them in one mask.
//  - attach-orphans: thing voxels no object of their class claimed join the
//    touching object of their class, or form a new one.
//  - merge-by-masks: touching objects the views held in one mask (of one
//    class, or of confused classes) merge, surest first, never through a
//    chain that joins objects the views held apart; small or nested pieces
//    and seams that fit one object of the class join it.
//  - judge-fragments: an object labelled by few of the views that observed
//    its voxels is a fragment: it folds into the object it touches or goes.
//  - claim-fronts, claim-stranded, claim-enclosed: structure off its planes
//    that no other class can take (a chair's legs every view called floor, a
//    shelf's back panel inside its outline) joins the things it touches,
//    while they still fit their class's size.
//  - release-far-specks: pieces under 5% of a thing, far from the rest of it,
//    that make it too large for its class join what they touch or go.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "semrec/core/label_map.h"
#include "semrec/fuse/structure_planes.h"
#include "semrec/fuse/voxel_votes.h"

namespace semrec::fuse {

/// The resolver's passes that can be left out, in the order they run (after
/// the cells are collected; docs/fusion.md).
const std::vector<std::string>& MapResolverPassNames();

struct MapObjectOptions {
  /// Passes of the resolver left out (MapResolverPassNames(); for ablations:
  /// scripts/ablate_resolver, `--resolver-skip`).
  std::set<std::string> skip_passes;
  /// Gate structure classes by planes (off: the histogram winner as it is).
  bool structure_planes = true;
  StructurePlaneOptions planes;
  /// A structure class whose planes (furniture fronts included) hold less
  /// than this share of its voxels, within 1.5 x their tolerance, is measured
  /// too poorly for planes to say where it is: it is not gated (as when too
  /// little of it was seen). Bonn crowd's floor, 4-5 m from the camera,
  /// spreads over 0.9 m of height: its plane held 6% of it, and the rest,
  /// stranded, was claimed by the things it touched. Synthetic scenes: 98-100%
  /// (every class); 7-Scenes chess: wall 61% (on its furniture fronts), floor
  /// 83%.
  double min_structure_on_planes = 0.3;
  /// Fragments: labelled views / observing views, summed over the object's
  /// voxels, below this.
  double min_seen_ratio = 0.3;
  /// A voxel's class that only far views gave it (VoxelEvidenceMap::FarVotes;
  /// its ranged views said another) counts as seen there when at least this
  /// many far views agree: a shelf its one ranged view called plant is no
  /// fragment. Counting a single far view kept pieces the ranged views had
  /// left as fragments (office seed 3: 1.30 -> 1.57 objects per GT object).
  uint32_t min_far_views = 2;
  /// Objects with fewer voxels are fragments whatever their visibility (20
  /// voxels: about 20 x 20 cm of surface).
  size_t min_voxels = 20;
  /// Off its planes, a structure class gives way to the next class only when
  /// that class held the voxel in at least one view and has at least this
  /// share of its votes.
  double min_takeover_share = 0.1;
  /// Structure voxels off their class's planes that no other class can take
  /// (every view called them wall or floor) join the thing they touch when
  /// no larger than it (fuse/map_resolver.h: ClaimStranded).
  bool claim_stranded = true;
  /// ... when at least this share of the group's voxels touch a thing.
  double min_stranded_contact_share = 0.25;
  /// Stranded voxels on a furniture front (StructurePlaneOptions::
  /// min_top_surface_share) join the thing holding at least this share of
  /// the front's voxels (and lying mostly on it).
  double min_front_share = 0.1;
  /// A front no thing takes whose voxels are mostly stranded (every view
  /// called it wall) becomes an object of its own, with the stranded voxels
  /// on its top (OnTopOfFront): of the label set's front class
  /// (LabelClass::furniture_front) that things took the scene's other fronts
  /// with, else the one with the most votes on it, else the lowest id. A row
  /// of base cabinets every view called wall is furniture, not wall. Off, or
  /// with no front class, it stays wall. Likewise a thing lying on a front
  /// (three quarters of its voxels) whose class is too small to take the
  /// front (StillFits) takes the most voted front class: a counter's front
  /// one view called plant is a counter, not a 2.6 m plant.
  bool objects_from_fronts = true;
  /// Wall voxels a thing's voxels at the wall close in on the wall's plane
  /// join the thing (fuse/map_resolver.h: ClaimEnclosed).
  bool claim_enclosed = true;
  /// A split-off piece with fewer voxels than this joins a touching object of
  /// its class instead of standing alone.
  size_t min_piece_voxels = 20;
  /// Voxels this many voxels apart (Chebyshev) or closer touch: parts of one
  /// object with a gap of one voxel (an occluded strip, a thin leg missed by
  /// the depth camera) stay one object.
  int touch_voxels = 2;
  /// Mask consensus: two parts are one when at least min_one_views views
  /// (for a split: one) held both in one mask and one > two_weight x (views
  /// that held them in different masks). A mask holds a part when it covers
  /// at least min_hold_share of the part's voxels (and 5, or all of a
  /// smaller part).
  size_t min_one_views = 2;
  double two_weight = 0.5;
  /// Touching objects of one class that as many views held in one mask as
  /// apart (1 : 1) are one when at least this many of the smaller one's
  /// voxels touch the other directly (26-neighbours), not just within
  /// touch_voxels.
  size_t min_tie_contact_voxels = 3;
  /// A piece of one class at most max_attached_size_ratio the size of an
  /// object it touches, with at least min_attached_contact_share of its
  /// voxels in direct contact (26-neighbours) with it, is part of it whatever
  /// the masks said (7-Scenes chess: a chair's 29-voxel piece, 26 of them
  /// touching the chair, held apart by 14 of 20 views; a mask generator cuts
  /// the same part off in every view). So is such a piece of another class
  /// that every view seeing both held in one mask with it (a board one view
  /// called sofa with the box it lies on), while it is still a piece of its
  /// own; the object keeps its class. max_attached_size_ratio 0: never.
  double min_attached_contact_share = 0.5;
  double max_attached_size_ratio = 0.25;
  /// Touching pieces of one class that the views held apart (a mask
  /// generator cuts a sofa's back off its seat in every view) are one when at
  /// least this share of the smaller one's voxels touch the other directly
  /// and together they are no longer than one object of the class can be
  /// (MapContext::max_length_m: two chairs side by side are too long for one
  /// chair). 1: never.
  double min_part_contact_share = 0.05;
  /// Touching pieces of a class of no known size (min_tie_contact_voxels in
  /// direct contact) are one when at least this share of one lies inside the
  /// other's upright box: objects do not interpenetrate (a bookcase's boards
  /// inside its frame). 0: never.
  double min_nested_share = 0.8;
  /// Objects that at least this many views held in different masks (and few
  /// in one) are never joined through a chain of merges of other objects.
  size_t min_apart_views = 2;
  double min_hold_share = 0.2;
  /// Parts of one fusion object are cut apart when views held them in
  /// different masks and the views holding them in one mask are at most this
  /// share of those: 1 : 3 is apart (two kitchen chairs joined only by their
  /// one close view), 1 : 2 is not. Also the bar of "held apart" for chains
  /// of merges (min_apart_views).
  double max_one_share = 0.34;
  /// Structure voxels on their plane join a touching thing of a class given
  /// at least this share of their votes (1: never): a headboard or a shelf's
  /// back flush with the wall, 2-6 cm in front of it, that most views near
  /// the wall called wall. A wall's own voxels get no thing votes beyond a
  /// mask's ragged edge (a few pixels of a voxel's ~10 at 3 m).
  double min_flush_share = 0.15;
  /// Touching objects of different classes merge when most views that saw
  /// both held them in one mask and one's votes give the other's class at
  /// least this share; the class more views gave over both wins (each view
  /// once, however many voxels it covered; voxel votes on a tie).
  double confusion_share = 0.25;
  /// ... or, when as many views held them apart as in one mask, when one's
  /// votes give the other's class at least this share.
  double tie_confusion_share = 0.4;
  /// How much larger than one object of its class (MapContext::max_length_m /
  /// max_width_m) an object may be: a merge of two confused classes keeps
  /// the class that fits the whole, given at least min_size_class_share of
  /// the object's votes (two chairs one merge joined are no sofa because a
  /// stray view said so); cuts, joins and specks are judged against it
  /// (below). size_slack 0: sizes are never checked.
  double size_slack = 1.25;
  double min_size_class_share = 0.25;
  /// A speck of a thing (a piece with under 5% of its voxels, kept with it
  /// because a mask held both or it was too small to stand alone) farther
  /// than this from the thing's pieces that are no specks, where the thing
  /// with it is larger than one of its class can be (size_slack) and it
  /// makes it larger (any size for classes of no known size), leaves it: it
  /// joins the object it touches (a thing only while it still fits its
  /// class), else it is dropped. One view's
  /// mask over a chair and a bit of the table 1.5 m away stretched the
  /// chair's mesh to 2.4 x 2.3 m (3DMatch); a chair's legs cut off from its
  /// seat stay. 0: never.
  double max_speck_gap_m = 0.3;

  void Check() const;
};

/// What the map knows besides its evidence.
struct MapContext {
  /// Up (world frame).
  Eigen::Vector3d up_world = Eigen::Vector3d::UnitZ();
  /// Per class id: kind (thing/stuff) and where structure lives.
  std::map<uint16_t, ClassKind> kinds;
  std::map<uint16_t, StructureGeometry> geometry;
  /// Per thing class id: the longest horizontal extent of one object (m;
  /// absent or 0: unknown; LabelClass::max_length_m).
  std::map<uint16_t, double> max_length_m;
  /// Per thing class id: the shortest side of one object's footprint at most
  /// (m; absent or 0: unknown; LabelClass::max_width_m).
  std::map<uint16_t, double> max_width_m;
  /// Thing classes of furniture with a front (LabelClass::furniture_front),
  /// by id.
  std::vector<uint16_t> front_classes;
  /// The fusion objects' current class and kind, by (current) id.
  struct Object {
    uint16_t class_id = 0;
    ClassKind kind = ClassKind::kThing;
  };
  std::map<uint32_t, Object> objects;
};

/// Kinds, structure geometry and footprints of every class in `classes`.
MapContext MakeMapContext(const LabelSet& classes,
                          const Eigen::Vector3d& up_world);

struct MapObject {
  uint32_t id = 0;
  uint16_t class_id = 0;
  ClassKind kind = ClassKind::kThing;
  /// Its voxels (keys, sorted).
  std::vector<uint64_t> voxels;
  /// Votes per class over its voxels (distance-weighted view shares x 100).
  std::map<uint16_t, uint64_t> class_votes;
  /// Fusion objects whose points it took.
  std::vector<uint32_t> sources;
  /// Labelled views / observing views (see above).
  double seen_ratio = 0.0;
  /// Views labelling it (max over voxels): 1 = seen once.
  uint32_t max_views = 0;
};

/// Voxel -> final object, and which fusion object's volume has its surface
/// (the one most views put it in, whatever the class): a mesh cut by these
/// gives each object its own surface once.
struct VoxelOwner {
  uint32_t owner = 0;
  uint32_t source = 0;
};

struct MapResolution {
  std::vector<MapObject> objects;  // sorted by id
  std::unordered_map<uint64_t, VoxelOwner> owners;
  std::vector<StructurePlane> planes;
  /// Voxels whose class changed by the structure gate; objects split off,
  /// merged by mask consensus, made from unclaimed voxels, and dropped or
  /// folded as fragments.
  size_t gated_voxels = 0;
  size_t split_objects = 0;
  size_t merged_objects = 0;
  size_t new_objects = 0;
  size_t fragments_folded = 0;
  size_t fragments_dropped = 0;
  /// Structure voxels off their planes that joined the thing they touch.
  size_t stranded_voxels_claimed = 0;
  /// Things lying on a furniture front that took the front's class
  /// (ClaimFronts).
  size_t reclassed_on_fronts = 0;
  /// Furniture fronts no thing held that became objects of a front class.
  size_t objects_from_fronts = 0;
  /// Wall voxels closed in by a thing at the wall that joined it.
  size_t enclosed_voxels_claimed = 0;
  /// Specks far from the rest of their object that left it.
  size_t far_specks_moved = 0;
};

/// Decides the objects. `resolve`: a fusion id's current id (0: dropped).
/// `next_id`: the first id free for new objects (advanced).
MapResolution ResolveMapObjects(
    const VoxelEvidenceMap& map, const MapContext& context,
    const MapObjectOptions& options,
    const std::function<uint32_t(uint32_t)>& resolve, uint32_t* next_id);

}  // namespace semrec::fuse
