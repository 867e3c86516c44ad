// Running a tracker over a whole detection sequence, and the offline steps
// that need the finished tracks: boxes of tracks that were tentative when
// seen but confirmed later, gaps filled by interpolation, short tracks
// dropped. These trade latency (a track's boxes are final only when it ends or
// is confirmed) for fewer misses and false positives: a MOTChallenge result
// file is written after the sequence anyway.
#pragma once

#include <functional>
#include <map>
#include <vector>

#include "semrec/io/mot_io.h"
#include "semrec/track/tracker.h"

namespace semrec::track {

/// One tracked box in one frame.
struct TrackPoint {
  int frame = 0;
  TrackedBox box;
  /// Filled in by interpolation, not observed.
  bool interpolated = false;
};

struct OfflineOptions {
  /// Report the early, tentative boxes of tracks that reached min_hits later
  /// (tracks that never did are still dropped).
  bool backfill_tentative = false;
  /// Fill a track's gaps of up to this many frames by linear interpolation
  /// between the reported boxes on either side (0 = off); not across a
  /// re-identification.
  int max_gap_frames = 0;
  /// Tracks observed in fewer frames are dropped (1 = keep all).
  int min_track_frames = 1;

  void Check() const;
  /// All off: the online tracker's confirmed boxes as they are.
  bool Off() const;
  /// The improved configuration's offline steps: tentative boxes reported,
  /// gaps up to 10 frames (the improved tracker's max_lost_frames) filled,
  /// tracks seen in fewer than 3 frames dropped. On TUD-Campus MOTA 0.605 ->
  /// 0.674; gap filling alone gives 0.660 (docs/results.md, bench_track).
  static OfflineOptions Improved();
};

/// MOTChallenge boxes (det.txt) as detections per frame; confidence -> score.
std::map<int, std::vector<Detection>> DetectionsByFrame(
    const std::vector<io::MotBox>& boxes);

/// Tracked boxes as MOTChallenge result lines.
std::vector<io::MotBox> ToMotBoxes(const std::vector<TrackPoint>& points);

/// Runs `tracker` over frames 1..last_frame (frames missing from `by_frame`
/// have no detections) and returns every box it reported, tentative ones
/// included, in frame order. `tick` is called once per frame (progress).
std::vector<TrackPoint> TrackSequence(
    Tracker* tracker, const std::map<int, std::vector<Detection>>& by_frame,
    int last_frame, const std::function<void()>& tick = {});

/// The result boxes: confirmed ones, plus what `options` adds or removes;
/// sorted by frame, then track id.
std::vector<TrackPoint> FinishTracks(const std::vector<TrackPoint>& points,
                                     const OfflineOptions& options);

}  // namespace semrec::track
