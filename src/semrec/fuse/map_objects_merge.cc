// Orphan voxels, merges by masks and fragments judged by visibility (see
// map_resolver.h).
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <vector>

#include <spdlog/spdlog.h>

#include "semrec/fuse/map_resolver.h"

namespace semrec::fuse::internal {

bool MapResolver::OneObject(const std::vector<size_t>& a,
                            const std::vector<size_t>& b, uint32_t id_a,
                            uint32_t id_b, const PairViews& views,
                            size_t contact_voxels) const {
  const uint16_t ca = owner_class_.at(id_a), cb = owner_class_.at(id_b);
  if (ca == cb) {
    if (views.two == 0 || SaysOne(views, options_.min_one_views)) return true;
    // Sparse views see a place once or twice: as many views held the two in
    // one mask as apart (1 : 1), touching directly, is one object (mask
    // generators cut objects far more often than they join two).
    return views.one >= 1 && views.one >= views.two &&
           contact_voxels >= options_.min_tie_contact_voxels;
  }
  // Different classes need more: most views that saw both held them in one
  // mask (sparse views: one view that joined a plant to the chair beside it
  // is a third of the plant's votes), or as many as held them apart and the
  // votes of one give the other's class nearly half (a sofa seen whole in
  // one view and cut, with a piece called plant, in the other: 46%).
  const double share = std::max(VoteShare(a, cb), VoteShare(b, ca));
  if (views.one > views.two) {
    // Counted by views too, when several views held them in one mask: a
    // part only its one flipped view saw whole (a shelf's side called sofa)
    // has few voxel votes for the shelf, but the views that held it with the
    // shelf called it shelf. (One view joining a plant to a chair is not
    // enough: each view's class counts as much as the plant's own view.)
    double view_share = 0.0;
    if (views.one >= options_.min_one_views) {
      // Where some view held them apart, only for a part of the other (at
      // most half its size) that one view at most gave its own class: two
      // views that agree on it (a cabinet beside a counter) keep it apart,
      // and so does a counter one view called plant from the chair beside it.
      // Where none did, for either part whatever its size (a counter's
      // larger part its one close view called plant).
      const bool held_apart = views.two > 0;
      const auto part_share = [&](const std::vector<size_t>& part, uint16_t own,
                                  uint16_t other) {
        const std::vector<size_t>& rest = &part == &a ? b : a;
        if (held_apart && 2 * part.size() > rest.size()) return 0.0;
        const std::map<uint16_t, double> votes = ViewVotes(part);
        const auto it = votes.find(own);
        if (held_apart && it != votes.end() && it->second > 1.0) return 0.0;
        return ShareOf(votes, other);
      };
      view_share = std::max(part_share(a, ca, cb), part_share(b, cb, ca));
    }
    return std::max(share, view_share) >= options_.confusion_share;
  }
  return views.one >= 1 && views.one == views.two &&
         share >= options_.tie_confusion_share;
}

bool MapResolver::Attached(size_t size_a, size_t size_b,
                           size_t contact_voxels) const {
  const auto smaller = static_cast<double>(std::min(size_a, size_b));
  const auto larger = static_cast<double>(std::max(size_a, size_b));
  return static_cast<double>(contact_voxels) >=
             options_.min_attached_contact_share * smaller &&
         smaller <= options_.max_attached_size_ratio * larger;
}

std::vector<MapResolver::MergeLink> MapResolver::MergeLinks(
    const Members& members, const MaskHolders& holders) const {
  std::set<std::pair<uint32_t, uint32_t>> pairs;
  for (const auto& [id, cells] : members) {
    for (size_t i : cells) {
      ForNeighbours(i, [&](size_t n) {
        const uint32_t other = cells_[n].owner;
        if (other > id && IsThingCell(cells_[n])) pairs.emplace(id, other);
      });
    }
  }
  // Cells of each object in direct contact (26-neighbours) with another.
  std::map<std::pair<uint32_t, uint32_t>, size_t> contact;
  for (const auto& [id, cells] : members) {
    for (size_t i : cells) {
      std::set<uint32_t> seen;
      ForNeighbours(
          i,
          [&](size_t n) {
            const uint32_t other = cells_[n].owner;
            if (other != id && other != 0 && IsThingCell(cells_[n]) &&
                seen.insert(other).second) {
              ++contact[{id, other}];
            }
          },
          1);
    }
  }
  // Judged on the objects as they were: a chain of merges does not change
  // the evidence of a pair.
  std::vector<MergeLink> links;
  for (const auto& [a, b] : pairs) {
    const std::vector<size_t>& ca = members.at(a);
    const std::vector<size_t>& cb = members.at(b);
    const PairViews v = CoViews(holders.at(a), holders.at(b));
    // The smaller one's cells in direct contact with the other.
    const auto it = contact.find(ca.size() <= cb.size() ? std::pair{a, b}
                                                        : std::pair{b, a});
    const size_t contact_voxels = it == contact.end() ? 0 : it->second;
    const uint16_t class_a = owner_class_.at(a);
    const bool same = class_a == owner_class_.at(b);
    const bool attached =
        same && Attached(ca.size(), cb.size(), contact_voxels);
    if (attached || OneObject(ca, cb, a, b, v, contact_voxels)) {
      links.push_back({a, b, v, contact_voxels, attached, false, false, same});
    } else if (!same && v.one >= 1 && v.two == 0 &&
               Attached(ca.size(), cb.size(), contact_voxels)) {
      links.push_back({a, b, v, contact_voxels, true, false, false, false,
                       ca.size() <= cb.size() ? a : b});
    } else if (same && PartsOfOne(ca, cb, class_a, contact_voxels)) {
      links.push_back({a, b, v, contact_voxels, true, true, false});
    } else if (same && !context_.max_length_m.count(class_a) &&
               contact_voxels >= options_.min_tie_contact_voxels &&
               Nested(ca, cb)) {
      links.push_back({a, b, v, contact_voxels, true, false, true});
    }
    spdlog::debug(
        "objects {} and {} (classes {} and {}, {} and {} voxels): {} views "
        "one, {} two, {} voxels in contact",
        a, b, class_a, owner_class_.at(b), ca.size(), cb.size(), v.one, v.two,
        contact_voxels);
  }
  // Surest links first: the most views holding the pair in one mask, the
  // fewest apart, the widest contact.
  std::stable_sort(links.begin(), links.end(),
                   [](const MergeLink& x, const MergeLink& y) {
                     if (x.views.one != y.views.one) {
                       return x.views.one > y.views.one;
                     }
                     if (x.views.two != y.views.two) {
                       return x.views.two < y.views.two;
                     }
                     return x.contact > y.contact;
                   });
  return links;
}

bool MapResolver::HeldApart(const std::vector<uint32_t>& x_parts,
                            const std::vector<uint32_t>& y_parts,
                            const MaskHolders& holders,
                            const MergeLink& link) const {
  for (uint32_t p : x_parts) {
    for (uint32_t q : y_parts) {
      // An attached piece joins whatever its own masks said.
      if (link.attached &&
          ((p == link.a && q == link.b) || (p == link.b && q == link.a))) {
        continue;
      }
      const PairViews v = CoViews(holders.at(p), holders.at(q));
      if (v.two >= options_.min_apart_views && SaysApart(v)) return true;
    }
  }
  return false;
}

uint16_t MapResolver::ConfusedWinner(const std::vector<size_t>& keep,
                                     const std::vector<size_t>& gone,
                                     uint16_t ck, uint16_t cg,
                                     uint16_t attached_to, bool* fits) const {
  *fits = true;
  std::vector<size_t> both = keep;
  both.insert(both.end(), gone.begin(), gone.end());
  uint16_t winner = attached_to;
  if (winner == kNoClass) {
    // Counted by views; by voxel evidence where the views tie (not the
    // larger part's class: sparse views tie voxel by voxel). A piece too
    // small to stand alone (a voxel or two a mask took into another class)
    // does not give its class to the object it joins by votes (only by the
    // size rule below).
    const std::map<uint16_t, double> views = ViewVotes(both);
    const double view_cg = ShareOf(views, cg), view_ck = ShareOf(views, ck);
    const bool gone_wins =
        gone.size() >= options_.min_piece_voxels &&
        (view_cg != view_ck ? view_cg > view_ck
                            : VoteShare(both, cg) > VoteShare(both, ck));
    winner = gone_wins ? cg : ck;
  }
  const uint16_t other = winner == ck ? cg : ck;
  const double slack = options_.size_slack;
  if (slack <= 0.0 || MaxFootprint(winner).x() <= 0.0) return winner;
  const Eigen::Vector2d size_m = CoreFootprintSize(both, kSizeTrimShare);
  if (FitsSize(size_m, winner, slack)) return winner;
  // A class too small for the whole gives way to one that fits it (a counter
  // one view called plant) ...
  if (ThingShares(both)[other] >= options_.min_size_class_share &&
      FitsSize(size_m, other, slack)) {
    spdlog::debug(
        "  {:.2f} x {:.2f} m together: class {} does not fit, class "
        "{} does",
        size_m.x(), size_m.y(), winner, other);
    return other;
  }
  // ... and when neither can name the pair (the other too small too, or
  // with too few votes), they are two objects (kitchen 5: a chair and the
  // counter it stands at, which views held in one mask: a 2.2 m chair);
  // unless the larger is too large already and the other does not make it
  // larger (it fills in its footprint, as StillFits allows), or is an
  // attached piece.
  *fits = attached_to != kNoClass || StillFits(keep, winner, gone);
  return winner;
}

void MapResolver::JoinClasses(uint32_t keep, uint32_t gone, uint16_t winner) {
  std::set<uint16_t>& joined = part_classes_[keep];
  joined.insert({owner_class_[keep], owner_class_[gone]});
  if (const auto it = part_classes_.find(gone); it != part_classes_.end()) {
    joined.insert(it->second.begin(), it->second.end());
  }
  owner_class_[keep] = winner;
}

// The groups links join: each object's group (a union-find over object ids),
// the objects and voxels each group holds, and each group's mask holders.
struct MapResolver::MergeGroups {
  Members members;
  MaskHolders holders;  // per object, as it was before merging
  std::map<uint32_t, uint32_t> into;
  // The objects each group holds, as they were before merging.
  std::map<uint32_t, std::vector<uint32_t>> parts;
  // Each merged group's mask holders, computed when first needed (a large
  // group meets many links).
  MaskHolders holders_of_group;

