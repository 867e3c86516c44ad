#include "semrec/pipeline/people_3d.h"

#include <fmt/format.h>

#include "semrec/core/error.h"
#include "semrec/fuse/voxel.h"
#include "semrec/io/image_io.h"

namespace fs = std::filesystem;

namespace semrec::pipeline {

PersonMapSource::PersonMapSource(const std::string& spec,
                                 const io::SequenceReader& reader)
    : reader_(reader), paths_(reader.size()) {
  const auto& frames = reader.index().frames;
  size_t found = 0;
  if (spec == "gt") {
    for (size_t i = 0; i < frames.size(); ++i) {
      const auto it = frames[i].layers.find("person");
      if (it != frames[i].layers.end()) {
        paths_[i] = it->second;
        ++found;
      }
    }
    if (found == 0) {
      throw IoError(reader.root(),
                    "people 'gt' needs a sequence with a person layer (e.g. "
                    "from semrec synth --preset people)");
    }
    return;
  }
  const fs::path dir = spec;
  if (!fs::is_directory(dir)) {
    throw IoError(dir,
                  "people folder does not exist (give the persons/ folder "
                  "that semrec track wrote, or 'gt')");
  }
  for (size_t i = 0; i < frames.size(); ++i) {
    for (const fs::path& name :
         {frames[i].color_path.filename(), frames[i].depth_path.filename()}) {
      if (!name.empty() && fs::is_regular_file(dir / name)) {
        paths_[i] = dir / name;
        ++found;
        break;
      }
    }
  }
  if (found == 0) {
    throw IoError(dir,
                  fmt::format("no person map named like the sequence's "
                              "images (e.g. {}) in this folder",
                              frames.front().color_path.filename().string()));
  }
}

std::optional<LabelMap> PersonMapSource::Get(size_t i) const {
  const fs::path& path = paths_.at(i);
  if (path.empty()) return std::nullopt;
  LabelMap map = io::ReadLabelImage(path);
  const CameraIntrinsics& k = reader_.intrinsics();
  if (!map.SameSize(k.width, k.height)) {
    throw FormatError(
        path, fmt::format("person map is {}x{} but the frames are {}x{}",
                          map.width(), map.height(), k.width, k.height));
  }
  return map;
}

void People3dOptions::Check() const {
  CheckArgument(max_depth_m > 0.0, "people: max_depth_m must be > 0");
  CheckArgument(voxel_size_m > 0.0, "people: voxel_size_m must be > 0");
}

People3d::People3d(const People3dOptions& options) : options_(options) {
  options_.Check();
}

void People3d::Add(const Frame& frame, const LabelMap& person_ids) {
  CheckArgument(person_ids.SameSize(frame.depth.width(), frame.depth.height()),
                "people: person map and depth differ in size");
  std::map<uint32_t, fuse::Cloud> clouds;
  for (int v = 0; v < frame.depth.height(); ++v) {
    for (int u = 0; u < frame.depth.width(); ++u) {
      const uint16_t id = person_ids(u, v);
      const float z = frame.depth(u, v);
      if (id == 0 || !(z > 0.0f) || z > options_.max_depth_m) continue;
      const Eigen::Vector3d p_world =
          frame.T_world_camera * frame.intrinsics.BackProject(u, v, z);
      clouds[id].push_back(p_world.cast<float>());
    }
  }
  for (auto& [id, cloud] : clouds) {
    usd::PersonSample sample;
    sample.frame = frame.index;
    sample.points_world = fuse::VoxelDownsample(cloud, options_.voxel_size_m);
    if (sample.points_world.size() < options_.min_points) continue;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& p : cloud) sum += p.cast<double>();
    sample.centroid_world =
        (sum / static_cast<double>(cloud.size())).cast<float>();
    samples_[id].push_back(std::move(sample));
  }
}

std::vector<usd::PersonTrack> People3d::Tracks() const {
  std::vector<usd::PersonTrack> tracks;
  for (const auto& [id, samples] : samples_) {
    usd::PersonTrack track;
    track.track_id = id;
    track.color = LabelColor(id);
    track.samples = samples;
    tracks.push_back(std::move(track));
  }
  return tracks;
}

}  // namespace semrec::pipeline
