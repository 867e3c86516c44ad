#include "semrec/synth/generator.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/random.h"
#include "semrec/core/stopwatch.h"
#include "semrec/io/image_io.h"
#include "semrec/io/label_set_io.h"
#include "semrec/io/ply_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/synth/render.h"
#include "semrec/synth/seed.h"

namespace fs = std::filesystem;

namespace semrec::synth {
namespace {

// Raw depth units per metre in the written PNGs (0.2 mm steps, up to 13.1 m).
constexpr double kDepthScale = 5000.0;

DepthImage16 ToRaw(const DepthImage& depth) {
  DepthImage16 raw(depth.width(), depth.height(), 1);
  for (size_t i = 0; i < depth.NumPixels(); ++i) {
    raw.values()[i] = static_cast<uint16_t>(std::min(
        65535.0,
        std::round(static_cast<double>(depth.values()[i]) * kDepthScale)));
  }
  return raw;
}

nlohmann::json PrimitiveJson(const Primitive& p) {
  auto vec = [](const Eigen::Vector3d& v) {
    return std::vector<double>{v.x(), v.y(), v.z()};
  };
  if (const auto* b = std::get_if<Box>(&p)) {
    const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> rm = b->R_world_box;
    const std::vector<double> r(rm.data(), rm.data() + 9);
    return {{"type", "box"},
            {"center", vec(b->center)},
            {"half_extents", vec(b->half)},
            {"R_world_box", r}};
  }
  if (const auto* c = std::get_if<Cylinder>(&p)) {
    return {{"type", "cylinder"},
            {"a", vec(c->a)},
            {"b", vec(c->b)},
            {"radius", c->radius}};
  }
  if (const auto* c = std::get_if<Capsule>(&p)) {
    return {{"type", "capsule"},
            {"a", vec(c->a)},
            {"b", vec(c->b)},
            {"radius", c->radius}};
  }
  const auto& s = std::get<Sphere>(p);
  return {{"type", "sphere"}, {"center", vec(s.center)}, {"radius", s.radius}};
}

uint64_t FileSize(const fs::path& p) {
  std::error_code ec;
  const auto size = fs::file_size(p, ec);
  return ec ? 0 : size;
}

}  // namespace

void SynthOptions::Check() const {
  scene.Check();
  trajectory.Check();
  noise.Check();
  CheckArgument(frames > 0,
                fmt::format("synth: frames must be > 0, got {}", frames));
  CheckArgument(frames <= 100000, "synth: at most 100000 frames");
  CheckArgument(fps > 0.0, "synth: fps must be > 0");
  CheckArgument(
      width >= 16 && height >= 16 && width <= 8192 && height <= 8192,
      fmt::format("synth: resolution must be between 16 and 8192, got {}x{}",
                  width, height));
  CheckArgument(fx > 0.0 && fy > 0.0, "synth: focal lengths must be > 0");
  CheckArgument(
      noise.max_depth_m * kDepthScale < 65535.0,
      "synth: max_depth_m must be < 13.1 (depth PNGs store 0.2 mm steps)");
  label_noise.Check();
  CheckArgument(gt_object_spacing_m >= 0.001 && gt_structure_spacing_m >= 0.001,
                "synth: ground-truth sample spacing must be >= 1 mm");
  CheckArgument(gt_hidden_contact_m >= 0.0 && gt_hidden_contact_m <= 0.05,
                "synth: gt_hidden_contact_m must be in [0, 0.05]");
  CheckArgument(trajectory.kind != TrajectoryOptions::Kind::kOrbit ||
                    trajectory.height_m < scene.room_height_m - 0.1,
                "synth: the camera must be below the ceiling");
  CheckArgument(trajectory.kind != TrajectoryOptions::Kind::kSparse ||
                    trajectory.sparse_max_height_m < scene.room_height_m - 0.1,
                "synth: sparse cameras must stay below the ceiling");
}

CameraIntrinsics SynthOptions::Intrinsics() const {
  return {width, height, fx, fy, (width - 1) / 2.0, (height - 1) / 2.0};
}

std::vector<std::string> SynthOptions::PresetNames() {
  return {"six-objects", "people", "office", "flat", "kitchen"};
}

SynthOptions SynthOptions::Preset(const std::string& name) {
  SynthOptions o;
  if (name == "six-objects") {
    // A room with 6 objects, as in the paper's runtime table; table and chair
    // usually touch.
    o.scene.object_classes = {"table", "chair",   "sofa",
                              "shelf", "cabinet", "plant"};
    o.frames = 60;
  } else if (name == "people") {
    // A static camera watching people walk loops that leave the view and come
    // back.
    o.scene.room_width_m = 8.0;
    o.scene.room_depth_m = 6.0;
    o.scene.room_height_m = 2.8;
    o.scene.object_classes = {"sofa", "shelf", "table", "chair", "plant"};
    o.scene.num_people = 3;
    o.trajectory.kind = TrajectoryOptions::Kind::kStatic;
    o.trajectory.height_m = 1.6;
    o.frames = 200;
    o.fps = 10.0;
  } else if (name == "office") {
    o.scene.room_width_m = 12.0;
    o.scene.room_depth_m = 9.0;
    o.scene.room_height_m = 3.0;
    o.scene.object_classes = {
        "table", "chair",   "chair",   "monitor", "table",   "chair",
        "chair", "monitor", "table",   "chair",   "monitor", "shelf",
        "shelf", "cabinet", "cabinet", "box",     "box",     "box",
        "plant", "plant",   "lamp",    "sofa",    "box",     "lamp"};
    o.scene.touching_probability = 0.5;
    o.trajectory.kind = TrajectoryOptions::Kind::kWalkthrough;
    o.trajectory.height_m = 2.2;
    o.frames = 300;
  } else if (name == "flat") {
    // Three rooms in a row (living room, dining room, bedroom) joined by
    // doorways: furniture against interior walls seen from both sides, as in
    // a house walk-through.
    o.scene.room_width_m = 12.0;
    o.scene.room_depth_m = 5.0;
    o.scene.room_height_m = 2.6;
    o.scene.partitions_x_m = {4.0, 8.0};
    o.scene.object_classes = {"sofa",    "table",   "chair", "chair",
                              "cabinet", "shelf",   "table", "chair",
                              "chair",   "cabinet", "bed",   "cabinet",
                              "plant",   "lamp",    "box",   "sofa"};
    o.scene.touching_probability = 0.5;
    o.trajectory.kind = TrajectoryOptions::Kind::kWalkthrough;
    o.trajectory.height_m = 1.6;
    o.frames = 300;
  } else if (name == "kitchen") {
    // A kitchen-dining room like 7-Scenes chess: rows of base cabinets under
    // a worktop against the walls (with --label-bleed the 2D model calls them
    // wall), a table with chairs.
    o.scene.room_width_m = 5.0;
    o.scene.room_depth_m = 4.5;
    o.scene.room_height_m = 2.6;
    o.scene.object_classes = {"counter", "counter", "table",   "chair",
                              "chair",   "chair",   "cabinet", "plant"};
    o.scene.touching_probability = 0.3;
    o.trajectory.kind = TrajectoryOptions::Kind::kWalkthrough;
    o.trajectory.height_m = 1.6;
    o.frames = 300;
  } else {
    throw InvalidArgument(
        fmt::format("synth: unknown preset '{}' (choose six-objects, people, "
                    "office, flat or kitchen)",
                    name));
  }
  return o;
}

namespace {

// MOTChallenge rows from a frame's person map: boxes of the visible pixels,
// visibility ratio against the unoccluded silhouette.
std::string MotRows(const RenderedFrame& r, const Scene& scene, int frame,
                    double time_s, const Transform& T_world_camera,
                    const CameraIntrinsics& k, int* visible_people) {
  std::map<uint16_t, std::array<int, 5>> boxes;  // id -> x0, y0, x1, y1, pixels
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const uint16_t pid = r.person(u, v);
      if (pid == 0) continue;
      auto [it, inserted] =
          boxes.try_emplace(pid, std::array<int, 5>{u, v, u, v, 0});
      auto& b = it->second;
      b[0] = std::min(b[0], u), b[1] = std::min(b[1], v);
      b[2] = std::max(b[2], u), b[3] = std::max(b[3], v);
      ++b[4];
    }
  }
  std::string rows;
  for (const auto& [pid, b] : boxes) {
    const Silhouette full =
        UnoccludedSilhouette(scene, pid, time_s, T_world_camera, k);
    const double visibility =
        full.pixels > 0 ? std::min(1.0, static_cast<double>(b[4]) / full.pixels)
                        : 1.0;
    rows +=
        fmt::format("{},{},{},{},{},{},1,1,{:.4f}\n", frame + 1, pid, b[0] + 1,
                    b[1] + 1, b[2] - b[0] + 1, b[3] - b[1] + 1, visibility);
  }
  *visible_people = static_cast<int>(boxes.size());
  return rows;
}

