#include "semrec/mesh/object_mesher.h"

#include <gtest/gtest.h>

#include "semrec/core/random.h"

namespace semrec::mesh {
namespace {

// The erosion against its definition, pixel by pixel, on random label maps
// (sizes down to smaller than the neighbourhood).
TEST(InteriorMask, MatchesTheDefinition) {
  Rng rng(4);
  for (int trial = 0; trial < 300; ++trial) {
    const int w = static_cast<int>(rng.UniformInt(1, 24)),
              h = static_cast<int>(rng.UniformInt(1, 24));
    const int num_labels = static_cast<int>(rng.UniformInt(1, 3));
    LabelMap labels(w, h);
    for (auto& v : labels.values()) {
      v = static_cast<uint16_t>(rng.UniformInt(0, num_labels - 1));
    }
    for (int r = 0; r <= 3; ++r) {
      const std::vector<uint8_t> got = InteriorMask(labels, r);
      ASSERT_EQ(got.size(), labels.NumPixels());
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          bool interior = true;
          for (int dy = -r; dy <= r; ++dy) {
            for (int dx = -r; dx <= r; ++dx) {
              const int u = x + dx, v = y + dy;
              interior = interior && u >= 0 && u < w && v >= 0 && v < h &&
                         labels(u, v) == labels(x, y);
            }
          }
          ASSERT_EQ(got[static_cast<size_t>(y) * w + x], interior ? 1 : 0)
              << w << "x" << h << " r " << r << " at " << x << "," << y;
        }
      }
    }
  }
}

// Two walls side by side in one frame, labelled 1 and 2: each object's mesh
// covers only its own half, and only changed objects are re-meshed.
TEST(ObjectMesher, MasksAndRemeshesOnlyChangedObjects) {
  Frame frame;
  frame.intrinsics = {64, 48, 50.0, 50.0, 31.5, 23.5};
  frame.color = ColorImage(64, 48, 3, 100);
  frame.depth = DepthImage(64, 48, 1, 1.0f);
  LabelMap labels(64, 48);
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) labels(u, v) = u < 32 ? 1 : 2;
  }
  ObjectMeshingOptions options;
  ObjectMesher mesher(options);
  mesher.Integrate(frame, labels, {{1, 10}, {2, 20}});
  auto meshes = mesher.UpdateMeshes();
  ASSERT_EQ(meshes.size(), 2u);
  EXPECT_EQ(mesher.remeshed_last_update(), 2u);
  for (const auto& v : meshes.at(10)->vertices_) {
    EXPECT_LT(v.x(), 0.02);  // left half: x < 0
  }
  for (const auto& v : meshes.at(20)->vertices_) {
    EXPECT_GT(v.x(), -0.02);  // right half
  }
  EXPECT_FALSE(meshes.at(10)->vertex_normals_.empty());
  // Only object 20 sees new data: only it is re-meshed.
  mesher.Integrate(frame, labels, {{2, 20}});
  meshes = mesher.UpdateMeshes();
  EXPECT_EQ(mesher.remeshed_last_update(), 1u);
  EXPECT_EQ(meshes.size(), 2u);
  mesher.UpdateMeshes();
  EXPECT_EQ(mesher.remeshed_last_update(), 0u);
}

// A thin stray label inside another object (4 px) is eroded away entirely with
// a 2-px erosion.
TEST(ObjectMesher, ErosionDropsThinMaskFringes) {
  Frame frame;
  frame.intrinsics = {64, 48, 50.0, 50.0, 31.5, 23.5};
  frame.color = ColorImage(64, 48, 3, 100);
  frame.depth = DepthImage(64, 48, 1, 1.0f);
  LabelMap labels(64, 48, 1, 1);
  for (int v = 0; v < 48; ++v) {
    for (int u = 40; u < 44; ++u) labels(u, v) = 2;
  }
  ObjectMeshingOptions erode2;
  erode2.mask_erosion_px = 2;
  ObjectMesher eroded(erode2);
  eroded.Integrate(frame, labels, {{1, 1}, {2, 2}});
  const auto meshes = eroded.UpdateMeshes();
  EXPECT_TRUE(meshes.count(2) == 0 || meshes.at(2)->vertices_.empty());
  ObjectMeshingOptions no_erosion;
  no_erosion.mask_erosion_px = 0;
  ObjectMesher raw(no_erosion);
  raw.Integrate(frame, labels, {{2, 2}});
  EXPECT_FALSE(raw.UpdateMeshes().at(2)->vertices_.empty());
}

}  // namespace
}  // namespace semrec::mesh
