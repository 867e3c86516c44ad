// The generic semrec layout: a YAML (or JSON, which YAML reads too) manifest
// listing frames.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/layouts.h"

namespace fs = std::filesystem;

namespace semrec::io::internal {
namespace {

template <typename T>
T Get(const YAML::Node& node, const char* key, const fs::path& path,
      const std::string& where) {
  const YAML::Node value = node[key];
  if (!value) {
    throw FormatError(path, fmt::format("{}: missing key '{}'", where, key));
  }
  try {
    return value.as<T>();
  } catch (const YAML::Exception&) {
    throw FormatError(
        path, fmt::format("{}: key '{}' has the wrong type", where, key));
  }
}

fs::path Resolve(const fs::path& base, const std::string& p) {
  const fs::path path(p);
  return path.is_absolute() ? path : base / path;
}

SequenceIndex IndexFromYaml(const YAML::Node& root, const fs::path& manifest,
                            const SequenceReaderOptions& options) {
  if (!root.IsMap() || Get<std::string>(root, "format", manifest, "manifest") !=
                           "semrec-sequence") {
    throw FormatError(
        manifest,
        "not a semrec sequence manifest (expected 'format: semrec-sequence')");
  }
  const int version = Get<int>(root, "version", manifest, "manifest");
  if (version != 1) {
    throw FormatError(
        manifest,
        fmt::format("unsupported manifest version {} (this build reads 1)",
                    version));
  }
  const fs::path base = manifest.parent_path();
  SequenceIndex index;
  index.layout = "semrec";
  index.root = base;
  index.pose_source = manifest.filename().string();
  const YAML::Node k = root["intrinsics"];
  if (!k || !k.IsMap()) throw FormatError(manifest, "missing map 'intrinsics'");
  index.intrinsics = {Get<int>(k, "width", manifest, "intrinsics"),
                      Get<int>(k, "height", manifest, "intrinsics"),
                      Get<double>(k, "fx", manifest, "intrinsics"),
                      Get<double>(k, "fy", manifest, "intrinsics"),
                      Get<double>(k, "cx", manifest, "intrinsics"),
                      Get<double>(k, "cy", manifest, "intrinsics")};
  index.intrinsics_source = manifest.filename().string();
  if (!options.intrinsics_path.empty()) {
    index.intrinsics =
        ReadIntrinsicsFile(options.intrinsics_path, index.intrinsics.width,
                           index.intrinsics.height);
    index.intrinsics_source = options.intrinsics_path.string();
  }
  if (root["depth_scale"]) {
    index.depth_scale = Get<double>(root, "depth_scale", manifest, "manifest");
  }
  if (root["depth_invalid"]) {
    index.depth_invalid =
        Get<uint16_t>(root, "depth_invalid", manifest, "manifest");
  }
  if (!(index.depth_scale > 0.0)) {
    throw FormatError(manifest, "depth_scale must be > 0");
  }

  const YAML::Node frames = root["frames"];
  if (!frames || !frames.IsSequence()) {
    throw FormatError(manifest, "missing list 'frames'");
  }
  for (size_t i = 0; i < frames.size(); ++i) {
    const YAML::Node f = frames[i];
    const std::string where = fmt::format("frame {}", i);
    FrameRecord record;
    record.color_path =
        Resolve(base, Get<std::string>(f, "color", manifest, where));
    record.depth_path =
        Resolve(base, Get<std::string>(f, "depth", manifest, where));
    record.timestamp_s = f["timestamp_s"]
                             ? Get<double>(f, "timestamp_s", manifest, where)
                             : static_cast<double>(i) / 30.0;
    const auto m =
        Get<std::vector<double>>(f, "T_world_camera", manifest, where);
    if (m.size() != 16) {
      throw FormatError(
          manifest,
          fmt::format("{}: T_world_camera must have 16 numbers (row-major "
                      "4x4), got {}",
                      where, m.size()));
    }
    const Eigen::Matrix4d matrix =
        Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(
            m.data());
    try {
      record.T_world_camera =
          Transform::FromMatrix(matrix, where + " T_world_camera");
    } catch (const InvalidArgument& e) {
      throw FormatError(manifest, e.what());
    }
    if (const YAML::Node layers = f["layers"]) {
      if (!layers.IsMap()) {
        throw FormatError(manifest, where + ": 'layers' must be a map");
      }
      for (const auto& kv : layers) {
        record.layers[kv.first.as<std::string>()] =
            Resolve(base, kv.second.as<std::string>());
      }
    }
    for (const fs::path& p : {record.color_path, record.depth_path}) {
      if (!fs::is_regular_file(p)) {
        throw FormatError(manifest, fmt::format("{}: file {} does not exist",
                                                where, p.string()));
      }
    }
    index.frames.push_back(std::move(record));
  }
  return index;
}

}  // namespace

std::optional<SequenceIndex> IndexManifest(
    const fs::path& path, const SequenceReaderOptions& options) {
  fs::path manifest;
  if (fs::is_regular_file(path)) {
    manifest = path;
  } else {
    for (const char* name :
         {"sequence.yaml", "sequence.yml", "sequence.json"}) {
      if (fs::is_regular_file(path / name)) {
        manifest = path / name;
        break;
      }
    }
  }
  if (manifest.empty()) return std::nullopt;

  YAML::Node root;
  try {
    root = YAML::Load(ReadTextFile(manifest));
  } catch (const YAML::Exception& e) {
    throw FormatError(manifest, std::string("invalid YAML/JSON: ") + e.what());
  }
  // yaml-cpp throws for a node of the wrong kind anywhere (a scalar where a
  // map is expected, ...): all of it is a broken manifest.
  try {
    return IndexFromYaml(root, manifest, options);
  } catch (const YAML::Exception& e) {
    throw FormatError(manifest,
                      std::string("malformed manifest: ") + e.what());
  }
}

}  // namespace semrec::io::internal
