#include "semrec/usd/glb_writer.h"

#include <cstring>

#include <gtest/gtest.h>
#include <tiny_gltf.h>
#include <Eigen/Geometry>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/testing/test_util.h"
#include "semrec/usd/usd_test_util.h"

namespace semrec::usd {
namespace {

MeshPrim Box(const std::string& label, uint32_t id, bool structure,
             bool colors) {
  MeshPrim m;
  m.label = label;
  m.instance_id = id;
  m.structure = structure;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 1.5f}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  if (colors) {
    m.vertex_colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {51, 102, 153}};
  }
  m.color = {10, 20, 30};
  m.point_count = 77;
  return m;
}

using test_scenes::Walker;

tinygltf::Model Load(const std::string& bytes) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  const bool ok = loader.LoadBinaryFromMemory(
      &model, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
      static_cast<unsigned>(bytes.size()));
  EXPECT_TRUE(ok) << err;
  EXPECT_TRUE(err.empty()) << err;
  return model;
}

const tinygltf::Node* Named(const tinygltf::Model& model,
                            const std::string& name) {
  for (const auto& n : model.nodes) {
    if (n.name == name) return &n;
  }
  return nullptr;
}

// The float values of an accessor (tightly packed, as we write them).
std::vector<float> Floats(const tinygltf::Model& model, int accessor) {
  const auto& a = model.accessors.at(accessor);
  const auto& view = model.bufferViews.at(a.bufferView);
  const auto& data = model.buffers.at(view.buffer).data;
  const size_t n = a.count * tinygltf::GetNumComponentsInType(a.type);
  std::vector<float> out(n);
  std::memcpy(out.data(), data.data() + view.byteOffset + a.byteOffset,
              n * sizeof(float));
  return out;
}

TEST(Glb, ObjectsAreNamedNodesWithClassesColoursAndYUp) {
  StageOptions options;  // Z-up, metres
  const auto model = Load(GlbBytes(
      {Box("chair", 3, false, true), Box("dining table", 4, false, false),
       Box("floor", 1, true, true)},
      options));
  ASSERT_EQ(model.scenes.size(), 1u);
  const auto* chair = Named(model, "chair_3");
  const auto* table = Named(model, "dining_table_4");
  const auto* floor = Named(model, "floor");
  ASSERT_TRUE(chair && table && floor);
  EXPECT_EQ(chair->extras.Get("semrec_class").Get<std::string>(), "chair");
  EXPECT_EQ(chair->extras.Get("semrec_instance_id").Get<int>(), 3);
  EXPECT_EQ(chair->extras.Get("semrec_kind").Get<std::string>(), "thing");
  EXPECT_EQ(table->extras.Get("semrec_class").Get<std::string>(),
            "dining table");
  EXPECT_EQ(floor->extras.Get("semrec_kind").Get<std::string>(), "structure");

  const auto& prim = model.meshes.at(chair->mesh).primitives.at(0);
  EXPECT_EQ(prim.mode, TINYGLTF_MODE_TRIANGLES);
  EXPECT_EQ(model.accessors.at(prim.indices).count, 12u);
  const auto positions = Floats(model, prim.attributes.at("POSITION"));
  ASSERT_EQ(positions.size(), 12u);
  EXPECT_FLOAT_EQ(positions[7], 2.0f);  // vertex 2, y
  EXPECT_EQ(model.accessors.at(prim.attributes.at("POSITION")).maxValues,
            (std::vector<double>{1.0, 2.0, 1.5}));
  const auto colors = Floats(model, prim.attributes.at("COLOR_0"));
  EXPECT_FLOAT_EQ(colors[9], 0.2f);   // 51/255
  EXPECT_FLOAT_EQ(colors[11], 0.6f);  // 153/255
  // Without vertex colours the material carries the constant colour.
  const auto& table_prim = model.meshes.at(table->mesh).primitives.at(0);
  EXPECT_EQ(table_prim.attributes.count("COLOR_0"), 0u);
  EXPECT_NEAR(model.materials.at(table_prim.material)
                  .pbrMetallicRoughness.baseColorFactor[1],
              20.0 / 255.0, 1e-9);

  // The root turns Z-up into glTF's Y-up: world up (0, 0, 1) becomes (0, 1, 0).
  const auto* world = Named(model, "World");
  ASSERT_TRUE(world);
  ASSERT_EQ(world->rotation.size(), 4u);
  const Eigen::Quaterniond q(world->rotation[3], world->rotation[0],
                             world->rotation[1], world->rotation[2]);
  EXPECT_TRUE(
      (q * Eigen::Vector3d(0, 0, 1)).isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));
  EXPECT_TRUE((q * Eigen::Vector3d(0, 1, 0))
                  .isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
  EXPECT_TRUE(model.animations.empty());

  StageOptions y_up;
  y_up.up_axis = "Y";
  const auto y_model = Load(GlbBytes({Box("chair", 3, false, true)}, y_up));
  EXPECT_TRUE(Named(y_model, "World")->rotation.empty());
}

