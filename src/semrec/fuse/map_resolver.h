// Internal to fuse/map_objects.h: the resolver whose steps decide the map's
// objects, shared by map_objects.cc (cells, structure gate, owners, the
// result), map_objects_split.cc (cuts by masks and by connectivity) and
// map_objects_merge.cc (orphans, merges by masks, fragments),
// map_objects_size.cc (footprints, fits, nesting),
// map_objects_claim.cc (fronts and stranded structure claimed by things) and
// map_objects_enclosed.cc (walls enclosed by things). docs/fusion.md lists
// the passes in the order MapResolver::Run calls them. Not installed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "semrec/fuse/map_objects.h"
#include "semrec/fuse/voxel.h"

namespace semrec::fuse::internal {

constexpr uint16_t kNoClass = 0xFFFF;

// The id with the most votes (ties: the smaller id) among `votes` passing
// `accept`; 0 when none.
template <typename Accept>
uint32_t MostVoted(const std::map<uint32_t, float>& votes,
                   const Accept& accept) {
  uint32_t best = 0;
  float best_views = 0.0f;
  for (const auto& [id, views] : votes) {
    if (views > best_views && accept(id)) best = id, best_views = views;
  }
  return best;
}

class MapResolver {
 public:
  MapResolver(const VoxelEvidenceMap& map, const MapContext& context,
              const MapObjectOptions& options,
              const std::function<uint32_t(uint32_t)>& resolve,
              uint32_t* next_id)
      : map_(map),
        context_(context),
        options_(options),
        resolve_(resolve),
        next_id_(next_id) {}

  MapResolution Run();

  // One pass of Run: its name (MapResolverPassNames), the member that runs
  // it, and whether the options turn it on (null: always).
  struct Pass {
    const char* name;
    void (MapResolver::*run)();
    bool (*enabled)(const MapObjectOptions&);
  };
  static const std::vector<Pass>& Passes();

 private:
  struct Cell {
    uint64_t key = 0;
    Eigen::Vector3f p;
    const VoxelEvidence* evidence = nullptr;
    uint16_t class_id = kNoClass;
    uint32_t owner = 0;
    uint32_t source = 0;
    /// Structure classes set aside here (off their planes).
    std::vector<uint16_t> excluded;
    /// Off its class's planes with no other class to take over: structure
    /// where no structure can be (see ClaimStranded).
    bool stranded = false;
  };

  bool IsStuff(uint16_t class_id) const {
    const auto it = context_.kinds.find(class_id);
    return it != context_.kinds.end() && it->second == ClassKind::kStuff;
  }
  // A few voxels two objects share are the mixed depths at their contact,
  // not a view's evidence about them (Holders, PiecesSeededBy, ViewVotes).
  static constexpr size_t kContactVoxels = 5;

  bool IsThingCell(const Cell& c) const {
    return c.class_id != kNoClass && !IsStuff(c.class_id);
  }
  // Structure off its planes that no other class could take (GateStructure).
  bool IsStranded(const Cell& c) const {
    return c.stranded && IsStuff(c.class_id);
  }

  // Labelled voxels in key order (deterministic), with their winners.
  void CollectCells();

  // Structure evidence off its planes is set aside; the next class wins.
  void GateStructure();
  /// Share of `points` within 1.5 x the tolerance of any of `planes` or
  /// `fronts` (1 without any).
  double ShareOnPlanes(const Cloud& points,
                       const std::vector<StructurePlane>& planes,
                       const std::vector<StructurePlane>& fronts) const;
  // Structure voxels on their plane that many views gave a thing's class,
  // connected to voxels of that class: the thing's part flush with the wall
  // or the floor (a headboard, a shelf's back) that views near the wall
  // called wall.
  void ReleaseFlushParts();

  // The next class takes a voxel off structure only on real evidence: a view
  // where it held most of the voxel's pixels and a share of its votes (not
  // the stray vote of a mask's fringe).
  bool CanTakeOver(const VoxelEvidence& v, uint16_t class_id) const;
  // A structure class that lives on planes, none of which was found, and a
  // surface not turned as that class's surfaces are (null: unknown, false).
  bool UnplacedAndTurnedAway(uint16_t class_id,
                             const Eigen::Vector3f* surface_axis) const;

  uint32_t StructureId(uint16_t class_id);

  // Thing voxels go to the object of their class most views put them in;
  // unclaimed ones stay 0 (orphans) for now.
  void AssignOwners();

