#include "semrec/io/tf_tree.h"

#include <algorithm>

#include <fmt/format.h>

namespace semrec::io {

void TfTree::Add(const RosTransform& t, bool is_static) {
  if (t.child_frame_id.empty() || t.header.frame_id.empty() ||
      t.child_frame_id == t.header.frame_id) {
    ++conflicts_;
    return;
  }
  auto [it, fresh] = edges_.try_emplace(t.child_frame_id);
  Edge& e = it->second;
  if (fresh) {
    e.parent = t.header.frame_id;
    e.is_static = is_static;
  } else if (e.parent != t.header.frame_id) {
    ++conflicts_;
    return;
  }
  if (e.is_static) {
    // The latest static transform holds.
    e.samples.assign(1, {0, t.T_parent_child});
    return;
  }
  const int64_t stamp = t.header.StampNs();
  if (!e.samples.empty() && stamp < e.samples.back().first) e.sorted = false;
  e.samples.emplace_back(stamp, t.T_parent_child);
}

bool TfTree::Has(const std::string& frame) const {
  if (edges_.count(frame)) return true;
  for (const auto& [child, e] : edges_) {
    if (e.parent == frame) return true;
  }
  return false;
}

std::set<std::string> TfTree::Frames() const {
  std::set<std::string> out;
  for (const auto& [child, e] : edges_) {
    out.insert(child);
    out.insert(e.parent);
  }
  return out;
}

std::set<std::string> TfTree::Roots() const {
  std::set<std::string> out;
  for (const auto& [child, e] : edges_) {
    if (!edges_.count(e.parent)) out.insert(e.parent);
  }
  return out;
}

std::vector<std::string> TfTree::Ancestors(const std::string& frame) const {
  std::vector<std::string> out = {frame};
  std::set<std::string> seen = {frame};
  for (auto it = edges_.find(frame); it != edges_.end();
       it = edges_.find(it->second.parent)) {
    if (!seen.insert(it->second.parent).second) break;  // a loop
    out.push_back(it->second.parent);
  }
  return out;
}

std::vector<std::string> TfTree::Chain(const std::string& target,
                                       const std::string& source) const {
  const auto up_source = Ancestors(source);
  const auto up_target = Ancestors(target);
  for (size_t i = 0; i < up_source.size(); ++i) {
    const auto hit =
        std::find(up_target.begin(), up_target.end(), up_source[i]);
    if (hit == up_target.end()) continue;
    // target ... common ... source
    std::vector<std::string> chain(up_target.begin(), hit + 1);
    for (size_t j = i; j-- > 0;) chain.push_back(up_source[j]);
    return chain;
  }
  return {};
}

std::optional<Transform> TfTree::EdgeAt(const std::string& child, const Edge& e,
                                        int64_t t_ns, std::string* why) const {
  if (e.samples.empty()) return std::nullopt;
  if (e.is_static) return e.samples.front().second;
  if (!e.sorted) {
    std::stable_sort(
        e.samples.begin(), e.samples.end(),
        [](const auto& a, const auto& b) { return a.first < b.first; });
    e.sorted = true;
  }
  const auto& s = e.samples;
  if (t_ns < s.front().first - tolerance_ns_ ||
      t_ns > s.back().first + tolerance_ns_) {
    if (why != nullptr) {
      *why = fmt::format(
          "{} -> {} has no sample at {:.3f} s (samples from {:.3f} to {:.3f} "
          "s; no extrapolation)",
          e.parent, child, 1e-9 * t_ns, 1e-9 * s.front().first,
          1e-9 * s.back().first);
    }
    return std::nullopt;
  }
  const auto after = std::lower_bound(
      s.begin(), s.end(), t_ns,
      [](const auto& sample, int64_t t) { return sample.first < t; });
  if (after == s.begin()) return s.front().second;
  if (after == s.end()) return s.back().second;
  const auto before = after - 1;
  const double span = static_cast<double>(after->first - before->first);
  const double a = span > 0 ? (t_ns - before->first) / span : 0.0;
  const Eigen::Quaterniond q =
      before->second.Quaternion().slerp(a, after->second.Quaternion());
  const Eigen::Vector3d t = (1.0 - a) * before->second.translation() +
                            a * after->second.translation();
  return Transform::FromQuaternion(q, t);
}

std::optional<Transform> TfTree::Lookup(const std::string& target,
                                        const std::string& source, int64_t t_ns,
                                        std::string* why) const {
  if (target == source) return Transform();
  const std::vector<std::string> chain = Chain(target, source);
  if (chain.empty()) {
    if (why != nullptr) {
      *why = fmt::format("no TF path from '{}' to '{}'{}", target, source,
                         Has(source) ? ""
                                     : " ('" + source +
                                           "' is in no "
                                           "transform)");
    }
    return std::nullopt;
  }
  Transform T_target_source;
  for (size_t i = 0; i + 1 < chain.size(); ++i) {
    const std::string &a = chain[i], &b = chain[i + 1];
    // Down the tree (a is b's parent) or up (b is a's parent).
    const auto down = edges_.find(b);
    if (down != edges_.end() && down->second.parent == a) {
      const auto T = EdgeAt(b, down->second, t_ns, why);
      if (!T) return std::nullopt;
      T_target_source = T_target_source * *T;
    } else {
      const auto T = EdgeAt(a, edges_.at(a), t_ns, why);
      if (!T) return std::nullopt;
      T_target_source = T_target_source * T->Inverse();
    }
  }
  return T_target_source;
}

}  // namespace semrec::io
