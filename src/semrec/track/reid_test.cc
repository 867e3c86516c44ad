#include "semrec/track/reid.h"

#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/SVD>

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"
#include "semrec/track/tracker.h"

namespace semrec::track {
namespace {

// Samples mean + 3 u a + 1 v b + 0.01 noise in 6-D, a, b standard normal.
std::vector<std::vector<float>> Samples(int n, const Eigen::VectorXd& mean,
                                        const Eigen::VectorXd& u,
                                        const Eigen::VectorXd& v) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  std::vector<std::vector<float>> out;
  for (int i = 0; i < n; ++i) {
    Eigen::VectorXd x = mean + 3.0 * normal(rng) * u + 1.0 * normal(rng) * v;
    std::vector<float> s(x.size());
    for (int k = 0; k < x.size(); ++k)
      s[k] = static_cast<float>(x(k) + 0.01 * normal(rng));
    out.push_back(s);
  }
  return out;
}

TEST(Pca, MatchesSvdOfTheCentredData) {
  Eigen::VectorXd mean(6), u(6), v(6);
  mean << 1, 2, 3, 4, 5, 6;
  u << 1, 1, 0, 0, 0, 0;
  v << 0, 0, 1, -1, 1, 0;
  u.normalize();
  v.normalize();
  const auto samples = Samples(500, mean, u, v);
  const PcaProjection pca = PcaProjection::Fit(samples, 2, /*whiten=*/false);
  EXPECT_EQ(pca.input_dims(), 6);
  EXPECT_EQ(pca.output_dims(), 2);
  EXPECT_GT(pca.explained_variance(), 0.999);

  // Independent reference: SVD of the centred data matrix.
  Eigen::MatrixXd x(samples.size(), 6);
  for (size_t i = 0; i < samples.size(); ++i) {
    for (int k = 0; k < 6; ++k) x(i, k) = samples[i][k];
  }
  const Eigen::VectorXd m = x.colwise().mean().transpose();
  x.rowwise() -= m.transpose();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(x, Eigen::ComputeThinV);
  for (int k = 0; k < 2; ++k) {
    const Eigen::VectorXd ref = svd.matrixV().col(k);
    // Project a unit step along the reference component from the mean.
    std::vector<float> probe(6);
    for (int i = 0; i < 6; ++i) probe[i] = static_cast<float>(m(i) + ref(i));
    const Eigen::VectorXd p = pca.Project(probe);
    EXPECT_NEAR(std::abs(p(k)), 1.0, 1e-4) << "component " << k;
    EXPECT_NEAR(p(1 - k), 0.0, 1e-4) << "component " << k;
  }
  // The first component is the 3-sigma direction u (sign free).
  std::vector<float> along_u(6);
  for (int i = 0; i < 6; ++i) along_u[i] = static_cast<float>(m(i) + u(i));
  EXPECT_NEAR(std::abs(pca.Project(along_u)(0)), 1.0, 1e-3);
}

TEST(Pca, WhitenedCoordinatesHaveUnitSpread) {
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(6), u(6), v(6);
  u << 0, 0, 0, 0, 1, 0;
  v << 1, 0, 0, 0, 0, 0;
  const auto samples = Samples(2000, mean, u, v);
  const PcaProjection pca = PcaProjection::Fit(samples, 2, /*whiten=*/true);
  Eigen::Vector2d sum = Eigen::Vector2d::Zero(), sq = Eigen::Vector2d::Zero();
  for (const auto& s : samples) {
    const Eigen::VectorXd p = pca.Project(s);
    sum += p;
    sq += p.cwiseProduct(p);
  }
  const double n = static_cast<double>(samples.size());
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(sum(k) / n, 0.0, 1e-9);
    EXPECT_NEAR(std::sqrt(sq(k) / (n - 1)), 1.0, 1e-6);
  }
}

TEST(Pca, SaveLoadRoundTripAndBadFiles) {
  const testing::TempDir dir;
  Eigen::VectorXd mean = Eigen::VectorXd::Ones(6), u(6), v(6);
  u << 0, 1, 0, 0, 0, 0;
  v << 0, 0, 0, 1, 0, 0;
  const auto samples = Samples(50, mean, u, v);
  const PcaProjection pca = PcaProjection::Fit(samples, 3);
  pca.Save((dir / "pca.json").string());
  const PcaProjection back = PcaProjection::Load((dir / "pca.json").string());
  EXPECT_EQ(back.output_dims(), 3);
  EXPECT_LT((back.Project(samples[3]) - pca.Project(samples[3])).norm(), 1e-9);

  EXPECT_THROW(PcaProjection::Load((dir / "missing.json").string()), IoError);
  std::ofstream(dir / "bad.json")
      << "{\"mean\": [1, 2], \"components\": [[1]]}";
  EXPECT_THROW(PcaProjection::Load((dir / "bad.json").string()), FormatError);
  std::ofstream(dir / "junk.json") << "not json";
  EXPECT_THROW(PcaProjection::Load((dir / "junk.json").string()), FormatError);
  EXPECT_THROW(back.Project({1.0f, 2.0f}), InvalidArgument);
  EXPECT_THROW(PcaProjection::Fit({samples[0]}, 1), InvalidArgument);
  EXPECT_THROW(PcaProjection::Fit(samples, 7), InvalidArgument);
  EXPECT_TRUE(PcaProjection().identity());
}