  // Cells within `radius` voxels (Chebyshev; 0: touch_voxels) of cell i, in
  // (dx, dy, dz) order.
  template <typename Visit>
  void ForNeighbours(size_t i, const Visit& visit, int radius = 0) const {
    const int r = radius > 0 ? radius : options_.touch_voxels;
    if (r == options_.touch_voxels && !neighbour_start_.empty()) {
      // The touching cells, listed once (NeighbourLists): components and
      // footprints walk them many times.
      for (uint32_t k = neighbour_start_[i]; k < neighbour_start_[i + 1]; ++k) {
        visit(static_cast<size_t>(neighbours_[k]));
      }
      return;
    }
    const Eigen::Vector3i v = UnpackVoxel(cells_[i].key);
    for (int dx = -r; dx <= r; ++dx) {
      for (int dy = -r; dy <= r; ++dy) {
        for (int dz = -r; dz <= r; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          const auto it =
              index_.find(PackVoxel(v.x() + dx, v.y() + dy, v.z() + dz));
          if (it != index_.end()) visit(it->second);
        }
      }
    }
  }

  // Connected cells (from `seed`) for which `member` holds.
  template <typename Member>
  std::vector<size_t> Component(size_t seed, std::vector<bool>* done,
                                const Member& member) const {
    std::vector<size_t> component{seed};
    (*done)[seed] = true;
    for (size_t k = 0; k < component.size(); ++k) {
      ForNeighbours(component[k], [&](size_t n) {
        if (!(*done)[n] && member(n)) {
          (*done)[n] = true;
          component.push_back(n);
        }
      });
    }
    return component;
  }

  // The thing object of `class_id` (other than `except`) touching `cells`
  // most; 0 when none.
  uint32_t MostTouching(const std::vector<size_t>& cells, uint16_t class_id,
                        uint32_t except,
                        const std::set<uint32_t>& refused = {}) const;

  // Views that saw two groups of cells: holding both in one mask, or in
  // different masks.
  struct PairViews {
    size_t one = 0, two = 0;
  };
  // Per frame, the masks holding `cells`: covering min_hold_share of the
  // cells that view put in object masks (a view sees part of a large object)
  // and at least 5 of them (or all of a smaller part), not a few voxels at the
  // contact where the depths of two touching objects mix.
  std::map<size_t, std::set<uint64_t>> Holders(
      const std::vector<size_t>& cells) const;
  static PairViews CoViews(const std::map<size_t, std::set<uint64_t>>& a,
                           const std::map<size_t, std::set<uint64_t>>& b);
  // Cut apart: some view put them in different masks and the views putting
  // them in one mask are at most max_one_share of those. Stricter than not
  // merging (OneObject): the overlap rule fused them on geometry, so a cut
  // needs the views' clear majority (a 5% join of two cabinets does not keep
  // them one; a chair cut in two by half its views stays a chair).
  bool SaysApart(const PairViews& v) const;
  bool SaysOne(const PairViews& v, size_t min_one) const;

  // The overlap rule fuses touching objects of one class (monitors side by
  // side, two cabinets) that every view showed in different masks: such a
  // fusion object is cut into the parts the views held apart. A cut can
  // reveal another (three monitors, one view showing two of them): a few
  // rounds.
  void SplitByMasks();

  // Candidate cuts come from the views that put the object in two or more
  // large masks (min_piece_voxels each; the most even first, a few): each
  // such mask seeds a piece, every other view's mask joins the piece it
  // overlaps most, and each voxel the piece most of its masks joined. The
  // pieces are then grouped by all views (GroupPieces); the first candidate
  // that leaves two groups or more cuts the object.
  bool SplitObjectByMasks(uint32_t owner, const std::vector<size_t>& cells);

  // Pieces (global cell indices) seeded by one view's masks `seeds` (size,
  // mask): the seeds' cells, then each other mask joins the piece holding
  // most of its cells (at least 5 of them: a few are the mixed depths at a
  // contact; none when it holds min_hold_share of two seeds: a view that
  // joined them says nothing of where their cells go), each remaining cell
  // the piece most of its masks joined; cells no mask places take their
  // touching neighbours' piece, or the first.
  std::vector<std::vector<size_t>> PiecesSeededBy(
      const std::vector<size_t>& cells,
      const std::unordered_map<uint64_t, std::vector<size_t>>& mask_cells,
      const std::vector<std::pair<size_t, uint64_t>>& seeds) const;

