#include "semrec/synth/generator.h"

#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/transform.h"
#include "semrec/io/image_io.h"
#include "semrec/io/ply_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/synth/render.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::synth {
namespace {

ProgressOptions Quiet() {
  ProgressOptions p;
  p.mode = ProgressOptions::Mode::kOff;
  return p;
}

SynthOptions Small(const std::string& preset, int frames) {
  SynthOptions o = SynthOptions::Preset(preset);
  o.frames = frames;
  o.width = 160;
  o.height = 120;
  o.fx = o.fy = 131.25;
  o.gt_object_spacing_m = 0.02;
  o.gt_structure_spacing_m = 0.1;
  return o;
}

// Office tables each carry at most one monitor (all of them once stood on the
// first table, inside each other: no view could tell them apart).
TEST(Synth, OfficeMonitorsStandOnTablesOfTheirOwn) {
  for (const uint64_t seed : {1u, 2u, 3u}) {
    SynthOptions o = SynthOptions::Preset("office");
    o.scene.seed = seed;
    const Scene scene = GenerateScene(o.scene);
    std::vector<Eigen::AlignedBox3d> monitors;
    for (const SceneObject& object : scene.objects) {
      if (object.name.rfind("monitor", 0) == 0) {
        monitors.push_back(object.Bounds());
      }
    }
    ASSERT_EQ(monitors.size(), 3u);
    for (size_t i = 0; i < monitors.size(); ++i) {
      for (size_t j = i + 1; j < monitors.size(); ++j) {
        EXPECT_FALSE(monitors[i].intersects(monitors[j]))
            << "seed " << seed << ": monitors " << i << " and " << j;
      }
    }
  }
}

// The flat: interior walls are drawn (structure, not room faces), furniture
// never stands in them or in a doorway, and a camera in a doorway sees the
// wall beside the door and the next room through it.
TEST(Synth, FlatHasInteriorWallsWithFreeDoorways) {
  for (const uint64_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    SynthOptions o = SynthOptions::Preset("flat");
    o.scene.seed = seed;
    const Scene scene = GenerateScene(o.scene);
    std::vector<const SceneObject*> walls;
    for (const SceneObject& s : scene.objects) {
      if (s.structure && !s.room_face) walls.push_back(&s);
    }
    ASSERT_EQ(walls.size(), o.scene.partitions_x_m.size());
    const double d = o.scene.room_depth_m, door = o.scene.door_width_m;
    for (const SceneObject& s : scene.objects) {
      if (s.structure) continue;
      const Eigen::AlignedBox3d b = s.Bounds();
      for (const double x : o.scene.partitions_x_m) {
        const bool in_wall = b.min().x() < x + 0.049 && b.max().x() > x - 0.049;
        EXPECT_FALSE(in_wall) << s.name;
        const bool in_doorway =
            b.min().x() < x + 0.6 && b.max().x() > x - 0.6 &&
            b.min().y() < d / 2 + door / 2 && b.max().y() > d / 2 - door / 2;
        EXPECT_FALSE(in_doorway) << s.name;
      }
    }
    // In the first doorway's clearance, 0.6 m before the wall, beside the
    // door's edge, looking through it.
    const double x = o.scene.partitions_x_m[0];
    const Eigen::Vector3d eye(x - 0.6, d / 2 - door / 2 + 0.1, 1.6);
    const Transform pose = LookAt(eye, eye + Eigen::Vector3d::UnitX());
    const CameraIntrinsics k{160, 120, 131.25, 131.25, 79.5, 59.5};
    const RenderedFrame f = Render(scene, 0.0, pose, k);
    size_t wall = 0, beyond = 0;
    for (size_t p = 0; p < f.instance.NumPixels(); ++p) {
      wall += f.instance.data()[p] == walls[0]->instance_id;
      beyond += f.depth.data()[p] > 1.0f;
    }
    EXPECT_GT(wall, f.instance.NumPixels() / 10);
    EXPECT_GT(beyond, f.instance.NumPixels() / 10);
  }
}

// The kitchen's counters are rows of base cabinets under a worktop: 0.9 m
// high, 0.64 m deep, 2 m or longer; most stand against a wall (their back
// within 2 cm of it).
TEST(Synth, KitchenCountersAreLongLowRowsAgainstTheWalls) {
  const uint16_t counter = *SynthClasses().FindByName("counter");
  size_t counters = 0, against = 0;
  for (const uint64_t seed : {1u, 2u, 3u, 4u}) {
    SynthOptions o = SynthOptions::Preset("kitchen");
    o.scene.seed = seed;
    const Scene scene = GenerateScene(o.scene);
    for (const SceneObject& s : scene.objects) {
      if (s.class_id != counter) continue;
      ++counters;
      const Eigen::AlignedBox3d b = s.Bounds();
      EXPECT_NEAR(b.max().z(), 0.9, 0.01) << s.name;
      const Eigen::Vector3d size = b.sizes();
      EXPECT_GE(std::max(size.x(), size.y()), 2.0) << s.name;
      EXPECT_NEAR(std::min(size.x(), size.y()), 0.64, 0.01) << s.name;
      const Eigen::Vector3d& room = scene.room_size;
      const double to_wall =
          std::min({b.min().x(), b.min().y(), room.x() - b.max().x(),
                    room.y() - b.max().y()});
      against += to_wall < 0.02;
    }
  }
  EXPECT_EQ(counters, 8u);
  EXPECT_GE(against, 5u);
}

TEST(Synth, BadOptionsGiveClearErrors) {
  EXPECT_THROW(SynthOptions::Preset("garage"), InvalidArgument);
  try {
    SynthOptions::Preset("garage");
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown preset 'garage'"),
              std::string::npos);
  }
  SynthOptions o = SynthOptions::Preset("six-objects");
  o.frames = 0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = SynthOptions::Preset("six-objects");
  o.noise.strength = -0.5;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = SynthOptions::Preset("six-objects");
  o.scene.object_classes.push_back("unicorn");
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = SynthOptions::Preset("six-objects");
  o.width = 0;
  EXPECT_THROW(o.Check(), InvalidArgument);
}