TEST(ReidMemory, AssignsOneToOneUnderTau) {
  ReidOptions options;
  options.tau = 0.5;
  ReidMemory memory(options, PcaProjection());
  memory.Remember(1, {0, 0});
  memory.Remember(2, {1, 0});
  memory.Remember(3, {0, 1});
  // Two queries near track 2: only the closer one takes it; the other is
  // within tau of nothing else.
  const std::vector<int> ids =
      memory.Match({{0.9f, 0.05f}, {1.2f, 0.0f}, {0.05f, 0.95f}, {5, 5}});
  EXPECT_EQ(ids, (std::vector<int>{2, -1, 3, -1}));
  EXPECT_EQ(memory.size(), 1u);  // matched tracks leave the memory
  EXPECT_EQ(memory.Match({{0.2f, 0.1f}}), std::vector<int>{1});
  EXPECT_EQ(memory.Match({{0.0f, 0.0f}}), std::vector<int>{-1});
}

TEST(ReidMemory, GlobalAssignmentBeatsGreedy) {
  ReidOptions options;
  options.tau = 2.0;
  ReidMemory memory(options, PcaProjection());
  memory.Remember(1, {0.0f});
  memory.Remember(2, {1.0f});
  // Greedy (closest pair first) gives query 0 track 2 (0.4) and query 1
  // track 1 (1.5), total 1.9; the optimum pairs 0->1, 1->2 (0.6 + 0.5).
  EXPECT_EQ(memory.Match({{0.6f}, {1.5f}}), (std::vector<int>{1, 2}));
}

TEST(ReidMemory, ForgetsTheOldestAndSupportsCosine) {
  ReidOptions options;
  options.memory_size = 2;
  options.metric = ReidOptions::Metric::kCosine;
  options.tau = 0.05;
  ReidMemory memory(options, PcaProjection());
  memory.Remember(1, {1, 0});
  memory.Remember(2, {0, 1});
  memory.Remember(3, {1, 1});
  EXPECT_EQ(memory.size(), 2u);
  // Cosine ignores scale: (10, 0) is track 1's direction, but 1 is forgotten.
  EXPECT_EQ(memory.Match({{10, 0}, {0, 3}, {2, 2}}),
            (std::vector<int>{-1, 2, 3}));
  options.memory_size = 0;
  EXPECT_THROW(ReidMemory(options, PcaProjection()), InvalidArgument);
}

Detection Person(double x, std::vector<float> embedding) {
  Detection d;
  d.box = {x, 100, 50, 150};
  d.embedding = std::move(embedding);
  return d;
}

// Person A walks right, leaves for 5 frames, re-enters far away; B enters
// while A is away. Returns the ids given to A's re-entry and to B.
std::pair<int, int> Walk(bool reid) {
  TrackerOptions options = TrackerOptions::Paper();
  options.reid.enabled = reid;
  options.reid.tau = 0.5;
  Tracker tracker(options);
  const std::vector<float> a = {1, 0, 0}, b = {0, 1, 0};
  int a_id = 0;
  for (int f = 0; f < 5; ++f) {
    a_id = tracker.Update({Person(10.0 + 5 * f, a)}).at(0).track_id;
  }
  for (int f = 0; f < 5; ++f) EXPECT_TRUE(tracker.Update({}).empty());
  const int b_id = tracker.Update({Person(300, b)}).at(0).track_id;
  const auto out =
      tracker.Update({Person(300, b), Person(500, {0.9f, 0.1f, 0})});
  EXPECT_EQ(out.at(0).track_id, b_id);
  EXPECT_EQ(out.at(1).reidentified, reid && out.at(1).track_id == a_id);
  return {out.at(1).track_id == a_id ? 1 : 0, b_id == a_id ? 1 : 0};
}

TEST(TrackerReid, ReappearingPersonGetsTheOldId) {
  EXPECT_EQ(Walk(true), std::make_pair(1, 0));
  EXPECT_EQ(Walk(false), std::make_pair(0, 0));
}

TEST(TrackerReid, DetectionsWithoutEmbeddingNeverReidentify) {
  TrackerOptions options = TrackerOptions::Paper();
  Tracker tracker(options);
  const int id = tracker.Update({Person(10, {})}).at(0).track_id;
  tracker.Update({});
  EXPECT_NE(tracker.Update({Person(10, {})}).at(0).track_id, id);
}

}  // namespace
}  // namespace semrec::track