  // Groups pieces; returns each one's group (a piece index). Pieces join
  // unless the views hold them apart (SaysApart), and never into a group
  // holding a piece held apart from one of theirs; pairs more views held in
  // one mask join first.
  std::vector<size_t> GroupPieces(
      const std::vector<std::vector<size_t>>& pieces) const;

  // Pieces of an object that do not touch: those the views held in one mask
  // stay with the largest; other large groups become objects, small ones
  // orphans (joined below).
  void SplitDisconnected();
  // Each thing object's pieces: its cells' components (touch_voxels apart),
  // largest first.
  std::map<uint32_t, std::vector<std::vector<size_t>>> ThingPieces() const;
  // Specks of things far from the rest of their object (max_speck_gap_m),
  // where the object with them is too large for its class and they make it
  // larger (or its class has no known size), leave it: each joins the object
  // it touches most (a thing only while it still fits), else it is dropped.
  void ReleaseFarSpecks();
  // The specks of `owner` (its `pieces`, largest first) that leave it.
  std::vector<std::vector<size_t>> FarSpecks(
      uint32_t owner, const std::vector<std::vector<size_t>>& pieces) const;
  // Distance from `speck` to the nearest larger piece of `pieces` (logs).
  float SpeckGap(const std::vector<size_t>& speck,
                 const std::vector<std::vector<size_t>>& pieces) const;

  // Share of `cells`' class evidence that goes to `class_id`.
  double VoteShare(const std::vector<size_t>& cells, uint16_t class_id) const;
  // Per class, the views that gave it to `cells`, each view one vote split
  // over the classes of its masks there (a view counts where it put at least
  // 5 of the cells, or all, in object masks); far views add, per class, the
  // most that voted it on any one cell. A close view covers many voxels and
  // a far one few, so voxel sums weigh the close view's class; these count
  // each view once.
  std::map<uint16_t, double> ViewVotes(const std::vector<size_t>& cells) const;
  // Share of `votes` (ViewVotes) that goes to `class_id`.
  static double ShareOf(const std::map<uint16_t, double>& votes,
                        uint16_t class_id);

  // A piece of one class much smaller than the object it touches, most of
  // its voxels in direct contact with it (a chair's rail, a seat's edge that
  // the mask generator cuts off in every view): part of it, whatever the
  // masks said.
  bool Attached(size_t size_a, size_t size_b, size_t contact_voxels) const;

  // The voxel centres of `cells` without specks: connected parts
  // (touch_voxels apart) under kSpeckShare of the cells, unless the largest:
  // a few voxels a metre away (mixed depth at an edge, labelled with the
  // object) would blow up a box (on flat seed 1 a 1.8 m sofa's voxels spanned
  // 3.1 m).
  static constexpr double kSpeckShare = 0.05;
  std::vector<Eigen::Vector3d> SpecklessPoints(
      const std::vector<size_t>& cells) const;
  // The sides of `cells`' footprint (without specks), longer first: the
  // smallest box around it, turned about the vertical (m).
  Eigen::Vector2d FootprintSize(const std::vector<size_t>& cells) const;
  // ... with every voxel, specks included.
  Eigen::Vector2d FootprintWithSpecks(const std::vector<size_t>& cells) const;
  // Whether `a` and `b` together (without specks) are no longer and no wider
  // than one object of the class can be (false for classes of no known
  // size).
  bool FitsOne(const std::vector<size_t>& a, const std::vector<size_t>& b,
               uint16_t class_id) const;
  // The sides of `cells`' footprint (without specks) as FootprintSize, less
  // the trim_share of the points at each end of each side (plus a voxel):
  // mixed depths at an object's silhouette put a few voxels out of place,
  // which a box around all of them counts (a 0.4 m lamp measured 0.92 m).
  Eigen::Vector2d CoreFootprintSize(const std::vector<size_t>& cells,
                                    double trim_share) const;
  static constexpr double kSizeTrimShare = 0.05;
  // The longest and widest footprint one object of the class can have
  // (label-set data; a width of 0: not limited); zero when the class has no
  // known size.
  Eigen::Vector2d MaxFootprint(uint16_t class_id) const;
  // Whether footprint sides `size_m` (longer first) are no longer and no
  // wider than one object of the class can be times `slack` (true for
  // classes of no known size).
  bool FitsSize(const Eigen::Vector2d& size_m, uint16_t class_id,
                double slack) const;
  // Each thing class's share of the thing classes' votes over `cells`.
  std::map<uint16_t, double> ThingShares(
      const std::vector<size_t>& cells) const;
  // Whether `a` and `b` together (without specks) fit one object of the class
  // with size_slack (true for classes of no known size, or size_slack 0).
  bool FitsTogether(const std::vector<size_t>& a, const std::vector<size_t>& b,
                    uint16_t class_id) const;
  // Touching pieces of one class that views held apart, joined along a seam
  // (min_part_contact_share of the smaller one) and fitting one object of the
  // class together (FitsOne): a mask generator's consistent cut (a sofa's
  // back off its seat), not two objects.
  bool PartsOfOne(const std::vector<size_t>& a, const std::vector<size_t>& b,
                  uint16_t class_id, size_t contact_voxels) const;
  // Whether at least min_nested_share of one piece (without specks) lies in
  // the other's upright box (smallest footprint, grown by a voxel),
  // the larger box holding the smaller: objects do not interpenetrate, so such
  // pieces are parts of one (a bookcase's boards inside its frame, drawers in
  // a cabinet's front), whatever the views said. Linked only for classes of
  // no known size (for the others FitsOne decides: a piece that is already
  // two chairs has a box that holds a third).
  bool Nested(const std::vector<size_t>& a, const std::vector<size_t>& b) const;
  // Share of the voxels of the piece with the smaller box (without specks)
  // inside the other's upright box.
  double ShareInside(const std::vector<size_t>& a,
                     const std::vector<size_t>& b) const;

