#include "semrec/mesh/object_mesher.h"

#include <gtest/gtest.h>

namespace semrec::mesh {
namespace {

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
  for (const auto& v : meshes.at(10)->vertices_)
    EXPECT_LT(v.x(), 0.02);  // left half: x < 0
  for (const auto& v : meshes.at(20)->vertices_)
    EXPECT_GT(v.x(), -0.02);  // right half
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
