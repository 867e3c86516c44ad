#include "semrec/pipeline/reconstruct.h"

#include <algorithm>
#include <map>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/synth/generator.h"
#include "semrec/synth/scene.h"
#include "semrec/testing/small_scene.h"
#include "semrec/testing/test_util.h"
#include "semrec/usd/usda_reader.h"

namespace fs = std::filesystem;

namespace semrec::pipeline {
namespace {

// SmallScene without sensor noise.
synth::SynthOptions SmallNoiselessScene(const std::string& preset, int frames) {
  synth::SynthOptions o = testing::SmallScene(preset, frames);
  o.noise.enabled = false;
  return o;
}

// Synthetic six-objects scene -> one USD Mesh prim per object with the right
// class, valid for the independent parser; meshes lie on the ground-truth
// surfaces.
TEST(Reconstruct, SixObjectsBecomeSixLabelledMeshPrims) {
  testing::TempDir dir;
  const synth::SynthOptions o = SmallNoiselessScene("six-objects", 12);
  synth::WriteSyntheticSequence(o, dir / "seq", testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  const auto source = fuse::SegmentationSource::Create("gt", reader);
  const ReconstructResult r =
      Reconstruct(reader, *source, {}, dir / "out", testing::QuietProgress());
  EXPECT_EQ(r.frames, 12u);
  const auto summary =
      nlohmann::json::parse(ReadTextFile(dir / "out/summary.json"));
  std::map<std::string, int> per_class;
  for (const auto& object : summary["objects"])
    ++per_class[object["class"].get<std::string>()];
  for (const char* cls :
       {"table", "chair", "sofa", "shelf", "cabinet", "plant"}) {
    EXPECT_EQ(per_class[cls], 1) << cls;
  }
  EXPECT_TRUE(fs::is_regular_file(dir / "out/scene.usda"));
  // Refuses to overwrite.
  EXPECT_THROW(
      Reconstruct(reader, *source, {}, dir / "out", testing::QuietProgress()),
      IoError);
  const auto report = testing::ValidateUsd(dir / "out/static.usda", dir.path());
  if (!report) SEMREC_SKIP("tinyusdz (npm) or node missing: run scripts/setup");
  ASSERT_TRUE((*report)["ok"].get<bool>()) << (*report)["error"];
  EXPECT_EQ((*report)["meshes"].size(), r.scene.objects);
  const std::string layer = (*report)["layer"];
  EXPECT_NE(layer.find("semantics:labels:class = [\"chair\"]"),
            std::string::npos);
}

// The room's shell (stuff classes) becomes one structure prim per class; an
// upright synthetic world is kept exactly; asked for Y up, the floor ends at
// y = 0 with the furniture above it.
TEST(Reconstruct, StructureIsOnePrimPerClassAndTheSceneIsUpright) {
  testing::TempDir dir;
  const synth::SynthOptions o = SmallNoiselessScene("six-objects", 8);
  synth::WriteSyntheticSequence(o, dir / "seq", testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  const auto source = fuse::SegmentationSource::Create("gt", reader);
  const ReconstructResult r =
      Reconstruct(reader, *source, {}, dir / "z", testing::QuietProgress());
  EXPECT_EQ(r.scene.gravity.method, "already upright");
  EXPECT_EQ(r.scene.gravity.T_upright_world.Matrix(),
            Eigen::Matrix4d::Identity());
  const auto summary =
      nlohmann::json::parse(ReadTextFile(dir / "z/summary.json"));
  EXPECT_EQ(summary["gravity"]["method"], "already upright");
  std::map<std::string, int> structure;
  for (const auto& object : summary["objects"]) {
    if (object["kind"] == "structure") ++structure[object["class"]];
  }
  EXPECT_EQ(structure["wall"], 1);
  EXPECT_EQ(structure["floor"], 1);
  EXPECT_EQ(r.scene.structure, structure.size());
  const std::string layer = ReadTextFile(dir / "z/static.usda");
  EXPECT_NE(layer.find("def Scope \"Structure\""), std::string::npos);
  EXPECT_NE(layer.find("def Mesh \"wall\""), std::string::npos);
  EXPECT_NE(layer.find("customLayerData"), std::string::npos);
  for (const usd::MeshPrim& m : usd::ReadScene(dir / "z/scene.usda")) {
    EXPECT_EQ(m.structure, structure.count(m.label) != 0) << m.label;
  }

  ReconstructOptions y_up;
  y_up.scene.stage.up_axis = "Y";
  Reconstruct(reader, *source, y_up, dir / "y", testing::QuietProgress());
  bool saw_floor = false, saw_table = false;
  for (const usd::MeshPrim& m : usd::ReadScene(dir / "y/scene.usda")) {
    float top = -1e9f;
    for (const auto& p : m.points) top = std::max(top, p.y());
    if (m.label == "floor") {
      saw_floor = true;
      for (const auto& p : m.points) ASSERT_NEAR(p.y(), 0.0f, 0.05f);
    }
    if (m.label == "table") {
      saw_table = true;
      EXPECT_GT(top, 0.5f);
    }
  }
  EXPECT_TRUE(saw_floor && saw_table);
}

// Synthetic people: each person id becomes a time-sampled prim whose
// translation follows the ground-truth walking position, and the stage plays
// at the sequence's frame rate.
TEST(Reconstruct, PeopleBecomeTimeSampledPrimsOnTheirGroundTruthPaths) {
  testing::TempDir dir;
  const synth::SynthOptions o = SmallNoiselessScene("people", 40);
  synth::WriteSyntheticSequence(o, dir / "seq", testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  const auto source = fuse::SegmentationSource::Create("gt", reader);
  ReconstructOptions options;
  options.people = "gt";
  options.usdz = true;
  const ReconstructResult r = Reconstruct(reader, *source, options, dir / "out",
                                          testing::QuietProgress());
  ASSERT_GE(r.scene.people, 2u);

  // Positions: the centroid of the visible points is within a body's width of
  // the person's floor position (partly visible people pull it sideways).
  const synth::Scene scene = synth::GenerateScene(o.scene);
  People3d people;
  PersonMapSource maps("gt", reader);
  for (size_t i = 0; i < reader.size(); ++i) {
    if (const auto ids = maps.Get(i)) people.Add(reader.Read(i), *ids);
  }
  const auto tracks = people.Tracks();
  ASSERT_EQ(tracks.size(), r.scene.people);
  std::vector<double> errors;
  for (const auto& track : tracks) {
    const synth::Person* truth = nullptr;
    for (const auto& p : scene.people)
      if (p.person_id == track.track_id) truth = &p;
    ASSERT_NE(truth, nullptr) << track.track_id;
    for (const auto& sample : track.samples) {
      const Eigen::Vector2d at =
          synth::PoseAt(*truth, static_cast<double>(sample.frame) / o.fps)
              .position;
      errors.push_back(
          (sample.centroid_world.head<2>().cast<double>() - at).norm());
      EXPECT_GT(sample.centroid_world.z(), 0.2);
      EXPECT_LT(sample.centroid_world.z(), truth->height_m);
    }
  }
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.12) << "median floor error (m)";
  EXPECT_LT(errors.back(), 0.4) << "worst floor error (m)";

  const std::string text = ReadTextFile(dir / "out/dynamic.usda");
  EXPECT_NE(text.find(fmt::format("timeCodesPerSecond = {}", o.fps)),
            std::string::npos);
  EXPECT_NE(text.find("endTimeCode = 39"), std::string::npos);
  // A people folder that does not exist is an error naming it.
  ReconstructOptions no_people = options;
  no_people.people = (dir / "nopeople").string();
  no_people.overwrite = true;
  EXPECT_THROW(Reconstruct(reader, *source, no_people, dir / "out2",
                           testing::QuietProgress()),
               IoError);

  const auto report = testing::ValidateUsd(dir / "out/scene.usda", dir.path());
  if (!report) SEMREC_SKIP("tinyusdz (npm) or node missing: run scripts/setup");
  ASSERT_TRUE((*report)["ok"].get<bool>()) << (*report)["error"];
  const auto dynamic =
      testing::ValidateUsd(dir / "out/dynamic.usda", dir.path());
  ASSERT_TRUE((*dynamic)["ok"].get<bool>()) << (*dynamic)["error"];
  const auto package = testing::ValidateUsd(dir / "out/scene.usdz", dir.path());
  ASSERT_TRUE((*package)["ok"].get<bool>()) << (*package)["error"];
  EXPECT_EQ((*package)["meshes"].size(), r.scene.objects);
  const std::string layer = (*dynamic)["layer"];
  for (const auto& track : tracks) {
    EXPECT_NE(layer.find("person_" + std::to_string(track.track_id)),
              std::string::npos);
  }
}

}  // namespace
}  // namespace semrec::pipeline

namespace semrec::pipeline {
namespace {

// Real Redwood frames with one label: the object mesh matches a whole-scene
// Open3D volume of the same voxel size (vertex count within 5%).
TEST(Reconstruct, RedwoodSingleLabelMatchesWholeSceneVolume) {
  SEMREC_REQUIRE_SAMPLE_DATA(data, "redwood_livingroom1_5");
  testing::TempDir dir;
  const io::SequenceReader reader = io::SequenceReader::Open(data);
  const auto source = fuse::SegmentationSource::Create("single:scene", reader);
  ReconstructOptions options;
  const ReconstructResult r = Reconstruct(reader, *source, options, dir / "out",
                                          testing::QuietProgress());
  ASSERT_EQ(r.scene.objects, 1u);
  mesh::TsdfIntegrator whole(options.scene.meshing.tsdf);
  for (size_t i = 0; i < reader.size(); ++i) whole.Integrate(reader.Read(i));
  const size_t reference = whole.ExtractMesh()->vertices_.size();
  const auto summary =
      nlohmann::json::parse(ReadTextFile(dir / "out/summary.json"));
  const double vertices = summary["objects"][0]["vertices"].get<double>();
  EXPECT_NEAR(vertices / reference, 1.0, 0.05)
      << vertices << " vs " << reference;
}

}  // namespace
}  // namespace semrec::pipeline