  uint32_t Find(uint32_t id) {
    while (into.count(id)) id = into[id];
    return id;
  }
  const std::map<size_t, std::set<uint64_t>>& GroupHolders(
      const MapResolver& resolver, uint32_t id) {
    if (parts[id].size() == 1) return holders.at(id);
    auto it = holders_of_group.find(id);
    if (it == holders_of_group.end()) {
      it = holders_of_group.emplace(id, resolver.Holders(members[id])).first;
    }
    return it->second;
  }
  void Join(uint32_t keep, uint32_t gone) {
    into[gone] = keep;
    holders_of_group.erase(keep);
    holders_of_group.erase(gone);
    members[keep].insert(members[keep].end(), members[gone].begin(),
                         members[gone].end());
    parts[keep].insert(parts[keep].end(), parts[gone].begin(),
                       parts[gone].end());
  }
};

bool MapResolver::MayJoin(const MergeLink& link, uint32_t x, uint32_t y,
                          MergeGroups* g) {
  const bool same = owner_class_[x] == owner_class_[y];
  // A piece attached to an object of another class joins it only as itself:
  // once joined to others (a table's piece), its group is no piece.
  if (link.piece != 0 && g->parts[g->Find(link.piece)].size() != 1) {
    spdlog::debug("objects {} and {}: not joined, {} is no longer a piece",
                  link.a, link.b, link.piece);
    return false;
  }
  Members& members = g->members;
  const bool fits = same && FitsOne(members[x], members[y], owner_class_[x]);
  // Parts of one object must still fit one object together, or still be
  // nested.
  if (link.parts && !fits) return false;
  const bool nested = link.nested && Nested(members[x], members[y]);
  if (link.nested && !nested) return false;
  if (same && link.views.one < options_.min_one_views && !link.attached &&
      !link.nested && !FitsTogether(members[x], members[y], owner_class_[x])) {
    spdlog::debug(
        "objects {} and {}: not joined, {} view(s) saw them in one mask "
        "and their groups ({} and {} voxels) are too large for one",
        link.a, link.b, link.views.one, members[x].size(), members[y].size());
    return false;
  }
  // No chain of links joins two objects the views held apart (chairs round
  // a table, each touching a small piece that touches the next: six views
  // showed two of them in different masks, none in one). Where one object
  // of the class has a known size, fitting it decides instead: a mask
  // generator that cuts a sofa's back off its seat in every view holds
  // every piece of the back apart from every piece of the seat.
  if (!fits && !nested &&
      HeldApart(g->parts[x], g->parts[y], g->holders, link)) {
    spdlog::debug("objects {} and {}: not joined, held apart", link.a, link.b);
    return false;
  }
  // Two classes: the views are counted again on the groups the link would
  // join, and more views holding them apart than in one mask keep them
  // apart (a box whose pieces joined first, seen in its own mask by four
  // views, is not one with the shelf three views held it with, though the
  // piece at the shelf was held with it by more views than apart). The
  // class evidence stays the pair's: a group dilutes a confused part's
  // votes. A link of one class between groups of two (a table's piece
  // joined the cabinet beside it first) says nothing of their classes: the
  // groups must be one by the rule for two classes.
  if (!same && (g->parts[x].size() > 1 || g->parts[y].size() > 1)) {
    const PairViews v =
        CoViews(g->GroupHolders(*this, x), g->GroupHolders(*this, y));
    const bool one = link.same_class ? OneObject(members[x], members[y], x, y,
                                                 v, link.contact)
                                     : v.one >= v.two;
    if (!one) {
      spdlog::debug(
          "objects {} and {}: not joined, their groups ({} and {} voxels, "
          "{} views one, {} two) are not one",
          link.a, link.b, members[x].size(), members[y].size(), v.one, v.two);
      return false;
    }
  }
  return true;
}

void MapResolver::MergeByMasks() {
  MergeGroups g;
  g.members = ThingMembers();
  for (const auto& [id, cells] : g.members) g.holders[id] = Holders(cells);
  const std::vector<MergeLink> links = MergeLinks(g.members, g.holders);
  for (const auto& entry : g.members) g.parts[entry.first] = {entry.first};
  Members& members = g.members;
  for (const MergeLink& link : links) {
    const uint32_t x = g.Find(link.a), y = g.Find(link.b);
    if (x == y || !MayJoin(link, x, y, &g)) continue;
    const bool x_keeps = members[x].size() >= members[y].size();
    const uint32_t keep = x_keeps ? x : y, gone = x_keeps ? y : x;
    const uint16_t ck = owner_class_[keep], cg = owner_class_[gone];
    uint16_t winner = ck;
    if (ck != cg) {
      // An attached piece of another class takes the object's class.
      const uint32_t piece_group = link.piece != 0 ? g.Find(link.piece) : 0;
      const uint16_t attached_to =
          piece_group == 0 ? kNoClass : (piece_group == keep ? cg : ck);
      bool fits = true;
      winner = ConfusedWinner(members[keep], members[gone], ck, cg, attached_to,
                              &fits);
      if (!fits) {
        spdlog::debug(
            "objects {} and {}: not joined, neither class {} nor {} fits "
            "their groups ({} and {} voxels) together",
            link.a, link.b, ck, cg, members[x].size(), members[y].size());
        continue;
      }
    }
    spdlog::debug(
        "objects {} and {} joined (groups {} and {}: {} and {} voxels; "
        "{} views one, {} two, {} in contact{}{}{})",
        link.a, link.b, x, y, members[x].size(), members[y].size(),
        link.views.one, link.views.two, link.contact,
        link.attached ? ", attached" : "", link.parts ? ", parts" : "",
        link.nested ? ", nested" : "");
    g.Join(keep, gone);
    if (ck != cg) JoinClasses(keep, gone, winner);
    ++result_.merged_objects;
  }
  for (Cell& c : cells_) {
    if (c.owner == 0 || !IsThingCell(c)) continue;
    c.owner = g.Find(c.owner);
    c.class_id = owner_class_[c.owner];
  }
}

void MapResolver::AttachOrphans() {
  std::vector<bool> done(cells_.size(), false);
  for (size_t i = 0; i < cells_.size(); ++i) {
    const Cell& c = cells_[i];
    if (done[i] || c.owner != 0 || !IsThingCell(c)) continue;
    const uint16_t cls = c.class_id;
    const auto group = Component(i, &done, [&](size_t n) {
      return cells_[n].owner == 0 && cells_[n].class_id == cls;
    });
    uint32_t id = MostTouching(group, cls, 0);
    spdlog::debug("orphan voxels: {} of class {} -> object {}", group.size(),
                  cls, id);
    if (id == 0) {
      id = (*next_id_)++;
      owner_class_[id] = cls;
      ++result_.new_objects;
    }
    for (size_t n : group) cells_[n].owner = id;
  }
}

void MapResolver::JudgeFragments() {
  Members members = ThingMembers();
  std::vector<std::pair<size_t, uint32_t>> fragments;  // (size, id)
  for (const auto& [id, cells] : members) {
    const auto parts = part_classes_.find(id);
    const auto [ratio, max_views] =
        Visibility(cells, parts == part_classes_.end() ? std::set<uint16_t>{}
                                                       : parts->second);
    seen_[id] = {ratio, max_views};
    if (cells.size() < options_.min_voxels || ratio < options_.min_seen_ratio) {
      fragments.emplace_back(cells.size(), id);
      spdlog::debug("fragment {} (class {}): {} voxels, seen ratio {:.2f}", id,
                    owner_class_[id], cells.size(), ratio);
    }
  }
  std::sort(fragments.begin(), fragments.end());
  std::set<uint32_t> refused;
  for (const auto& [size, id] : fragments) refused.insert(id);
  for (const auto& [size, id] : fragments) {
    const std::vector<size_t>& cells = members[id];
    const uint32_t into = MostTouching(cells, owner_class_[id], id, refused);
    for (size_t i : cells) {
      cells_[i].owner = into;
      if (into == 0) cells_[i].class_id = kNoClass;
    }
    spdlog::debug("fragment {} {}", id, into ? "folded" : "dropped");
    ++(into ? result_.fragments_folded : result_.fragments_dropped);
  }
}

std::pair<double, uint32_t> MapResolver::Visibility(
    const std::vector<size_t>& cells, const std::set<uint16_t>& parts) const {
  double labelled = 0.0, observed = 0.0;
  uint32_t max_views = 0;
  const auto counted = [&parts](const Cell& c,
                                const std::vector<ClassEvidence>& in) {
    uint32_t views = 0;
    for (const ClassEvidence& e : in) {
      if (e.class_id == c.class_id || parts.count(e.class_id) != 0 ||
          std::find(c.excluded.begin(), c.excluded.end(), e.class_id) !=
              c.excluded.end()) {
        views += e.views;
      }
    }
    return views;
  };
  for (size_t i : cells) {
    const Cell& c = cells_[i];
    uint32_t views = counted(c, c.evidence->classes);
    uint32_t could = c.evidence->views;
    // A class only far views gave the voxel (its ranged views said another):
    // seen by those when min_far_views agree, out of the ranged and far views
    // that could see it. A class some ranged view gave is judged by the
    // ranged views alone: counting far views there kept pieces the ranged
    // views had left as fragments.
    if (const auto far = far_.find(c.key); views == 0 && far != far_.end()) {
      const uint32_t far_views = counted(c, far->second.classes);
      if (far_views >= options_.min_far_views) {
        views = far_views;
        could += far->second.views;
      }
    }
    labelled += views;
    observed += std::max(could, views);
    max_views = std::max(max_views, views);
  }
  return {observed > 0.0 ? labelled / observed : 0.0, max_views};
}

}  // namespace semrec::fuse::internal