TEST(Synth, WritesAReadableSequenceWhoseDepthLiesOnTheGroundTruth) {
  testing::TempDir dir;
  SynthOptions o = Small("six-objects", 3);
  o.noise.enabled = false;
  const SynthSummary summary = WriteSyntheticSequence(o, dir.path(), Quiet());
  EXPECT_EQ(summary.frames, 3u);
  EXPECT_EQ(summary.objects_per_class.at("chair"), 1);
  EXPECT_GT(summary.bytes_written, 10000u);

  const io::SequenceReader reader = io::SequenceReader::Open(dir.path());
  EXPECT_EQ(reader.layout(), "semrec");
  ASSERT_EQ(reader.size(), 3u);
  EXPECT_EQ(reader.intrinsics(), o.Intrinsics());
  SceneOptions scene_options = o.scene;
  scene_options.seed = o.seed;
  const Scene scene = GenerateScene(scene_options);
  double sum = 0;
  size_t n = 0;
  std::set<uint16_t> seen_objects;
  for (size_t i = 0; i < reader.size(); ++i) {
    const Frame frame = reader.Read(i);
    const auto& layers = reader.index().frames[i].layers;
    const LabelMap instance = io::ReadLabelImage(layers.at("instance"));
    const LabelMap semantic = io::ReadLabelImage(layers.at("semantic"));
    for (int v = 0; v < frame.depth.height(); ++v) {
      for (int u = 0; u < frame.depth.width(); ++u) {
        const SceneObject* object = scene.FindObject(instance(u, v));
        ASSERT_NE(object, nullptr);
        ASSERT_EQ(object->class_id, semantic(u, v))
            << "instance and semantic maps disagree";
        const float z = frame.depth(u, v);
        if (z <= 0.0f) continue;  // beyond the 4 m cut-off
        const Eigen::Vector3d p =
            frame.T_world_camera * frame.intrinsics.BackProject(u, v, z);
        sum += object->DistanceToSurface(p);
        ++n;
        if (!object->structure) seen_objects.insert(object->instance_id);
      }
    }
  }
  ASSERT_GT(n, 10000u);
  EXPECT_LT(sum / n, 0.001)
      << "mean distance of back-projected depth to the GT surface";
  EXPECT_GE(seen_objects.size(), 3u);

  // Ground-truth files exist and agree with the scene.
  const auto objects =
      nlohmann::json::parse(ReadTextFile(dir / "gt/objects.json"));
  ASSERT_EQ(objects.size(), scene.objects.size());
  for (const auto& o_json : objects) {
    const SceneObject* object =
        scene.FindObject(o_json["instance_id"].get<uint16_t>());
    ASSERT_NE(object, nullptr);
    EXPECT_EQ(o_json["class_id"].get<uint16_t>(), object->class_id);
    EXPECT_TRUE(
        fs::is_regular_file(dir / "gt" / o_json["mesh"].get<std::string>()));
  }
  EXPECT_TRUE(fs::is_regular_file(dir / "gt/surface_points.ply"));
  EXPECT_TRUE(fs::is_regular_file(dir / "gt/classes.json"));
}

