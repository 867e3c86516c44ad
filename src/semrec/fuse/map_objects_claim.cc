// Stranded structure voxels claimed by things: furniture fronts (the front
// of a counter some views called wall) and the rest (see map_resolver.h).
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <vector>

#include <spdlog/spdlog.h>

#include "semrec/fuse/map_resolver.h"

namespace semrec::fuse::internal {
namespace {

// The candidate with the largest positive weight (the first on ties);
// kNoClass when none has any.
template <typename Weight>
uint16_t MostOf(const std::vector<uint16_t>& candidates,
                const std::map<uint16_t, Weight>& weights) {
  uint16_t best = kNoClass;
  Weight best_weight = 0;
  for (uint16_t c : candidates) {
    const auto it = weights.find(c);
    if (it != weights.end() && it->second > best_weight) {
      best = c, best_weight = it->second;
    }
  }
  return best;
}

}  // namespace

std::map<uint32_t, size_t> MapResolver::ThingSizes() const {
  std::map<uint32_t, size_t> size;
  for (const Cell& c : cells_) {
    if (c.owner != 0 && IsThingCell(c)) ++size[c.owner];
  }
  return size;
}

std::vector<size_t> MapResolver::StrandedAmong(
    const std::vector<size_t>& cells) const {
  std::vector<size_t> stranded;
  for (size_t k : cells) {
    if (IsStranded(cells_[k])) stranded.push_back(k);
  }
  return stranded;
}

MapResolver::Members MapResolver::ThingMembers() const {
  Members members;
  for (size_t i = 0; i < cells_.size(); ++i) {
    if (cells_[i].owner != 0 && IsThingCell(cells_[i])) {
      members[cells_[i].owner].push_back(i);
    }
  }
  return members;
}

MapResolver::FrontCells MapResolver::CellsOnFronts() const {
  FrontCells fc;
  fc.on.resize(fronts_.size());
  fc.on_any.assign(cells_.size(), false);
  for (size_t i = 0; i < cells_.size(); ++i) {
    const Eigen::Vector3d q = cells_[i].p.cast<double>();
    for (size_t f = 0; f < fronts_.size(); ++f) {
      const StructurePlane& front = fronts_[f];
      if (std::abs(front.normal.dot(q) - front.offset) >
              front.Tolerance(options_.planes) ||
          !front.Covers(q)) {
        continue;
      }
      fc.on[f].push_back(i);
      if (!fc.on_any[i] && cells_[i].owner != 0 && IsThingCell(cells_[i])) {
        ++fc.on_fronts[cells_[i].owner];
      }
      fc.on_any[i] = true;
    }
  }
  return fc;
}

void MapResolver::ClaimFronts() {
  if (fronts_.empty()) return;
  FrontClaim s;
  s.fc = CellsOnFronts();
  s.front_of.assign(cells_.size(), fronts_.size());
  for (size_t f = fronts_.size(); f-- > 0;) {
    for (size_t i : s.fc.on[f]) s.front_of[i] = f;
  }
  s.members = ThingMembers();
  std::map<uint16_t, float> named;  // front class -> voxels of fronts taken
  const std::vector<size_t> unclaimed = DecideFronts(&s, &named);
  // Breadth first from the things over stranded voxels on fronts: the
  // nearest thing takes each, across the corner of an L-shaped counter too.
  SpreadOverFronts(&s, 0);
  spdlog::debug("{} stranded voxels on furniture fronts joined things",
                s.claimed);
  if (options_.objects_from_fronts && !context_.front_classes.empty()) {
    ObjectsFromFronts(&s, unclaimed, named);
  }
  result_.stranded_voxels_claimed += s.claimed;
}

bool MapResolver::FitsFront(FrontClaim* s, uint32_t id, size_t f) {
  const auto [it, fresh] = s->may_take.try_emplace({id, f}, false);
  if (!fresh) return it->second;
  const std::vector<size_t> rest = StrandedAmong(s->fc.on[f]);
  // Objects made from fronts have no members yet: they take every front
  // they reach (they are that furniture; front classes have no size).
  it->second = StillFits(s->members[id], owner_class_[id], rest);
  if (it->second) {
    s->members[id].insert(s->members[id].end(), rest.begin(), rest.end());
  }
  return it->second;
}

void MapResolver::TakeFrontCell(FrontClaim* s, size_t i, uint32_t id) {
  JoinThing(i, id);
  cells_[i].stranded = false;
  s->frontier.push_back(i);
  ++s->claimed;
}

void MapResolver::SpreadOverFronts(FrontClaim* s, size_t from) {
  for (size_t f = from; f < s->frontier.size(); ++f) {
    const uint32_t id = cells_[s->frontier[f]].owner;
    ForNeighbours(s->frontier[f], [&](size_t n) {
      if (s->fc.on_any[n] && IsStranded(cells_[n]) &&
          (s->front_of[n] == fronts_.size() ||
           FitsFront(s, id, s->front_of[n]))) {
        TakeFrontCell(s, n, id);
      }
    });
  }
}

std::vector<size_t> MapResolver::DecideFronts(
    FrontClaim* s, std::map<uint16_t, float>* named) {
  const std::map<uint32_t, size_t> size = ThingSizes();
  const auto& on = s->fc.on;
  const auto on_fronts = [&](uint32_t id) {
    const auto it = s->fc.on_fronts.find(id);
    return it == s->fc.on_fronts.end() ? size_t{0} : it->second;
  };
  const auto size_of = [&](uint32_t id) {
    const auto it = size.find(id);
    return it == size.end() ? size_t{0} : it->second;
  };
  std::vector<size_t> unclaimed;  // fronts no thing holds nor takes
  for (size_t f = 0; f < fronts_.size(); ++f) {
    std::map<uint32_t, size_t> held;  // thing -> its voxels on this front
    for (size_t i : on[f]) {
      if (cells_[i].owner != 0 && IsThingCell(cells_[i])) {
        ++held[cells_[i].owner];
      }
    }
    uint32_t best = 0;
    size_t best_held = 0;
    for (const auto& [id, n] : held) {
      if (n > best_held) best = id, best_held = n;
    }
    const bool holds_it =
        best != 0 &&
        static_cast<double>(best_held) >=
            options_.min_front_share * static_cast<double>(on[f].size()) &&
        2 * on_fronts(best) >= size_of(best);
    // A thing of a known size takes a front only while it still fits one
    // object of its class (a table does not take a 3 m front).
    bool takes = holds_it && FitsFront(s, best, f);
    // A thing lying on the front (three quarters of it) that its class is
    // too small to take is that furniture misnamed (kitchen 5: a counter's
    // front one view called plant, the others wall): it takes a front class
    // that can.
    if (holds_it && !takes && options_.objects_from_fronts &&
        !context_.front_classes.empty() &&
        4 * on_fronts(best) >= 3 * size_of(best) &&
        TakeFrontClass(best, s->members[best], on[f], *named)) {
      std::erase_if(s->may_take, [&](const auto& e) {
        return e.first.first == best && !e.second;
      });
      takes = FitsFront(s, best, f);
    }
    spdlog::debug(
        "furniture front (class {}, {} voxels on it): object {} holds {} of "
        "them ({} on fronts, {} in all){}",
        fronts_[f].class_id, on[f].size(), best, best_held, on_fronts(best),
        size_of(best),
        takes ? ": takes the stranded rest"
              : (holds_it ? ": would outgrow its class" : ""));
    if (!takes) {
      // A front a thing holds a fair part of without taking it (a table
      // standing against it, or too large with it) is not furniture no view
      // named: views named a thing there (Bonn crowd: a wall's band, 14% of
      // it "table", became a 4 m cabinet no view voted for).
      if (best == 0 ||
          static_cast<double>(best_held) <
              options_.min_front_share * static_cast<double>(on[f].size())) {
        unclaimed.push_back(f);
      }
      continue;
    }
    (*named)[owner_class_[best]] += static_cast<float>(on[f].size());
    for (size_t i : on[f]) {
      if (cells_[i].owner == best && IsThingCell(cells_[i])) {
        s->frontier.push_back(i);
      }
    }
  }
  return unclaimed;
}

void MapResolver::ObjectsFromFronts(FrontClaim* s,
                                    const std::vector<size_t>& unclaimed,
                                    const std::map<uint16_t, float>& named) {
  std::set<uint32_t> made;
  for (size_t f : unclaimed) {
    const uint32_t id = NewObjectFromFront(s->fc.on[f], named);
    if (id == 0) continue;
    made.insert(id);
    const size_t start = s->frontier.size();
    for (size_t i : s->fc.on[f]) {
      if (IsStranded(cells_[i])) TakeFrontCell(s, i, id);
    }
    SpreadOverFronts(s, start);
  }
  // Their tops (a worktop every view called wall too: no front holds it),
  // on each front a new object holds, the other leg of an L too.
  for (size_t f : unclaimed) {
    std::map<uint32_t, float> holders;
    for (size_t i : s->fc.on[f]) {
      if (made.count(cells_[i].owner)) holders[cells_[i].owner] += 1.0f;
    }
    const uint32_t id = MostVoted(holders, [](uint32_t) { return true; });
    if (id == 0) continue;
    const size_t start = s->frontier.size();
    for (size_t i = 0; i < cells_.size(); ++i) {
      if (IsStranded(cells_[i]) &&
          OnTopOfFront(cells_[i].p, fronts_[f], context_.up_world,
                       options_.planes)) {
        TakeFrontCell(s, i, id);
      }
    }
    SpreadOverFronts(s, start);
  }
}

bool MapResolver::TakeFrontClass(uint32_t id, const std::vector<size_t>& cells,
                                 const std::vector<size_t>& on_front,
                                 const std::map<uint16_t, float>& named) {
  const uint16_t was = owner_class_[id];
  const uint16_t cls = FrontClassOf(cells, named);
  if (cls == was || !StillFits(cells, cls, StrandedAmong(on_front))) {
    return false;
  }
  spdlog::debug("object {} of class {} lies on a furniture front: class {}", id,
                was, cls);
  owner_class_[id] = cls;
  for (size_t i : cells) {
    // (Not the stranded rest of a front it took: still to be reached.)
    if (cells_[i].owner == id && IsThingCell(cells_[i])) {
      cells_[i].class_id = cls;
    }
  }
  ++result_.reclassed_on_fronts;
  return true;
}

uint16_t MapResolver::FrontClassOf(
    const std::vector<size_t>& cells,
    const std::map<uint16_t, float>& named) const {
  // The front class with the most votes on them, else the one things took
  // the scene's other fronts with, else the label set's first.
  const std::map<uint16_t, double> shares = ThingShares(cells);
  if (const uint16_t c = MostOf(context_.front_classes, shares);
      c != kNoClass) {
    return c;
  }
  const uint16_t c = MostOf(context_.front_classes, named);
  return c != kNoClass ? c : context_.front_classes.front();
}

uint32_t MapResolver::NewObjectFromFront(
    const std::vector<size_t>& on, const std::map<uint16_t, float>& named) {
  const auto stranded = static_cast<size_t>(std::count_if(
      on.begin(), on.end(), [&](size_t i) { return IsStranded(cells_[i]); }));
  // Mostly things, structure on a plane, or reached from an earlier front
  // (the other leg of an L-shaped counter): no new object.
  if (stranded == 0 || 2 * stranded < on.size()) return 0;
  // The front class of the scene's other fronts (a kitchen's counters are
  // counters), else the one with the most votes on it, else the first.
  uint16_t cls = MostOf(context_.front_classes, named);
  if (cls == kNoClass) {
    std::map<uint16_t, float> votes;
    for (uint16_t candidate : context_.front_classes) {
      for (size_t i : on) {
        if (const ClassEvidence* e = cells_[i].evidence->Find(candidate)) {
          votes[candidate] += e->weight;
        }
      }
    }
    cls = MostOf(context_.front_classes, votes);
  }
  if (cls == kNoClass) cls = context_.front_classes.front();
  const uint32_t id = (*next_id_)++;
  owner_class_[id] = cls;
  ++result_.objects_from_fronts;
  spdlog::debug(
      "furniture front no thing holds ({} of its {} voxels stranded): new "
      "object {} of class {}",
      stranded, on.size(), id, cls);
  return id;
}

bool MapResolver::StillFits(const std::vector<size_t>& cells, uint16_t class_id,
                            const std::vector<size_t>& added) const {
  const double slack = options_.size_slack;
  if (MaxFootprint(class_id).x() <= 0.0 || slack <= 0.0) return true;
  const Eigen::Vector2d before = CoreFootprintSize(cells, kSizeTrimShare);
  std::vector<size_t> both = cells;
  both.insert(both.end(), added.begin(), added.end());
  const Eigen::Vector2d after = CoreFootprintSize(both, kSizeTrimShare);
  if (!FitsSize(before, class_id, slack)) {
    // Too large already (FitClassesToSizes found no class that fits): it
    // may fill in its footprint, not grow (Bonn crowd: a 4 m "table" took
    // 10k voxels of the wall's lower bands).
    return (after - before).maxCoeff() <= map_.voxel_size_m() + 1e-6;
  }
  return FitsSize(after, class_id, slack);
}

MapResolver::StrandedContacts MapResolver::ContactsOf(
    const std::vector<size_t>& cells, const std::set<uint32_t>& refused,
    const std::map<uint32_t, size_t>& size) const {
  StrandedContacts c;
  for (size_t k : cells) {
    std::map<uint32_t, float> contacts;
    ForNeighbours(k, [&](size_t n) {
      if (cells_[n].owner != 0 && IsThingCell(cells_[n]) &&
          refused.count(cells_[n].owner) == 0) {
        contacts[cells_[n].owner] += 1.0f;
      }
    });
    for (const auto& [id, n] : contacts) {
      c.largest = std::max(c.largest, size.at(id));
    }
    if (!contacts.empty()) {
      c.touching.push_back(k);
      c.contacts_of[k] = std::move(contacts);
    }
  }
  return c;
}

std::map<uint32_t, std::vector<size_t>> MapResolver::SpreadStranded(
    const StrandedContacts& c) const {
  // Each voxel joins the thing nearest to it (breadth first from the
  // contacts), so a chair's top and the table beside it each take their own
  // part.
  std::vector<size_t> frontier;
  std::map<size_t, uint32_t> owner;
  for (size_t k : c.touching) {
    owner[k] = MostVoted(c.contacts_of.at(k), [](uint32_t) { return true; });
    frontier.push_back(k);
  }
  for (size_t f = 0; f < frontier.size(); ++f) {
    const uint32_t id = owner[frontier[f]];
    ForNeighbours(frontier[f], [&](size_t n) {
      if (IsStranded(cells_[n]) && !owner.count(n)) {
        owner[n] = id;
        frontier.push_back(n);
      }
    });
  }
  std::map<uint32_t, std::vector<size_t>> shares;
  for (const auto& [k, id] : owner) shares[id].push_back(k);
  return shares;
}

void MapResolver::ClaimStranded() {
  const std::map<uint32_t, size_t> size = ThingSizes();
  // Each thing's cells, kept current as it takes stranded voxels (StillFits).
  Members members = ThingMembers();
  auto stranded = [&](size_t n) { return IsStranded(cells_[n]); };
  std::vector<bool> done(cells_.size(), false);
  size_t claimed = 0;
  for (size_t i = 0; i < cells_.size(); ++i) {
    if (done[i] || !stranded(i)) continue;
    std::vector<size_t> left = Component(i, &done, stranded);
    // In rounds: each voxel joins the thing nearest to it; a thing of a known
    // size takes its share only while it still fits one object of its class
    // (a counter every view called wall, stranded beside a plant, is no part
    // of the plant: kitchen 2, a 2.5 m "plant"), and the shares refused go,
    // in the next round, to the other things they touch, those that took a
    // share included (kitchen 2: a counter's top every view called wall,
    // nearest to a table that refused it, went to the counter beside it).
    std::set<uint32_t> refused;
    for (bool first = true; !left.empty(); first = false) {
      const StrandedContacts c = ContactsOf(left, refused, size);
      if (first) {
        spdlog::debug("stranded structure voxels: {} ({} touching things)",
                      left.size(), c.touching.size());
      }
      // Larger than every thing it touches, or touching them only along a
      // small part of it: more likely structure no plane was fitted to (a
      // floor seen twice after drift) than a part of a thing.
      if (c.touching.empty() || left.size() > c.largest ||
          (first && static_cast<double>(c.touching.size()) <
                        options_.min_stranded_contact_share *
                            static_cast<double>(left.size()))) {
        break;
      }
      size_t joined = 0;
      for (const auto& [id, share] : SpreadStranded(c)) {
        if (!StillFits(members[id], owner_class_[id], share)) {
          spdlog::debug(
              "  {} of them left out: object {} would outgrow its class",
              share.size(), id);
          refused.insert(id);
          continue;
        }
        for (size_t k : share) JoinThing(k, id);
        members[id].insert(members[id].end(), share.begin(), share.end());
        joined += share.size();
      }
      claimed += joined;
      if (joined == 0) break;
      std::erase_if(left, [&](size_t k) { return !stranded(k); });
    }
  }
  result_.stranded_voxels_claimed += claimed;
  spdlog::debug("{} stranded structure voxels joined things", claimed);
}

}  // namespace semrec::fuse::internal