// Renders frame i and writes its images (colour, noisy and clean depth, the
// label layers, noisy labels when asked); returns the bytes written.
uint64_t WriteFrame(const SynthOptions& options, const Scene& scene,
                    const CameraIntrinsics& k, const Transform& T_world_camera,
                    int i, const fs::path& out_dir, io::FrameRecord* record,
                    std::string* mot_rows, int* visible_people) {
  const double time_s = i / options.fps;
  const RenderedFrame r = Render(scene, time_s, T_world_camera, k);
  const DepthImage noisy = ApplyDepthNoise(
      r.depth, r.cos_incidence, k, options.noise, MixSeed(options.seed, i + 1));
  DepthNoiseOptions clean_options = options.noise;
  clean_options.enabled = false;
  const DepthImage clean =
      ApplyDepthNoise(r.depth, r.cos_incidence, k, clean_options, 0);
  const std::string stem = fmt::format("{:06}.png", i);
  record->color_path = out_dir / "color" / stem;
  record->depth_path = out_dir / "depth" / stem;
  record->timestamp_s = time_s;
  record->T_world_camera = T_world_camera;
  record->layers = {{"depth_clean", out_dir / "depth_clean" / stem},
                    {"semantic", out_dir / "semantic" / stem},
                    {"instance", out_dir / "instance" / stem},
                    {"person", out_dir / "person" / stem}};
  io::WritePng(record->color_path, r.color);
  io::WritePng(record->depth_path, ToRaw(noisy));
  io::WritePng(record->layers["depth_clean"], ToRaw(clean));
  io::WritePng(record->layers["semantic"], r.semantic);
  io::WritePng(record->layers["instance"], r.instance);
  io::WritePng(record->layers["person"], r.person);
  uint64_t bytes = FileSize(record->color_path) + FileSize(record->depth_path);
  if (options.write_noisy_labels) {
    const NoisyLabels noisy_labels =
        ApplyLabelNoise(r, scene, T_world_camera, k, options.label_noise,
                        MixSeed(MixSeed(options.seed, 0x1abe1), i + 1),
                        MixSeed(options.seed, 0xb1eed));
    const fs::path noisy_dir = out_dir / "labels_noisy";
    io::WritePng(noisy_dir / "instance" / stem, noisy_labels.instance);
    io::WritePng(noisy_dir / "semantic" / stem, noisy_labels.semantic);
    bytes += FileSize(noisy_dir / "instance" / stem) +
             FileSize(noisy_dir / "semantic" / stem);
  }
  for (const auto& [name, path] : record->layers) bytes += FileSize(path);
  *mot_rows = MotRows(r, scene, i, time_s, T_world_camera, k, visible_people);
  return bytes;
}

