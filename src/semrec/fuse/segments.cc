#include "semrec/fuse/segments.h"

#include <algorithm>
#include <cstdlib>
#include <map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/io/image_io.h"
#include "semrec/io/json_file.h"
#include "semrec/io/label_set_io.h"

namespace fs = std::filesystem;

namespace semrec::fuse {
namespace {

LabelMap ReadChecked(const fs::path& path, const CameraIntrinsics& k) {
  LabelMap labels = io::ReadLabelImage(path);
  if (!labels.SameSize(k.width, k.height)) {
    throw FormatError(
        path, fmt::format("label map is {}x{} but the frames are {}x{}",
                          labels.width(), labels.height(), k.width, k.height));
  }
  return labels;
}

class LayerSource : public SegmentationSource {
 public:
  explicit LayerSource(const io::SequenceReader& reader) {
    const fs::path classes = reader.root() / "gt" / "classes.json";
    if (!fs::is_regular_file(classes)) {
      throw IoError(classes,
                    "class table missing (labels 'gt' need the sequence's "
                    "gt/classes.json)");
    }
    classes_ = io::ReadLabelSetJson(classes);
  }
  FrameLabels Get(const io::SequenceReader& reader, size_t i) const override {
    const auto& layers = reader.index().frames.at(i).layers;
    for (const char* name : {"instance", "semantic"}) {
      if (layers.count(name) == 0) {
        throw FormatError(
            reader.root() / "sequence.yaml",
            fmt::format("frame {} has no '{}' layer (labels 'gt' need the "
                        "instance and semantic layers)",
                        i, name));
      }
    }
    return {ReadChecked(layers.at("instance"), reader.intrinsics()),
            ReadChecked(layers.at("semantic"), reader.intrinsics()),
            layers.at("instance").string()};
  }
  const LabelSet& classes() const override { return classes_; }

 private:
  LabelSet classes_;
};

// `semrec segment` writes each instance's confidence (what fusion weighs its
// votes by) into masks/<stem>.json; label folders without it weigh 1.
void ReadConfidence(const fs::path& file, FrameLabels* labels) {
  std::error_code ec;
  if (!fs::exists(file, ec)) return;
  const nlohmann::json j = io::ReadJsonFile(file);
  const auto it = j.find("instance_confidence");
  if (it == j.end()) return;
  if (!it->is_object()) {
    throw FormatError(file, "'instance_confidence' is not an object");
  }
  for (const auto& [key, value] : it->items()) {
    char* end = nullptr;
    const int64_t id = std::strtol(key.c_str(), &end, 10);
    if (end == key.c_str() || *end != '\0' || id < 1 || id > 65535 ||
        !value.is_number() || value.get<double>() < 0.0 ||
        value.get<double>() > 1.0) {
      throw FormatError(file, fmt::format("instance_confidence: '{}': {} is "
                                          "not an instance id with a "
                                          "confidence in [0, 1]",
                                          key, value.dump()));
    }
    labels->confidence[static_cast<uint16_t>(id)] = value.get<float>();
  }
}

class FolderSource : public SegmentationSource {
 public:
  explicit FolderSource(const fs::path& folder) : folder_(folder) {
    classes_ = io::ReadLabelSetJson(folder / "classes.json");
  }
  FrameLabels Get(const io::SequenceReader& reader, size_t i) const override {
    const fs::path name = reader.index().frames.at(i).depth_path.filename();
    std::error_code ec;
    if (!fs::exists(folder_ / "instance" / name, ec)) {
      // Usually labels made for every n-th frame (`semrec segment --stride`).
      throw IoError(folder_ / "instance" / name,
                    fmt::format("no labels for frame {} of the sequence ({}); "
                                "if {} was made with `semrec segment "
                                "--stride N`, fuse with the same --stride",
                                i, name.string(), folder_.string()));
    }
    FrameLabels labels{
        ReadChecked(folder_ / "instance" / name, reader.intrinsics()),
        ReadChecked(folder_ / "semantic" / name, reader.intrinsics()),
        (folder_ / "instance" / name).string()};
    ReadConfidence(folder_ / "masks" / (name.stem().string() + ".json"),
                   &labels);
    return labels;
  }
  const LabelSet& classes() const override { return classes_; }

