// Re-identification of people who leave the view and come back (the paper's
// Section II-B, part ii): appearance embeddings of lost tracks are kept in a
// finite memory; a new, unmatched detection takes the id of the closest
// remembered track when the distance between their PCA-projected embeddings is
// below tau, else it starts a new track.
#pragma once

#include <deque>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace semrec::track {

/// Linear projection of embeddings onto their first principal components,
/// fitted on a calibration sequence and stored in a JSON file. A default-
/// constructed projection is the identity (the embedding is used as is).
class PcaProjection {
 public:
  PcaProjection() = default;

  /// Fits `dims` components to `samples` (all of one length, at least 2
  /// samples). With `whiten` each component is divided by its standard
  /// deviation, so distances are in units of the calibration spread and one
  /// tau suits embeddings of any scale. Throws InvalidArgument on bad input.
  static PcaProjection Fit(const std::vector<std::vector<float>>& samples,
                           int dims, bool whiten = true);

  /// Reads / writes {"input_dims", "mean", "components", "scale"} (atomic
  /// write). Load throws IoError / FormatError naming the file.
  static PcaProjection Load(const std::string& path);
  void Save(const std::string& path) const;

  bool identity() const { return components_.size() == 0; }
  int input_dims() const { return static_cast<int>(mean_.size()); }
  int output_dims() const { return static_cast<int>(components_.rows()); }
  /// Fraction of the calibration variance the kept components explain.
  double explained_variance() const { return explained_; }

  /// Projects one embedding. Throws InvalidArgument when its length does not
  /// match the fitted input.
  Eigen::VectorXd Project(const std::vector<float>& embedding) const;

 private:
  Eigen::VectorXd mean_;
  Eigen::MatrixXd components_;  // dims x input, rows already scaled
  double explained_ = 1.0;
};

struct ReidOptions {
  enum class Metric { kEuclidean, kCosine };
  /// Off reproduces pure geometric tracking (every re-appearance is a new id).
  bool enabled = true;
  /// Lost tracks remembered; the oldest is forgotten first.
  int memory_size = 16;
  /// Distance below which a detection is the remembered person. Euclidean on
  /// whitened 3-D PCA coordinates: 1.0 = one calibration standard deviation
  /// (see bench_track for how it separates people on the synthetic sequence).
  /// For cosine: 1 - cos.
  double tau = 1.0;
  Metric metric = Metric::kEuclidean;
  /// Weight of the newest observation in a track's running embedding (1 =
  /// last observation only).
  double embedding_update = 0.3;
  void Check() const;
};

/// Embeddings of lost tracks and the assignment of new detections to them.
class ReidMemory {
 public:
  ReidMemory(const ReidOptions& options, PcaProjection pca);

  /// Remembers (or refreshes) a lost track's embedding; forgets the oldest
  /// entry beyond memory_size. Empty embeddings are ignored.
  void Remember(int track_id, const std::vector<float>& embedding);
  void Forget(int track_id);

  /// One-to-one assignment of `queries` to remembered tracks minimising the
  /// total distance, pairs with distance >= tau excluded: the track id per
  /// query, or -1. Matched tracks leave the memory. Empty queries get -1.
  std::vector<int> Match(const std::vector<std::vector<float>>& queries);

  double Distance(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const;
  const PcaProjection& pca() const { return pca_; }
  size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    int track_id;
    Eigen::VectorXd projected;
  };
  ReidOptions options_;
  PcaProjection pca_;
  std::deque<Entry> entries_;  // oldest first
};

}  // namespace semrec::track