// Faces no camera sees (a bed's underside on the floor, the floor beneath it,
// a headboard's back against the wall) are not ground truth: at the contact
// line they lie within --observed-in's depth tolerance and were scored as
// seen (the flat's video walk: wall IoU 75 with ground-truth labels).
TEST(Synth, GroundTruthLeavesOutFacesHiddenAtContacts) {
  testing::TempDir dir;
  SynthOptions o = Small("flat", 1);
  o.gt_structure_spacing_m = 0.05;
  WriteSyntheticSequence(o, dir.path(), Quiet());
  SceneOptions scene_options = o.scene;
  scene_options.seed = o.seed;
  const Scene scene = GenerateScene(scene_options);
  const io::PlyData gt = io::ReadPly(dir.path() / "gt/surface_points.ply");
  const std::vector<int32_t>* instance = nullptr;
  for (const auto& [name, values] : gt.int_properties) {
    if (name == "instance") instance = &values;
  }
  ASSERT_NE(instance, nullptr);
  ASSERT_EQ(instance->size(), gt.points.size());
  size_t on_the_floor = 0, at_contacts = 0, things = 0, under_things = 0;
  for (size_t i = 0; i < gt.points.size(); ++i) {
    const Eigen::Vector3d p = gt.points[i].cast<double>();
    const SceneObject* self =
        scene.FindObject(static_cast<uint16_t>((*instance)[i]));
    ASSERT_NE(self, nullptr);
    if (!self->structure) {
      ++things;
      on_the_floor += p.z() < 0.005;
    }
    for (const SceneObject& other : scene.objects) {
      if (&other == self) continue;
      if (other.DistanceToSurface(p) < 0.005) {
        ++at_contacts;
        under_things += self->structure && !other.structure;
        break;
      }
    }
  }
  ASSERT_GT(things, 1000u);
  EXPECT_EQ(on_the_floor, 0u) << "undersides of things on the floor";
  EXPECT_EQ(under_things, 0u) << "structure beneath or behind things";
  EXPECT_EQ(at_contacts, 0u);
  // The option off, the hidden faces come back.
  testing::TempDir all;
  o.gt_hidden_contact_m = 0.0;
  WriteSyntheticSequence(o, all.path(), Quiet());
  EXPECT_GT(io::ReadPly(all.path() / "gt/surface_points.ply").points.size(),
            gt.points.size() + 1000);
}

