#include "semrec/track/reid.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/track/hungarian.h"

namespace semrec::track {

PcaProjection PcaProjection::Fit(const std::vector<std::vector<float>>& samples,
                                 int dims, bool whiten) {
  CheckArgument(samples.size() >= 2, "PCA: need at least 2 embeddings, got " +
                                         std::to_string(samples.size()));
  const size_t d = samples[0].size();
  CheckArgument(d >= 1, "PCA: embeddings are empty");
  CheckArgument(dims >= 1 && static_cast<size_t>(dims) <= d,
                "PCA: dims must be in 1.." + std::to_string(d));
  Eigen::MatrixXd x(samples.size(), d);
  for (size_t i = 0; i < samples.size(); ++i) {
    CheckArgument(samples[i].size() == d,
                  "PCA: embeddings have different lengths (" +
                      std::to_string(samples[i].size()) + " vs " +
                      std::to_string(d) + ")");
    for (size_t j = 0; j < d; ++j) x(i, j) = samples[i][j];
  }
  PcaProjection pca;
  pca.mean_ = x.colwise().mean().transpose();
  x.rowwise() -= pca.mean_.transpose();
  const Eigen::MatrixXd cov =
      x.transpose() * x / static_cast<double>(samples.size() - 1);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(cov);
  // Eigenvalues ascending: the last `dims` are the principal components.
  const Eigen::VectorXd values = solver.eigenvalues().cwiseMax(0.0);
  pca.components_.resize(dims, d);
  double kept = 0.0;
  for (int k = 0; k < dims; ++k) {
    const int col = static_cast<int>(d) - 1 - k;
    Eigen::VectorXd v = solver.eigenvectors().col(col);
    // Deterministic sign: the largest-magnitude entry is positive.
    Eigen::Index arg;
    v.cwiseAbs().maxCoeff(&arg);
    if (v(arg) < 0) v = -v;
    double scale = 1.0;
    if (whiten) {
      // A component without spread cannot be whitened; leave it unscaled.
      scale = values(col) > 1e-12 ? 1.0 / std::sqrt(values(col)) : 1.0;
    }
    pca.components_.row(k) = scale * v.transpose();
    kept += values(col);
  }
  const double total = values.sum();
  pca.explained_ = total > 0.0 ? kept / total : 1.0;
  return pca;
}

PcaProjection PcaProjection::Load(const std::string& path) {
  const std::string text = ReadTextFile(path);
  PcaProjection pca;
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    const auto mean = j.at("mean").get<std::vector<double>>();
    const auto rows =
        j.at("components").get<std::vector<std::vector<double>>>();
    if (mean.empty() || rows.empty()) {
      throw FormatError(path, "PCA file has no mean or no components");
    }
    pca.mean_ = Eigen::Map<const Eigen::VectorXd>(mean.data(), mean.size());
    pca.components_.resize(rows.size(), mean.size());
    for (size_t r = 0; r < rows.size(); ++r) {
      if (rows[r].size() != mean.size()) {
        throw FormatError(path, "PCA component " + std::to_string(r) + " has " +
                                    std::to_string(rows[r].size()) +
                                    " values, the mean has " +
                                    std::to_string(mean.size()));
      }
      for (size_t c = 0; c < mean.size(); ++c) {
        pca.components_(r, c) = rows[r][c];
      }
    }
    pca.explained_ = j.value("explained_variance", 1.0);
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(path, std::string("not a PCA file: ") + e.what());
  }
  if (!pca.mean_.allFinite() || !pca.components_.allFinite()) {
    throw FormatError(path, "PCA file holds non-finite numbers");
  }
  return pca;
}

void PcaProjection::Save(const std::string& path) const {
  CheckArgument(!identity(), "PCA: nothing to save (identity projection)");
  nlohmann::json j;
  j["input_dims"] = input_dims();
  j["output_dims"] = output_dims();
  j["explained_variance"] = explained_;
  j["mean"] = std::vector<double>(mean_.data(), mean_.data() + mean_.size());
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < components_.rows(); ++r) {
    std::vector<double> row(components_.cols());
    for (int c = 0; c < components_.cols(); ++c) row[c] = components_(r, c);
    rows.push_back(row);
  }
  j["components"] = rows;
  WriteTextFileAtomic(path, j.dump(1) + "\n");
}

Eigen::VectorXd PcaProjection::Project(
    const std::vector<float>& embedding) const {
  Eigen::VectorXd x(embedding.size());
  for (size_t i = 0; i < embedding.size(); ++i) x(i) = embedding[i];
  if (identity()) return x;
  CheckArgument(x.size() == mean_.size(),
                "PCA: embedding has " + std::to_string(x.size()) +
                    " values, the projection was fitted on " +
                    std::to_string(mean_.size()));
  return components_ * (x - mean_);
}

void ReidOptions::Check() const {
  CheckArgument(memory_size >= 1, "re-id: memory_size must be >= 1");
  CheckArgument(tau > 0.0, "re-id: tau must be > 0");
  CheckArgument(embedding_update > 0.0 && embedding_update <= 1.0,
                "re-id: embedding_update must be in (0, 1]");
}

ReidMemory::ReidMemory(const ReidOptions& options, PcaProjection pca)
    : options_(options), pca_(std::move(pca)) {
  options_.Check();
}

void ReidMemory::Remember(int track_id, const std::vector<float>& embedding) {
  if (embedding.empty()) return;
  Forget(track_id);
  entries_.push_back({track_id, pca_.Project(embedding)});
  while (entries_.size() > static_cast<size_t>(options_.memory_size)) {
    entries_.pop_front();
  }
}

void ReidMemory::Forget(int track_id) {
  entries_.erase(
      std::remove_if(entries_.begin(), entries_.end(),
                     [&](const Entry& e) { return e.track_id == track_id; }),
      entries_.end());
}

double ReidMemory::Distance(const Eigen::VectorXd& a,
                            const Eigen::VectorXd& b) const {
  if (options_.metric == ReidOptions::Metric::kEuclidean) return (a - b).norm();
  const double na = a.norm(), nb = b.norm();
  if (na == 0.0 || nb == 0.0) return 1.0;
  return 1.0 - a.dot(b) / (na * nb);
}

std::vector<int> ReidMemory::Match(
    const std::vector<std::vector<float>>& queries) {
  std::vector<int> out(queries.size(), -1);
  if (entries_.empty() || queries.empty()) return out;
  Eigen::MatrixXd cost(queries.size(), entries_.size());
  for (size_t q = 0; q < queries.size(); ++q) {
    if (queries[q].empty()) {
      cost.row(q).setConstant(kForbidden);
      continue;
    }
    const Eigen::VectorXd p = pca_.Project(queries[q]);
    for (size_t e = 0; e < entries_.size(); ++e) {
      const double dist = Distance(p, entries_[e].projected);
      cost(q, e) = dist < options_.tau ? dist : kForbidden;
    }
  }
  std::vector<int> matched_ids;
  for (const auto& [q, e] : SolveAssignment(cost).pairs) {
    out[q] = entries_[e].track_id;
    matched_ids.push_back(entries_[e].track_id);
  }
  for (int id : matched_ids) Forget(id);
  return out;
}

}  // namespace semrec::track
