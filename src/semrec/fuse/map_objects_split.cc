// Cuts of the map's objects: by the views' masks and by connectivity (see
// map_resolver.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "semrec/core/union_find.h"
#include "semrec/fuse/map_resolver.h"

namespace semrec::fuse::internal {

void MapResolver::SplitByMasks() {
  for (int round = 0; round < 3; ++round) {
    const Members members = ThingMembers();
    bool split = false;
    for (const auto& [owner, cells] : members) {
      split = SplitObjectByMasks(owner, cells) || split;
    }
    if (!split) break;
  }
}

bool MapResolver::SplitObjectByMasks(uint32_t owner,
                                     const std::vector<size_t>& cells) {
  std::unordered_map<uint64_t, std::vector<size_t>> mask_cells;
  for (size_t k = 0; k < cells.size(); ++k) {
    for (uint64_t m : cells_[cells[k]].evidence->masks) {
      mask_cells[m].push_back(k);
    }
  }
  std::map<size_t, std::vector<std::pair<size_t, uint64_t>>> large;
  for (const auto& [m, ks] : mask_cells) {
    if (ks.size() >= options_.min_piece_voxels) {
      large[MaskFrame(m)].emplace_back(ks.size(), m);
    }
  }
  std::vector<std::pair<size_t, size_t>> candidates;  // (2nd size, frame)
  for (auto& [frame, masks] : large) {
    if (masks.size() < 2) continue;
    std::sort(masks.rbegin(), masks.rend());
    candidates.emplace_back(masks[1].first, frame);
  }
  std::sort(candidates.rbegin(), candidates.rend());
  if (candidates.size() > 3) candidates.resize(3);
  for (const auto& [second, frame] : candidates) {
    const auto pieces = PiecesSeededBy(cells, mask_cells, large[frame]);
    const std::vector<size_t> group = GroupPieces(pieces);
    std::set<size_t> groups(group.begin(), group.end());
    spdlog::debug("object {}: {} cells, frame {} cuts {} pieces, {} groups",
                  owner, cells.size(), frame, pieces.size(), groups.size());
    if (groups.size() < 2) continue;
    // The group with the most cells keeps the id.
    std::map<size_t, size_t> group_cells;
    for (size_t p = 0; p < pieces.size(); ++p) {
      group_cells[group[p]] += pieces[p].size();
    }
    const size_t keep = std::max_element(group_cells.begin(), group_cells.end(),
                                         [](const auto& a, const auto& b) {
                                           return a.second < b.second;
                                         })
                            ->first;
    std::map<size_t, uint32_t> id_of_group{{keep, owner}};
    for (size_t p = 0; p < pieces.size(); ++p) {
      if (!id_of_group.count(group[p])) {
        id_of_group[group[p]] = (*next_id_)++;
        owner_class_[id_of_group[group[p]]] = owner_class_[owner];
        ++result_.split_objects;
      }
      for (size_t i : pieces[p]) cells_[i].owner = id_of_group[group[p]];
    }
    return true;
  }
  return false;
}

std::vector<std::vector<size_t>> MapResolver::PiecesSeededBy(
    const std::vector<size_t>& cells,
    const std::unordered_map<uint64_t, std::vector<size_t>>& mask_cells,
    const std::vector<std::pair<size_t, uint64_t>>& seeds) const {
  constexpr size_t kNone = std::numeric_limits<size_t>::max();
  const size_t n = seeds.size();
  std::vector<size_t> piece_of(cells.size(), kNone);
  for (size_t j = 0; j < n; ++j) {
    for (size_t k : mask_cells.at(seeds[j].second)) piece_of[k] = j;
  }
  // A mask holding a good part of two seeds joins them (the view that saw
  // both as one): it says nothing about where the cells between them go.
  std::vector<size_t> seed_cells(n, 0);
  for (size_t j = 0; j < n; ++j) {
    seed_cells[j] = mask_cells.at(seeds[j].second).size();
  }
  std::unordered_map<uint64_t, size_t> mask_piece;
  for (const auto& [m, ks] : mask_cells) {
    std::vector<size_t> count(n, 0);
    for (size_t k : ks) {
      if (piece_of[k] != kNone) ++count[piece_of[k]];
    }
    size_t held = 0;
    for (size_t j = 0; j < n; ++j) {
      if (static_cast<double>(count[j]) >=
          options_.min_hold_share * static_cast<double>(seed_cells[j])) {
        ++held;
      }
    }
    if (held >= 2) continue;
    // A few voxels in common are a contact (kContactVoxels).
    const auto best = std::max_element(count.begin(), count.end());
    if (*best >= std::min(kContactVoxels, ks.size())) {
      mask_piece[m] = static_cast<size_t>(best - count.begin());
    }
  }
  std::vector<size_t> unplaced;
  for (size_t k = 0; k < cells.size(); ++k) {
    if (piece_of[k] != kNone) continue;
    std::vector<size_t> count(n, 0);
    for (uint64_t m : cells_[cells[k]].evidence->masks) {
      if (const auto it = mask_piece.find(m); it != mask_piece.end()) {
        ++count[it->second];
      }
    }
    const auto best = std::max_element(count.begin(), count.end());
    if (*best > 0) {
      piece_of[k] = static_cast<size_t>(best - count.begin());
    } else {
      unplaced.push_back(k);
    }
  }
  // Unplaced cells (no masks of their own that overlap) spread from placed
  // neighbours, a ring per pass.
  std::unordered_map<size_t, size_t> local;  // cell -> position in `cells`
  if (!unplaced.empty()) {
    for (size_t k = 0; k < cells.size(); ++k) local[cells[k]] = k;
  }
  for (int pass = 0; pass < 8 && !unplaced.empty(); ++pass) {
    std::vector<std::pair<size_t, size_t>> placed;
    std::vector<size_t> left;
    for (size_t k : unplaced) {
      std::vector<size_t> count(n, 0);
      ForNeighbours(cells[k], [&](size_t i) {
        const auto it = local.find(i);
        if (it != local.end() && piece_of[it->second] != kNone) {
          ++count[piece_of[it->second]];
        }
      });
      const auto best = std::max_element(count.begin(), count.end());
      if (*best > 0) {
        placed.emplace_back(k, static_cast<size_t>(best - count.begin()));
      } else {
        left.push_back(k);
      }
    }
    for (const auto& [k, p] : placed) piece_of[k] = p;
    unplaced = std::move(left);
  }
  std::vector<std::vector<size_t>> pieces(n);
  for (size_t k = 0; k < cells.size(); ++k) {
    pieces[piece_of[k] == kNone ? 0 : piece_of[k]].push_back(cells[k]);
  }
  return pieces;
}

std::vector<size_t> MapResolver::GroupPieces(
    const std::vector<std::vector<size_t>>& pieces) const {
  const size_t n = pieces.size();
  std::vector<std::map<size_t, std::set<uint64_t>>> holders;
  for (const auto& piece : pieces) holders.push_back(Holders(piece));
  std::vector<std::vector<bool>> apart(n, std::vector<bool>(n));
  std::vector<std::tuple<size_t, size_t, size_t>> pairs;  // (one, a, b)
  for (size_t a = 0; a < n; ++a) {
    for (size_t b = a + 1; b < n; ++b) {
      const PairViews v = CoViews(holders[a], holders[b]);
      apart[a][b] = apart[b][a] = SaysApart(v);
      if (!apart[a][b]) pairs.emplace_back(v.one, a, b);
    }
  }
  std::stable_sort(pairs.begin(), pairs.end(),
                   [](const auto& x, const auto& y) {
                     return std::get<0>(x) > std::get<0>(y);
                   });
  std::vector<size_t> group(n);
  for (size_t p = 0; p < n; ++p) group[p] = p;
  for (const auto& [one, a, b] : pairs) {
    const size_t ga = group[a], gb = group[b];
    if (ga == gb) continue;
    bool held_apart = false;
    for (size_t x = 0; x < n && !held_apart; ++x) {
      for (size_t y = 0; y < n && !held_apart; ++y) {
        held_apart = group[x] == ga && group[y] == gb && apart[x][y];
      }
    }
    if (held_apart) continue;
    for (size_t& g : group) {
      if (g == gb) g = ga;
    }
  }
  return group;
}

std::map<uint32_t, std::vector<std::vector<size_t>>> MapResolver::ThingPieces()
    const {
  std::vector<bool> done(cells_.size(), false);
  std::map<uint32_t, std::vector<std::vector<size_t>>> pieces;
  for (size_t i = 0; i < cells_.size(); ++i) {
    if (done[i] || cells_[i].owner == 0 || !IsThingCell(cells_[i])) continue;
    const uint32_t owner = cells_[i].owner;
    pieces[owner].push_back(Component(
        i, &done, [&](size_t n) { return cells_[n].owner == owner; }));
  }
  for (auto& [owner, list] : pieces) {
    std::stable_sort(
        list.begin(), list.end(),
        [](const auto& a, const auto& b) { return a.size() > b.size(); });
  }
  return pieces;
}

void MapResolver::SplitDisconnected() {
  std::map<uint32_t, std::vector<std::vector<size_t>>> pieces = ThingPieces();
  for (auto& [owner, list] : pieces) {
    if (list.size() < 2) continue;
    std::vector<std::map<size_t, std::set<uint64_t>>> holders;
    for (const auto& piece : list) holders.push_back(Holders(piece));
    // Pieces a view held in one mask stay one (a table whose middle a chair
    // hides), when together they can be one object of the class: one mask
    // over a row of chairs does not make the row a chair. Specks stay as
    // they were (they do not count in a size, and alone they would be
    // objects of a voxel or two), and so do the pieces of an object too small
    // to stand alone (a fragment, judged as one later).
    const uint16_t cls = owner_class_[owner];
    size_t total = 0;
    for (const auto& piece : list) total += piece.size();
    const bool sized = MaxFootprint(cls).x() > 0.0 &&
                       options_.size_slack > 0.0 &&
                       total >= options_.min_piece_voxels;
    std::vector<std::vector<size_t>> group_cells;  // by root, when sized
    if (sized) group_cells = list;
    const auto speck = [&](const std::vector<size_t>& cells) {
      return static_cast<double>(cells.size()) <
             kSpeckShare * static_cast<double>(total);
    };
    // Groups found too large together stay so as they grow: asked once.
    std::set<std::pair<size_t, size_t>> too_large;
    UnionFind groups(list.size());
    for (size_t a = 0; a < list.size(); ++a) {
      for (size_t b = a + 1; b < list.size(); ++b) {
        const size_t ra = groups.Find(a), rb = groups.Find(b);
        if (ra == rb || too_large.count(std::minmax(ra, rb)) ||
            !SaysOne(CoViews(holders[a], holders[b]), 1)) {
          continue;
        }
        if (sized) {
          if (!speck(group_cells[ra]) && !speck(group_cells[rb]) &&
              !FitsTogether(group_cells[ra], group_cells[rb], cls)) {
            too_large.insert(std::minmax(ra, rb));
            continue;
          }
          const size_t keep = std::min(ra, rb), gone = std::max(ra, rb);
          group_cells[keep].insert(group_cells[keep].end(),
                                   group_cells[gone].begin(),
                                   group_cells[gone].end());
          group_cells[gone].clear();
        }
        groups.Unite(a, b);
      }
    }
    if (spdlog::should_log(spdlog::level::debug)) {
      std::string sizes;
      for (size_t k = 0; k < list.size(); ++k) {
        sizes += fmt::format(" {}:{}", list[k].size(), groups.Find(k));
      }
      spdlog::debug("object {}: disconnected pieces (voxels:group){}", owner,
                    sizes);
    }
    std::map<size_t, uint32_t> group_id{{groups.Find(0), owner}};
    for (size_t k = 1; k < list.size(); ++k) {
      const size_t g = groups.Find(k);
      if (!group_id.count(g)) {
        group_id[g] = 0;
        if (list[k].size() >= options_.min_piece_voxels) {
          group_id[g] = (*next_id_)++;
          owner_class_[group_id[g]] = owner_class_[owner];
          ++result_.split_objects;
        }
      }
      for (size_t i : list[k]) cells_[i].owner = group_id[g];
    }
  }
}

void MapResolver::ReleaseFarSpecks() {
  std::map<uint32_t, std::vector<std::vector<size_t>>> pieces = ThingPieces();
  // First every far speck, judged on the objects as they stand (one leaving
  // its object changes no other's), then where each goes.
  struct Far {
    uint32_t owner;
    std::vector<size_t> cells;
  };
  std::vector<Far> far;
  std::vector<bool> leaving(cells_.size(), false);
  for (auto& [owner, list] : pieces) {
    if (list.size() < 2) continue;
    for (std::vector<size_t>& piece : FarSpecks(owner, list)) {
      for (size_t i : piece) leaving[i] = true;
      far.push_back({owner, std::move(piece)});
    }
  }
  if (far.empty()) return;
  // What each touches (the other leaving specks aside): structure as it
  // stands, or a thing that still fits its class with it.
  Members members = ThingMembers();
  size_t released = 0, dropped = 0;
  for (const Far& f : far) {
    std::map<uint32_t, float> contacts;
    for (size_t i : f.cells) {
      ForNeighbours(i, [&](size_t n) {
        const Cell& c = cells_[n];
        if (c.owner != 0 && c.owner != f.owner && c.class_id != kNoClass &&
            !leaving[n]) {
          contacts[c.owner] += 1.0f;
        }
      });
    }
    uint32_t to = 0;
    float most = 0.0f;
    for (const auto& [id, n] : contacts) {
      const bool thing = !IsStuff(owner_class_[id]);
      if (n > most &&
          (!thing || StillFits(members[id], owner_class_[id], f.cells))) {
        to = id, most = n;
      }
    }
    if (spdlog::should_log(spdlog::level::debug)) {
      spdlog::debug(
          "object {}: a speck of {} voxels {:.2f} m from the rest -> object "
          "{}",
          f.owner, f.cells.size(), SpeckGap(f.cells, pieces[f.owner]), to);
    }
    std::vector<size_t>& from = members[f.owner];
    std::erase_if(from, [&](size_t i) { return leaving[i]; });
    for (size_t i : f.cells) {
      if (to == 0) {
        cells_[i].owner = 0;
      } else {
        JoinThing(i, to);
        if (!IsStuff(owner_class_[to])) members[to].push_back(i);
      }
    }
    ++(to == 0 ? dropped : released);
  }
  result_.far_specks_moved += released + dropped;
  spdlog::debug("far specks: {} joined what they touch, {} dropped", released,
                dropped);
}

std::vector<std::vector<size_t>> MapResolver::FarSpecks(
    uint32_t owner, const std::vector<std::vector<size_t>>& pieces) const {
  size_t total = 0;
  for (const auto& piece : pieces) total += piece.size();
  const auto speck = [&](size_t k) {
    return k > 0 && static_cast<double>(pieces[k].size()) <
                        kSpeckShare * static_cast<double>(total);
  };
  // A class of known size at size_slack 0 is never too large.
  const uint16_t cls = owner_class_.at(owner);
  const bool sized = MaxFootprint(cls).x() > 0.0;
  if (sized && options_.size_slack <= 0.0) return {};
  std::vector<size_t> rest;  // the pieces that are no specks
  for (size_t k = 0; k < pieces.size(); ++k) {
    if (!speck(k)) rest.insert(rest.end(), pieces[k].begin(), pieces[k].end());
  }
  // `rest` bucketed in cubes of the gap: a speck within it of the rest has
  // a rest voxel in one of the 27 cubes around its own.
  const auto gap_m = static_cast<float>(options_.max_speck_gap_m);
  const auto cube = [&](const Eigen::Vector3f& p) {
    return (p / gap_m).array().floor().cast<int>().eval();
  };
  std::unordered_map<uint64_t, std::vector<size_t>> cubes;
  for (size_t i : rest) {
    const Eigen::Vector3i c = cube(cells_[i].p);
    cubes[PackVoxel(c.x(), c.y(), c.z())].push_back(i);
  }
  const auto near_rest = [&](const std::vector<size_t>& piece) {
    for (size_t a : piece) {
      const Eigen::Vector3i c = cube(cells_[a].p);
      for (int dx = -1; dx <= 1; ++dx) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dz = -1; dz <= 1; ++dz) {
            const auto it =
                cubes.find(PackVoxel(c.x() + dx, c.y() + dy, c.z() + dz));
            if (it == cubes.end()) continue;
            for (size_t b : it->second) {
              if ((cells_[a].p - cells_[b].p).squaredNorm() <= gap_m * gap_m) {
                return true;
              }
            }
          }
        }
      }
    }
    return false;
  };
  const Eigen::Vector2d rest_m =
      sized ? FootprintWithSpecks(rest) : Eigen::Vector2d::Zero();
  std::vector<std::vector<size_t>> far;
  for (size_t k = 1; k < pieces.size(); ++k) {
    if (!speck(k) || near_rest(pieces[k])) continue;
    if (sized) {
      // A chair's legs, cut off from its seat where the depth missed them,
      // lie within a chair's footprint: a speck stays unless the object is
      // too large with it and it is what makes it larger (by more than a
      // voxel: an object already too large keeps the specks within it).
      std::vector<size_t> with = rest;
      with.insert(with.end(), pieces[k].begin(), pieces[k].end());
      const Eigen::Vector2d with_m = FootprintWithSpecks(with);
      if (FitsSize(with_m, cls, options_.size_slack) ||
          (with_m - rest_m).maxCoeff() <= map_.voxel_size_m()) {
        continue;
      }
    }
    far.push_back(pieces[k]);
  }
  return far;
}

float MapResolver::SpeckGap(
    const std::vector<size_t>& speck,
    const std::vector<std::vector<size_t>>& pieces) const {
  float gap2 = std::numeric_limits<float>::max();
  for (const auto& piece : pieces) {
    if (piece.size() <= speck.size()) continue;
    for (size_t a : speck) {
      for (size_t b : piece) {
        gap2 = std::min(gap2, (cells_[a].p - cells_[b].p).squaredNorm());
      }
    }
  }
  return std::sqrt(gap2);
}

}  // namespace semrec::fuse::internal