// Whether surface sample s of object `self` lies within the contact distance
// of another object (hidden where they touch).
class ContactTest {
 public:
  ContactTest(const Scene& scene, double contact_m)
      : scene_(scene), contact_m_(contact_m) {
    const Eigen::Vector3d pad = Eigen::Vector3d::Constant(contact_m);
    for (const SceneObject& o : scene.objects) {
      const Eigen::AlignedBox3d b = o.Bounds();
      near_bounds_.emplace_back(b.min() - pad, b.max() + pad);
    }
  }
  bool TouchesAnother(size_t self, const Eigen::Vector3d& s) const {
    if (contact_m_ <= 0.0) return false;
    for (size_t k = 0; k < scene_.objects.size(); ++k) {
      if (k == self || !near_bounds_[k].contains(s)) continue;
      for (const Primitive& p : scene_.objects[k].parts) {
        if (SignedDistance(p, s) < contact_m_) return true;
      }
    }
    return false;
  }

 private:
  const Scene& scene_;
  double contact_m_;
  std::vector<Eigen::AlignedBox3d> near_bounds_;
};

// Whether a surface sample of part `part` of object o belongs to the visible
// surface: not outside the room, not inside another part of o, and for an
// interior wall not where its parts meet or on the room's bounds.
bool VisibleSample(const SceneObject& o, size_t part, const Eigen::Vector3d& s,
                   const Eigen::Vector3d& room_size) {
  const Eigen::Vector3d lo = -Eigen::Vector3d::Constant(1e-6);
  const Eigen::Vector3d hi = room_size + Eigen::Vector3d::Constant(1e-6);
  if ((s.array() < lo.array()).any() || (s.array() > hi.array()).any()) {
    return false;
  }
  const bool inside = std::any_of(
      o.parts.begin(), o.parts.end(),
      [&](const Primitive& p) { return SignedDistance(p, s) < -1e-6; });
  if (inside) return false;
  // An interior wall's faces where its parts meet, and those on the room's
  // bounds (floor, ceiling, outer walls), no camera can see.
  if (o.structure && !o.room_face) {
    const Eigen::Vector3d in_lo = lo.array() + 2e-6;
    const Eigen::Vector3d in_hi = hi.array() - 2e-6;
    if ((s.array() < in_lo.array()).any() ||
        (s.array() > in_hi.array()).any()) {
      return false;
    }
    for (size_t j = 0; j < o.parts.size(); ++j) {
      if (j != part && SignedDistance(o.parts[j], s) < 1e-6) return false;
    }
  }
  return true;
}