 private:
  fs::path folder_;
  LabelSet classes_;
};

class SingleClassSource : public SegmentationSource {
 public:
  explicit SingleClassSource(const std::string& name) : classes_("single") {
    classes_.Add({1, name, {200, 200, 200}});
  }
  FrameLabels Get(const io::SequenceReader& reader, size_t) const override {
    const CameraIntrinsics& k = reader.intrinsics();
    return {LabelMap(k.width, k.height, 1, 1),
            LabelMap(k.width, k.height, 1, 1), "single class"};
  }
  const LabelSet& classes() const override { return classes_; }

 private:
  LabelSet classes_;
};

}  // namespace

LabelSpec LabelSpec::Parse(const std::string& text) {
  CheckArgument(!text.empty(),
                "labels must be 'models', 'gt', 'single:<class>' or a label "
                "folder");
  if (text == "models") return {Kind::kModels, ""};
  if (text == "gt") return {Kind::kSequence, ""};
  if (text.rfind("single:", 0) == 0) {
    CheckArgument(text.size() > 7, "labels 'single:<class>' need a class name");
    return {Kind::kSingleClass, text.substr(7)};
  }
  return {Kind::kFolder, text};
}

std::string LabelSpec::Text() const {
  switch (kind) {
    case Kind::kModels:
      return "models";
    case Kind::kSequence:
      return "gt";
    case Kind::kFolder:
      return value;
    case Kind::kSingleClass:
      return "single:" + value;
  }
  return "?";
}

std::unique_ptr<SegmentationSource> SegmentationSource::Create(
    const LabelSpec& spec, const io::SequenceReader& reader) {
  switch (spec.kind) {
    case LabelSpec::Kind::kModels:
      break;
    case LabelSpec::Kind::kSequence:
      return std::make_unique<LayerSource>(reader);
    case LabelSpec::Kind::kSingleClass:
      return std::make_unique<SingleClassSource>(spec.value);
    case LabelSpec::Kind::kFolder:
      if (!fs::is_directory(spec.value)) {
        throw IoError(spec.value,
                      "labels must be 'gt', 'single:<class>' or an existing "
                      "folder with instance/, semantic/ and classes.json");
      }
      return std::make_unique<FolderSource>(spec.value);
  }
  throw InvalidArgument(
      "labels 'models' come from the segmentation models, not from files");
}

std::unique_ptr<SegmentationSource> SegmentationSource::Create(
    const std::string& spec, const io::SequenceReader& reader) {
  return Create(LabelSpec::Parse(spec), reader);
}

Eigen::Vector3f SurfaceNormalAt(const DepthImage& depth,
                                const CameraIntrinsics& k, int u, int v,
                                int step_px) {
  const float z = depth(u, v);
  if (z <= 0.0f) return Eigen::Vector3f::Zero();
  const Eigen::Vector3f c = k.BackProject(u, v, z).cast<float>();
  // The point step_px pixels along (du, dv), when on the same surface.
  auto neighbour = [&](int du, int dv, Eigen::Vector3f* q) {
    const int nu = u + du * step_px, nv = v + dv * step_px;
    if (nu < 0 || nv < 0 || nu >= depth.width() || nv >= depth.height()) {
      return false;
    }
    const float zn = depth(nu, nv);
    if (zn <= 0.0f || std::abs(zn - z) > 0.1f * z) return false;
    *q = k.BackProject(nu, nv, zn).cast<float>();
    return true;
  };
  // Difference along one image axis: central where both sides are there.
  auto difference = [&](int du, int dv, Eigen::Vector3f* d) {
    Eigen::Vector3f plus, minus;
    const bool has_plus = neighbour(du, dv, &plus);
    const bool has_minus = neighbour(-du, -dv, &minus);
    if (has_plus && has_minus) {
      *d = plus - minus;
    } else if (has_plus) {
      *d = plus - c;
    } else if (has_minus) {
      *d = c - minus;
    } else {
      return false;
    }
    return true;
  };
  Eigen::Vector3f du, dv;
  if (!difference(1, 0, &du) || !difference(0, 1, &dv)) {
    return Eigen::Vector3f::Zero();
  }
  Eigen::Vector3f n = du.cross(dv);
  const float norm = n.norm();
  if (!(norm > 0.0f)) return Eigen::Vector3f::Zero();
  n /= norm;
  return n.dot(c) > 0.0f ? Eigen::Vector3f(-n) : n;
}

void SegmentExtractionOptions::Check() const {
  CheckArgument(pixel_stride >= 1, "segments: pixel_stride must be >= 1");
}

std::vector<FrameSegment> ExtractFrameSegments(
    const Frame& frame, const FrameLabels& labels, const LabelSet& classes,
    const SegmentExtractionOptions& options) {
  options.Check();
  const int w = frame.depth.width(), h = frame.depth.height();
  if (!labels.instance.SameSize(w, h) || !labels.semantic.SameSize(w, h)) {
    throw FormatError(
        labels.source,
        fmt::format("label maps are {}x{} / {}x{} but the depth is {}x{}",
                    labels.instance.width(), labels.instance.height(),
                    labels.semantic.width(), labels.semantic.height(), w, h));
  }
  // Per instance: its points and a histogram of its semantic labels.
  struct Accumulator {
    Cloud points;
    Cloud normals;
    std::map<uint16_t, size_t> votes;
  };
  std::map<uint16_t, Accumulator> by_instance;
  const CameraIntrinsics& k = frame.intrinsics;
  // The normal's pixel step grows with depth (3 pixels per metre at 640
  // wide: a 1.1 cm baseline each way at 1 m, 18 cm at 4 m): a depth sensor's
  // noise and its disparity steps grow with the square of the depth, and a
  // far wall's normals from neighbouring pixels point along the rays.
  const float normal_step_per_m = 3.0f * static_cast<float>(w) / 640.0f;
  const Eigen::Matrix3f R_world_camera =
      frame.T_world_camera.rotation().cast<float>();
  for (int v = 0; v < h; v += options.pixel_stride) {
    for (int u = 0; u < w; u += options.pixel_stride) {
      const uint16_t instance = labels.instance(u, v);
      if (instance == 0) continue;
      Accumulator& acc = by_instance[instance];
      ++acc.votes[labels.semantic(u, v)];
      const float z = frame.depth(u, v);
      if (z <= 0.0f) continue;
      acc.points.push_back(
          (frame.T_world_camera * k.BackProject(u, v, z)).cast<float>());
      acc.normals.push_back(
          R_world_camera *
          SurfaceNormalAt(frame.depth, k, u, v,
                          std::max(2, static_cast<int>(std::lround(
                                          normal_step_per_m * z)))));
    }
  }
  std::vector<FrameSegment> out;
  for (auto& [instance, acc] : by_instance) {
    uint16_t cls = 0;
    size_t best = 0;
    for (const auto& [label, count] : acc.votes) {
      if (count > best) best = count, cls = label;
    }
    // 0 is "unlabelled" unless the class table names it (PASCAL VOC's
    // "background": a mask voted background is still a surface, a wall or a
    // floor, worth fusing as its own class).
    if (cls == 0 && !classes.Contains(0)) continue;
    if (!classes.Contains(cls)) {
      throw FormatError(
          labels.source,
          fmt::format("semantic label {} is not in the class table "
                      "'{}' ({} classes)",
                      cls, classes.name(), classes.size()));
    }
    if (options.excluded_classes.count(classes.Get(cls).name) != 0) continue;
    if (acc.points.size() < options.min_points) continue;
    const auto map_object = labels.map_objects.find(instance);
    const auto confidence = labels.confidence.find(instance);
    out.push_back(
        {cls, instance, std::move(acc.points), classes.Get(cls).kind,
         map_object == labels.map_objects.end() ? 0u : map_object->second,
         confidence == labels.confidence.end() ? 1.0f : confidence->second,
         std::move(acc.normals)});
  }
  return out;
}

namespace {

// FarView of `frame`: its labels at the centres of the grid cells without
// depth, and its reach.
void ObserveFar(const Frame& frame, const FrameLabels& labels,
                const LabelMap* person_ids, FarView* far) {
  const int w = frame.depth.width(), h = frame.depth.height();
  far->T_world_camera = frame.T_world_camera;
  far->intrinsics = frame.intrinsics;
  if (!labels.semantic.SameSize(w, h) || frame.intrinsics.width != w ||
      frame.intrinsics.height != h) {
    return;
  }
  const bool check_people = person_ids != nullptr && person_ids->SameSize(w, h);
  const bool has_instances = labels.instance.SameSize(w, h);
  const bool check_map = !labels.map_objects.empty() && has_instances;
  std::vector<float> depths;
  constexpr int kStride = FarView::kStride;
  for (int row = 0, v = kStride / 2; v < h; ++row, v += kStride) {
    for (int col = 0, u = kStride / 2; u < w; ++col, u += kStride) {
      const float z = frame.depth(u, v);
      if (z > 0.0f) {
        depths.push_back(z);
        continue;
      }
      const uint16_t cls = labels.semantic(u, v);
      if (cls == 0 || (check_people && (*person_ids)(u, v) != 0)) continue;
      const uint16_t instance = has_instances ? labels.instance(u, v) : 0;
      if (check_map && labels.map_objects.count(instance) != 0) continue;
      const auto sure = labels.confidence.find(instance);
      far->cells.push_back(static_cast<uint32_t>(row * far->columns() + col));
      far->class_ids.push_back(cls);
      far->confidence.push_back(sure == labels.confidence.end() ? 1.0f
                                                                : sure->second);
    }
  }
  if (depths.empty()) return;
  const size_t k = depths.size() * 99 / 100;
  std::nth_element(depths.begin(), depths.begin() + static_cast<ptrdiff_t>(k),
                   depths.end());
  far->max_ranged_depth_m = depths[k];
}

}  // namespace

FrameObservation ObserveFrame(const Frame& frame, const FrameLabels& labels,
                              const LabelMap* person_ids, int pixel_stride) {
  CheckArgument(pixel_stride >= 1, "ObserveFrame: pixel_stride must be >= 1");
  const int w = frame.depth.width(), h = frame.depth.height();
  const bool check_map =
      !labels.map_objects.empty() && labels.instance.SameSize(w, h);
  const bool check_people = person_ids != nullptr && person_ids->SameSize(w, h);
  FrameObservation observation;
  observation.camera_position_world =
      frame.T_world_camera.translation().cast<float>();
  Cloud& out = observation.observed_world;
  out.reserve(static_cast<size_t>(w / pixel_stride + 1) *
              static_cast<size_t>(h / pixel_stride + 1));
  for (int v = 0; v < h; v += pixel_stride) {
    for (int u = 0; u < w; u += pixel_stride) {
      const float z = frame.depth(u, v);
      if (z <= 0.0f) continue;
      if (check_people && (*person_ids)(u, v) != 0) continue;
      if (check_map && labels.map_objects.count(labels.instance(u, v)) != 0) {
        continue;
      }
      out.push_back(
          (frame.T_world_camera * frame.intrinsics.BackProject(u, v, z))
              .cast<float>());
    }
  }
  ObserveFar(frame, labels, person_ids, &observation.far);
  return observation;
}

}  // namespace semrec::fuse
