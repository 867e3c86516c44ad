#include "semrec/segment/segment_io.h"

#include <algorithm>
#include <map>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/image_io.h"
#include "semrec/io/sequence_reader.h"

namespace fs = std::filesystem;

namespace semrec::segment {
namespace {

bool IsImageFile(const fs::path& p) {
  const std::string ext = LowerExtension(p);
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".ppm";
}

// Files that are sequences of their own: bags, ScanNet .sens, manifests.
bool IsSequenceFile(const fs::path& path) {
  const std::string ext = LowerExtension(path);
  return ext == ".mcap" || ext == ".db3" || ext == ".sens" || ext == ".yaml" ||
         ext == ".yml" || ext == ".json";
}

}  // namespace

std::vector<SegmentInput> ListSegmentInputs(const fs::path& path, int stride,
                                            size_t max_frames) {
  CheckArgument(stride >= 1, "segment: stride must be >= 1");
  std::vector<SegmentInput> inputs;
  if (fs::is_regular_file(path) && !IsSequenceFile(path)) {
    if (!IsImageFile(path)) {
      throw FormatError(path,
                        "not an image (.png, .jpg, .jpeg) nor an RGB-D "
                        "sequence file (.mcap, .db3, .sens, sequence.yaml)");
    }
    inputs.push_back({path.stem().string() + ".png", path, nullptr, 0});
    return inputs;
  }
  // An RGB-D sequence first: 7-Scenes and 3DMatch keep colour and depth
  // images side by side in one folder, which is not an image folder; bags
  // and .sens files are single files.
  io::SequenceReaderOptions options;
  options.stride = stride;
  options.max_frames = max_frames;
  if (auto reader = io::SequenceReader::TryOpen(path, options)) {
    auto shared =
        std::make_shared<const io::SequenceReader>(std::move(*reader));
    for (size_t i = 0; i < shared->size(); ++i) {
      const auto& frame = shared->index().frames[i];
      inputs.push_back(
          {frame.depth_path.filename().string(), frame.color_path, shared, i});
    }
    return inputs;
  }
  if (fs::is_regular_file(path)) {
    throw FormatError(path, "not an RGB-D sequence semrec reads");
  }
  RequireDirectory(path, "input");
  std::vector<fs::path> images;
  for (const auto& e : fs::directory_iterator(path)) {
    if (e.is_regular_file() && IsImageFile(e.path())) {
      images.push_back(e.path());
    }
  }
  if (images.empty()) {
    throw IoError(path,
                  "no images (.png, .jpg, .jpeg) and no known RGB-D sequence "
                  "layout in this folder");
  }
  std::sort(images.begin(), images.end());
  for (size_t i = 0; i < images.size(); i += static_cast<size_t>(stride)) {
    inputs.push_back(
        {images[i].stem().string() + ".png", images[i], nullptr, 0});
    if (max_frames && inputs.size() >= max_frames) break;
  }
  return inputs;
}

ColorImage SegmentInput::Load() const {
  return sequence ? sequence->Read(frame).color : io::ReadColorImage(image);
}

ColorImage RenderLabelOverlay(const ColorImage& rgb, const LabelMap& semantic,
                              const LabelMap& instance,
                              const LabelSet& labels) {
  CheckArgument(semantic.width() == rgb.width() &&
                    semantic.height() == rgb.height() &&
                    instance.SameSize(semantic),
                "overlay: labels and image differ in size");
  ColorImage out = rgb;
  const int w = rgb.width(), h = rgb.height();
  // Colours and regions in flat tables by label (the class table's maps,
  // looked up per pixel, were most of an overlay's time).
  constexpr size_t kLabels = size_t{1} << 16;
  std::vector<std::array<uint8_t, 3>> colors;
  std::vector<int32_t> color_of(kLabels, -1);
  // Names go where a region is widest: the pixel farthest from any instance
  // boundary (a centroid can fall outside a non-convex region).
  cv::Mat inside(h, w, CV_8UC1);
  const uint16_t* inst_data = instance.data();
  const uint16_t* sem_data = semantic.data();
  const uint8_t* in = rgb.data();
  uint8_t* o = out.data();
  for (int y = 0; y < h; ++y) {
    const uint16_t* row = inst_data + static_cast<size_t>(y) * w;
    uint8_t* inside_row = inside.ptr<uint8_t>(y);
    for (int x = 0; x < w; ++x) {
      const uint16_t inst = row[x];
      const bool edge = (x + 1 < w && row[x + 1] != inst) ||
                        (y + 1 < h && row[x + w] != inst);
      const bool border = x == 0 || y == 0 || x + 1 == w || y + 1 == h;
      inside_row[x] = edge || border ? 0 : 255;
      const size_t at = static_cast<size_t>(y) * w + x;
      const uint16_t id = sem_data[at];
      if (color_of[id] < 0) {
        color_of[id] = static_cast<int32_t>(colors.size());
        colors.push_back(labels.Contains(id) ? labels.Get(id).color
                                             : LabelColor(id));
      }
      const std::array<uint8_t, 3>& color = colors[color_of[id]];
      // Mask outlines in white.
      for (int c = 0; c < 3; ++c) {
        o[at * 3 + c] =
            edge ? 255 : static_cast<uint8_t>((in[at * 3 + c] + color[c]) / 2);
      }
    }
  }
  cv::Mat distance;
  cv::distanceTransform(inside, distance, cv::DIST_L2, 3);
  struct Region {
    uint16_t instance = 0;
    int64_t area = 0;
    float best = -1.0f;
    int bx = 0, by = 0;
    std::vector<std::pair<uint16_t, int64_t>> classes;  // few per region
  };
  std::vector<Region> found;
  std::vector<int32_t> region_of(kLabels, -1);
  for (int y = 0; y < h; ++y) {
    const float* d_row = distance.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      const size_t at = static_cast<size_t>(y) * w + x;
      const uint16_t inst = inst_data[at];
      if (inst == 0) continue;
      if (region_of[inst] < 0) {
        region_of[inst] = static_cast<int32_t>(found.size());
        found.emplace_back().instance = inst;
      }
      Region& r = found[region_of[inst]];
      ++r.area;
      const uint16_t id = sem_data[at];
      auto c = std::find_if(r.classes.begin(), r.classes.end(),
                            [id](const auto& e) { return e.first == id; });
      if (c == r.classes.end()) {
        r.classes.emplace_back(id, 1);
      } else {
        ++c->second;
      }
      const float d = d_row[x];
      if (d > r.best) {
        r.best = d;
        r.bx = x;
        r.by = y;
      }
    }
  }
  // By instance, each region's classes by id: names drawn in the same order
  // and ties decided as before.
  std::sort(found.begin(), found.end(), [](const Region& a, const Region& b) {
    return a.instance < b.instance;
  });
  for (Region& r : found) std::sort(r.classes.begin(), r.classes.end());
  cv::Mat canvas(h, w, CV_8UC3, out.data());
  const double scale = std::clamp(w / 1200.0, 0.35, 1.0);
  for (const Region& r : found) {
    if (r.area < 400) continue;  // no room for a name
    const uint16_t id = std::max_element(r.classes.begin(), r.classes.end(),
                                         [](const auto& a, const auto& b) {
                                           return a.second < b.second;
                                         })
                            ->first;
    if (id == 0 && !labels.Contains(0)) continue;
    const std::string name =
        labels.Contains(id) ? labels.Get(id).name : std::to_string(id);
    int baseline = 0;
    const cv::Size size =
        cv::getTextSize(name, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
    const cv::Point at(
        std::clamp(r.bx - size.width / 2, 0, std::max(0, w - size.width)),
        std::clamp(r.by + size.height / 2, size.height, h - 1));
    cv::putText(canvas, name, at, cv::FONT_HERSHEY_SIMPLEX, scale,
                cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
    cv::putText(canvas, name, at, cv::FONT_HERSHEY_SIMPLEX, scale,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  return out;
}

ColorImage RenderOverlay(const ColorImage& rgb, const HybridResult& result,
                         const LabelSet& labels) {
  return RenderLabelOverlay(rgb, result.vote.semantic, result.vote.instance,
                            labels);
}

void WriteSegmentation(const fs::path& out_dir, const SegmentInput& input,
                       const ColorImage& rgb, const HybridResult& result,
                       const LabelSet& labels) {
  io::WritePng(out_dir / "semantic" / input.name, result.vote.semantic);
  io::WritePng(out_dir / "instance" / input.name, result.vote.instance);
  io::WritePng(out_dir / "overlay" / input.name,
               RenderOverlay(rgb, result, labels));
  const auto class_name = [&](uint16_t id) {
    return labels.Contains(id) ? labels.Get(id).name : std::string();
  };
  nlohmann::json masks = nlohmann::json::array();
  for (size_t m = 0; m < result.masks.size(); ++m) {
    const Mask& mask = result.masks[m];
    const uint16_t id = result.vote.mask_labels[m];
    nlohmann::json evidence = nlohmann::json::array();
    float stuff_scale = 1.0f;
    if (m < result.mask_evidence.size()) {
      for (const ClassWeight& e : result.mask_evidence[m].weights) {
        evidence.push_back({{"class", class_name(e.class_id)},
                            {"label", e.class_id},
                            {"weight", e.weight}});
      }
      stuff_scale = result.mask_evidence[m].stuff_scale;
    }
    const int detection =
        m < result.mask_detection.size() ? result.mask_detection[m] : -1;
    const int part_of =
        m < result.mask_part_of.size() ? result.mask_part_of[m] : -1;
    masks.push_back(
        {{"instance", m < result.mask_instance.size()
                          ? result.mask_instance[m]
                          : static_cast<uint16_t>(m + 1)},
         {"label", id},
         {"class", labels.Contains(id) ? labels.Get(id).name : ""},
         {"area", mask.area},
         {"bbox",
          {mask.box.x0, mask.box.y0, mask.box.width(), mask.box.height()}},
         {"predicted_iou", mask.predicted_iou},
         {"stability", mask.stability},
         {"vote_agreement", result.vote.mask_agreement[m]},
         {"confidence", m < result.vote.mask_confidence.size()
                            ? result.vote.mask_confidence[m]
                            : result.vote.mask_agreement[m]},
         {"point", {mask.point_x, mask.point_y}},
         {"detection", detection},
         {"part_of", part_of},
         {"detector_evidence", evidence},
         {"stuff_scale", stuff_scale}});
  }
  nlohmann::json detections = nlohmann::json::array();
  for (const ObjectDetection& d : result.detections) {
    detections.push_back(
        {{"class", class_name(d.class_id)},
         {"label", d.class_id},
         {"detector_class", d.detector_class},
         {"score", d.score},
         {"bbox", {d.box.x0, d.box.y0, d.box.width(), d.box.height()}}});
  }
  // What `semrec run` would give fusion for each instance (the vote's mass on
  // the winning class; unmasked pixels: mean softmax): `run --labels` on this
  // folder reads it back.
  nlohmann::json instance_confidence = nlohmann::json::object();
  for (const auto& [id, c] :
       InstanceConfidence(result.vote, result.semantic_branch.confidence)) {
    instance_confidence[std::to_string(id)] = c;
  }
  const nlohmann::json j = {
      {"image", input.image.string()},
      {"width", rgb.width()},
      {"height", rgb.height()},
      {"label_set", labels.name()},
      {"masks", masks},
      {"detections", detections},
      {"detections_matched", result.detections_matched},
      {"detections_added", result.detections_added},
      {"detection_parts", result.detection_parts},
      {"parts_joined", result.parts_joined},
      {"instance_confidence", instance_confidence},
      {"seconds",
       {{"semantic", result.semantic_seconds},
        {"detect", result.detect_seconds},
        {"object_masks", result.object_mask_seconds},
        {"mask_encode", result.mask_stats.encode_seconds},
        {"mask_decode", result.mask_stats.decode_seconds},
        {"mask_postprocess", result.mask_stats.postprocess_seconds},
        {"vote", result.vote_seconds}}},
      {"prompts",
       {{"total", result.mask_stats.prompts_total},
        {"decoded", result.mask_stats.prompts_decoded},
        {"rejected_on_preview", result.mask_stats.prompts_rejected_early},
        {"candidates", result.mask_stats.candidates}}}};
  WriteTextFileAtomic(
      out_dir / "masks" / (fs::path(input.name).stem().string() + ".json"),
      j.dump(2) + "\n");
}

}  // namespace semrec::segment