  // Whether touching objects a and b are one. One class: when no view held
  // them in different masks, when enough views held them in one mask
  // (SaysOne), or when as many held them in one mask as apart and they touch
  // directly, `contact_voxels` (the smaller one's voxels with a 26-neighbour
  // in the other) >= min_tie_contact_voxels: masks cut one object far more
  // often than they join two, and sparse views see an object once or twice,
  // so 1 : 1 is the common split of one object (attached pieces, Attached,
  // are linked besides). Two classes: when most views that saw both held them
  // in one mask and one's votes give the other's class at least
  // confusion_share (one object, its class confused); when several views
  // did, also one's ViewVotes, for a part at most half the other's size whose
  // own class one view at most gave (a shelf's side its one close view
  // called sofa), or for either part where no view held them apart.
  bool OneObject(const std::vector<size_t>& a, const std::vector<size_t>& b,
                 uint32_t id_a, uint32_t id_b, const PairViews& views,
                 size_t contact_voxels) const;

  using Members = std::map<uint32_t, std::vector<size_t>>;
  using MaskHolders = std::map<uint32_t, std::map<size_t, std::set<uint64_t>>>;
  // A pair of touching objects that are one.
  struct MergeLink {
    uint32_t a = 0, b = 0;
    PairViews views;
    size_t contact = 0;
    // Joined whatever the pair's own masks said (Attached, PartsOfOne).
    bool attached = false;
    // PartsOfOne: the groups it joins must still fit one object.
    bool parts = false;
    // Nested: the groups it joins must still be nested.
    bool nested = false;
    // The pair was of one class (the groups it joins may not be).
    bool same_class = true;
    // A piece of another class attached to the object (Attached, every view
    // that saw both held them in one mask): its id; it joins only as itself,
    // and the object keeps its class.
    uint32_t piece = 0;
  };
  // Touching pairs that are one (OneObject, Attached, PartsOfOne or Nested),
  // judged on the objects as they were, surest first: the most views holding
  // the pair in one mask, the fewest apart, the widest contact.
  std::vector<MergeLink> MergeLinks(const Members& members,
                                    const MaskHolders& holders) const;
  // Whether joining groups that hold objects x_parts and y_parts would join
  // two objects >= min_apart_views views held apart (SaysApart); a link's
  // own pair does not count when it is attached.
  bool HeldApart(const std::vector<uint32_t>& x_parts,
                 const std::vector<uint32_t>& y_parts,
                 const MaskHolders& holders, const MergeLink& link) const;