nlohmann::json ObjectJson(const SceneObject& o, const std::string& mesh_name) {
  const Eigen::AlignedBox3d b = o.Bounds();
  nlohmann::json parts = nlohmann::json::array();
  for (const Primitive& p : o.parts) parts.push_back(PrimitiveJson(p));
  return {{"instance_id", o.instance_id},
          {"class_id", o.class_id},
          {"class", SynthClasses().Get(o.class_id).name},
          {"name", o.name},
          {"structure", o.structure},
          {"color", o.color},
          {"bounds_min", {b.min().x(), b.min().y(), b.min().z()}},
          {"bounds_max", {b.max().x(), b.max().y(), b.max().z()}},
          {"mesh", mesh_name},
          {"parts", parts}};
}

// gt/objects.json, gt/meshes/*.ply and the visible surface's samples
// (gt/surface_points.ply, what `semrec eval scene` reads: per point the class
// and the instance; `label` repeats the instance for older readers). Returns
// the number of surface points.
size_t WriteObjectsGroundTruth(const SynthOptions& options, const Scene& scene,
                               const fs::path& gt) {
  nlohmann::json objects = nlohmann::json::array();
  io::PlyData surface;
  std::vector<int32_t> semantic, instance;
  const ContactTest contact(scene, options.gt_hidden_contact_m);
  for (size_t oi = 0; oi < scene.objects.size(); ++oi) {
    const SceneObject& o = scene.objects[oi];
    const std::string mesh_name = fmt::format("meshes/{}.ply", o.name);
    objects.push_back(ObjectJson(o, mesh_name));
    TriangleMesh mesh;
    std::vector<Eigen::Vector3d> samples;
    const double spacing = o.structure ? options.gt_structure_spacing_m
                                       : options.gt_object_spacing_m;
    std::vector<size_t> sample_part;
    for (size_t j = 0; j < o.parts.size(); ++j) {
      AppendMesh(o.parts[j], 24, &mesh);
      AppendSurfaceSamples(o.parts[j], spacing, &samples);
      sample_part.resize(samples.size(), j);
    }
    io::PlyData mesh_ply;
    for (const auto& v : mesh.vertices) {
      mesh_ply.points.push_back(v.cast<float>());
    }
    mesh_ply.triangles = mesh.triangles;
    io::WritePly(gt / mesh_name, mesh_ply);
    for (size_t i = 0; i < samples.size(); ++i) {
      const Eigen::Vector3d& s = samples[i];
      if (!VisibleSample(o, sample_part[i], s, scene.room_size)) continue;
      if (contact.TouchesAnother(oi, s)) continue;
      surface.points.push_back(s.cast<float>());
      surface.colors.push_back(o.color);
      surface.labels.push_back(o.instance_id);
      semantic.push_back(o.class_id);
      instance.push_back(o.instance_id);
    }
  }
  WriteTextFileAtomic(gt / "objects.json", objects.dump(2) + "\n");
  surface.int_properties = {{"semantic", std::move(semantic)},
                            {"instance", std::move(instance)}};
  io::WritePly(gt / "surface_points.ply", surface);
  return surface.points.size();
}

// gt/people.json and gt/people/gt.txt (MOTChallenge).
void WritePeopleGroundTruth(const Scene& scene,
                            const std::vector<std::string>& mot_rows,
                            const fs::path& gt) {
  nlohmann::json people = nlohmann::json::array();
  for (const Person& p : scene.people) {
    nlohmann::json path = nlohmann::json::array();
    for (const auto& q : p.path) path.push_back({q.x(), q.y()});
    people.push_back({{"person_id", p.person_id},
                      {"instance_id", kPersonInstanceBase + p.person_id},
                      {"height_m", p.height_m},
                      {"speed_mps", p.speed_mps},
                      {"start_offset_m", p.start_offset_m},
                      {"shirt", p.shirt},
                      {"pants", p.pants},
                      {"path", path}});
  }
  WriteTextFileAtomic(gt / "people.json", people.dump(2) + "\n");
  std::string mot;
  for (const std::string& rows : mot_rows) mot += rows;
  WriteTextFileAtomic(gt / "people" / "gt.txt", mot);
}

