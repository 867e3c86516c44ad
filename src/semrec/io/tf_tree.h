// A ROS TF tree from recorded /tf and /tf_static messages: each frame has
// one parent; static edges hold at every time, dynamic edges are sampled and
// interpolated (slerp for the rotation, lerp for the translation) at the time
// asked for. Like tf2, a lookup does not extrapolate beyond the samples
// (except by a small tolerance for stamps that jitter at the ends).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "semrec/core/transform.h"
#include "semrec/io/ros_messages.h"

namespace semrec::io {

class TfTree {
 public:
  /// Samples within this much outside an edge's first/last stamp are
  /// clamped to it.
  explicit TfTree(int64_t tolerance_ns = 50'000'000)
      : tolerance_ns_(tolerance_ns) {}

  /// Adds one edge sample (T_parent_child at its stamp). A frame that is
  /// given a second parent keeps the first (counted in conflicts()).
  void Add(const RosTransform& t, bool is_static);

  /// T_target_source at `t_ns`: the pose of `source` in `target`. nullopt
  /// with `why` set when the frames are not connected or an edge has no
  /// sample near `t_ns`.
  std::optional<Transform> Lookup(const std::string& target,
                                  const std::string& source, int64_t t_ns,
                                  std::string* why = nullptr) const;

  /// The frames from `target` down to `source` (target first), empty when
  /// they are not connected.
  std::vector<std::string> Chain(const std::string& target,
                                 const std::string& source) const;

  bool Has(const std::string& frame) const;
  std::set<std::string> Frames() const;
  /// Frames without a parent.
  std::set<std::string> Roots() const;
  size_t conflicts() const { return conflicts_; }

 private:
  struct Edge {
    std::string parent;
    bool is_static = false;
    // Sorted by stamp on first lookup.
    mutable std::vector<std::pair<int64_t, Transform>> samples;
    mutable bool sorted = true;
  };
  // T_parent_child of `child`'s edge at t_ns.
  std::optional<Transform> EdgeAt(const std::string& child, const Edge& edge,
                                  int64_t t_ns, std::string* why) const;
  // `frame` and its ancestors, frame first.
  std::vector<std::string> Ancestors(const std::string& frame) const;

  int64_t tolerance_ns_;
  std::map<std::string, Edge> edges_;  // by child frame
  size_t conflicts_ = 0;
};

}  // namespace semrec::io