  // Touching objects that are one (MergeLinks) become one, unless that joins
  // objects held apart (HeldApart) that together neither fit one object of
  // their class (FitsOne) nor are nested (Nested), or joins groups of two
  // classes that more views held apart than in one mask, or joins groups of
  // one class too large for one object of it (FitsTogether) on a link fewer
  // than min_one_views views saw in one mask (touching, or one view, is all
  // that joined it: sparse views each see a part of one object, but chairs
  // side by side are also touching, and one mask may hold a row of them);
  // the larger keeps its id.
  void MergeByMasks();
  // MergeByMasks' groups as its links join them.
  struct MergeGroups;
  // Whether `link` may join groups x and y (the vetoes above but the class
  // fit, ConfusedWinner's); says why not in the debug log.
  bool MayJoin(const MergeLink& link, uint32_t x, uint32_t y,
               MergeGroups* groups);
  // Group `gone` joins `keep` (of another class): `keep` takes `winner` and
  // remembers the classes its parts had (part_classes_).
  void JoinClasses(uint32_t keep, uint32_t gone, uint16_t winner);
  // The class two groups of confused classes take together (`keep` the
  // larger's cells, of class ck; `gone` the other's, of cg; `attached_to`:
  // the class an attached piece takes, else kNoClass): the one more views
  // gave over both, or the other when only it fits their size; `fits` false
  // when neither can name them (and the larger is not already too large,
  // the other filling in its footprint).
  uint16_t ConfusedWinner(const std::vector<size_t>& keep,
                          const std::vector<size_t>& gone, uint16_t ck,
                          uint16_t cg, uint16_t attached_to, bool* fits) const;

  // Thing voxels no object of their class claimed: each connected group joins
  // the object of its class it touches most, or becomes a new object.
  void AttachOrphans();

  // Seen in few of the views that observed it: folded into the touching object
  // of its class, or dropped. A view that called the place structure where no
  // structure can be (set aside by the gate) did see it: it counts as a
  // sighting.
  void JudgeFragments();

  // Stranded structure voxels (off their class's planes, nothing else voted
  // there: a chair's legs every view called floor, a dark monitor called
  // wall) are parts of the things they touch: each voxel of a connected group
  // joins the thing nearest to it, unless the group is larger than every
  // thing it touches (then it is more likely structure no plane was fitted
  // to, e.g. a wall seen twice after drift).
  void ClaimStranded();
  // The cells of a stranded group that touch things (not `refused`), with
  // their contacts, and the largest of those things (`size`: voxels).
  struct StrandedContacts {
    std::vector<size_t> touching;
    std::map<size_t, std::map<uint32_t, float>> contacts_of;
    size_t largest = 0;
  };
  StrandedContacts ContactsOf(const std::vector<size_t>& cells,
                              const std::set<uint32_t>& refused,
                              const std::map<uint32_t, size_t>& size) const;
  // Each stranded voxel reachable from the contacts joins the nearest thing:
  // the voxels each thing takes.
  std::map<uint32_t, std::vector<size_t>> SpreadStranded(
      const StrandedContacts& contacts) const;

  // A furniture front (a row of cabinets under a counter) is one surface:
  // where views named part of it (a cabinet) and called the rest wall, the
  // stranded rest joins that thing, spreading over the fronts from it. The
  // thing must hold a fair part of a front and lie mostly on fronts (a chair
  // touching the cabinets does not take them; an L-shaped counter's cabinet
  // lies on two).
  void ClaimFronts();
  // The cells on each front, which lie on any, and per thing its voxels on
  // any front (an L-shaped counter is one cabinet over two fronts).
  struct FrontCells {
    std::vector<std::vector<size_t>> on;
    std::vector<bool> on_any;
    std::map<uint32_t, size_t> on_fronts;
  };
  FrontCells CellsOnFronts() const;
  // The stranded ones among `cells` (a front's rest a thing may take).
  std::vector<size_t> StrandedAmong(const std::vector<size_t>& cells) const;
  // ClaimFronts' state: the cells on the fronts (and the first front each
  // lies on), each thing's cells with the fronts it takes, whether a thing
  // may spread over a front's stranded voxels (its class's size, StillFits;
  // decided once per thing and front), the breadth-first frontier and the
  // voxels claimed.
  struct FrontClaim {
    FrontCells fc;
    std::vector<size_t> front_of;
    Members members;
    std::map<std::pair<uint32_t, size_t>, bool> may_take;
    std::vector<size_t> frontier;
    size_t claimed = 0;
  };
  bool FitsFront(FrontClaim* s, uint32_t id, size_t f);
  void TakeFrontCell(FrontClaim* s, size_t i, uint32_t id);
  // Breadth first from frontier[from...] over stranded voxels on fronts.
  void SpreadOverFronts(FrontClaim* s, size_t from);
  // Per front, the thing holding a fair part of it (and lying mostly on
  // fronts) takes it, seeding the frontier (`named`: front class -> voxels
  // of the fronts taken with it); returns the fronts no thing holds.
  std::vector<size_t> DecideFronts(FrontClaim* s,
                                   std::map<uint16_t, float>* named);
  // Fronts no thing holds, mostly stranded, become objects of a front class
  // (NewObjectFromFront), with the fronts they reach and their tops.
  void ObjectsFromFronts(FrontClaim* s, const std::vector<size_t>& unclaimed,
                         const std::map<uint16_t, float>& named);
  // The front class (MapContext::front_classes, not empty) with the most
  // votes over `cells`, else the most `named` (front class -> voxels of the
  // fronts things took with it), else the first.
  uint16_t FrontClassOf(const std::vector<size_t>& cells,
                        const std::map<uint16_t, float>& named) const;
  // Thing `id` (its `cells`) takes its front class (FrontClassOf) when that
  // class differs and fits it with the stranded voxels of `on_front`: true
  // when it did.
  bool TakeFrontClass(uint32_t id, const std::vector<size_t>& cells,
                      const std::vector<size_t>& on_front,
                      const std::map<uint16_t, float>& named);