TEST(Glb, PeopleFollowTheirCentroidAndVanishOutOfView) {
  StageOptions options;
  options.time_codes_per_second = 10.0;
  options.start_time_code = 0;
  options.end_time_code = 6;
  const auto model = Load(GlbBytes({Box("chair", 3, false, true)}, options,
                                   {Walker(7, {0, 1, 2, 5})}));
  const auto* person = Named(model, "person_7");
  ASSERT_TRUE(person);
  EXPECT_EQ(person->extras.Get("semrec_kind").Get<std::string>(), "person");
  EXPECT_EQ(model.meshes.at(person->mesh).primitives.at(0).mode,
            TINYGLTF_MODE_POINTS);
  ASSERT_EQ(model.animations.size(), 1u);
  const auto& anim = model.animations[0];
  ASSERT_EQ(anim.channels.size(), 2u);
  std::vector<float> times, translation, scale;
  for (const auto& channel : anim.channels) {
    const auto& sampler = anim.samplers.at(channel.sampler);
    EXPECT_EQ(sampler.interpolation, "STEP");
    times = Floats(model, sampler.input);
    (channel.target_path == "scale" ? scale : translation) =
        Floats(model, sampler.output);
  }
  ASSERT_EQ(times.size(), 7u);  // frames 0..6
  EXPECT_FLOAT_EQ(times[5], 0.5f);
  // Seen at 0, 1, 2, 5: scale 1 there, 0 at 3, 4, 6; position held while out of
  // view.
  const std::vector<float> visible = {1, 1, 1, 0, 0, 1, 0};
  for (size_t f = 0; f < 7; ++f) {
    EXPECT_EQ(scale[3 * f], visible[f]) << "frame " << f;
  }
  // Frame 3 holds frame 2's x = 0.5 * 2.
  EXPECT_FLOAT_EQ(translation[size_t{3} * 3], 1.0f);
  EXPECT_FLOAT_EQ(translation[size_t{3} * 5], 2.5f);
}

TEST(Glb, BadInputIsRefusedAndTheFileWrittenAtomically) {
  MeshPrim broken = Box("chair", 3, false, true);
  broken.triangles.push_back({0, 1, 9});
  EXPECT_THROW(GlbBytes({broken}, StageOptions{}), InvalidArgument);
  MeshPrim colours = Box("chair", 3, false, true);
  colours.vertex_colors.pop_back();
  EXPECT_THROW(GlbBytes({colours}, StageOptions{}), InvalidArgument);
  StageOptions bad_axis;
  bad_axis.up_axis = "X";
  EXPECT_THROW(GlbBytes({Box("chair", 3, false, true)}, bad_axis),
               InvalidArgument);

  testing::TempDir dir;
  const auto path = dir.path() / "scene.glb";
  WriteSceneGlb(path, {Box("chair", 3, false, true)}, StageOptions{});
  const auto bytes = ReadFileBytes(path);
  ASSERT_GT(bytes.size(), 12u);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + 4), "glTF");
  EXPECT_THROW(WriteSceneGlb(path / "sub.glb", {Box("chair", 3, false, true)},
                             StageOptions{}),
               IoError);
}

}  // namespace
}  // namespace semrec::usd