nlohmann::json SceneInfoJson(const SynthOptions& options, const Scene& scene,
                             size_t surface_points) {
  return {{"generator", "semrec synth"},
          {"seed", options.seed},
          {"frames", options.frames},
          {"fps", options.fps},
          {"room_size_m",
           {scene.room_size.x(), scene.room_size.y(), scene.room_size.z()}},
          {"views", options.trajectory.kind == TrajectoryOptions::Kind::kSparse
                        ? "sparse"
                        : "video"},
          {"noise", options.noise.enabled ? "kinect" : "none"},
          {"label_noise", options.write_noisy_labels},
          {"label_bleed_share",
           options.write_noisy_labels && options.label_noise.bleed
               ? options.label_noise.bleed_share
               : 0.0},
          {"label_consistent_cuts",
           options.write_noisy_labels ? options.label_noise.consistent_cut_share
                                      : 0.0},
          {"noise_strength", options.noise.strength},
          {"max_depth_m", options.noise.max_depth_m},
          {"depth_scale", kDepthScale},
          {"gt_object_spacing_m", options.gt_object_spacing_m},
          {"gt_structure_spacing_m", options.gt_structure_spacing_m},
          {"gt_hidden_contact_m", options.gt_hidden_contact_m},
          {"objects", scene.objects.size()},
          {"people", scene.people.size()},
          {"surface_points", surface_points}};
}

}  // namespace

SynthSummary WriteSyntheticSequence(const SynthOptions& options_in,
                                    const fs::path& out_dir,
                                    const ProgressOptions& progress_options) {
  const Stopwatch time;
  SynthOptions options = options_in;
  options.scene.seed = options.seed;
  options.Check();
  std::error_code ec;
  if (fs::exists(out_dir, ec)) {
    if (!fs::is_directory(out_dir)) {
      throw IoError(out_dir, "output exists and is not a folder");
    }
    RequireEmptyOrOverwrite(out_dir, options.overwrite);
  }
  fs::create_directories(out_dir, ec);
  if (ec) {
    throw IoError(out_dir, "cannot create output folder: " + ec.message());
  }

  const Scene scene = GenerateScene(options.scene);
  const CameraIntrinsics k = options.Intrinsics();
  const std::vector<Transform> poses = MakeTrajectory(
      scene, options.trajectory, options.frames, options.fps, options.seed);

  SynthSummary summary;
  summary.frames = static_cast<size_t>(options.frames);
  summary.people = static_cast<int>(scene.people.size());
  for (const SceneObject& o : scene.objects) {
    ++summary.objects_per_class[SynthClasses().Get(o.class_id).name];
  }

  io::SequenceIndex index;
  index.layout = "semrec";
  index.root = out_dir;
  index.intrinsics = k;
  index.depth_scale = kDepthScale;
  index.frames.resize(options.frames);
  std::vector<std::string> mot_rows(options.frames);
  std::vector<int> visible_people(options.frames, 0);
  std::atomic<uint64_t> bytes{0};
  std::mutex progress_mutex;
  Progress progress("rendering", options.frames, progress_options);
  tbb::parallel_for(0, options.frames, [&](int i) {
    bytes += WriteFrame(options, scene, k, poses[i], i, out_dir,
                        &index.frames[i], &mot_rows[i], &visible_people[i]);
    std::lock_guard<std::mutex> lock(progress_mutex);
    progress.Tick();
  });
  progress.Finish();
  for (int n : visible_people) ++summary.frames_with_people[n];

  io::WriteSequenceManifest(out_dir / "sequence.yaml", index);

  // Ground truth.
  const fs::path gt = out_dir / "gt";
  io::WriteLabelSetJson(gt / "classes.json", SynthClasses());
  if (options.write_noisy_labels) {
    io::WriteLabelSetJson(out_dir / "labels_noisy" / "classes.json",
                          SynthClasses());
  }
  const size_t surface_points = WriteObjectsGroundTruth(options, scene, gt);
  WritePeopleGroundTruth(scene, mot_rows, gt);
  WriteTextFileAtomic(
      gt / "scene.json",
      SceneInfoJson(options, scene, surface_points).dump(2) + "\n");

  for (const auto& entry : fs::recursive_directory_iterator(gt)) {
    if (entry.is_regular_file()) bytes += entry.file_size();
  }
  bytes += FileSize(out_dir / "sequence.yaml");
  summary.bytes_written = bytes;
  summary.seconds = time.Elapsed();
  return summary;
}

}  // namespace semrec::synth