  // Wall voxels on a vertical plane that a thing's voxels at the wall close
  // in, in the plane (four-connected, within the box of those voxels), join
  // the thing: the back panel of a shelf between its sides and boards. A
  // chair's back or a table against the wall leaves the wall open below or
  // beside it.
  void ClaimEnclosed();
  // A front no thing took (`on`: its cells) whose voxels are mostly
  // stranded gets a new object id of a front class (that of the fronts
  // things took, `named`: class -> their voxels, if any; else the most
  // voted on it; else the first). Returns the id (0: none); the caller
  // hands it the voxels.
  uint32_t NewObjectFromFront(const std::vector<size_t>& on,
                              const std::map<uint16_t, float>& named);

  // Cell `i` joins thing `id` (its class set aside, the thing's taken).
  void JoinThing(size_t i, uint32_t id) {
    Cell& c = cells_[i];
    c.excluded.push_back(c.class_id);
    c.class_id = owner_class_[id];
    c.owner = id;
  }
  // Voxels per thing object (owner), over the thing cells.
  std::map<uint32_t, size_t> ThingSizes() const;
  // The thing cells of each thing object (owner), in cell order.
  Members ThingMembers() const;
  // Whether a thing of class `class_id` with cells `cells` and the cells
  // `added` still fits one object of its class (CoreFootprintSize within
  // size_slack); one that did not fit before may take cells within its
  // footprint (a voxel of growth). True for classes of no known size, or
  // size_slack 0.
  bool StillFits(const std::vector<size_t>& cells, uint16_t class_id,
                 const std::vector<size_t>& added) const;

  // Of the views that could see `cells` (ranged, and far ones for a class
  // only far views gave), the share that gave them their class, and the most
  // views any cell had of its class: fragments are objects seen in few of
  // the views that could have seen them. The classes of `parts` count as
  // the object's (the confused parts it was joined from: a shelf its one
  // close view called plant was seen by that view).
  std::pair<double, uint32_t> Visibility(
      const std::vector<size_t>& cells,
      const std::set<uint16_t>& parts = {}) const;

  MapResolution Build();

  const VoxelEvidenceMap& map_;
  const MapContext& context_;
  const MapObjectOptions& options_;
  const std::function<uint32_t(uint32_t)>& resolve_;
  uint32_t* next_id_;
  std::vector<Cell> cells_;
  std::unordered_map<uint64_t, size_t> index_;
  // Per cell its cells within touch_voxels (ForNeighbours' order): cell i's
  // are neighbours_[neighbour_start_[i] .. neighbour_start_[i + 1]).
  std::vector<uint32_t> neighbour_start_, neighbours_;
  void NeighbourLists();
  // Voxels the far views voted on: their evidence with those votes added
  // (VoxelEvidenceMap::FarVotes); the cells point here instead of the map.
  std::unordered_map<uint64_t, VoxelEvidence> amended_;
  std::unordered_map<uint64_t, VoxelEvidenceMap::FarEvidence> far_;
  std::map<uint16_t, uint32_t> structure_ids_;
  // Structure planes per class (GateStructure).
  std::map<uint16_t, std::vector<StructurePlane>> planes_;
  // Vertical planes of structure classes that are furniture fronts.
  std::vector<StructurePlane> fronts_;
  std::map<uint32_t, uint16_t> owner_class_;
  // Classes of the confused parts each object was joined from (MergeByMasks).
  std::map<uint32_t, std::set<uint16_t>> part_classes_;
  std::map<uint32_t, std::pair<double, uint32_t>> seen_;
  MapResolution result_;
};

}  // namespace semrec::fuse::internal