std::map<std::string, std::string> AllFiles(const fs::path& root) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) {
      out[fs::relative(e.path(), root).string()] = ReadTextFile(e.path());
    }
  }
  return out;
}

TEST(Synth, IdenticalSeedsGiveIdenticalBytes) {
  testing::TempDir a, b, c;
  SynthOptions o = Small("six-objects", 2);
  WriteSyntheticSequence(o, a.path(), Quiet());
  WriteSyntheticSequence(o, b.path(), Quiet());
  const auto files_a = AllFiles(a.path());
  EXPECT_GT(files_a.size(), 20u);
  EXPECT_TRUE(files_a == AllFiles(b.path()));
  o.seed = 2;
  WriteSyntheticSequence(o, c.path(), Quiet());
  EXPECT_FALSE(files_a == AllFiles(c.path()));
}

TEST(Synth, RefusesNonEmptyOutputUnlessOverwrite) {
  testing::TempDir dir;
  testing::WriteText(dir / "keep.txt", "x");
  SynthOptions o = Small("six-objects", 1);
  EXPECT_THROW(WriteSyntheticSequence(o, dir.path(), Quiet()), IoError);
  o.overwrite = true;
  EXPECT_NO_THROW(WriteSyntheticSequence(o, dir.path(), Quiet()));
  EXPECT_TRUE(fs::exists(dir / "keep.txt"));
}

// The people preset: frames with nobody and with several people, people who
// leave and come back, and MOT boxes that match the person maps.
TEST(Synth, PeoplePresetHasReEntryAndConsistentTracks) {
  testing::TempDir dir;
  SynthOptions o = Small("people", 200);
  o.noise.enabled = false;
  SynthSummary summary = WriteSyntheticSequence(o, dir.path(), Quiet());
  EXPECT_EQ(summary.people, 3);
  EXPECT_GT(summary.frames_with_people[0], 0) << "some frames must have nobody";
  int several = 0;
  for (const auto& [count, frames] : summary.frames_with_people) {
    several += count >= 2 ? frames : 0;
  }
  EXPECT_GT(several, 10) << "several frames must show 2+ people";

  std::map<int, std::vector<int>> frames_of;  // person id -> frames with a box
  std::map<std::pair<int, int>, std::array<int, 4>> box;
  std::istringstream mot(ReadTextFile(dir / "gt/people/gt.txt"));
  std::string line;
  while (std::getline(mot, line)) {
    int f, id, x, y, w, h;
    ASSERT_EQ(
        std::sscanf(line.c_str(), "%d,%d,%d,%d,%d,%d", &f, &id, &x, &y, &w, &h),
        6)
        << line;
    frames_of[id].push_back(f);
    box[{f, id}] = {x, y, w, h};
  }
  int re_entries = 0;
  for (const auto& [id, frames] : frames_of) {
    for (size_t i = 1; i < frames.size(); ++i) {
      re_entries += frames[i] - frames[i - 1] > 5;
    }
  }
  EXPECT_GT(re_entries, 0) << "someone must leave the view and come back";

  // Boxes are the bounding boxes of the person map (MOT: 1-based left/top).
  const io::SequenceReader reader = io::SequenceReader::Open(dir.path());
  for (const auto& [key, b] : box) {
    if (key.first % 25 != 0) continue;
    const LabelMap person = io::ReadLabelImage(
        reader.index().frames[key.first - 1].layers.at("person"));
    int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
    for (int v = 0; v < person.height(); ++v) {
      for (int u = 0; u < person.width(); ++u) {
        if (person(u, v) != key.second) continue;
        x0 = std::min(x0, u), y0 = std::min(y0, v), x1 = std::max(x1, u),
        y1 = std::max(y1, v);
      }
    }
    EXPECT_EQ(b,
              (std::array<int, 4>{x0 + 1, y0 + 1, x1 - x0 + 1, y1 - y0 + 1}));
  }
}

}  // namespace
}  // namespace semrec::synth
