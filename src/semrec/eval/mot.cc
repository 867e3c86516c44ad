#include "semrec/eval/mot.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <Eigen/Core>

#include "semrec/core/error.h"
#include "semrec/track/hungarian.h"
#include "semrec/track/tracker.h"

namespace semrec::eval {
namespace {

// Boxes of one frame, with ids mapped to dense indices.
struct FrameBoxes {
  std::vector<const io::MotBox*> gt, predicted;
  std::vector<int> gt_index, predicted_index;
};

Eigen::MatrixXd IouMatrix(const FrameBoxes& f) {
  Eigen::MatrixXd iou(f.gt.size(), f.predicted.size());
  for (size_t i = 0; i < f.gt.size(); ++i) {
    for (size_t j = 0; j < f.predicted.size(); ++j) {
      iou(i, j) = BoxIou(*f.gt[i], *f.predicted[j]);
    }
  }
  return iou;
}

// Every box indexed by frame, its track id mapped to a dense index.
struct IndexedBoxes {
  std::map<int, FrameBoxes> frames;
  int gt_ids = 0, predicted_ids = 0;
};

IndexedBoxes IndexBoxes(const std::vector<io::MotBox>& gt,
                        const std::vector<io::MotBox>& predicted) {
  IndexedBoxes out;
  std::map<int, int> gt_ids, pred_ids;  // id -> dense index
  for (const auto& b : gt) {
    const int idx =
        gt_ids.try_emplace(b.id, static_cast<int>(gt_ids.size())).first->second;
    out.frames[b.frame].gt.push_back(&b);
    out.frames[b.frame].gt_index.push_back(idx);
  }
  for (const auto& b : predicted) {
    const int idx =
        pred_ids.try_emplace(b.id, static_cast<int>(pred_ids.size()))
            .first->second;
    out.frames[b.frame].predicted.push_back(&b);
    out.frames[b.frame].predicted_index.push_back(idx);
  }
  out.gt_ids = static_cast<int>(gt_ids.size());
  out.predicted_ids = static_cast<int>(pred_ids.size());
  return out;
}

// What CLEAR MOT's matching leaves per ground-truth track, for the track
// coverage and identity metrics.
struct ClearMotState {
  std::vector<int> last_match;  // gt -> predicted id index last matched to
  std::vector<int> frames_present, frames_tracked;
  std::vector<std::vector<char>> tracked_history;  // per present frame
  Eigen::MatrixXi overlap_count;  // gt x predicted frames at IoU >= threshold
  double distance_sum = 0.0;

  ClearMotState(int G, int P)
      : last_match(G, -1),
        frames_present(G, 0),
        frames_tracked(G, 0),
        tracked_history(G),
        overlap_count(Eigen::MatrixXi::Zero(G, P)) {}
};

// One frame's matches: last frame's that still hold, then Hungarian on the
// rest (cost 1 - IoU, pairs below the IoU threshold forbidden). Returns the
// predicted box of each gt box (-1: none); counts identity switches into m.
std::vector<int> MatchFrame(const FrameBoxes& f, const Eigen::MatrixXd& iou,
                            double iou_threshold, const ClearMotState& state,
                            MotMetrics* m) {
  const size_t ng = f.gt.size(), np = f.predicted.size();
  std::vector<int> match_of_gt(ng, -1);
  std::vector<char> pred_taken(np, 0);
  for (size_t i = 0; i < ng; ++i) {
    const int previous = state.last_match[f.gt_index[i]];
    if (previous < 0) continue;
    for (size_t j = 0; j < np; ++j) {
      if (!pred_taken[j] && f.predicted_index[j] == previous &&
          iou(i, j) >= iou_threshold) {
        match_of_gt[i] = static_cast<int>(j);
        pred_taken[j] = 1;
        break;
      }
    }
  }
  std::vector<int> free_gt, free_pred;
  for (size_t i = 0; i < ng; ++i) {
    if (match_of_gt[i] < 0) free_gt.push_back(static_cast<int>(i));
  }
  for (size_t j = 0; j < np; ++j) {
    if (!pred_taken[j]) free_pred.push_back(static_cast<int>(j));
  }
  Eigen::MatrixXd cost(free_gt.size(), free_pred.size());
  for (size_t a = 0; a < free_gt.size(); ++a) {
    for (size_t b = 0; b < free_pred.size(); ++b) {
      const double v = iou(free_gt[a], free_pred[b]);
      cost(a, b) = v >= iou_threshold ? 1.0 - v : track::kForbidden;
    }
  }
  for (const auto& [a, b] : track::SolveAssignment(cost).pairs) {
    const int i = free_gt[a], j = free_pred[b];
    match_of_gt[i] = j;
    const int g = f.gt_index[i];
    if (state.last_match[g] >= 0 &&
        state.last_match[g] != f.predicted_index[j]) {
      ++m->id_switches;
    }
  }
  return match_of_gt;
}

void ClearMot(const IndexedBoxes& boxes, double iou_threshold,
              ClearMotState* state, MotMetrics* m) {
  for (const auto& [frame, f] : boxes.frames) {
    const Eigen::MatrixXd iou = IouMatrix(f);
    const size_t ng = f.gt.size(), np = f.predicted.size();
    const std::vector<int> match_of_gt =
        MatchFrame(f, iou, iou_threshold, *state, m);
    size_t matched = 0;
    for (size_t i = 0; i < ng; ++i) {
      const int g = f.gt_index[i];
      ++state->frames_present[g];
      const int j = match_of_gt[i];
      state->tracked_history[g].push_back(j >= 0);
      if (j < 0) continue;
      ++matched;
      ++state->frames_tracked[g];
      state->last_match[g] = f.predicted_index[j];
      state->distance_sum += 1.0 - iou(i, j);
    }
    m->true_positives += matched;
    m->false_negatives += ng - matched;
    m->false_positives += np - matched;
    for (size_t i = 0; i < ng; ++i) {
      for (size_t j = 0; j < np; ++j) {
        if (iou(i, j) >= iou_threshold) {
          ++state->overlap_count(f.gt_index[i], f.predicted_index[j]);
        }
      }
    }
  }
}

// Fragmentations (within each gt track's tracked span, transitions from
// tracked to missed) and mostly tracked / partially tracked / mostly lost.
void TrackCoverage(const ClearMotState& state, MotMetrics* m) {
  const int G = static_cast<int>(state.frames_present.size());
  for (int g = 0; g < G; ++g) {
    const auto& h = state.tracked_history[g];
    const auto first = std::find(h.begin(), h.end(), 1);
    if (first == h.end()) continue;
    const auto last = std::find(h.rbegin(), h.rend(), 1).base();
    for (auto it = first + 1; it != last; ++it) {
      m->fragmentations += (!*it && *(it - 1)) ? 1 : 0;
    }
    const double ratio =
        static_cast<double>(state.frames_tracked[g]) / state.frames_present[g];
    if (ratio >= 0.8) {
      ++m->mostly_tracked;
    } else if (ratio >= 0.2) {
      ++m->partially_tracked;
    }
  }
  for (int g = 0; g < G; ++g) {
    const double ratio = state.frames_present[g]
                             ? static_cast<double>(state.frames_tracked[g]) /
                                   state.frames_present[g]
                             : 0;
    if (ratio < 0.2) ++m->mostly_lost;
  }
}

// Identity metrics: one-to-one gt/predicted trajectory matching maximising
// co-tracked frames.
void IdentityMetrics(const Eigen::MatrixXi& overlap_count, MotMetrics* m) {
  if (overlap_count.rows() > 0 && overlap_count.cols() > 0) {
    const Eigen::MatrixXd cost = -overlap_count.cast<double>();
    for (const auto& [g, p] : track::SolveAssignment(cost).pairs) {
      m->idtp += overlap_count(g, p);
    }
  }
  m->idp = m->predicted_boxes
               ? static_cast<double>(m->idtp) / m->predicted_boxes
               : 0.0;
  m->idr = m->gt_boxes ? static_cast<double>(m->idtp) / m->gt_boxes : 0.0;
  m->idf1 = m->gt_boxes + m->predicted_boxes
                ? 2.0 * m->idtp /
                      static_cast<double>(m->gt_boxes + m->predicted_boxes)
                : 0.0;
}

constexpr double kEps = std::numeric_limits<double>::epsilon();

// HOTA's global alignment score of each gt/predicted track pair.
Eigen::MatrixXd HotaAlignment(const IndexedBoxes& boxes,
                              const std::vector<Eigen::MatrixXd>& ious,
                              Eigen::VectorXd* gt_count,
                              Eigen::VectorXd* pred_count) {
  const int G = boxes.gt_ids, P = boxes.predicted_ids;
  Eigen::MatrixXd potential = Eigen::MatrixXd::Zero(G, P);
  *gt_count = Eigen::VectorXd::Zero(G);
  *pred_count = Eigen::VectorXd::Zero(P);
  size_t k = 0;
  for (const auto& [frame, f] : boxes.frames) {
    const Eigen::MatrixXd& s = ious[k++];
    const Eigen::RowVectorXd col_sum = s.colwise().sum();
    const Eigen::VectorXd row_sum = s.rowwise().sum();
    for (int i = 0; i < s.rows(); ++i) {
      for (int j = 0; j < s.cols(); ++j) {
        const double denom = row_sum(i) + col_sum(j) - s(i, j);
        if (denom > kEps) {
          potential(f.gt_index[i], f.predicted_index[j]) += s(i, j) / denom;
        }
      }
    }
    for (int g : f.gt_index) (*gt_count)(g) += 1;
    for (int p : f.predicted_index) (*pred_count)(p) += 1;
  }
  Eigen::MatrixXd global(G, P);
  for (int g = 0; g < G; ++g) {
    for (int p = 0; p < P; ++p) {
      global(g, p) =
          potential(g, p) / ((*gt_count)(g) + (*pred_count)(p)-potential(g, p));
    }
  }
  return global;
}

// HOTA, DetA and AssA averaged over 19 localisation thresholds (TrackEval's
// algorithm).
void Hota(const IndexedBoxes& boxes, MotMetrics* m) {
  const int G = boxes.gt_ids, P = boxes.predicted_ids;
  std::vector<Eigen::MatrixXd> ious;
  for (const auto& [frame, f] : boxes.frames) ious.push_back(IouMatrix(f));
  Eigen::VectorXd gt_count, pred_count;
  const Eigen::MatrixXd global =
      HotaAlignment(boxes, ious, &gt_count, &pred_count);
  constexpr int kAlphas = 19;
  std::vector<Eigen::MatrixXd> matches(kAlphas, Eigen::MatrixXd::Zero(G, P));
  std::vector<double> tp(kAlphas, 0), fn(kAlphas, 0), fp(kAlphas, 0);
  size_t k = 0;
  for (const auto& [frame, f] : boxes.frames) {
    const Eigen::MatrixXd& s = ious[k++];
    const size_t ng = f.gt.size(), np = f.predicted.size();
    if (ng == 0 || np == 0) {
      for (int a = 0; a < kAlphas; ++a) fn[a] += ng, fp[a] += np;
      continue;
    }
    Eigen::MatrixXd score(ng, np);
    for (size_t i = 0; i < ng; ++i) {
      for (size_t j = 0; j < np; ++j) {
        score(i, j) = -global(f.gt_index[i], f.predicted_index[j]) * s(i, j);
      }
    }
    const auto pairs = track::SolveAssignment(score).pairs;
    for (int a = 0; a < kAlphas; ++a) {
      const double alpha = 0.05 * (a + 1);
      size_t n = 0;
      for (const auto& [i, j] : pairs) {
        if (s(i, j) < alpha - kEps) continue;
        ++n;
        matches[a](f.gt_index[i], f.predicted_index[j]) += 1;
      }
      tp[a] += n, fn[a] += ng - n, fp[a] += np - n;
    }
  }
  for (int a = 0; a < kAlphas; ++a) {
    double ass = 0.0;
    for (int g = 0; g < G; ++g) {
      for (int p = 0; p < P; ++p) {
        const double c = matches[a](g, p);
        if (c > 0) {
          ass += c * c / std::max(1.0, gt_count(g) + pred_count(p) - c);
        }
      }
    }
    const double assa = ass / std::max(1.0, tp[a]);
    const double deta = tp[a] / std::max(1.0, tp[a] + fn[a] + fp[a]);
    m->assa += assa / kAlphas;
    m->deta += deta / kAlphas;
    m->hota += std::sqrt(deta * assa) / kAlphas;
  }
}

}  // namespace

double BoxIou(const io::MotBox& a, const io::MotBox& b) {
  return track::Iou({a.left, a.top, a.width, a.height},
                    {b.left, b.top, b.width, b.height});
}

MotMetrics EvaluateMot(const std::vector<io::MotBox>& gt,
                       const std::vector<io::MotBox>& predicted,
                       double iou_threshold) {
  CheckArgument(iou_threshold > 0.0 && iou_threshold <= 1.0,
                "MOT evaluation: IoU threshold must be in (0, 1]");
  const IndexedBoxes boxes = IndexBoxes(gt, predicted);
  MotMetrics m;
  m.frames = boxes.frames.empty()
                 ? 0
                 : static_cast<size_t>(boxes.frames.rbegin()->first);
  m.gt_boxes = gt.size();
  m.predicted_boxes = predicted.size();
  m.gt_ids = boxes.gt_ids;
  m.predicted_ids = boxes.predicted_ids;

  ClearMotState state(boxes.gt_ids, boxes.predicted_ids);
  ClearMot(boxes, iou_threshold, &state, &m);
  TrackCoverage(state, &m);
  const double n_gt = static_cast<double>(m.gt_boxes);
  m.mota =
      n_gt > 0
          ? 1.0 - (m.false_negatives + m.false_positives + m.id_switches) / n_gt
          : 0.0;
  m.motp = m.true_positives > 0 ? state.distance_sum / m.true_positives : 0.0;
  m.recall = n_gt > 0 ? m.true_positives / n_gt : 0.0;
  m.precision = m.true_positives + m.false_positives > 0
                    ? static_cast<double>(m.true_positives) /
                          (m.true_positives + m.false_positives)
                    : 0.0;
  IdentityMetrics(state.overlap_count, &m);
  Hota(boxes, &m);
  return m;
}

}  // namespace semrec::eval
